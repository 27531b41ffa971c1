"""``relloc bench cooperative``: how large a team the centralised EIF localizes in real time.

A grid team (:func:`relloc.sim.cooperative.grid_team_scenario`: robots 30 m apart, 50 m
sensing range, so each sees its ~8 nearest neighbours, plus a few landmarks) is simulated at
10 Hz (odometry and bearings every 0.1 s); :func:`relloc.pipeline.replay.replay` then runs the
team filter (:class:`relloc.estimators.cooperative.CooperativeEstimator`) over it with the EIF
(:mod:`relloc.estimators.eif`) and, as the baseline measured in the same run, the
covariance-form joint EKF (:mod:`relloc.estimators.joint_ekf`), recording the belief of every
robot at every step (the per-detection update records, a few µs each, are not kept: the
benchmark times the localization). Both are checked to give the same estimates before timing
counts.

The sizes grow until the EIF falls below real time; the EKF baseline stops once its
real-time factor is below 0.5. Reported per team size ``n``: wall time per 0.1 s step (best
of ``repeats``), the real-time factor (simulated time / wall time; > 1 is faster than real
time), rows per step, and the largest ``|EIF − EKF|`` of the means. ``realtime_limit_n`` is
the team size at which the EIF's real-time factor crosses 1 (log-log interpolation between
the sizes measured).

One core: the measurement runs in a child process started with single-threaded BLAS
(``OPENBLAS_NUM_THREADS=OMP_NUM_THREADS=MKL_NUM_THREADS=1``, which must be set before numpy is
imported) and pinned to one CPU (``os.sched_setaffinity``). Multi-threaded BLAS on a shared
machine makes a 150 × 150 Cholesky factorisation tens of times slower through thread
contention, which would measure the machine rather than the filter.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from relloc.core.checks import count, sequence
from relloc.errors import ConfigError, ModelError
from relloc.estimators.cooperative import (
    CooperativeEstimator,
    CooperativeSettings,
    Counts,
    OdometryModel,
    SensorModel,
)
from relloc.pipeline.replay import replay
from relloc.sim.cooperative import CooperativeSim, grid_team_scenario, simulate

Array = NDArray[np.float64]

SIZES = (5, 10, 25, 50, 100, 150, 200, 300, 400)
STEPS = 30
REPEATS = 2
EQUIVALENCE_TOL = 1e-6


@dataclass(frozen=True, kw_only=True)
class BenchSize:
    """How much work the benchmark does: the team ``sizes`` tried in order, ``steps`` of 0.1 s
    simulated per size, best of ``repeats`` replays (defaults: :data:`SIZES`, :data:`STEPS`,
    :data:`REPEATS`)."""

    sizes: tuple[int, ...] = SIZES
    steps: int = STEPS
    repeats: int = REPEATS

    def __post_init__(self) -> None:
        sizes = tuple(sequence(self.sizes, "BenchSize.sizes", "team sizes"))
        if not sizes:
            raise ConfigError("BenchSize.sizes: expected at least one team size")
        object.__setattr__(self, "sizes", tuple(count(n, "BenchSize.sizes", low=2) for n in sizes))
        for name in ("steps", "repeats"):
            count(getattr(self, name), f"BenchSize.{name}")


def _time_run(
    sim: CooperativeSim, settings: CooperativeSettings, repeats: int
) -> tuple[float, Array, Counts]:
    """Best wall time of ``repeats`` replays, the recorded means ``(T, n, 3)`` and the counts."""
    rec = sim.recording
    t = rec.truth[0].t if rec.truth is not None else np.zeros(0)
    best = np.inf
    mean, counts = np.zeros(0), Counts()
    for _ in range(repeats):
        start = time.perf_counter()
        estimator = CooperativeEstimator(
            rec.robots, sim.prior, settings, rec.landmarks, record_updates=False
        )
        estimates = replay(rec, [estimator], record_times=t, start=0.0, end=float(t[-1]))
        best = min(best, time.perf_counter() - start)
        _, mean, _ = estimates.stacked(estimator.owner, rec.robots)
        counts = estimator.counts
    return float(best), mean, counts


def _crossing(sizes: list[int], factors: list[float]) -> float | None:
    """``n`` where the real-time factor crosses 1 (log-log interpolation), if it does."""
    for k in range(1, len(sizes)):
        if factors[k - 1] >= 1.0 > factors[k]:
            x0, x1 = np.log(sizes[k - 1]), np.log(sizes[k])
            y0, y1 = np.log(factors[k - 1]), np.log(factors[k])
            return float(np.exp(x0 + (0.0 - y0) * (x1 - x0) / (y1 - y0)))
    return None


def measure(size: BenchSize | None = None) -> dict[str, Any]:
    """Measure the team sizes of ``size`` (default :class:`BenchSize`), stopping at the first
    size below real time."""
    size = BenchSize() if size is None else size
    pinned = hasattr(os, "sched_setaffinity")
    previous = os.sched_getaffinity(0) if pinned else None
    if pinned:
        os.sched_setaffinity(0, {min(previous or {0})})
    rows: list[dict[str, Any]] = []
    try:
        ekf_active = True
        for i, n in enumerate(size.sizes):
            scenario = grid_team_scenario(n, duration=size.steps * 0.1)
            sim = simulate(scenario, np.random.default_rng(n))
            odometry = OdometryModel.from_discrete(scenario.sigma_v, scenario.sigma_w, 0.1)
            sensor = SensorModel(sigma_bearing=scenario.sigma_bearing)
            timing: dict[str, float] = {}
            means: dict[str, Array] = {}
            counts: dict[str, Counts] = {}
            for kind in ("eif", "ekf") if ekf_active else ("eif",):
                settings = CooperativeSettings(
                    odometry=odometry, sensor=sensor, anchors=(0, 1), filter=kind
                )
                if i == 0:  # the first replay of a kind pays one-off costs (lazy imports): untimed
                    _time_run(sim, settings, 1)
                timing[kind], means[kind], counts[kind] = _time_run(sim, settings, size.repeats)
            t0, t1 = sim.recording.span
            duration = t1 - t0
            row: dict[str, Any] = {
                "n": n,
                "state_dim": 3 * n,
                "rows_per_step": counts["eif"].used / max(counts["eif"].epochs, 1),
                "eif_ms_per_step": 1e3 * timing["eif"] / size.steps,
                "eif_realtime_factor": duration / timing["eif"],
                "ekf_ms_per_step": None,
                "ekf_realtime_factor": None,
                "max_mean_diff_eif_ekf": None,
            }
            if "ekf" in means:
                row["ekf_ms_per_step"] = 1e3 * timing["ekf"] / size.steps
                row["ekf_realtime_factor"] = duration / timing["ekf"]
                diff = float(np.max(np.abs(means["eif"] - means["ekf"])))
                if not diff < EQUIVALENCE_TOL:
                    raise ModelError(f"EIF and EKF disagree by {diff:g} for n = {n}")
                row["max_mean_diff_eif_ekf"] = diff
                # the baseline is dropped once it is well below real time (it only gets slower)
                ekf_active = row["ekf_realtime_factor"] >= 0.5
            rows.append(row)
            if row["eif_realtime_factor"] < 1.0:
                break
    finally:
        if pinned and previous is not None:
            os.sched_setaffinity(0, previous)
    sizes = [r["n"] for r in rows]
    result = {
        "benchmark": "cooperative",
        "rate_hz": 10.0,
        "steps": size.steps,
        "one_core": pinned,
        "load_average": list(os.getloadavg()) if hasattr(os, "getloadavg") else None,
        "sizes": rows,
        "realtime_at_50": next(
            (r["eif_realtime_factor"] >= 1.0 for r in rows if r["n"] == 50), None
        ),
        "realtime_limit_n": _crossing(sizes, [r["eif_realtime_factor"] for r in rows]),
        "ekf_realtime_limit_n": _crossing(
            [r["n"] for r in rows if r["ekf_realtime_factor"] is not None],
            [r["ekf_realtime_factor"] for r in rows if r["ekf_realtime_factor"] is not None],
        ),
        "blas_threads": os.environ.get("OPENBLAS_NUM_THREADS"),
    }
    return result


def run(quiet: bool = False, *, size: BenchSize | None = None) -> dict[str, Any]:
    """Run :func:`measure` in a child process with single-threaded BLAS; print a table."""
    size = BenchSize() if size is None else size
    env = dict(os.environ)
    env.update({"OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"})
    proc = subprocess.run(
        [sys.executable, "-m", "relloc.bench.cooperative", json.dumps(asdict(size))],
        env=env,
        capture_output=True,
        text=True,
        check=False,
    )
    if proc.returncode != 0:
        raise ModelError(f"cooperative benchmark child failed: {proc.stderr.strip()[-2000:]}")
    result: dict[str, Any] = json.loads(proc.stdout)
    rows = result["sizes"]
    if not quiet:
        from rich.console import Console
        from rich.table import Table

        table = Table(title="Centralised cooperative localization at 10 Hz, one core")
        for col in ("n", "rows/step", "EIF ms/step", "EIF × real time", "EKF ms/step", "EKF ×"):
            table.add_column(col)
        for r in rows:
            table.add_row(
                str(r["n"]),
                f"{r['rows_per_step']:.0f}",
                f"{r['eif_ms_per_step']:.2f}",
                f"{r['eif_realtime_factor']:.1f}",
                "—" if r["ekf_ms_per_step"] is None else f"{r['ekf_ms_per_step']:.2f}",
                "—" if r["ekf_realtime_factor"] is None else f"{r['ekf_realtime_factor']:.1f}",
            )
        Console().print(table)
        Console().print(f"EIF real-time limit: n ≈ {result['realtime_limit_n']}")
    return result


if __name__ == "__main__":
    from relloc.pipeline.output import to_jsonable

    given = json.loads(sys.argv[1]) if len(sys.argv) > 1 else {}
    print(json.dumps(to_jsonable(measure(BenchSize(**given)))))
