"""Observability branches that user models, options or hostile input reach: refused options
and inputs (each naming where), rows that cannot be judged at a probe point, fallbacks for
too many inputs or too large expressions, and rigid motions that do not fill a null space."""

from __future__ import annotations

from typing import Any

import networkx as nx
import numpy as np
import pytest
import sympy as sp

from relloc.errors import ConfigError, DataError, ModelError
from relloc.models import symbolic as S
from relloc.models.motion import VelocityNoise
from relloc.models.planar_measurement import empty_rows
from relloc.observability.analysis import analyse, describe_conditions, rank_at
from relloc.observability.builtin import ModelOptions, resolve_models
from relloc.observability.lie import lie_rows
from relloc.observability.pcrlb import relative_pair_pcrlb, unicycle_team_pcrlb
from relloc.observability.pcrlb_recursion import (
    measurement_information,
    pcrlb_information,
    pcrlb_ratio,
)
from relloc.observability.rank import numeric_rank, precise_rank
from relloc.observability.rpmg import (
    measurement_edges,
    minimal_moving_sets,
    name_unobservable_directions,
    team_observability_matrix,
)

X, Y = sp.symbols("x y", real=True)
U = sp.Symbol("u", real=True)


# ------------------------------------------------------------------------- built-in models


@pytest.mark.parametrize(
    ("opts", "match"),
    [
        (dict(robots=7), "--robots must be in 1..6 for symbolic analysis, got 7"),
        (dict(robots=2, gps=(3,)), r"--gps robots must be in 1\.\.2, got \[3\]"),
    ],
)
def test_model_options_out_of_range_are_refused(opts: dict[str, Any], match: str) -> None:
    with pytest.raises(ConfigError, match=match):
        ModelOptions(**opts)


@pytest.mark.parametrize(
    ("spec", "match"),
    [
        ("relloc.models.symbolic:", "user model must be 'package.module:function'"),
        (":unicycle_team", "user model must be 'package.module:function'"),
        ("relloc.models.symbolic:UNICYCLE_STATES", "'UNICYCLE_STATES' is not a callable"),
    ],
)
def test_user_model_specs_that_name_no_function_are_refused(spec: str, match: str) -> None:
    with pytest.raises(ConfigError, match=match):
        resolve_models(spec, ModelOptions())


def test_built_in_models_take_the_measurements_and_inputs_asked_for() -> None:
    (model,) = resolve_models("relative-nonlinear", ModelOptions(measurements=("range",)))
    assert len(model.outputs) == 1 and model.outputs == S.relative_nonlinear(("range",)).outputs
    (team,) = resolve_models("unicycle-team", ModelOptions(robots=2, inputs=("v_1",)))
    assert team.input_names == ("v_1",)
    assert len(team.input_fields) == 1


# ---------------------------------------------------------------------------- the analysis


def test_condition_descriptions_of_unenumerated_and_unreachable_ranks() -> None:
    assert describe_conditions(None) == "not enumerated (too many inputs)"
    assert describe_conditions([]) == "the generic rank is never reached with any input"


def test_analysis_refuses_bad_options_and_a_model_singular_everywhere(toy_symbolic_model) -> None:
    with pytest.raises(ModelError, match="analyse: samples must be ≥ 1, got 0"):
        analyse(toy_symbolic_model(), samples=0)
    with pytest.raises(ModelError, match=r"analyse: directions must be auto\|numeric\|none"):
        analyse(toy_symbolic_model(), directions="symbolic")
    nowhere = toy_symbolic_model(outputs=(sp.sqrt(X),), state_box=((-2.0, -1.0), (-1.0, 1.0)))
    with pytest.raises(ModelError, match="model 'toy': could not find finite evaluation points"):
        analyse(nowhere, samples=2)


def test_conditions_are_not_enumerated_for_more_than_ten_input_groups(toy_symbolic_model) -> None:
    """``ẋ = Σ u_k`` over eleven inputs: ``x`` is observable with none of them, ``y`` never."""
    inputs = sp.symbols("u0:11", real=True)
    model = toy_symbolic_model(inputs=inputs, input_fields=tuple((1, 0) for _ in inputs))
    result = analyse(model, order=1, samples=2)
    assert result.rank == 1 and result.conditions is None and result.input_conditions is None
    assert "11 input groups: condition enumeration skipped" in result.notes


def test_a_large_null_vector_expression_falls_back_to_a_numeric_direction(
    toy_symbolic_model,
) -> None:
    """``h`` a long polynomial of ``x`` alone: ``y`` is unobservable, ``(x, y) ∝ (0, 1)``; the
    gradient row is too large for Cramer's rule in closed form."""
    h = sum(sp.Integer(k) * X**k * sp.sin(k * X) for k in range(1, 80))
    result = analyse(toy_symbolic_model(outputs=(h,)), order=0, samples=1)
    assert result.rank == 1
    assert result.unobservable_directions == ("(x, y) ∝ (0, 1) (numeric, at the witness)",)


def test_rank_at_refuses_a_negative_order_and_wrong_sizes(toy_symbolic_model) -> None:
    model = toy_symbolic_model()
    with pytest.raises(ModelError, match="rank_at: order must be ≥ 0, got -1"):
        rank_at(model, [0.0, 0.0], [1.0], order=-1)
    with pytest.raises(ModelError, match=r"rank_at: state needs 2 values \('x', 'y'\)"):
        rank_at(model, [0.0], [1.0])
    with pytest.raises(ModelError, match=r"inputs 1 values \('u',\)"):
        rank_at(model, [0.0, 0.0], [1.0, 2.0])


def test_rows_that_cannot_be_judged_at_a_probe_point_are_kept(toy_symbolic_model) -> None:
    """``√x`` and ``x`` have parallel gradients: where both are finite (x > 0) the second is
    pruned; where ``√x`` has none (x < 0) neither can be judged against it, and both stay."""
    outputs = (sp.sqrt(X), X)
    positive = toy_symbolic_model(
        outputs=outputs, output_names=("a", "b"), state_box=((1.0, 2.0), (0, 1))
    )
    assert [r.output for r in lie_rows(positive, 0)] == [0]
    negative = toy_symbolic_model(
        outputs=outputs, output_names=("a", "b"), state_box=((-2.0, -1.0), (0, 1))
    )
    assert [r.output for r in lie_rows(negative, 0)] == [0, 1]
    swapped = toy_symbolic_model(
        outputs=outputs[::-1], output_names=("b", "a"), state_box=((-2, -1), (0, 1))
    )
    assert [r.output for r in lie_rows(swapped, 0)] == [0, 1]
    with pytest.raises(ModelError, match="Lie derivative order must be ≥ 0, got -1"):
        lie_rows(positive, -1)


def test_precise_rank_of_a_zero_matrix_is_zero() -> None:
    assert precise_rank(lambda s, p: [[0.0, 0.0], [0.0, 0.0]], np.zeros(2), np.zeros(0)) == 0
    assert precise_rank(lambda s, p: [[1.0, 0.0], [0.0, 0.0]], np.zeros(2), np.zeros(0)) == 1


# --------------------------------------------------------------------------------- the PCRLB


def test_pair_pcrlb_refuses_malformed_inputs() -> None:
    T = 3
    X = np.tile([2.0, 1.0, 0.0, 0.0], (T, 1))
    noise = VelocityNoise(observer=(0.1,) * 4, observed=(0.1,) * 4)
    ok: dict[str, Any] = dict(
        true_states=X,
        u_obs=np.zeros((T, 4)),
        u_tgt=np.zeros((T, 4)),
        dt=0.1,
        measurement_mask=np.ones(T, bool),
        sigma_r=0.1,
        sigma_theta=0.05,
        sigma_alpha=0.05,
        velocity_noise=noise,
        P0=np.eye(4),
    )
    cases = [
        ({"dt": [0.1]}, r"PCRLB: dt must be a float or 2 finite step lengths ≥ 0"),
        ({"dt": [0.1, -0.1]}, r"PCRLB: dt must be a float or 2 finite step lengths ≥ 0"),
        ({"u_obs": np.zeros((T, 3))}, r"PCRLB: u_obs has shape \(1, 3, 3\)"),
        ({"P0": np.eye(3)}, r"PCRLB: P0 has shape \(3, 3\), expected \(4, 4\)"),
        ({"u_tgt": np.zeros((T + 1, 4))}, r"PCRLB: inputs \(1, 3, 4\)/\(1, 4, 4\) must match"),
        ({"sigma_r": 0.0}, "PCRLB: sensor sigmas must be finite and > 0"),
    ]
    for change, match in cases:
        with pytest.raises(DataError, match=match):
            relative_pair_pcrlb(**{**ok, **change})


def test_team_pcrlb_refuses_malformed_inputs() -> None:
    T, n = 3, 2
    poses = np.zeros((T, n, 3))
    u = np.zeros((T, n, 2))
    rows = [empty_rows()] * T
    with pytest.raises(DataError, match=r"PCRLB: true_poses has shape \(1, 3, 2, 2\)"):
        unicycle_team_pcrlb(poses[..., :2], u, 0.1, rows, input_sigma=[0.1, 0.1], P0=np.eye(6))
    with pytest.raises(DataError, match=r"PCRLB: u has shape \(1, 3, 2, 3\)"):
        unicycle_team_pcrlb(
            poses, np.zeros((T, n, 3)), 0.1, rows, input_sigma=[0.1, 0.1], P0=np.eye(6)
        )
    with pytest.raises(DataError, match="PCRLB: input_sigma must be finite and ≥ 0"):
        unicycle_team_pcrlb(poses, u, 0.1, rows, input_sigma=[-0.1, 0.1], P0=np.eye(6))


def test_pcrlb_recursion_refuses_mismatched_stacks() -> None:
    with pytest.raises(DataError, match=r"measurement_information: H \(2, 3\) and R \(3, 3\)"):
        measurement_information(np.zeros((2, 3)), np.eye(3))
    F = np.tile(np.eye(2), (1, 2, 1, 1))
    info = np.zeros((1, 3, 2, 2))
    with pytest.raises(DataError, match=r"pcrlb: F \(1, 2, 2, 2\) and Q \(1, 2, 3, 3\)"):
        pcrlb_information(F, np.tile(np.eye(3), (1, 2, 1, 1)), info, np.eye(2))
    with pytest.raises(DataError, match=r"pcrlb: J0 has shape \(3, 3\), expected \(2, 2\)"):
        pcrlb_information(F, F, info, np.eye(3))


def test_pcrlb_ratio_of_one_run_and_its_refusals() -> None:
    """One run of errors (T, n) is the R = 1 case: per state ``√(mean e² / B_ii)`` over the
    steps from ``start``."""
    errors = np.array([[3.0, 4.0], [0.0, 2.0], [1.0, 1.0]])
    bound = np.tile(np.eye(2), (3, 1, 1))
    np.testing.assert_allclose(pcrlb_ratio(errors, bound, start=1), np.sqrt([0.5, 2.5]))
    with pytest.raises(DataError, match=r"pcrlb_ratio: start=3 outside 0\.\.2"):
        pcrlb_ratio(errors, bound, start=3)
    with pytest.raises(ModelError, match="pcrlb_ratio: the bound has a non-positive diagonal"):
        pcrlb_ratio(errors, 0.0 * bound)


# ---------------------------------------------------------------------------------- the RPMG


def _graph(n: int, l: int, edges: list[tuple[Any, Any]]) -> nx.DiGraph:
    G = nx.DiGraph(n_robots=n, n_landmarks=l)
    G.add_nodes_from(range(n + l))
    G.add_edges_from(edges)
    return G


def test_rpmg_refuses_named_nodes_wrong_speeds_and_unknown_gps_robots() -> None:
    with pytest.raises(DataError, match=r"RPMG edge 'a'→1: nodes must be integers 0\.\.1"):
        measurement_edges(_graph(2, 0, [("a", 1)]))
    G = _graph(2, 0, [(0, 1)])
    poses = np.array([[0.0, 0.0, 0.0], [2.0, 0.0, 0.0]])
    with pytest.raises(DataError, match=r"team matrix: graph has 2 robots/0 landmarks"):
        team_observability_matrix(G, poses, np.zeros((3, 2)), np.zeros((0, 2)))
    with pytest.raises(DataError, match=r"team matrix: GPS robot 2 outside 0\.\.1"):
        team_observability_matrix(G, poses, np.zeros((2, 2)), np.zeros((0, 2)), gps=[2])


def test_a_still_pair_has_null_directions_beyond_the_rigid_motions() -> None:
    """Robot 1 bears robot 2, nobody moves: one row, a 5-dimensional null space. The rigid
    motions of the pair give three (the rotation about the landmark is the rotation about the
    origin plus a translation, so adds none); two are left."""
    G = _graph(2, 1, [(0, 1)])
    poses = np.array([[0.0, 0.0, 0.0], [2.0, 0.0, 0.0]])
    landmarks = np.array([[5.0, 5.0]])
    M = team_observability_matrix(G, poses, np.zeros((2, 2)), landmarks)
    rank = numeric_rank(M)
    assert rank == 1
    assert name_unobservable_directions(G, poses, landmarks, M, rank) == [
        "translation along x of robots 1,2",
        "translation along y of robots 1,2",
        "rotation about the origin of robots 1,2",
        "2 further direction(s) not a rigid motion",
    ]


def test_moving_sets_are_not_enumerated_for_large_teams() -> None:
    n = 11
    G = _graph(n, 0, [(i, i + 1) for i in range(n - 1)])
    poses = np.column_stack([np.arange(n) * 2.0, np.zeros(n), np.zeros(n)])
    assert minimal_moving_sets(G, poses, np.ones((n, 2)), np.zeros((0, 2))) is None
