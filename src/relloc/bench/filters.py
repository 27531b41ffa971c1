"""``relloc bench filters``: cost of one predict + update of the relative filters.

Measured in one process, on one core, on the same pre-generated sequence (an aerial robot
2 m above a ground observer, 100 Hz odometry inputs, Table-2 precise sensor):

* ``per_update_us``: microseconds for one predict + one update of one pair with
  :class:`~relloc.estimators.relative.RelativeTracker` (PLKF and TEKF) and with filterpy's
  ``ExtendedKalmanFilter`` running the *same* TEKF model — relloc's ``relative_step``,
  ``F``/``Q`` from ``relative_jacobians``/``process_noise``, ``h``/``H`` from
  ``range_bearing``/``range_bearing_jacobian`` and the wrapped residual. Both filters are checked
  to produce the same estimates before anything is timed.
* ``ratio_vs_filterpy``: filterpy's time over relloc's TEKF time (the same filter; target ≥ 3);
  ``ratio_vs_filterpy_by_filter`` gives it for the PLKF too. Part of filterpy's time is spent
  evaluating relloc's general (batched numpy) model functions, so
  ``filterpy_ekf_algebra_only`` replays the recorded ``F``, ``Q``, ``H``, ``h(x)`` of the same
  run and times filterpy's own predict/update algebra alone (a lower bound for any model code).
* ``batched_pair_updates_per_s``: predict + PLKF update of ``pairs`` pairs at once through the
  array API (:func:`predict_arrays`, :func:`update_plkf_arrays`), in pair-updates per second
  (target ≥ 100,000 on one core), and ``batched_speedup_vs_loop`` against updating the same
  pairs one at a time with the tracker (results checked equal).

Timings are the best of several repeats (``time.perf_counter``), the usual way to filter out
interference from other processes; ``load_average`` records how busy the machine was.
"""

from __future__ import annotations

import os
import platform
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from relloc.core.angles import wrap_angle
from relloc.core.checks import count
from relloc.core.gaussian import Gaussian
from relloc.errors import ConfigError, ModelError, require
from relloc.estimators.relative import (
    FilterSettings,
    RelativeTracker,
    predict_arrays,
    update_plkf_arrays,
)
from relloc.models.measurement import RangeBearingNoise, range_bearing, range_bearing_jacobian
from relloc.models.motion import VelocityNoise, process_noise, relative_jacobians, relative_step

MOTION = VelocityNoise(observer=(0.05, 0.05, 0.01, 0.02), observed=(0.05, 0.05, 0.01, 0.02))
SENSOR = RangeBearingNoise(sigma_r=0.0068, sigma_azimuth=0.0036, sigma_elevation=0.0036)
DT = 0.01


@dataclass(frozen=True, kw_only=True)
class BenchSize:
    """How much work each measurement does: ``steps`` of the one-pair sequence, ``pairs`` updated
    together for ``batch_steps`` steps, best of ``repeats``."""

    steps: int = 400
    pairs: int = 1000
    batch_steps: int = 20
    repeats: int = 5

    def __post_init__(self) -> None:
        for name in ("steps", "pairs", "batch_steps", "repeats"):
            count(getattr(self, name), f"BenchSize.{name}")
        if self.batch_steps >= self.steps:
            raise ConfigError("BenchSize.batch_steps: must be smaller than steps")


def _sequence(rng: np.random.Generator, steps: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Odometry inputs and measurements of one pair (truth by the exact model)."""
    t = DT * np.arange(steps)
    u_l = np.stack([0.3 + 0.1 * np.sin(0.3 * t), 0 * t, 0 * t, 0.2 * np.sin(0.5 * t)], axis=-1)
    u_c = np.stack([0.4 + 0 * t, 0.1 * np.cos(0.4 * t), 0 * t, -0.25 * np.cos(0.35 * t)], -1)
    truth = np.empty((steps, 4))
    x = np.array([3.0, 1.0, 2.0, 0.5])
    for k in range(steps):
        x = relative_step(x, u_l[k], u_c[k], DT)
        truth[k] = x
    sig_u = np.sqrt(np.diag(MOTION.covariance))
    odo_l = u_l + rng.normal(size=u_l.shape) * sig_u[:4]
    odo_c = u_c + rng.normal(size=u_c.shape) * sig_u[4:]
    z = range_bearing(truth) + rng.normal(size=(steps, 3)) * np.sqrt(SENSOR.variances)
    return odo_l, odo_c, z


def _best_of(fn: Callable[[], Any], repeats: int) -> float:
    best = np.inf
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - start)
    return float(best)


def _prior() -> Gaussian:
    return Gaussian(mean=np.array([3.0, 1.0, 2.0, 0.5]), cov=np.diag([0.01, 0.01, 0.01, 0.05]))


def _run_tracker(kind: str, odo_l: np.ndarray, odo_c: np.ndarray, z: np.ndarray) -> Gaussian:
    settings = FilterSettings(kind=kind, motion_noise=MOTION, sensor_noise=SENSOR)  # type: ignore[arg-type]
    tracker = RelativeTracker(_prior(), settings)
    ul, uc, zz = odo_l.tolist(), odo_c.tolist(), z.tolist()
    for k in range(len(zz)):
        tracker.predict(ul[k], uc[k], DT)
        tracker.update(zz[k])
    return tracker.belief


def _constant(value: np.ndarray) -> Callable[..., np.ndarray]:
    """A model function that returns a value recorded earlier (replay)."""
    return lambda *_args: value


def _filterpy_ekf_runner() -> Callable[..., Gaussian]:
    kalman = require("filterpy.kalman", "bench")

    class RelativeEKF(kalman.ExtendedKalmanFilter):  # type: ignore[misc, name-defined]
        """filterpy's EKF with relloc's nonlinear state propagation."""

        replay_x: np.ndarray | None = None

        def predict_x(self, u: tuple[np.ndarray, np.ndarray] = ()) -> None:  # type: ignore[assignment]
            if self.replay_x is not None:
                self.x = self.replay_x.copy()
            else:
                self.x = relative_step(self.x, u[0], u[1], DT)

    def residual(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        d = a - b
        d[1:] = wrap_angle(d[1:])
        return d

    R = SENSOR.covariance

    def run(
        odo_l: np.ndarray,
        odo_c: np.ndarray,
        z: np.ndarray,
        recorded: list[tuple[np.ndarray, ...]] | None = None,
        record: list[tuple[np.ndarray, ...]] | None = None,
    ) -> Gaussian:
        """Run filterpy's EKF; with ``recorded`` it replays the model matrices of an earlier
        run instead of evaluating the model (filterpy's own algebra only)."""
        prior = _prior()
        ekf = RelativeEKF(dim_x=4, dim_z=3)
        ekf.x = prior.mean.copy()
        ekf.P = prior.cov.copy()
        h_jac: Callable[..., np.ndarray]
        h_fun: Callable[..., np.ndarray]
        for k in range(len(z)):
            if recorded is None:
                F, G = relative_jacobians(ekf.x, odo_l[k], odo_c[k], DT)
                ekf.F, ekf.Q = F, process_noise(G, MOTION)
                h_jac, h_fun = range_bearing_jacobian, range_bearing
            else:
                ekf.F, ekf.Q, H, hx, ekf.replay_x = recorded[k]
                h_jac, h_fun = _constant(H), _constant(hx)

            ekf.predict(u=(odo_l[k], odo_c[k]))
            if record is not None:
                record.append((ekf.F, ekf.Q, h_jac(ekf.x), h_fun(ekf.x), ekf.x.copy()))
            ekf.update(z[k], h_jac, h_fun, R=R, residual=residual)
        return Gaussian(mean=ekf.x, cov=ekf.P)

    return run


def _batched(
    odo_l: np.ndarray, odo_c: np.ndarray, z: np.ndarray, size: BenchSize
) -> tuple[np.ndarray, np.ndarray]:
    """``size.pairs`` pairs (each offset along the sequence) updated together."""
    prior = _prior()
    mean = np.tile(prior.mean, (size.pairs, 1))
    cov = np.tile(prior.cov, (size.pairs, 1, 1))
    n = len(z) - size.batch_steps
    idx = np.arange(size.pairs) % n
    for k in range(size.batch_steps):
        mean, cov = predict_arrays(mean, cov, odo_l[idx + k], odo_c[idx + k], DT, MOTION)
        mean, cov, _ = update_plkf_arrays(mean, cov, z[idx + k], SENSOR)
    return mean, cov


def _loop(
    odo_l: np.ndarray, odo_c: np.ndarray, z: np.ndarray, size: BenchSize
) -> tuple[np.ndarray, np.ndarray]:
    """The same pairs as :func:`_batched`, one tracker at a time."""
    n = len(z) - size.batch_steps
    means, covs = [], []
    for i in range(size.pairs):
        j = i % n
        b = _run_tracker(
            "plkf",
            odo_l[j : j + size.batch_steps],
            odo_c[j : j + size.batch_steps],
            z[j : j + size.batch_steps],
        )
        means.append(b.mean)
        covs.append(b.cov)
    return np.array(means), np.array(covs)


def _check_same(
    a: tuple[np.ndarray, np.ndarray], b: tuple[np.ndarray, np.ndarray], what: str
) -> float:
    """Largest difference of two ``(mean, cov)`` results; ModelError if they disagree."""
    diff = float(max(np.abs(a[0] - b[0]).max(), np.abs(a[1] - b[1]).max()))
    if diff > 1e-8:
        raise ModelError(f"bench filters: {what} disagree by {diff:.3g}; timings would be unfair")
    return diff


def _moments(g: Gaussian) -> tuple[np.ndarray, np.ndarray]:
    return g.mean, g.cov


def run(quiet: bool = False, *, size: BenchSize | None = None) -> dict[str, Any]:
    """Measure and return the numbers (see the module docstring); print a table unless quiet."""
    size = BenchSize() if size is None else size
    odo_l, odo_c, z = _sequence(np.random.default_rng(0), size.steps)
    filterpy_run = _filterpy_ekf_runner()
    agreement = _check_same(
        _moments(_run_tracker("tekf", odo_l, odo_c, z)),
        _moments(filterpy_run(odo_l, odo_c, z)),
        "TEKF and filterpy",
    )
    batch_agreement = _check_same(
        _batched(odo_l, odo_c, z, size), _loop(odo_l, odo_c, z, size), "batched and loop"
    )

    recorded: list[tuple[np.ndarray, ...]] = []
    filterpy_run(odo_l, odo_c, z, record=recorded)
    _check_same(
        _moments(filterpy_run(odo_l, odo_c, z, recorded=recorded)),
        _moments(filterpy_run(odo_l, odo_c, z)),
        "filterpy with replayed and evaluated model",
    )

    per_update = {
        "plkf": _best_of(lambda: _run_tracker("plkf", odo_l, odo_c, z), size.repeats)
        / size.steps
        * 1e6,
        "tekf": _best_of(lambda: _run_tracker("tekf", odo_l, odo_c, z), size.repeats)
        / size.steps
        * 1e6,
        "filterpy_ekf": _best_of(lambda: filterpy_run(odo_l, odo_c, z), size.repeats)
        / size.steps
        * 1e6,
        "filterpy_ekf_algebra_only": _best_of(
            lambda: filterpy_run(odo_l, odo_c, z, recorded=recorded), size.repeats
        )
        / size.steps
        * 1e6,
    }
    n_updates = size.pairs * size.batch_steps
    batched_s = _best_of(lambda: _batched(odo_l, odo_c, z, size), size.repeats)
    loop_s = _best_of(lambda: _loop(odo_l, odo_c, z, size), min(2, size.repeats))
    result: dict[str, Any] = {
        "per_update_us": per_update,
        "ratio_vs_filterpy": per_update["filterpy_ekf"] / per_update["tekf"],
        "ratio_vs_filterpy_by_filter": {
            k: per_update["filterpy_ekf"] / per_update[k] for k in ("plkf", "tekf")
        },
        "ratio_vs_filterpy_algebra_only": per_update["filterpy_ekf_algebra_only"]
        / per_update["tekf"],
        "batched_pair_updates_per_s": n_updates / batched_s,
        "loop_pair_updates_per_s": n_updates / loop_s,
        "batched_speedup_vs_loop": loop_s / batched_s,
        "targets": {"ratio_vs_filterpy": 3.0, "batched_pair_updates_per_s": 100_000},
        "setup": {
            "pairs": size.pairs,
            "batched_steps": size.batch_steps,
            "sequence_steps": size.steps,
            "dt_s": DT,
            "repeats": size.repeats,
            "pair_update": "one predict + one measurement update",
            "max_difference_tekf_vs_filterpy": agreement,
            "max_difference_batched_vs_loop": batch_agreement,
        },
        "machine": {
            "python": platform.python_version(),
            "numpy": np.__version__,
            "cpu_count": os.cpu_count(),
            "load_average_1min": os.getloadavg()[0],
        },
    }
    if not quiet:
        _print_table(result)
    return result


def _print_table(result: dict[str, Any]) -> None:
    from rich.console import Console
    from rich.table import Table

    per = result["per_update_us"]
    table = Table(title="relloc bench filters (predict + update per pair)")
    table.add_column("measure")
    table.add_column("value", justify="right")
    table.add_column("target", justify="right")
    table.add_row("PLKF tracker [µs]", f"{per['plkf']:.1f}", "")
    table.add_row("TEKF tracker [µs]", f"{per['tekf']:.1f}", "")
    table.add_row("filterpy EKF, same model [µs]", f"{per['filterpy_ekf']:.1f}", "")
    table.add_row(
        "filterpy EKF, model replayed (its algebra only) [µs]",
        f"{per['filterpy_ekf_algebra_only']:.1f}",
        "",
    )
    table.add_row("filterpy / relloc TEKF", f"{result['ratio_vs_filterpy']:.1f}x", "≥ 3x")
    table.add_row(
        "filterpy algebra only / relloc TEKF",
        f"{result['ratio_vs_filterpy_algebra_only']:.1f}x",
        "",
    )
    table.add_row(
        f"batched PLKF, {result['setup']['pairs']} pairs \\[pair-updates/s]",
        f"{result['batched_pair_updates_per_s']:,.0f}",
        "≥ 100,000",
    )
    table.add_row(
        "one-pair loop \\[pair-updates/s]", f"{result['loop_pair_updates_per_s']:,.0f}", ""
    )
    table.add_row("batched / loop", f"{result['batched_speedup_vs_loop']:.1f}x", "")
    console = Console()
    console.print(table)
    console.print(
        f"1-min load average during the run: {result['machine']['load_average_1min']:.2f}"
    )
