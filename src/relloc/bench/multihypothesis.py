"""Benchmark of the Gaussian-sum fuser: cost per scan against teammates and clutter density.

``relloc bench multihypothesis``. One sensing robot tracks ``n`` teammates (n = 1, 2, 5, 10)
under the clutter densities of the seed-002 sweep (λ × 1, 10, 100, 1000 with λ = 1e-7 per
rad·rad·mm, i.e. ≈ 0.02 … 20 false bearings per scan). Teammates drive at 0.3 m/s with random
headings and turn rates on a ring 2–8 m around the observer; measurements have the paper's noise
and P_D = 0.95. The filter runs at 20 Hz and fuses a direct scan at 10 Hz, for 20 s of data
per point after a 5 s warm-up (not timed), on one core.

Baseline measured in the same run: the single-hypothesis relative EKF with *known*
correspondence (the batched ``predict_arrays`` + ``update_tekf_arrays`` of
:mod:`relloc.estimators.relative` over all teammates), fed the same data with the true bearing
of each teammate: ``baseline_ms_per_scan`` is what the correspondence problem costs on top.

Reported per point: ``ms_per_scan`` (one direct scan: height, range, bearings, reduction),
``ms_per_predict`` (one 20 Hz prediction of all filters), ``realtime_factor`` (seconds of data
processed per second of CPU: > 1 is faster than real time at 20 Hz/10 Hz), and the component
count per filter (``components_mean``, ``components_max``). The headline ``realtime_10x100``
is the real-time factor with 10 teammates and 100× clutter.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from relloc.core.angles import wrap_angle
from relloc.core.contract import Belief, HeldOdometry, TrackEvent, UpdateRecord
from relloc.core.recording import Measurements, Odometry, Recording, measurement_rows
from relloc.estimators.relative import predict_arrays, update_tekf_arrays
from relloc.experiments.desilva2015 import filter_settings
from relloc.fusion.gaussian_sum_estimator import GaussianSumEstimator
from relloc.models.measurement import RangeBearingNoise
from relloc.pipeline.replay import replay
from relloc.sim.multihypothesis import DeSilvaScenario

Array = NDArray[np.float64]

TEAM_SIZES = (1, 2, 5, 10)
CLUTTER_FACTORS = (1, 10, 100, 1000)
WARMUP_S = 5.0
TIMED_S = 20.0
SEED = 2026
#: sensor index of the known-correspondence (range, azimuth, elevation) rows the baseline uses
BASELINE_SENSOR = 1


def _recording(n: int, factor: int, rng: np.random.Generator) -> tuple[DeSilvaScenario, Recording]:
    """Observer ``R0`` at rest and ``n`` teammates driving around it (module docstring).

    Step ``k`` moves the teammates over ``[k dt, (k+1) dt)`` with the measured velocities
    ``u[k]`` (odometry stamped ``k dt``); every second step ends with a scan at ``(k+1) dt``:
    heights and ranges (known correspondence), the shuffled bearing set (unknown
    correspondence) and, for the baseline, each seen teammate's true range with its measured
    bearing as a known-correspondence ``"range_bearing_elevation"`` row.
    """
    sc = DeSilvaScenario(clutter_density=1e-7 * factor)
    dt = 1.0 / sc.filter_rate
    steps = round((WARMUP_S + TIMED_S) * sc.filter_rate)
    radius = rng.uniform(2.0, 8.0, n)
    angle = rng.uniform(-np.pi, np.pi, n)
    pos = np.stack([radius * np.cos(angle), radius * np.sin(angle), rng.uniform(0, 2, n)], -1)
    yaw = rng.uniform(-np.pi, np.pi, n)
    turn = rng.uniform(-0.3, 0.3, n)
    speed = 0.3
    u_true = np.zeros((steps, n, 4))
    u_true[..., 0] = speed
    u_true[..., 3] = turn
    u_meas = u_true + rng.normal(size=u_true.shape) * np.array(sc.velocity_sigmas)
    every = round(sc.filter_rate / sc.direct_rate)
    sa = np.sqrt(sc.var_azimuth)
    team = np.arange(1, n + 1)
    parts: list[Measurements] = []
    for k in range(steps):
        pos[:, 0] += speed * dt * np.cos(yaw)
        pos[:, 1] += speed * dt * np.sin(yaw)
        yaw = yaw + turn * dt
        if k % every:
            continue
        t = (k + 1) * dt
        r = np.linalg.norm(pos, axis=1)
        seen = rng.random(n) < sc.p_detect
        az = np.arctan2(pos[:, 1], pos[:, 0]) + sa * rng.normal(size=n)
        el = np.arctan2(pos[:, 2], np.hypot(pos[:, 0], pos[:, 1])) + sa * rng.normal(size=n)
        n_cl = rng.poisson(sc.expected_clutter)
        clutter = np.stack(
            [rng.uniform(-np.pi, np.pi, n_cl), rng.uniform(-np.pi / 2, np.pi / 2, n_cl)], -1
        )
        own = np.stack([wrap_angle(az), el], -1)
        bearings = np.concatenate([own[seen], clutter])
        origin = np.concatenate([team[seen], np.full(n_cl, -1)])
        ranges = np.where(
            rng.random(n) < sc.p_detect, r + sc.sigma_range * rng.normal(size=n), np.nan
        )
        heights = pos[:, 2] + sc.sigma_height * rng.normal(size=n)
        order = rng.permutation(len(bearings))
        ranged = np.isfinite(ranges)
        parts += [
            measurement_rows("height", t=np.full(n, t), observer=0, target=team, value=heights),
            measurement_rows(
                "range",
                t=np.full(ranged.sum(), t),
                observer=0,
                target=team[ranged],
                value=ranges[ranged],
            ),
            measurement_rows(
                "bearing_elevation",
                t=np.full(order.size, t),
                observer=0,
                value=bearings[order],
                origin=origin[order],
            ),
            measurement_rows(
                "range_bearing_elevation",
                t=np.full(seen.sum(), t),
                observer=0,
                target=team[seen],
                value=np.concatenate([r[:, None], own], axis=1)[seen],
                sensor=BASELINE_SENSOR,
            ),
        ]
    stamps: Array = np.arange(steps, dtype=np.float64) * dt
    sigma = np.array(sc.velocity_sigmas)
    odometry = [Odometry(t=stamps, velocity=np.zeros((steps, 4)), sigma=sigma)]
    odometry += [Odometry(t=stamps, velocity=u_meas[:, j], sigma=sigma) for j in range(n)]
    return sc, Recording(
        robots=tuple(f"R{j}" for j in range(n + 1)),
        platforms=("ground",) + ("aerial",) * n,
        odometry=tuple(odometry),
        measurements=Measurements.concatenate(parts),
        source="bench.multihypothesis",
    )


class _Timed:
    """An estimator that times another's ``advance`` (one prediction of all filters) and
    ``measure`` (one direct scan) in process CPU time, for events after ``from_t``."""

    def __init__(self, inner: GaussianSumEstimator, from_t: float) -> None:
        self.inner = inner
        self.owner = inner.owner
        self.name = inner.name
        self.from_t = from_t
        self._t = 0.0
        self.predict_s = self.scan_s = 0.0
        self.predicts = self.scans = 0

    def advance(self, t: float, odometry: HeldOdometry) -> None:
        self._t = t
        t0 = time.process_time()
        self.inner.advance(t, odometry)
        if t > self.from_t:
            self.predict_s += time.process_time() - t0
            self.predicts += 1

    def measure(self, batch: Measurements) -> None:
        t0 = time.process_time()
        self.inner.measure(batch)
        if self._t > self.from_t:
            self.scan_s += time.process_time() - t0
            self.scans += 1

    def beliefs(self) -> Sequence[Belief]:
        return self.inner.beliefs()

    def outbox(self) -> list[Any]:
        return self.inner.outbox()

    def receive(self, messages: Sequence[Any]) -> None:
        self.inner.receive(messages)

    def take_updates(self) -> list[UpdateRecord]:
        return self.inner.take_updates()

    def take_events(self) -> list[TrackEvent]:
        return self.inner.take_events()


def _one_point(n: int, factor: int) -> dict[str, Any]:
    rng = np.random.default_rng([SEED, n, factor])
    sc, rec = _recording(n, factor, rng)
    dt = 1.0 / sc.filter_rate
    timed = _Timed(GaussianSumEstimator(rec.robots, 0, filter_settings(sc)), WARMUP_S + 1e-9)
    scans = np.unique(rec.measurements.t)
    record = scans[scans > timed.from_t]
    estimates = replay(rec, [timed], record_times=record, end=len(rec.odometry[0].t) * dt)
    comps = np.zeros((record.size, n), dtype=np.int64)
    for s in estimates.beliefs:
        comps[np.searchsorted(record, s.t), rec.index(s.subject) - 1] = s.info["components"]
    cpu = timed.predict_s + timed.scan_s
    return {
        "teammates": n,
        "clutter_factor": factor,
        "expected_clutter_per_scan": sc.expected_clutter,
        "ms_per_scan": 1e3 * timed.scan_s / max(timed.scans, 1),
        "ms_per_predict": 1e3 * timed.predict_s / max(timed.predicts, 1),
        "realtime_factor": TIMED_S / cpu if cpu > 0 else float("inf"),
        "baseline_ms_per_scan": _baseline_ms_per_scan(sc, rec, timed.from_t),
        "components_mean": float(np.mean(comps)),
        "components_max": int(np.max(comps)),
    }


def _baseline_ms_per_scan(sc: DeSilvaScenario, rec: Recording, from_t: float) -> float:
    """Known-correspondence EKF (one track per teammate) on the same recording: ms per scan."""
    n = rec.n_robots - 1
    st = filter_settings(sc)
    noise = RangeBearingNoise(
        sigma_r=sc.sigma_range,
        sigma_azimuth=st.sigma_azimuth,
        sigma_elevation=st.sigma_elevation,
    )
    m = rec.measurements
    known = np.flatnonzero(m.sensor == BASELINE_SENSOR)
    scan_t = np.unique(m.t)

    def z_at(t: float) -> Array:
        z = np.full((n, 3), np.nan)
        rows = known[m.t[known] == t]
        z[m.target[rows] - 1] = m.value[rows]
        return z

    first = z_at(scan_t[0])
    mean = np.zeros((n, 4))
    ok = np.isfinite(first[:, 0])
    cb = np.cos(np.nan_to_num(first[:, 2]))
    mean[ok, 0] = (first[:, 0] * cb * np.cos(first[:, 1]))[ok]
    mean[ok, 1] = (first[:, 0] * cb * np.sin(first[:, 1]))[ok]
    mean[:, 0] = np.where(ok, mean[:, 0], 3.0)
    cov = np.broadcast_to(np.diag([0.1, 0.1, 0.05, 4 * np.pi]), (n, 4, 4)).copy()
    dt = 1.0 / sc.filter_rate
    u_self = rec.odometry[0].velocity
    u_team = np.stack([od.velocity for od in rec.odometry[1:]], axis=1)
    step_end = rec.odometry[0].t + dt
    at = np.minimum(np.searchsorted(scan_t, step_end - 1e-9), scan_t.size - 1)
    scan_of_step = np.where(np.abs(scan_t[at] - step_end) < 1e-9, at, -1)
    t_scan = 0.0
    n_scan = 0
    for k, s in enumerate(scan_of_step):
        mean, cov = predict_arrays(mean, cov, u_self[k], u_team[k], dt, st.velocity_noise)
        if s < 0:
            continue
        z = z_at(float(scan_t[s]))
        sel = np.flatnonzero(np.isfinite(z).all(axis=1))
        t0 = time.process_time()
        if sel.size:
            mm, P, _ = update_tekf_arrays(mean[sel], cov[sel], z[sel], noise)
            mean[sel], cov[sel] = mm, P
        if step_end[k] > from_t:
            t_scan += time.process_time() - t0
            n_scan += 1
    return 1e3 * t_scan / max(n_scan, 1)


def run(quiet: bool = False) -> dict[str, Any]:
    """Measure every (teammates, clutter) point; print a table unless ``quiet``."""
    points = [_one_point(n, f) for n in TEAM_SIZES for f in CLUTTER_FACTORS]
    headline = next(p for p in points if p["teammates"] == 10 and p["clutter_factor"] == 100)
    result = {
        "benchmark": "multihypothesis",
        "seed": SEED,
        "timed_seconds_of_data": TIMED_S,
        "points": points,
        "realtime_10x100": headline["realtime_factor"],
        "realtime_required": 1.0,
    }
    if not quiet:
        from rich.console import Console
        from rich.table import Table

        table = Table(title="Gaussian-sum fuser cost (one core, 20 Hz filter, 10 Hz scans)")
        for col in (
            "teammates",
            "clutter ×",
            "clutter/scan",
            "ms/scan",
            "baseline ms/scan",
            "ms/predict",
            "× real time",
            "comp. mean",
            "comp. max",
        ):
            table.add_column(col, justify="right")
        for p in points:
            table.add_row(
                str(p["teammates"]),
                str(p["clutter_factor"]),
                f"{p['expected_clutter_per_scan']:.2f}",
                f"{p['ms_per_scan']:.2f}",
                f"{p['baseline_ms_per_scan']:.2f}",
                f"{p['ms_per_predict']:.2f}",
                f"{p['realtime_factor']:.1f}",
                f"{p['components_mean']:.2f}",
                str(p["components_max"]),
            )
        Console().print(table)
    return result
