"""What calibrated odometry leaves of the turn rate, and the yaw random walk that implies.

**Residual.** For one robot on a window, on the ``GRID_DT_S`` grid of the window the residual
``e(t) = ω(t) − m(t)``: ``ω`` the true turn rate (central differences over ``t ± h``,
:func:`relloc.calibration.odometry.ground_truth_velocities`), ``m`` a model of it from the
commands — the calibrated response ``s_ω c_τ,T`` averaged over ``t ± h`` like the differences
(:func:`relloc.calibration.odometry.command_response`), or the best linear filter of the
commands (:class:`relloc.calibration.odometry.CommandFir`). Grid times where the ground truth is
invalid are left out. For a pair ``(i, j)`` the relative yaw ``φ = θ_j − θ_i`` has the error
rate ``e_j − e_i``, taken on the grid times valid for both.

**Statistics** (:class:`ResidualStats`): the mean and standard deviation ``σ`` of ``e``, and the
standard deviation ``σ_B`` of its means over consecutive, non-overlapping blocks of ``B`` seconds
(blocks holding an invalid time left out). A residual white beyond a correlation time ``t_c``
has ``σ_B ≈ σ √(t_c / B)``, vanishing with ``B``; one correlated over seconds keeps ``σ_B`` large.

**Yaw random walk.** Integrated, a block contributes a heading error of ``B`` times its mean;
independent blocks add as a random walk, so over a span ``L`` the heading error the residual
implies is ``σ_θ(L) = σ_B B √(L / B) = σ_B √(B L)`` (:meth:`ResidualStats.yaw_random_walk`).
That is the size of the yaw error a filter driven by these commands accumulates between the
corrections its measurements make; with the relative yaw observable only through slow motion,
over a steady-state span it is a floor no noise model lowers.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import asdict, dataclass

import numpy as np
from numpy.typing import NDArray

from relloc.calibration.odometry import (
    DIFFERENCE_STEP_S,
    GRID_DT_S,
    CommandFir,
    OdometryModelFit,
    command_response,
    fit_command_fir,
    ground_truth_velocities,
)
from relloc.calibration.window import CalibrationWindow
from relloc.datasets.mrclam import MrclamDataset, RobotData
from relloc.errors import ConfigError

Array = NDArray[np.float64]

#: Block length ``B`` (s) of the block means.
BLOCK_S = 5.0
#: The models of the turn rate compared: the calibrated response and the best linear filter.
MODELS: tuple[str, ...] = ("calibrated", "fir")


@dataclass(frozen=True)
class ResidualStats:
    """Mean and std (rad/s) of a turn-rate residual over ``samples`` grid times, and the std
    ``block_std`` of its means over ``blocks`` blocks of ``block_s`` seconds (module doc)."""

    mean: float
    std: float
    block_std: float
    blocks: int
    samples: int
    block_s: float

    def yaw_random_walk(self, span_s: float) -> float:
        """``σ_θ(L) = σ_B √(B L)`` (rad) over a span ``L = span_s`` (module docstring)."""
        return self.block_std * math.sqrt(self.block_s * span_s)

    def to_dict(self, span_s: float) -> dict[str, float | int]:
        """JSON-ready record with the random walk over ``span_s``."""
        return {**asdict(self), "yaw_random_walk_rad": self.yaw_random_walk(span_s)}


def residual_stats(
    e: Array, valid: NDArray[np.bool_], block_s: float = BLOCK_S, dt: float = GRID_DT_S
) -> ResidualStats:
    """:class:`ResidualStats` of ``e`` on a uniform ``dt`` grid where ``valid``."""
    if not (block_s >= dt > 0):
        raise ConfigError(f"residual_stats: need block_s ≥ dt > 0, got {block_s}, {dt}")
    steps = max(round(block_s / dt), 1)
    n = e.size // steps
    blocks = e[: n * steps].reshape(n, steps)
    full = valid[: n * steps].reshape(n, steps).all(axis=1)
    means = blocks[full].mean(axis=1)
    return ResidualStats(
        mean=float(np.mean(e[valid])) if valid.any() else math.nan,
        std=float(np.std(e[valid])) if valid.any() else math.nan,
        block_std=float(np.std(means)) if means.size > 1 else math.nan,
        blocks=int(means.size),
        samples=int(np.count_nonzero(valid)),
        block_s=float(steps * dt),
    )


def turn_rate_residual(
    robot: RobotData, t: Array, model: Callable[[Array], Array]
) -> tuple[Array, NDArray[np.bool_]]:
    """``e = ω − model(t)`` at times ``t`` and where the ground truth is valid."""
    _, w, ok = ground_truth_velocities(robot.groundtruth, t)
    return w - model(t), ok


def calibrated_turn_rate(
    robot: RobotData, fit: OdometryModelFit, scale_w: float
) -> Callable[[Array], Array]:
    """``t ↦ s_ω c_τ,T(t)`` averaged over ``t ± h`` (module docstring)."""

    def model(t: Array) -> Array:
        _, w = command_response(
            robot.odometry.at, t, fit.latency_s, fit.time_constant_s, DIFFERENCE_STEP_S
        )
        return scale_w * w

    return model


@dataclass(frozen=True)
class PairTurnRateResidual:
    """The turn-rate residual of a pair of robots: per robot (subject as a string) and for the
    relative yaw (``"relative"``), per window (name → :class:`CalibrationWindow`) and model
    (:data:`MODELS`), its :class:`ResidualStats`; ``fir`` the best linear filter of each robot,
    fitted on the odometry fit's calibration window."""

    robots: tuple[str, str]
    windows: Mapping[str, CalibrationWindow]
    fir: Mapping[str, CommandFir]
    stats: Mapping[str, Mapping[str, Mapping[str, ResidualStats]]]

    def to_dict(self, span_s: float) -> dict[str, object]:
        """JSON-ready record; the random walks over ``span_s`` (stated beside)."""
        return {
            "block_s": BLOCK_S,
            "yaw_random_walk_span_s": span_s,
            "yaw_random_walk_formula": "sigma_theta = sigma_B * sqrt(B * L)",
            "relative": f"robot {self.robots[1]} minus robot {self.robots[0]}",
            "windows": {k: w.to_dict() for k, w in self.windows.items()},
            "fir": {r: f.to_dict() for r, f in self.fir.items()},
            "residual": {
                who: {
                    win: {m: st.to_dict(span_s) for m, st in models.items()}
                    for win, models in by_window.items()
                }
                for who, by_window in self.stats.items()
            },
        }


def pair_turn_rate_residual(
    ds: MrclamDataset,
    pair: tuple[int, int],
    fit: OdometryModelFit,
    windows: Mapping[str, CalibrationWindow],
) -> PairTurnRateResidual:
    """:class:`PairTurnRateResidual` of robots ``pair = (i, j)`` of ``ds`` with the calibration
    ``fit`` (its per-robot ``s_ω``, ``τ``, ``T``) on each of ``windows``; the FIR of each robot is
    fitted on ``fit.calibration_window`` (:func:`relloc.calibration.odometry.fit_command_fir`)."""
    names = (str(pair[0]), str(pair[1]))
    robots = {name: ds.robot(subject) for name, subject in zip(names, pair, strict=True)}
    firs = {name: fit_command_fir(r, fit.calibration_window) for name, r in robots.items()}
    models: dict[str, dict[str, Callable[[Array], Array]]] = {
        name: {
            "calibrated": calibrated_turn_rate(r, fit, fit.scale_w[ds.robot_ids.index(subject)]),
            "fir": _fir_model(firs[name], r),
        }
        for (name, r), subject in zip(robots.items(), pair, strict=True)
    }
    stats: dict[str, dict[str, dict[str, ResidualStats]]] = {
        who: {} for who in (*names, "relative")
    }
    for win_name, window in windows.items():
        t = np.asarray(window.start_s + GRID_DT_S * np.arange(int(window.duration_s / GRID_DT_S)))
        for who in stats:
            stats[who][win_name] = {}
        for m in MODELS:
            residuals = {n: turn_rate_residual(robots[n], t, models[n][m]) for n in names}
            for n, (e, ok) in residuals.items():
                stats[n][win_name][m] = residual_stats(e, ok)
            (e_i, ok_i), (e_j, ok_j) = residuals[names[0]], residuals[names[1]]
            stats["relative"][win_name][m] = residual_stats(e_j - e_i, ok_i & ok_j)
    return PairTurnRateResidual(robots=names, windows=dict(windows), fir=firs, stats=stats)


def _fir_model(fir: CommandFir, robot: RobotData) -> Callable[[Array], Array]:
    """``t ↦`` the FIR's turn rate of ``robot``'s commands."""
    return lambda t: fir.predict(robot.odometry, t)
