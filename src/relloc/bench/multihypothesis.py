"""Benchmark of the Gaussian-sum fuser: cost per scan against teammates and clutter density.

``relloc bench multihypothesis``. One sensing robot tracks ``n`` teammates (n = 1, 2, 5, 10)
under the clutter densities of the seed-002 sweep (λ × 1, 10, 100, 1000 with λ = 1e-7 per
rad·rad·mm, i.e. ≈ 0.02 … 20 false bearings per scan). Teammates drive at 0.3 m/s with random
headings and turn rates on a ring 2–8 m around the observer; measurements have the paper's noise
and P_D = 0.95. The filter runs at 20 Hz and fuses a direct scan at 10 Hz, for 20 s of data
per point after a 5 s warm-up (not timed), on one core.

Baseline measured in the same run: the single-hypothesis relative EKF with *known*
correspondence (engineer A's batched ``predict_arrays`` + ``update_tekf_arrays`` over all
teammates), fed the same data with the true bearing of each teammate: ``baseline_ms_per_scan``
is what the correspondence problem costs on top.

Reported per point: ``ms_per_scan`` (one direct scan: height, range, bearings, reduction),
``ms_per_predict`` (one 20 Hz prediction of all filters), ``realtime_factor`` (seconds of data
processed per second of CPU: > 1 is faster than real time at 20 Hz/10 Hz), and the component
count per filter (``components_mean``, ``components_max``). The headline ``realtime_10x100``
is the real-time factor with 10 teammates and 100× clutter.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np
from numpy.typing import NDArray

from relloc.core.angles import wrap_angle
from relloc.estimators.gaussian_sum import GaussianSumFuser
from relloc.estimators.relative import predict_arrays, update_tekf_arrays
from relloc.experiments.desilva2015 import filter_settings
from relloc.models.measurement import RangeBearingNoise
from relloc.sim.multihypothesis import DeSilvaScenario

Array = NDArray[np.float64]

TEAM_SIZES = (1, 2, 5, 10)
CLUTTER_FACTORS = (1, 10, 100, 1000)
WARMUP_S = 5.0
TIMED_S = 20.0
SEED = 2026


def _scenario_data(
    n: int, factor: int, rng: np.random.Generator
) -> tuple[DeSilvaScenario, Array, Array, list[tuple[Array, Array, Array, Array]]]:
    """Teammate world states, measured velocities and per-scan (heights, ranges, bearings)."""
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
    scans = []
    every = round(sc.filter_rate / sc.direct_rate)
    sa = np.sqrt(sc.var_azimuth)
    for k in range(steps):
        pos[:, 0] += speed * dt * np.cos(yaw)
        pos[:, 1] += speed * dt * np.sin(yaw)
        yaw = yaw + turn * dt
        if k % every:
            continue
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
        ranges = np.where(
            rng.random(n) < sc.p_detect, r + sc.sigma_range * rng.normal(size=n), np.nan
        )
        heights = pos[:, 2] + sc.sigma_height * rng.normal(size=n)
        known = np.concatenate([r[:, None], own], axis=1)
        known[~seen] = np.nan
        scans.append((heights, ranges, bearings[rng.permutation(len(bearings))], known))
    return sc, u_meas, np.zeros(4), scans


def _one_point(n: int, factor: int) -> dict[str, Any]:
    rng = np.random.default_rng([SEED, n, factor])
    sc, u_meas, u_self, scans = _scenario_data(n, factor, rng)
    fus = GaussianSumFuser(0, list(range(1, n + 1)), filter_settings(sc))
    dt = 1.0 / sc.filter_rate
    every = round(sc.filter_rate / sc.direct_rate)
    warm = round(WARMUP_S * sc.filter_rate)
    t_pred = t_scan = 0.0
    n_pred = n_scan = 0
    comps: list[int] = []
    for k in range(u_meas.shape[0]):
        timed = k >= warm
        t0 = time.process_time()
        fus.predict(u_self, u_meas[k], dt)
        t1 = time.process_time()
        if timed:
            t_pred += t1 - t0
            n_pred += 1
        if k % every == 0:
            heights, ranges, bearings, _ = scans[k // every]
            t0 = time.process_time()
            fus.direct_scan(heights, ranges, bearings)
            t1 = time.process_time()
            if timed:
                t_scan += t1 - t0
                n_scan += 1
                counts = np.bincount(fus.tracks.groups, minlength=n)
                comps.extend(counts.tolist())
    cpu = t_pred + t_scan
    base_ms = _baseline_ms_per_scan(sc, u_meas, u_self, scans, warm, every)
    return {
        "teammates": n,
        "clutter_factor": factor,
        "expected_clutter_per_scan": sc.expected_clutter,
        "ms_per_scan": 1e3 * t_scan / max(n_scan, 1),
        "ms_per_predict": 1e3 * t_pred / max(n_pred, 1),
        "realtime_factor": TIMED_S / cpu if cpu > 0 else float("inf"),
        "baseline_ms_per_scan": base_ms,
        "components_mean": float(np.mean(comps)),
        "components_max": int(np.max(comps)),
    }


def _baseline_ms_per_scan(
    sc: DeSilvaScenario,
    u_meas: Array,
    u_self: Array,
    scans: list[tuple[Array, Array, Array, Array]],
    warm: int,
    every: int,
) -> float:
    """Known-correspondence EKF (one track per teammate) on the same data: ms per scan."""
    n = u_meas.shape[1]
    st = filter_settings(sc)
    noise = RangeBearingNoise(
        sigma_r=sc.sigma_range,
        sigma_azimuth=st.sigma_azimuth,
        sigma_elevation=st.sigma_elevation,
    )
    first = scans[0][3]
    mean = np.zeros((n, 4))
    ok = np.isfinite(first[:, 0])
    cb = np.cos(np.nan_to_num(first[:, 2]))
    mean[ok, 0] = (first[:, 0] * cb * np.cos(first[:, 1]))[ok]
    mean[ok, 1] = (first[:, 0] * cb * np.sin(first[:, 1]))[ok]
    mean[:, 0] = np.where(ok, mean[:, 0], 3.0)
    cov = np.broadcast_to(np.diag([0.1, 0.1, 0.05, 4 * np.pi]), (n, 4, 4)).copy()
    dt = 1.0 / sc.filter_rate
    t_scan = 0.0
    n_scan = 0
    for k in range(u_meas.shape[0]):
        mean, cov = predict_arrays(mean, cov, u_self, u_meas[k], dt, st.velocity_noise)
        if k % every == 0:
            z = scans[k // every][3]
            sel = np.flatnonzero(np.isfinite(z).all(axis=1))
            t0 = time.process_time()
            if sel.size:
                m, P, _ = update_tekf_arrays(mean[sel], cov[sel], z[sel], noise)
                mean[sel], cov[sel] = m, P
            if k >= warm:
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
