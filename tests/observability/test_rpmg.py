"""RPMG (seed 001): graph construction, Eqs. 20–22, edge blocks and the rank theorems."""

from __future__ import annotations

import networkx as nx
import numpy as np
import pytest

from relloc.errors import ConfigError, DataError, ModelError
from relloc.observability import rpmg
from relloc.observability.rank import numeric_rank, singular_values, stacked_singular_values
from relloc.observability.rpmg import (
    SensorSettings,
    adjacency_matrix,
    beta,
    build_rpmg,
    expected_rank,
    k_connectivity,
    team_observability,
    team_observability_matrix,
)

WIDE = SensorSettings(sensing_range=1e6)


def _moving(n: int, rng: np.random.Generator) -> np.ndarray:
    return np.column_stack([rng.uniform(1.0, 5.0, n), rng.uniform(-0.5, 0.5, n)])


def _chain(n: int) -> np.ndarray:
    """Robots 30 m apart on a bent line, headings generic."""
    rng = np.random.default_rng(n)
    xy = np.column_stack([30.0 * np.arange(n), 7.0 * (np.arange(n) % 2)])
    return np.column_stack([xy, rng.uniform(-np.pi, np.pi, n)])


def test_graph_respects_range_and_field_of_view() -> None:
    poses = np.array([[0.0, 0.0, 0.0], [10.0, 0.0, np.pi], [0.0, 50.0, 0.0]])
    G = build_rpmg(poses, np.array([[5.0, -5.0]]), SensorSettings(sensing_range=20.0))
    assert set(G.edges) == {(0, 1), (1, 0), (0, 3), (1, 3)}
    front = build_rpmg(poses, np.zeros((0, 2)), SensorSettings(sensing_range=20.0, fov=np.pi))
    assert set(front.edges) == {(0, 1), (1, 0)}  # each sees the other straight ahead
    half = build_rpmg(
        np.array([[0.0, 0.0, np.pi], [10.0, 0.0, np.pi]]),
        np.zeros((0, 2)),
        SensorSettings(sensing_range=20.0, fov=np.pi),
    )
    assert set(half.edges) == {(1, 0)}  # robot 0 faces away from robot 1


def test_k_connectivity_counts_walks_and_beta() -> None:
    # robots 0 → 1 → 2, robot 2 sees landmarks 3 and 4
    G = nx.DiGraph(n_robots=3, n_landmarks=2)
    G.add_nodes_from(range(5))
    G.add_edges_from([(0, 1), (1, 2), (2, 3), (2, 4)])
    A = adjacency_matrix(G)
    C1 = k_connectivity(A, 1)
    assert C1[0, 3] == 0 and C1[2, 3] == 1 and C1[0, 0] == 1
    C3 = k_connectivity(A, 3)
    assert C3[0, 3] == 1 and C3[0, 2] == 1
    assert beta(G) == 1
    G.remove_edge(1, 2)
    assert beta(G) == 0
    with pytest.raises(ConfigError):
        k_connectivity(A, -1)


def test_beta_by_reachability_is_eq_22_on_random_graphs() -> None:
    # β is computed by graph search; Eq. 22 defines it by the walk counts C_n (k_connectivity)
    rng = np.random.default_rng(2031)
    for _ in range(200):
        n, l = int(rng.integers(1, 7)), int(rng.integers(0, 4))
        G = nx.DiGraph(n_robots=n, n_landmarks=l)
        G.add_nodes_from(range(n + l))
        for i in range(n):
            for j in range(n + l):
                if i != j and rng.random() < 0.3:
                    G.add_edge(i, j)
        C = k_connectivity(adjacency_matrix(G), n)
        eq22 = l >= 2 and all(sum(C[i, n + k] > 0 for k in range(l)) >= 2 for i in range(n))
        assert beta(G) == int(eq22), sorted(G.edges)


@pytest.mark.parametrize("n", [2, 3, 5])
def test_theorems_on_hand_made_teams(n: int) -> None:
    rng = np.random.default_rng(10 + n)
    poses = _chain(n)
    speeds = _moving(n, rng)
    sensor = SensorSettings(sensing_range=40.0)  # neighbours only: a connected chain
    no_marks = team_observability(poses, speeds, np.zeros((0, 2)), sensor)
    assert no_marks.rank == 3 * (n - 1)  # Theorem 2
    marks = np.array([[0.0, -20.0], [-15.0, 10.0]])  # both near robot 0 only
    two = team_observability(poses, speeds, marks, sensor)
    assert two.rank == 3 * n and two.beta == 1  # Theorem 3
    gps = team_observability(poses, speeds, np.zeros((0, 2)), sensor, gps=[n - 1])
    assert gps.rank == 3 * n  # Theorem 4
    one = team_observability(poses, speeds, marks[:1], sensor)
    assert one.rank == 3 * n - 1  # one landmark: rotation about it stays unobservable


def test_disconnected_team_has_the_stated_rank() -> None:
    rng = np.random.default_rng(3)
    poses = np.vstack([_chain(3), _chain(2) + np.array([500.0, 0.0, 0.0])])
    speeds = _moving(5, rng)
    marks = np.array([[500.0, -20.0], [485.0, 10.0]])  # seen by the second group only
    r = team_observability(poses, speeds, marks, SensorSettings(sensing_range=40.0))
    assert r.expected_rank == 3 * 3 - 3 + 3 * 2 == r.rank == 12
    assert r.beta == 0 and r.sigma_min == 0.0


def test_random_teams_match_the_rank_formula() -> None:
    """Seeded random teams (sizes, sensing ranges, landmarks, GPS): rank = expected_rank."""
    rng = np.random.default_rng(2026)
    seen_deficits = set()
    for _ in range(40):
        n, l = int(rng.integers(1, 7)), int(rng.integers(0, 4))
        poses = np.column_stack([rng.uniform(0, 200, (n, 2)), rng.uniform(-np.pi, np.pi, n)])
        marks = rng.uniform(0, 200, (l, 2))
        gps = [int(rng.integers(n))] if rng.random() < 0.2 else []
        sensor = SensorSettings(sensing_range=float(rng.uniform(30, 150)))
        r = team_observability(poses, _moving(n, rng), marks, sensor, gps=gps)
        assert r.rank == r.expected_rank
        seen_deficits.add(3 * n - r.rank)
    assert len(seen_deficits) >= 3  # the sample covers several kinds of deficiency


def test_edge_blocks_rank_and_the_moving_target_condition() -> None:
    G = nx.DiGraph(n_robots=2, n_landmarks=0)
    G.add_nodes_from([0, 1])
    G.add_edge(0, 1)
    poses = np.array([[0.0, 0.0, 0.3], [10.0, 5.0, -1.0]])
    M = team_observability_matrix(G, poses, np.array([[1.0, 0.1], [1.0, 0.2]]), np.zeros((0, 2)))
    assert numeric_rank(M) == 3  # seed 001 Lemma 1
    no_lm = np.zeros((0, 2))
    still = team_observability_matrix(G, poses, np.array([[1.0, 0.1], [0.0, 0.0]]), no_lm)
    assert numeric_rank(still) == 2  # the measured robot must move
    L = nx.DiGraph(n_robots=1, n_landmarks=1)
    L.add_nodes_from([0, 1])
    L.add_edge(0, 1)
    mark = np.array([[10.0, 5.0]])
    pose = np.array([[0.0, 0.0, 0.3]])
    assert numeric_rank(team_observability_matrix(L, pose, np.array([[1.0, 0.0]]), mark)) == 2
    along = np.array([[0.0, 0.0, np.arctan2(5.0, 10.0)]])
    assert numeric_rank(team_observability_matrix(L, along, np.array([[1.0, 0.0]]), mark)) == 1


def test_twenty_robots_and_bad_input() -> None:
    rng = np.random.default_rng(20)
    n = 20
    poses = np.column_stack([rng.uniform(0, 300, (n, 2)), rng.uniform(-np.pi, np.pi, n)])
    marks = np.array([[100.0, 100.0], [200.0, 150.0]])
    r = team_observability(poses, _moving(n, rng), marks, SensorSettings(sensing_range=120.0))
    assert r.rank == r.expected_rank
    G = build_rpmg(poses, marks, WIDE)
    assert expected_rank(G) == 3 * n
    with pytest.raises(DataError):
        build_rpmg(np.zeros((2, 2)), marks, WIDE)
    bad = poses.copy()
    bad[3, 1] = np.nan
    with pytest.raises(DataError, match="NaN"):
        build_rpmg(bad, marks, WIDE)
    with pytest.raises(ConfigError, match="sensing_range"):
        SensorSettings(sensing_range=-1.0)


def test_stacked_singular_values_are_those_of_the_stacked_rows() -> None:
    """Chunks of any height (none, thinner than the width, taller) and a rank-deficient stack."""
    rng = np.random.default_rng(11)
    chunks = [rng.normal(size=(k, 9)) for k in (0, 2, 1, 30, 4)]
    full = np.linalg.svd(np.vstack(chunks), compute_uv=False)
    assert np.allclose(stacked_singular_values(chunks, 9), full, rtol=1e-12, atol=1e-12)
    basis = rng.normal(size=(4, 9))
    thin = [c[:, :4] @ basis for c in chunks]
    sv = stacked_singular_values(thin, 9)
    assert sv.shape == (9,) and np.count_nonzero(sv > 1e-8 * sv[0]) == 4
    assert np.all(stacked_singular_values([], 9) == 0.0)
    with pytest.raises(ModelError, match=r"a chunk of shape \(4, 3\) for 9 columns"):
        stacked_singular_values([np.ones((4, 3))], 9)  # was silently re-wrapped to (?, 9)


def test_team_figures_folded_chunk_by_chunk_are_the_assembled_matrix_ones(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A complete 40-robot graph: 780 pairs, folded into the triangular factor in chunks of
    48n = 1920 rows (the smallest chunk, :data:`rpmg.CHUNK_BYTES` set to 1), give the rank and
    σ_min of the SVD of the whole team matrix."""
    monkeypatch.setattr(rpmg, "CHUNK_BYTES", 1)
    rng = np.random.default_rng(40)
    n = 40
    poses = np.column_stack([rng.uniform(0, 300, (n, 2)), rng.uniform(-np.pi, np.pi, n)])
    speeds, marks = _moving(n, rng), np.array([[100.0, 100.0], [250.0, 40.0]])
    r = team_observability(poses, speeds, marks, WIDE)
    M = team_observability_matrix(build_rpmg(poses, marks, WIDE), poses, speeds, marks)
    assert r.rank == numeric_rank(M) == 3 * n
    assert r.sigma_min == pytest.approx(singular_values(M)[-1], rel=1e-9)


def test_minimal_moving_sets() -> None:
    from relloc.observability.rpmg import minimal_moving_sets

    G = nx.DiGraph(n_robots=2, n_landmarks=0)
    G.add_nodes_from([0, 1])
    G.add_edge(0, 1)
    poses = np.array([[0.0, 0.0, 0.3], [10.0, 5.0, -1.0]])
    speeds = np.array([[1.0, 0.1], [1.0, 0.2]])
    assert minimal_moving_sets(G, poses, speeds, np.zeros((0, 2))) == [[1]]  # the measured one
    L = nx.DiGraph(n_robots=1, n_landmarks=3)
    L.add_nodes_from([0, 1, 2, 3])
    L.add_edges_from([(0, 1), (0, 2)])
    marks = np.array([[10.0, 5.0], [-4.0, 9.0], [3.0, -8.0]])
    pose = np.array([[0.0, 0.0, 0.3]])
    moving = np.array([[1.0, 0.1]])
    assert minimal_moving_sets(L, pose, moving, marks) == [[0]]  # two bearings: must move
    L.add_edge(0, 3)
    # three landmark bearings fix the pose without motion (resection from the static rows)
    assert minimal_moving_sets(L, pose, moving, marks) == [[]]
