"""Degenerate-but-valid and hostile inputs to the observability API and CLI (audit).

Each case either pins a verified answer or a clear relloc error (never a NaN verdict, a raw
numpy/networkx exception or a hang).
"""

from __future__ import annotations

import networkx as nx
import numpy as np
import pytest
import sympy as sp

from relloc.cli import main
from relloc.errors import DataError, ModelError
from relloc.models.motion import VelocityNoise
from relloc.models.symbolic import SymbolicModel
from relloc.observability.analysis import analyse, rank_at
from relloc.observability.pcrlb import relative_pair_pcrlb
from relloc.observability.rank import numeric_rank, singular_values
from relloc.observability.rpmg import (
    SensorSettings,
    beta,
    build_rpmg,
    expected_rank,
    team_observability,
    team_observability_matrix,
)

WIDE = SensorSettings(sensing_range=1e6)
NO_MARKS = np.zeros((0, 2))
SIG = {"sigma_r": 0.1, "sigma_theta": 0.05, "sigma_alpha": 0.04}
NOISE = VelocityNoise(observer=(0.05,) * 4, observed=(0.05,) * 4)


def _moving(n: int) -> np.ndarray:
    return np.tile([[1.0, 0.2]], (n, 1))


def _graph(n: int, l: int, edges: list[tuple[int, int]], *, multi: bool = False) -> nx.DiGraph:
    G = (nx.MultiDiGraph if multi else nx.DiGraph)(n_robots=n, n_landmarks=l)
    G.add_nodes_from(range(n + l))
    G.add_edges_from(edges)
    return G


# --- rank tolerance ---------------------------------------------------------------------------


def _orthogonal(seed: int, n: int) -> np.ndarray:
    return np.linalg.qr(np.random.default_rng(seed).normal(size=(n, n)))[0]


def test_rank_is_scale_free() -> None:
    """The row floor is relative to the largest row: a uniformly tiny matrix keeps its rank."""
    for c in (1e-13, 1e-200, 1e200):
        assert numeric_rank(c * np.eye(3)) == 3
        assert numeric_rank(c * _orthogonal(0, 4)) == 4
    assert numeric_rank(np.zeros((3, 3))) == 0
    assert numeric_rank(np.array([[1e308, 1e308], [1e308, -1e308]])) == 2  # no norm overflow


def test_rank_of_badly_scaled_full_rank_and_noisy_deficient_matrices() -> None:
    Q = _orthogonal(1, 4)
    rows_scaled = np.diag([1.0, 1e-5, 1e-9, 1e-11]) @ Q  # rows of very different sizes
    assert numeric_rank(rows_scaled) == 4
    rng = np.random.default_rng(2)
    deficient = rng.normal(size=(8, 2)) @ rng.normal(size=(2, 4))  # rank 2
    noisy = deficient + 1e-12 * rng.normal(size=deficient.shape)
    assert numeric_rank(noisy) == 2
    sv = singular_values(noisy)
    assert sv[1] / sv[0] > 1e-3 and sv[2] / sv[0] < 1e-10  # a clear gap around RANK_RTOL


def _scaled_model(c: float) -> SymbolicModel:
    p, v, a = sp.symbols("p v a")
    return SymbolicModel(
        name="scaled",
        description="double integrator, position measured times c",
        states=(p, v),
        drift=(v, 0),
        inputs=(a,),
        input_fields=((0, 1),),
        outputs=(sp.Float(c) * p,),
        output_names=("cp",),
    )


@pytest.mark.parametrize("c", [1e-13, 1.0, 1e13])
def test_small_model_outputs_are_not_pruned(c: float) -> None:
    """Before: outputs of size 1e-13 were pruned as zero rows, then an IndexError."""
    r = analyse(_scaled_model(c), order=1, samples=2)
    assert r.rank == 2 and r.full_rank
    assert rank_at(_scaled_model(c), [1.0, 2.0], [0.0]) == 2


def test_model_measuring_nothing_has_rank_zero_and_every_direction() -> None:
    """Before: rank 0 crashed the symbolic direction search (IndexError)."""
    p, v, c = sp.symbols("p v c")
    blind = SymbolicModel(
        name="blind",
        description="output independent of the state",
        states=(p, v),
        drift=(v, 0),
        inputs=(),
        input_fields=(),
        outputs=(c,),
        output_names=("c",),
        parameters=(c,),
    )
    r = analyse(blind, order=1, samples=2)
    assert r.rank == 0 and len(r.unobservable_directions) == 2


# --- RPMG / team observability ----------------------------------------------------------------


def test_single_robot_cases() -> None:
    pose = np.array([[0.0, 0.0, 0.3]])
    alone = team_observability(pose, _moving(1), NO_MARKS, WIDE)
    assert (alone.rank, alone.expected_rank, alone.n_edges, alone.sigma_min) == (0, 0, 0, 0.0)
    one = team_observability(pose, _moving(1), np.array([[5.0, 5.0]]), WIDE)
    assert one.rank == one.expected_rank == 2
    collinear = team_observability(pose, _moving(1), np.array([[5.0, 5.0], [10.0, 10.0]]), WIDE)
    assert collinear.rank == collinear.expected_rank == 3  # moving: collinear is enough


def test_colocated_landmarks_count_once() -> None:
    """Before: expected_rank 3 (two landmark nodes) while the rank is 2 (one point)."""
    pose = np.array([[0.0, 0.0, 0.3]])
    r = team_observability(pose, _moving(1), np.array([[5.0, 5.0], [5.0, 5.0]]), WIDE)
    assert r.rank == r.expected_rank == 2


def test_two_robots_disconnected_and_colocated() -> None:
    two = np.array([[0.0, 0.0, 0.3], [3.0, 1.0, 1.0]])
    r = team_observability(two, _moving(2), NO_MARKS, WIDE)
    assert r.rank == r.expected_rank == 3 and r.n_edges == 2
    far = team_observability(two, _moving(2), NO_MARKS, SensorSettings(sensing_range=1.0))
    assert far.rank == far.expected_rank == 0 and far.n_edges == 0
    same = np.array([[0.0, 0.0, 0.3], [0.0, 0.0, 1.0]])  # one point: no bearing between them
    assert team_observability(same, _moving(2), NO_MARKS, WIDE).n_edges == 0


def test_zero_speeds_and_robots_on_a_line() -> None:
    two = np.array([[0.0, 0.0, 0.3], [3.0, 1.0, 1.0]])
    marks = np.array([[5.0, 5.0], [1.0, 9.0]])
    still = team_observability(two, np.zeros((2, 2)), marks, WIDE)
    assert still.rank == 6  # four landmark and two mutual bearings fix both poses
    assert team_observability(two, np.zeros((2, 2)), NO_MARKS, WIDE).rank == 2
    line = np.column_stack([10.0 * np.arange(4), np.zeros(4), np.zeros(4)])
    assert team_observability(line, _moving(4), marks, WIDE).rank == 12
    on_line = np.array([[50.0, 0.0], [70.0, 0.0]])  # and all driving straight along it
    straight = team_observability(line, np.tile([[1.0, 0.0]], (4, 1)), on_line, WIDE)
    assert straight.rank < straight.expected_rank == 12  # generic formula, special motion


def test_hand_made_graph_errors_are_data_errors() -> None:
    """Before: self-loop → 'singular configuration', bad nodes → IndexError, multigraph →
    ValueError, NaN speeds silently counted as moving."""
    P2 = np.array([[0.0, 0.0, 0.3], [3.0, 1.0, 1.0]])
    with pytest.raises(DataError, match="self-loop"):
        team_observability_matrix(_graph(2, 0, [(0, 0), (0, 1)]), P2, _moving(2), NO_MARKS)
    with pytest.raises(DataError, match="self-loop"):
        expected_rank(_graph(2, 0, [(1, 1)]))
    with pytest.raises(DataError, match="only robots"):
        team_observability_matrix(_graph(2, 1, [(2, 0)]), P2, _moving(2), np.ones((1, 2)))
    with pytest.raises(DataError, match="no node 5"):
        team_observability_matrix(_graph(2, 0, [(0, 5)]), P2, _moving(2), NO_MARKS)
    with pytest.raises(DataError, match="n_robots"):
        team_observability_matrix(nx.DiGraph([(0, 1)]), P2, _moving(2), NO_MARKS)
    twice = _graph(2, 0, [(0, 1), (0, 1)], multi=True)
    once = team_observability_matrix(_graph(2, 0, [(0, 1)]), P2, _moving(2), NO_MARKS)
    np.testing.assert_array_equal(team_observability_matrix(twice, P2, _moving(2), NO_MARKS), once)
    for bad in (np.nan, np.inf):
        with pytest.raises(DataError, match="speeds"):
            team_observability(P2, np.array([[bad, 0.0], [1.0, 0.0]]), NO_MARKS, WIDE)


def test_compressed_team_rank_equals_the_full_matrix() -> None:
    rng = np.random.default_rng(5)
    n = 12
    poses = np.column_stack([rng.uniform(0, 100, (n, 2)), rng.uniform(-np.pi, np.pi, n)])
    speeds = np.column_stack([rng.uniform(1, 3, n), rng.uniform(-0.5, 0.5, n)])
    marks = np.array([[30.0, 40.0], [70.0, 20.0]])
    sensor = SensorSettings(sensing_range=60.0)
    r = team_observability(poses, speeds, marks, sensor, gps=[3])
    G = build_rpmg(poses, marks, sensor)
    sv = singular_values(team_observability_matrix(G, poses, speeds, marks, gps=[3]))
    assert r.rank == numeric_rank(team_observability_matrix(G, poses, speeds, marks, gps=[3]))
    assert r.sigma_min == pytest.approx(sv[-1], rel=1e-9)


def test_beta_is_reachability_and_fast_for_long_chains() -> None:
    """β by graph search: a 150-robot chain ending at two landmarks (C_n took minutes)."""
    n = 150
    G = _graph(n, 2, [(i, i + 1) for i in range(n - 1)] + [(n - 1, n), (n - 1, n + 1)])
    assert beta(G) == 1
    G.remove_edge(n - 1, n + 1)
    assert beta(G) == 0


# --- PCRLB ------------------------------------------------------------------------------------


def _pair(X: np.ndarray, mask: np.ndarray | None = None, **kw: object) -> np.ndarray:
    T = X.shape[0]
    U = np.zeros_like(X)
    m = np.ones(T, bool) if mask is None else mask
    return relative_pair_pcrlb(
        X, U, U, 0.1, m, velocity_noise=NOISE, **{"P0": np.eye(4), **SIG, **kw}
    )


def test_pcrlb_empty_and_one_step_horizons() -> None:
    """Before: T = 0 raised numpy's ValueError (negative dimensions)."""
    with pytest.raises(DataError, match="no steps"):
        _pair(np.zeros((0, 4)))
    B = _pair(np.array([[1.0, 2.0, 3.0, 0.0]]))
    assert B.shape == (1, 4, 4) and np.all(np.isfinite(B))


def test_pcrlb_at_zero_horizontal_distance() -> None:
    """Before: 'meas_info contains NaN or inf' (no step named) plus RuntimeWarnings."""
    above = np.tile([0.0, 0.0, 2.0, 0.0], (3, 1))
    with pytest.raises(ModelError, match=r"step 0 .*ρ = √\(x² \+ y²\) = 0"):
        _pair(above)
    with np.errstate(all="raise"):  # unmeasured there, or range only: a finite bound
        assert np.all(np.isfinite(_pair(above, mask=np.zeros(3, bool))))
        assert np.all(np.isfinite(_pair(above, measured=("range",))))


def test_pcrlb_bad_prior_is_named() -> None:
    """Before: a singular P0 was reported as 'measurement noise R'."""
    X = np.tile([1.0, 2.0, 0.5, 0.0], (3, 1))
    with pytest.raises(ModelError, match="P0"):
        _pair(X, P0=np.zeros((4, 4)))
    with pytest.raises(ModelError, match="P0"):
        _pair(X, P0=np.diag([np.inf] * 4))


# --- CLI --------------------------------------------------------------------------------------


def test_cli_at_state_non_finite_and_singular(capsys: pytest.CaptureFixture[str]) -> None:
    for value in ("nan", "inf", "-inf", "1e999"):
        assert main(["observability", "relative-nonlinear", "--at-state", f"x={value}"]) == 2
    assert main(["observability", "relative-nonlinear", "--at-state", "x=0,y=0,z=1"]) == 2
    assert "singular configuration" in capsys.readouterr().err


def test_cli_pseudo_linear_at_coincident_robots(capsys: pytest.CaptureFixture[str]) -> None:
    """Before: rank 3 at x = y = z = 0, of the bearings atan2(0, 0) = 0 picked there. Straight
    above, where only the azimuth is arbitrary, the rows span the same space for any azimuth."""
    args = ["observability", "relative-pseudo-linear", "--at-inputs", "v_xc=1"]
    assert main([*args, "--at-state", "x=0,y=0,z=0"]) == 2
    assert "azimuth and elevation" in capsys.readouterr().err
    assert main([*args, "--at-state", "x=0,y=0,z=1"]) == 0
    assert "rank at the given state and constant inputs: 4" in capsys.readouterr().out


def test_cli_at_state_takes_landmark_parameters(capsys: pytest.CaptureFixture[str]) -> None:
    """Before: any --at-state of a landmark model failed ('free parameters need an rng')."""
    args = ["observability", "unicycle-landmarks", "--order", "1", "--samples", "1"]
    assert main([*args, "--at-state", "x=0,y=0"]) == 2
    assert "lx_0, ly_0" in capsys.readouterr().err
    assert main([*args, "--at-state", "x=0,y=0,lx_0=3,ly_0=4", "--at-inputs", "v=1"]) == 0
    assert "rank at the given state and constant inputs: 2" in capsys.readouterr().out
    assert main([*args, "--at-state", "x=3,y=4,lx_0=3,ly_0=4", "--at-inputs", "v=1"]) == 2


def test_cli_at_state_uses_order_and_does_not_hang(capsys: pytest.CaptureFixture[str]) -> None:
    """Before: rank_at used order n − 1 = 5 for two unicycles, which did not finish in 2 min."""
    args = ["observability", "unicycle-team", "--robots", "2", "--landmarks", "0"]
    at = ["--at-state", "x_1=0,y_2=4", "--at-inputs", "v_1=1,v_2=1", "--samples", "1"]
    assert main([*args, *at]) == 0
    assert "rank at the given state and constant inputs:" in capsys.readouterr().out
