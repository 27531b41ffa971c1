"""``relloc bench observability``: cost of the observability analyses and of the PCRLB.

Measured in one process (wall time, ``time.perf_counter``; ``load_average`` records how busy
the machine was):

* ``symbolic_s``: complete :func:`~relloc.observability.analysis.analyse` (Lie derivatives to
  order 2, generic rank at 5 random states, every input subset, directions) per built-in 4-state
  model, cold (nothing cached), and the baseline ``unpruned_rows_s``: building the same
  observability matrix *without* the redundancy pruning of :mod:`relloc.observability.lie`
  (all words to order 2) — the pruned build is part of ``symbolic_s``.
* ``team_matrix_s``: RPMG + team observability matrix from edge blocks + rank/σ_min for random
  connected teams of n = 5, 10, 20 robots with two landmarks (best of 3, blocks already
  lambdified), with the rank checked against the graph formula; the baseline
  ``symbolic_team_build_s`` builds the full symbolic 3-robot team matrix (the route edge blocks
  avoid). ``teams["200_complete"]``: 200 robots that all see each other, also with
  ``peak_mb``, the peak memory traced in one call, beside ``assembled_mb``, what the reduced
  team matrix would take assembled whole.
* ``pcrlb_s``: the seed-000 pair bound over 2000 steps and a 5-robot team bound over 200 steps.

On a machine shared by many processes, multi-threaded BLAS (used by the QR/SVD of large team
matrices) can oversubscribe the cores and inflate ``team_matrix_s`` several-fold; run with
``OPENBLAS_NUM_THREADS=1`` for stable numbers.
"""

from __future__ import annotations

import os
import time
from typing import Any

import numpy as np
from sympy.core.cache import clear_cache

from relloc.errors import ModelError
from relloc.models import symbolic as S
from relloc.models.motion import VelocityNoise, relative_step
from relloc.observability.analysis import analyse
from relloc.observability.lie import ObservabilityMatrix, lie_rows
from relloc.observability.pcrlb import relative_pair_pcrlb, unicycle_team_pcrlb
from relloc.observability.rpmg import (
    SensorSettings,
    TeamObservability,
    build_rpmg,
    team_observability,
)

SYMBOLIC_MODELS = {
    "relative-pseudo-linear case 1": lambda: S.relative_pseudo_linear(),
    "relative-pseudo-linear case 2": lambda: S.relative_pseudo_linear(("azimuth", "elevation")),
    "relative-nonlinear range+bearing": lambda: S.relative_nonlinear(),
    "relative-nonlinear bearing": lambda: S.relative_nonlinear(("azimuth", "elevation")),
    "relative-nonlinear range": lambda: S.relative_nonlinear(("range",)),
    "airground sw=3": lambda: S.airground_follower(3),
}


def _best(fn: Any, repeats: int = 3) -> float:
    best = np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return float(best)


def _connected_team(rng: np.random.Generator, n: int) -> tuple[np.ndarray, np.ndarray]:
    P = np.zeros((n, 3))
    for i in range(1, n):
        ang, dist = rng.uniform(-np.pi, np.pi), rng.uniform(25.0, 100.0)
        P[i, :2] = P[rng.integers(i), :2] + dist * np.array([np.cos(ang), np.sin(ang)])
    P[:, 2] = rng.uniform(-np.pi, np.pi, n)
    marks = P[rng.choice(n, 2, replace=False), :2] + rng.uniform(-60, 60, (2, 2))
    return P, marks


#: Robots of the complete-graph point of ``teams`` (:func:`_large_team`).
LARGE_TEAM = 200


def _check_rank(team: TeamObservability, what: str) -> None:
    """The numerical rank of the team matrix must be the graph formula's (module docstring)."""
    if team.rank != team.expected_rank:
        raise ModelError(
            f"team observability of {what}: rank {team.rank} but the graph formula gives "
            f"{team.expected_rank}"
        )


def _large_team() -> dict[str, Any]:
    """:data:`LARGE_TEAM` robots that all see each other and two landmarks: time (best of 2),
    ``peak_mb`` the largest memory traced during one call (:mod:`tracemalloc`, which sees
    numpy's arrays), and its baseline ``assembled_mb``, the bytes of the reduced team matrix
    (6 rows per pair, 3n columns) had it been assembled whole."""
    import tracemalloc

    rng = np.random.default_rng(LARGE_TEAM)
    n = LARGE_TEAM
    P = np.column_stack([rng.uniform(0, 400, (n, 2)), rng.uniform(-np.pi, np.pi, n)])
    speeds = np.column_stack([np.full(n, 5.0), rng.uniform(-0.3, 0.3, n)])
    marks = rng.uniform(0, 400, (2, 2))
    everyone = SensorSettings(sensing_range=1e6)
    tracemalloc.start()
    try:
        team = team_observability(P, speeds, marks, everyone)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    _check_rank(team, f"{n} robots that all see each other")
    seconds = _best(lambda: team_observability(P, speeds, marks, everyone), repeats=2)
    pairs = n * (n - 1) // 2
    return {
        "team_matrix_s": seconds,
        "rank": team.rank,
        "expected_rank": team.expected_rank,
        "edges": team.n_edges,
        "peak_mb": peak / 2**20,
        "assembled_mb": 6 * pairs * 3 * n * 8 / 2**20,
    }


def run(quiet: bool = False) -> dict[str, Any]:
    rng = np.random.default_rng(0)
    symbolic: dict[str, dict[str, Any]] = {}
    for name, make in SYMBOLIC_MODELS.items():
        model = make()
        clear_cache()  # SymPy memoises derivatives: time both routes cold
        t0 = time.perf_counter()
        r = analyse(model, order=2)
        t_analyse = time.perf_counter() - t0
        clear_cache()
        t0 = time.perf_counter()
        n_all = len(lie_rows(model, 2, prune=False))
        t_unpruned = time.perf_counter() - t0
        symbolic[name] = {
            "rank": r.rank,
            "symbolic_s": t_analyse,
            "rows_pruned": r.n_rows,
            "rows_unpruned": n_all,
            "unpruned_rows_s": t_unpruned,
        }

    sensor = SensorSettings(sensing_range=120.0)
    teams: dict[str, dict[str, Any]] = {}
    for n in (5, 10, 20):
        P, marks = _connected_team(rng, n)
        speeds = np.column_stack([np.full(n, 5.0), rng.uniform(-0.3, 0.3, n)])
        team = team_observability(P, speeds, marks, sensor)
        _check_rank(team, f"a random connected team of {n} robots")
        teams[str(n)] = {
            "team_matrix_s": _best(
                lambda P=P, s=speeds, m=marks: team_observability(P, s, m, sensor)
            ),
            "rank": team.rank,
            "expected_rank": team.expected_rank,
            "edges": team.n_edges,
        }
    teams[f"{LARGE_TEAM}_complete"] = _large_team()
    t0 = time.perf_counter()
    ObservabilityMatrix.build(
        S.unicycle_team(
            3, robot_edges=[(1, 2), (2, 3)], landmark_edges=[(1, 1), (1, 2)], n_landmarks=2
        ),
        2,
        prune=False,
    )
    symbolic_team = time.perf_counter() - t0

    T = 2000
    x = np.zeros((T, 4))
    x[0] = (3.0, 1.0, 0.8, 0.2)
    u_l = np.tile([0.3, 0.0, 0.0, 0.1], (T, 1))
    u_c = np.tile([0.5, 0.1, 0.0, -0.2], (T, 1))
    for k in range(T - 1):
        x[k + 1] = relative_step(x[k], u_l[k], u_c[k], 0.01)
    noise = VelocityNoise(observer=(0.05, 0.05, 0.01, 0.02), observed=(0.05, 0.05, 0.01, 0.02))
    pair_s = _best(
        lambda: relative_pair_pcrlb(
            x,
            u_l,
            u_c,
            0.01,
            np.arange(T) % 10 == 0,
            sigma_r=0.1,
            sigma_theta=0.05,
            sigma_alpha=0.05,
            velocity_noise=noise,
            P0=np.eye(4),
        ),
        repeats=2,
    )
    from relloc.models.planar_measurement import RowKind, ScalarRows

    n, Tt = 5, 200
    P, marks = _connected_team(rng, n)
    poses = np.repeat(P[None], Tt, axis=0)
    G = build_rpmg(P, marks, sensor)
    edges = [(i, j) for i, j in G.edges]
    rows = ScalarRows(
        kind=np.full(len(edges), RowKind.BEARING, dtype=np.int64),
        observer=np.array([i for i, _ in edges], dtype=np.int64),
        target=np.array([j if j < n else -1 for _, j in edges], dtype=np.int64),
        landmark_xy=np.array([marks[j - n] if j >= n else (0.0, 0.0) for _, j in edges]),
        z=np.zeros(len(edges)),
        sigma=np.full(len(edges), 0.1),
        group=np.arange(len(edges), dtype=np.int64),
    )
    team_s = _best(
        lambda: unicycle_team_pcrlb(
            poses,
            np.zeros((Tt, n, 2)),
            0.1,
            [rows] * Tt,
            input_sigma=[0.2, 0.2],
            P0=25 * np.eye(3 * n),
        ),
        repeats=2,
    )
    result = {
        "symbolic": symbolic,
        "teams": teams,
        "symbolic_team_build_s": symbolic_team,
        "pcrlb_s": {"relative_pair_2000_steps": pair_s, "team_5_robots_200_steps": team_s},
        "load_average": list(os.getloadavg()),
    }
    if not quiet:
        print("symbolic analysis (order 2):")
        for name, v in symbolic.items():
            print(
                f"  {name:34s} rank {v['rank']}  {v['symbolic_s']:6.2f} s  "
                f"rows {v['rows_pruned']:3d} (unpruned {v['rows_unpruned']:3d}, "
                f"build alone {v['unpruned_rows_s']:.2f} s)"
            )
        print("team observability matrix (edge blocks):")
        for n_r, v in teams.items():
            print(
                f"  n = {n_r:>2s}: {v['team_matrix_s'] * 1e3:8.1f} ms  rank {v['rank']} "
                f"(graph formula {v['expected_rank']}), {v['edges']} edges"
            )
            if "peak_mb" in v:
                print(
                    f"    peak memory {v['peak_mb']:.0f} MB (the assembled matrix alone: "
                    f"{v['assembled_mb']:.0f} MB)"
                )
        print(f"  baseline: symbolic 3-robot team build {symbolic_team:.2f} s")
        print(f"PCRLB: pair 2000 steps {pair_s:.3f} s, 5-robot team 200 steps {team_s:.3f} s")
        print(f"load average {result['load_average']}")
    return result
