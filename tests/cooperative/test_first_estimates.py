"""First-estimates (FEJ) and observability-constrained (OC) Jacobians: the linearised team
keeps the unobservable global frame.

The derivations are in :mod:`relloc.estimators.first_estimates` and
:mod:`relloc.estimators.observability_constrained`. These tests record every transition ``Φ_k``
(per-robot blocks, or dense for OC) and measurement Jacobian ``H_k`` the filter is handed over a
seeded short run (seed 001 scenario) and check the property the derivations promise: the
unobservable directions ``N`` travel with the transitions and stay in the null space of every
``H``, for the FEJ and OC filters exactly and for the plain filter not.
"""

from dataclasses import dataclass, field

import numpy as np
import pytest

import relloc.estimators.cooperative as cooperative
from relloc.errors import ConfigError
from relloc.estimators.cooperative import CooperativeSettings, OdometryModel, SensorModel
from relloc.estimators.first_estimates import first_estimates_transition
from relloc.estimators.observability_constrained import (
    constrained_rows,
    constrained_transition,
    unobservable_directions,
)
from relloc.models.planar_measurement import LinearisedRows
from relloc.pipeline.replay import replay
from relloc.sim.cooperative import sharma2013_scenario, simulate

J = np.array([[0.0, -1.0], [1.0, 0.0]])


def _rotation_direction(X: np.ndarray, centre: np.ndarray) -> np.ndarray:
    """``N_r (3n,)``: a common rotation of the team about ``centre``, per robot
    ``[J(p − c); 1]``."""
    return np.column_stack([(X[:, :2] - centre) @ J.T, np.ones(len(X))]).reshape(-1)


def _translations(n: int) -> np.ndarray:
    return np.tile(np.vstack([np.eye(2), np.zeros((1, 2))]), (n, 1))


def test_transition_carries_the_rotation_direction_between_first_estimates():
    rng = np.random.default_rng(11)
    first, now = rng.normal(size=(4, 3)) * 30, rng.normal(size=(4, 3)) * 30
    F = first_estimates_transition(now, first)
    for c in (np.zeros(2), np.array([12.0, -7.0])):
        carried = np.einsum("iab,ib->ia", F, _rotation_direction(first, c).reshape(4, 3))
        np.testing.assert_allclose(carried.reshape(-1), _rotation_direction(now, c), atol=1e-9)
    identity = np.tile(np.eye(3), (4, 1, 1))
    np.testing.assert_array_equal(first_estimates_transition(first, first), identity)


@dataclass
class RecordingFilter:
    """A joint filter that keeps every ``Φ`` and ``H`` it is handed (delegating the work)."""

    inner: cooperative.TeamFilter
    transitions: list[np.ndarray] = field(default_factory=list)
    jacobians: list[np.ndarray] = field(default_factory=list)

    def mean(self) -> np.ndarray:
        return self.inner.mean()

    def covariance(self) -> np.ndarray:
        return self.inner.covariance()

    def predict(self, mean_pred, F_blocks, Q_blocks) -> None:
        self.transitions.append(np.array(F_blocks))
        self.jacobians.append(None)
        self.inner.predict(mean_pred, F_blocks, Q_blocks)

    def update(self, rows: LinearisedRows) -> None:
        self.jacobians[-1] = rows.dense_jacobian(self.inner.mean().shape[0])
        self.inner.update(rows)


@pytest.fixture(scope="module")
def sharma_short():
    scenario = sharma2013_scenario(duration=20.0)
    return scenario, simulate(scenario, np.random.default_rng(3))


def _run(sharma_short, monkeypatch, linearisation, anchors=()):
    scenario, sim = sharma_short
    made: list[RecordingFilter] = []
    real = cooperative.make_filter

    def recording_filter(prior, kind):
        made.append(RecordingFilter(real(prior, kind)))
        return made[-1]

    monkeypatch.setattr(cooperative, "make_filter", recording_filter)
    settings = CooperativeSettings(
        odometry=OdometryModel.from_discrete(scenario.sigma_v, scenario.sigma_w, scenario.dt),
        sensor=SensorModel(sigma_bearing=scenario.sigma_bearing),
        anchors=anchors,
        linearisation=linearisation,
    )
    rec = sim.recording
    est = cooperative.CooperativeEstimator(rec.robots, sim.prior, settings, rec.landmarks)
    replay(rec, [est], record_times=np.array([20.0]), start=0.0, end=20.0)
    return made[0], sim.prior.mean.reshape(-1, 3), rec.landmarks[:, :2]


def _worst_leak(filt: RecordingFilter, N: np.ndarray) -> float:
    """max over epochs of ``‖H_k N_k‖ / (‖H_k‖ ‖N_k‖)`` with ``N_{k} = Φ_k N_{k−1}``."""
    n = N.shape[0] // 3
    worst = 0.0
    for F, H in zip(filt.transitions, filt.jacobians, strict=True):
        if F.ndim == 2:  # dense (OC)
            N = F @ N
        else:
            N = np.einsum("iab,ibk->iak", F, N.reshape(n, 3, -1)).reshape(3 * n, -1)
        if H is not None and H.size:
            worst = max(worst, np.linalg.norm(H @ N) / (np.linalg.norm(H) * np.linalg.norm(N)))
    return worst


@pytest.mark.parametrize("landmarks", [0, 1])
def test_fej_and_oc_keep_the_unobservable_directions_and_the_plain_filter_does_not(
    sharma_short, monkeypatch, landmarks
):
    leaks = {}
    for lin in ("first_estimates", "observability_constrained", "latest"):
        filt, X0, lm = _run(sharma_short, monkeypatch, lin, anchors=tuple(range(landmarks)))
        if landmarks == 0:  # translation and rotation about the origin
            N = np.column_stack([_translations(len(X0)), _rotation_direction(X0, np.zeros(2))])
        else:  # only the rotation about the landmark
            N = _rotation_direction(X0, lm[0])[:, None]
        assert sum(H is not None for H in filt.jacobians) > 50
        leaks[lin] = _worst_leak(filt, N)
    assert leaks["first_estimates"] < 1e-9, leaks
    assert leaks["observability_constrained"] < 1e-9, leaks
    assert leaks["latest"] > 1e-4, leaks


def test_oc_transition_is_the_least_change_that_carries_the_directions():
    rng = np.random.default_rng(12)
    n = 4
    before, after = rng.normal(size=(n, 3)) * 30, rng.normal(size=(n, 3)) * 30
    F_blocks = np.tile(np.eye(3), (n, 1, 1))
    F_blocks[:, :2, 2] = rng.normal(size=(n, 2))
    for anchors in (np.zeros((0, 2)), np.array([[12.0, -7.0]])):
        N0 = unobservable_directions(before, anchors, fixed=False)
        N1 = unobservable_directions(after, anchors, fixed=False)
        F = constrained_transition(F_blocks, N0, N1)
        np.testing.assert_allclose(F @ N0, N1, atol=1e-9)
        # least change: F − diag(F_blocks) has its rows in the span of N0ᵀ (the Lagrange form)
        plain = constrained_transition(F_blocks, np.zeros((3 * n, 0)), np.zeros((3 * n, 0)))
        change = F - plain
        np.testing.assert_allclose(change @ N0 @ np.linalg.pinv(N0), change, atol=1e-9)
        # any other solution is farther from the plain transition
        other = F + rng.normal(size=(3 * n, 3 * n)) @ (np.eye(3 * n) - N0 @ np.linalg.pinv(N0))
        np.testing.assert_allclose(other @ N0, N1, atol=1e-8)
        assert np.linalg.norm(other - plain) > np.linalg.norm(change)
    two = np.array([[0.0, 0.0], [10.0, 0.0]])
    assert unobservable_directions(before, two, fixed=False).shape == (3 * n, 0)
    assert unobservable_directions(before, np.zeros((0, 2)), fixed=True).shape == (3 * n, 0)


def test_oc_rows_annihilate_the_directions_within_their_sparsity():
    rng = np.random.default_rng(13)
    n, m = 4, 6
    X = rng.normal(size=(n, 3)) * 30
    N = unobservable_directions(X, np.zeros((0, 2)), fixed=False)
    index = np.array([[0, 1], [2, 3], [1, 0], [3, 2], [0, 2], [1, 3]])
    lin = LinearisedRows(
        residual=rng.normal(size=m),
        blocks=rng.normal(size=(m, 2, 3)),
        block_index=index,
        sigma=np.ones(m),
        group=np.arange(m),
    )
    out = constrained_rows(lin, N)
    H = out.dense_jacobian(n)
    np.testing.assert_allclose(H @ N, 0.0, atol=1e-9)
    np.testing.assert_array_equal(out.residual, lin.residual)
    # rows already annihilating N are unchanged
    again = constrained_rows(out, N)
    np.testing.assert_allclose(again.blocks, out.blocks, atol=1e-12)


def test_fej_oc_and_plain_filters_agree_before_the_first_update(sharma_short):
    scenario, sim = sharma_short
    rec = sim.recording
    beliefs = {}
    for lin in ("first_estimates", "observability_constrained", "latest"):
        settings = CooperativeSettings(
            odometry=OdometryModel.from_discrete(scenario.sigma_v, scenario.sigma_w, scenario.dt),
            sensor=SensorModel(sigma_bearing=scenario.sigma_bearing),
            use_bearing=False,
            linearisation=lin,
        )
        est = cooperative.CooperativeEstimator(rec.robots, sim.prior, settings, rec.landmarks)
        beliefs[lin] = replay(rec, [est], record_times=np.array([5.0]), start=0.0, end=5.0)
    b = beliefs["latest"].stacked("team", rec.robots)
    for lin in ("first_estimates", "observability_constrained"):
        a = beliefs[lin].stacked("team", rec.robots)
        np.testing.assert_array_equal(a[1], b[1])
        np.testing.assert_allclose(a[2], b[2], rtol=1e-12, atol=1e-12)


def test_linearisation_setting_is_validated():
    odo = OdometryModel.from_discrete(0.2, 0.2, 0.1)
    with pytest.raises(ConfigError, match="linearisation"):
        CooperativeSettings(odometry=odo, sensor=SensorModel(sigma_bearing=0.1), linearisation="x")
