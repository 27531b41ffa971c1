"""BeliefStack (a team's beliefs as stacked arrays) and the shortcuts the team filter's speed
rests on, each checked against the general path it replaces."""

import numpy as np
import pytest

from relloc.core.contract import Belief, BeliefStack
from relloc.core.estimates import Recorder
from relloc.core.gaussian import InformationState
from relloc.core.linalg import cholesky, symmetrise
from relloc.errors import DataError, ModelError
from relloc.models.planar_measurement import (
    RowKind,
    ScalarRows,
    bearing,
    bearing_jacobians,
    linearise_rows,
    planar_range,
    range_jacobians,
)


def _stack(rng: np.random.Generator, m: int = 3, d: int = 3) -> BeliefStack:
    A = rng.normal(size=(m, d, d))
    return BeliefStack(
        [f"r{i}" for i in range(m)], "world_pose2", rng.normal(size=(m, d)), A @ A.swapaxes(1, 2)
    )


def test_stack_is_a_sequence_of_beliefs():
    stack = _stack(np.random.default_rng(1))
    assert len(stack) == 3
    beliefs = list(stack)
    assert [b.subject for b in beliefs] == ["r0", "r1", "r2"]
    assert all(isinstance(b, Belief) and b.frame == "world_pose2" for b in beliefs)
    assert np.array_equal(stack[-1].mean, stack.mean[2]) and np.array_equal(
        stack[1].cov, stack.cov[1]
    )
    assert [b.subject for b in stack[1:]] == ["r1", "r2"]
    with pytest.raises(IndexError):
        stack[3]


def test_stack_validates_shapes():
    with pytest.raises(DataError, match="mean"):
        BeliefStack(["a", "b"], "f", np.zeros((3, 3)), np.zeros((3, 3, 3)))
    with pytest.raises(DataError, match="covariance"):
        BeliefStack(["a"], "f", np.zeros((1, 3)), np.zeros((1, 2, 2)))


def test_recorder_stores_a_stack_as_the_beliefs_it_holds():
    rng = np.random.default_rng(2)
    by_stack, by_belief = Recorder("x"), Recorder("x")
    for t in (0.0, 0.5, 1.0):
        stack = _stack(rng)
        by_stack.record(t, "team", stack)
        by_belief.record(t, "team", list(stack))
        stack.mean[:] = np.nan  # the recorder keeps copies, not the estimator's arrays
        stack.cov[:] = np.nan
    a, b = by_stack.results(), by_belief.results()
    assert a.labels == b.labels == ("team->r0", "team->r1", "team->r2")
    for sa, sb in zip(a.beliefs, b.beliefs, strict=True):
        for name in ("t", "mean", "cov", "age"):
            assert np.array_equal(getattr(sa, name), getattr(sb, name))
    # increments of a stack, and a series that has diagnostics keeps its columns aligned
    assert by_stack.take_new().beliefs[0].t.size == 3
    by_stack.record(
        1.5, "team", [Belief("r0", "world_pose2", np.zeros(3), np.eye(3), info={"w": 1.0})]
    )
    by_stack.record(2.0, "team", _stack(rng))
    (r0, *_) = by_stack.take_new().beliefs
    assert np.array_equal(r0.t, [1.5, 2.0]) and np.array_equal(
        r0.info["w"], [1.0, np.nan], equal_nan=True
    )


def test_symmetric_shortcuts_give_the_same_numbers():
    rng = np.random.default_rng(3)
    A = rng.normal(size=(9, 9))
    P = symmetrise(A @ A.T + 9 * np.eye(9))  # exactly symmetric
    assert np.array_equal(symmetrise(P), P)
    assert np.array_equal(cholesky(P, symmetric=True), cholesky(P))
    y = rng.normal(size=9)
    fast, checked = (
        InformationState.from_symmetric(y, P),
        InformationState(info_vector=y, info_matrix=P),
    )
    assert np.array_equal(fast.info_matrix, checked.info_matrix)
    assert np.array_equal(fast.info_vector, checked.info_vector)
    with pytest.raises(ModelError, match="non-finite"):
        InformationState.from_symmetric(np.full(9, np.nan), P)
    with pytest.raises(ModelError, match="shape"):
        InformationState.from_symmetric(y[:3], P)


def test_linearise_rows_of_mixed_kinds_equal_the_per_kind_models():
    """Each relative kind is linearised on its own rows; mixed batches give exactly what the
    bearing and range models give row by row."""
    rng = np.random.default_rng(5)
    X = rng.normal(size=(4, 3)) * [10, 10, 1]
    kind = np.array(
        [RowKind.RANGE, RowKind.BEARING, RowKind.RANGE, RowKind.BEARING, RowKind.POSE_X]
    )
    rows = ScalarRows(
        kind=kind,
        observer=np.array([0, 1, 2, 3, 1]),
        target=np.array([1, -1, 3, 0, -1]),
        landmark_xy=np.array([[0.0, 0.0], [25.0, 3.0], [0.0, 0.0], [0.0, 0.0], [0.0, 0.0]]),
        z=rng.normal(size=5),
        sigma=np.full(5, 0.1),
        group=np.arange(5),
    )
    lin = linearise_rows(X, rows)
    for r in range(4):
        obs = X[rows.observer[r]]
        tgt = X[rows.target[r], :2] if rows.target[r] >= 0 else rows.landmark_xy[r]
        is_b = kind[r] == RowKind.BEARING
        h = bearing(obs, tgt) if is_b else planar_range(obs, tgt)
        H_obs, H_tgt = (bearing_jacobians if is_b else range_jacobians)(obs, tgt)
        residual = rows.z[r] - h
        if is_b:
            residual = (residual + np.pi) % (2 * np.pi) - np.pi
        assert np.isclose(lin.residual[r], residual, atol=1e-12)
        assert np.array_equal(lin.blocks[r, 0], H_obs)
        expected_tgt = np.append(H_tgt, 0.0) if rows.target[r] >= 0 else np.zeros(3)
        assert np.array_equal(lin.blocks[r, 1], expected_tgt)
