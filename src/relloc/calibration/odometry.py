"""Odometry error models fitted against ground truth: latency, scale and noise.

Two fits, for two ways of driving a filter with recorded commands.

**Latency, scales and velocity-dependent variance rates** (:func:`fit_odometry_model`, a team,
used by the cooperative EIF of mrclam-cl). On a ``GRID_DT_S`` grid inside the window (1 s in
from each robot's first command and last ground-truth sample) the ground truth gives the true
forward speed and turn rate by central differences (:func:`ground_truth_velocities`).

1. *Latency* ``τ`` and *time constant* ``T`` (one each for the team; the commands lead the
   motion, and the robot follows a step of its command through a first-order lag,
   ``ẏ = (c(t − τ) − y)/T``): a grid search over ``LATENCY_GRID_S × TIME_CONSTANT_GRID_S``
   minimising ``Σ_robots Σ_{v,ω} ‖m − s c_τ,T‖² / ‖m‖²`` with ``m`` the true velocity,
   ``c_τ,T`` the delayed and lagged command (:func:`command_response`) and ``s`` its
   least-squares scale — the share of the velocity the modelled command cannot explain,
   normalised per robot and channel so that no robot dominates. A pure delay (``T = 0``) is
   on the grid; without the lag a delay alone fits the transients of a step by shrinking the
   scale, which then under-states every steady turn.
2. *Scales* ``s_v, s_ω`` per robot: ``s = m·c / c·c`` at that ``(τ, T)`` (1 for a robot with
   no samples in the window, which the fit lists in ``unfitted_robots``). A channel whose
   modelled command has an RMS ``√(c·c / N)`` over the ``N`` samples below
   ``MIN_COMMAND_RMS`` — the recorded commands' resolution — carries no motion to fit a scale
   on: the fit refuses it with a :class:`DataError` naming the robot, since ``s`` would be
   noise over (almost) nothing, and a scale of 0 would erase every later command of the robot.
   A scale ≤ 0 (a robot moving against its commands, or not with them at all) is refused the
   same way: it would erase or reverse every later command.
3. *Variance rates*: the calibrated commands are integrated over consecutive windows of
   ``integration_s = W`` seconds and compared with the ground truth's path over the window:
   ``D_v = s_path − Σ s_v c_v dt``, ``D_ω = Δθ − Σ s_ω c_ω dt`` (``c`` the modelled command
   ``c_τ,T``), with ``s_path = Σ_k (cos θ̄_k Δx_k + sin θ̄_k Δy_k)`` the forward components of the
   ``GRID_DT_S`` steps of the ground truth at their mid headings ``θ̄_k = θ_k + Δθ_k/2`` and
   ``Δθ = Σ_k wrap(θ_{k+1} − θ_k)`` the total turn (both sums telescope, so the ground truth's
   noise is not amplified). Both are exact however far the robot turns within a window; the
   end-to-end chord would fall short of the path by ``≈ s Δθ²/24`` (a deterministic error
   that grows with ``W`` and would be fitted as noise) and a wrapped end-to-end heading
   difference is off by 2π once the robot turns more than π.
   White input noise of variance rate ``q`` accumulates ``E[D²] = q W``, and the rates are
   modelled as ``q_v = q_v0 + k_v |v|``, ``q_ω = q_ω0 + k_ω |ω| + k_ωv |v|`` (mean |command| over
   the window), fitted by non-negative least squares on ``D²/W`` (rates cannot be negative).
   The constant terms are floored at ``RATE_FLOOR`` so that a still robot keeps some noise.
   ``W`` sets the time scale the rates are right at: the real errors are correlated over
   seconds, so the caller picks the horizon its filter must bridge. Fewer whole windows (valid
   ground truth, no gap in the grid) than coefficients of ``q_ω`` leave the rates unfitted: a
   :class:`DataError` naming the window, not the floor passed on as a fit.

**Velocities from the ground truth** (:func:`ground_truth_odometry`,
:func:`truth_velocity_dataset`): the central differences of :func:`ground_truth_velocities`
re-recorded as if they were a robot's odometry — an oracle no robot has, for measuring how much
of an error budget the odometry is.

**Best linear filter of the commands** (:func:`fit_command_fir`): the true turn rate regressed,
by least squares on a window, on the commands at a set of lags (a finite impulse response, FIR,
acausal lags included) plus a constant,
``ω(t) ≈ Σ_k a_k c_ω(t − ℓ_k) + Σ_k b_k c_v(t − ℓ'_k) + c₀``: every latency, lag, scale and
speed-to-turn coupling any linear time-invariant calibration of the commands could model, so the
residual it leaves is what no such calibration can explain. A robot whose turn-rate commands
have an RMS below ``MIN_COMMAND_RMS`` in the window gives the filter nothing to respond to (its
gain ``Σ a_k`` would be 0 and its mean delay undefined): DataError naming the robot.

:func:`calibrated_commands` applies a fit to a recording's odometry: the modelled response
``c_τ,T`` (re-stamped by when it acts, ``t + τ``; lagged, on a ``GRID_DT_S`` grid, when
``T > 0``) scaled (``s_v v``, ``s_ω ω``); :func:`calibrated_team` does so for every robot of a
team with its own scales.

**Equivalent white noise** (:func:`fit_odometry_noise`, one robot, used where the filter's
input noise is one σ per channel and propagation step). On a ``rate_hz`` grid the held commands
are integrated over windows of ``window_s = W`` seconds and compared with the ground-truth
body-frame increments ``cos θ Δx + sin θ Δy`` (forward), ``−sin θ Δx + cos θ Δy`` (lateral, which
a unicycle reports as 0) and ``Δθ``. White noise of σ held over each step ``dt`` accumulates a
displacement variance ``σ² dt W``, so the equivalent ``σ = √(mean(D²) / (dt W))`` with ``D`` the
windowed error — bias included, which makes the fit conservative; the bias itself is reported as
``mean(D)/W``. Windows touching a ground-truth gap are left out.

The real errors are correlated over seconds (command lag, scale errors), so an equivalent white
noise is right at one time scale only. A filter that bridges several time scales — the
relative yaw corrected only slowly through the motion, a teammate unseen for seconds to
minutes — must not be over-confident at any of them: :func:`fit_largest_odometry_noise` makes
the fit at each length of ``NOISE_WINDOWS_S`` that fits twice into the window and keeps the one
with the largest ``σ_ω``.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, replace

import numpy as np
from numpy.typing import NDArray

from relloc.calibration.window import CalibrationWindow
from relloc.core.angles import wrap_angle
from relloc.core.checks import number, positive
from relloc.core.recording import Odometry
from relloc.datasets.mrclam import GroundTruth, MrclamDataset, RobotData
from relloc.datasets.mrclam import Odometry as Commands
from relloc.errors import ConfigError, DataError

Array = NDArray[np.float64]

#: Integration lengths (s) of :func:`fit_largest_odometry_noise`: 1 s up to 40 s.
NOISE_WINDOWS_S: tuple[float, ...] = (1.0, 2.0, 5.0, 10.0, 20.0, 40.0)
#: Most samples of :func:`fit_odometry_noise`'s grid (a 15-minute window at 10 kHz is 9 million).
MAX_GRID_SAMPLES = 10_000_000
#: Resampling step (s) of the latency/scale/rate fit.
GRID_DT_S = 0.02
#: Latencies (s) searched by :func:`fit_odometry_model`.
LATENCY_GRID_S = np.arange(0.0, 0.5001, 0.01)
#: First-order time constants (s) searched by :func:`fit_odometry_model` (0: a pure delay).
TIME_CONSTANT_GRID_S = (0.0, 0.05, 0.1, 0.15, 0.2, 0.3, 0.4, 0.6)
#: Largest latency and time constant (s) :func:`fit_odometry_noise` calibrates with: the largest
#: :func:`fit_odometry_model` can fit (the ends of its grids).
MAX_LATENCY_S = float(LATENCY_GRID_S[-1])
MAX_TIME_CONSTANT_S = max(TIME_CONSTANT_GRID_S)
#: The lagged response starts this many time constants before the first time asked for
#: (its start-up transient has decayed to e⁻⁸ by then).
SETTLE_TIME_CONSTANTS = 8.0
#: Half-step (s) of the central differences of the ground truth.
DIFFERENCE_STEP_S = 0.05
#: Floor of the fitted constant variance rates ``q_v0``, ``q_ω0``.
RATE_FLOOR = 1e-6
#: Smallest RMS of a channel's modelled command (m/s, rad/s) over the window that a scale is
#: fitted on: the resolution of the recorded commands (1 mm/s, 1 mrad/s on MRCLAM).
MIN_COMMAND_RMS = 1e-3
#: Guard on ``c·c`` and ``m·m`` in the latency cost.
_TINY = 1e-12


# ----------------------------------------------------------------------------------------------
# Latency, scales and variance rates of a team (mrclam-cl)
# ----------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class OdometryModelFit:
    """Latency (s), first-order time constant (s), per-robot scales (in ``ds.robot_ids``
    order) and variance rates: ``q_v0``
    (m²/s), ``k_v`` (m), ``q_w0`` (rad²/s), ``k_w`` (rad), ``k_wv`` (rad²/m), fitted over
    ``odometry_window_s``-long integration windows inside ``calibration_window``.

    ``unfitted_robots``: the subjects of the robots without samples in the window, whose scales
    are the placeholder 1, not a fit (empty when every robot was fitted)."""

    calibration_window: CalibrationWindow
    latency_s: float
    time_constant_s: float
    scale_v: tuple[float, ...]
    scale_w: tuple[float, ...]
    q_v0: float
    k_v: float
    q_w0: float
    k_w: float
    k_wv: float
    odometry_window_s: float
    unfitted_robots: tuple[int, ...] = ()

    def to_dict(self) -> dict[str, object]:
        """JSON-ready record (the window as ``calibration_window``)."""
        return {**asdict(self), "calibration_window": self.calibration_window.to_dict()}


@dataclass(frozen=True)
class _RobotSamples:
    """One robot's grid inside the window with the true speed and turn rate on it."""

    robot: RobotData
    t: Array
    v: Array
    w: Array


def ground_truth_velocities(
    gt: GroundTruth, t: Array, h: float = DIFFERENCE_STEP_S
) -> tuple[Array, Array, NDArray[np.bool_]]:
    """Forward speed ``(cos θ Δx + sin θ Δy)/2h`` and turn rate ``Δθ/2h`` from central
    differences over ``t ± h``, and where all three poses are valid."""
    q0, q1, qm = gt.at(t - h), gt.at(t + h), gt.at(t)
    v = (np.cos(qm.theta) * (q1.x - q0.x) + np.sin(qm.theta) * (q1.y - q0.y)) / (2 * h)
    w = np.asarray(wrap_angle(q1.theta - q0.theta)) / (2 * h)
    return v, w, q0.valid & q1.valid & qm.valid


def ground_truth_odometry(robot: RobotData, dt: float = GRID_DT_S) -> Commands:
    """``robot``'s ground-truth forward speed and turn rate recorded like its commands: on a
    ``dt`` grid over the span of its commands (first to last record, the last stamp kept), the
    value held over ``[t_k, t_{k+1})`` the central difference (:func:`ground_truth_velocities`)
    at the step's middle ``t_k + dt/2``. Across a ground-truth gap the differences are those of
    the interpolated track (straight-line motion); outside the ground truth the track is held,
    so the velocity is 0. A robot without commands gets none."""
    if not (math.isfinite(dt) and dt > 0):
        raise ConfigError(f"ground_truth_odometry: dt must be > 0, got {dt}")
    od = robot.odometry
    if len(od.t) == 0 or len(robot.groundtruth.t) < 2:
        return Commands(t=np.zeros(0), v=np.zeros(0), omega=np.zeros(0))
    first, last = float(od.t[0]), float(od.t[-1])
    t = np.asarray(first + dt * np.arange(max(math.ceil((last - first) / dt), 1)), np.float64)
    if t[-1] < last:
        t = np.append(t, last)
    v, w, _ = ground_truth_velocities(robot.groundtruth, t + 0.5 * dt)
    return Commands(t=t, v=v, omega=w)


def truth_velocity_dataset(ds: MrclamDataset, dt: float = GRID_DT_S) -> MrclamDataset:
    """``ds`` with every robot's odometry replaced by :func:`ground_truth_odometry` (ground
    truth, camera readings and the time span unchanged)."""
    robots = {
        rid: replace(r, odometry=ground_truth_odometry(r, dt)) for rid, r in ds.robots.items()
    }
    return replace(ds, robots=robots)


def _robot_samples(
    robot: RobotData, window: CalibrationWindow, integration_s: float
) -> _RobotSamples:
    """The ``GRID_DT_S`` grid over :func:`_fit_span`; empty when that is not longer than three
    integration windows (or the robot has no odometry or no ground truth)."""
    lo, hi = _fit_span(robot, window)
    t = np.arange(lo, hi, GRID_DT_S) if hi > lo + 3 * integration_s else np.zeros(0)
    v, w, ok = ground_truth_velocities(robot.groundtruth, t)
    return _RobotSamples(robot, t[ok], v[ok], w[ok])


def _fit_span(robot: RobotData, window: CalibrationWindow) -> tuple[float, float]:
    """``(lo, hi)``: from 1 s after the robot's first command (or the window start) to 1 s
    before its last ground truth (or the window end); ``(0, 0)`` without odometry or ground
    truth."""
    odo, gt = robot.odometry.t, robot.groundtruth.t
    if not (len(odo) and len(gt)):
        return 0.0, 0.0
    return max(window.start_s, float(odo[0]) + 1.0), min(window.end_s, float(gt[-1]) - 1.0)


def _command_energy(
    robot: RobotData, command: Array, what: str, unit: str, window: CalibrationWindow
) -> float:
    """``c·c`` of one channel's ``command`` on the window's (non-empty) grid; DataError naming
    the robot and ``what`` it was to be fitted for when the RMS ``√(c·c / N)`` is below
    ``MIN_COMMAND_RMS`` (no commanded motion to fit on)."""
    energy = float(command @ command)
    rms = math.sqrt(energy / command.size)
    if rms < MIN_COMMAND_RMS:
        raise window.too_little(
            f"no commanded motion of robot {robot.subject} in the window to fit its {what} on "
            f"(RMS command {rms:.2g} {unit}, below {MIN_COMMAND_RMS:g})"
        )
    return energy


def _scales(
    s: _RobotSamples, commands: tuple[Array, Array], window: CalibrationWindow
) -> tuple[float, float]:
    """Least-squares ``s`` of ``measured ≈ s · command`` for the speed and the turn rate of
    ``s`` (module docstring, step 2); DataError naming the robot when a channel's command RMS
    is below ``MIN_COMMAND_RMS`` or its scale is not > 0."""
    scales = []
    for name, unit, measured, command in zip(
        ("speed", "turn-rate"), ("m/s", "rad/s"), (s.v, s.w), commands, strict=True
    ):
        energy = _command_energy(s.robot, command, f"{name} scale", unit, window)
        scale = float(measured @ command) / energy
        if not scale > 0:
            raise window.too_little(
                f"robot {s.robot.subject} does not move with its commands: its {name} scale "
                f"fits as {scale:.3g} (a scale must be > 0)"
            )
        scales.append(scale)
    return scales[0], scales[1]


def command_response(
    at: Callable[[Array], tuple[Array, Array]],
    t: Array,
    latency_s: float,
    time_constant_s: float,
    average_s: float = 0.0,
) -> tuple[Array, Array]:
    """The modelled motion ``(v, ω)`` at times ``t`` of the commands ``at`` (zero-order hold):
    delayed by ``τ`` and, for ``T > 0``, passed through the first-order lag
    ``ẏ = (c(t − τ) − y)/T``, integrated exactly on a ``GRID_DT_S`` grid
    (``y_k = (1 − a) y_{k−1} + a c_k``, ``a = 1 − e^{−dt/T}``) that starts
    ``SETTLE_TIME_CONSTANTS · T`` before ``min(t)`` at rest on its first command. With
    ``average_s = h > 0`` the mean of the response over ``[t − h, t + h]`` — what central
    differences of the ground truth over ``t ± h`` measure (:func:`ground_truth_velocities`),
    so that the fit compares like with like."""
    t = np.asarray(t, dtype=np.float64)
    if (time_constant_s <= 0.0 and average_s <= 0.0) or t.size == 0:
        return at(t - latency_s)
    from scipy.signal import lfilter

    start = float(t.min()) - SETTLE_TIME_CONSTANTS * time_constant_s - average_s - GRID_DT_S
    n = int((float(t.max()) + average_s - start) / GRID_DT_S) + 2
    grid = np.asarray(start + GRID_DT_S * np.arange(n), dtype=np.float64)
    a = 1.0 - np.exp(-GRID_DT_S / time_constant_s) if time_constant_s > 0.0 else 1.0
    out = []
    for c in at(grid - latency_s):
        y = c if a == 1.0 else lfilter([a], [1.0, a - 1.0], c, zi=[(1.0 - a) * c[0]])[0]
        if average_s <= 0.0:
            out.append(np.interp(t, grid, y))
            continue
        # y[k] holds over [grid[k], grid[k+1]): its integral at the cell edges
        integral = np.concatenate([[0.0], np.cumsum(y) * GRID_DT_S])
        edges = np.concatenate([grid, [grid[-1] + GRID_DT_S]])
        upper = np.interp(t + average_s, edges, integral)
        lower = np.interp(t - average_s, edges, integral)
        out.append((upper - lower) / (2.0 * average_s))
    return out[0], out[1]


def _latency_and_lag(samples: list[_RobotSamples]) -> tuple[float, float]:
    """Grid-search ``(τ, T)`` minimising the normalised unexplained velocity (module doc).

    The lag is time-invariant, so the response to the delayed command is the delayed response:
    one :func:`command_response` per robot and ``T`` at every ``t − τ`` of the grid."""
    taus = LATENCY_GRID_S
    best, best_cost = (0.0, 0.0), np.inf
    for lag in TIME_CONSTANT_GRID_S:
        cost = np.zeros(taus.size)
        for s in samples:
            if s.t.size == 0:
                continue
            shifted = (s.t[None, :] - taus[:, None]).reshape(-1)
            responses = command_response(s.robot.odometry.at, shifted, 0.0, lag, DIFFERENCE_STEP_S)
            for meas, cmd in zip((s.v, s.w), responses, strict=True):
                c = cmd.reshape(taus.size, s.t.size)
                scale = (c @ meas) / np.maximum(np.einsum("ij,ij->i", c, c), _TINY)
                residual = meas[None, :] - scale[:, None] * c
                cost += np.sum(residual**2, axis=1) / max(float(meas @ meas), _TINY)
        k = int(np.argmin(cost))
        if cost[k] < best_cost:
            best, best_cost = (float(taus[k]), float(lag)), float(cost[k])
    return best


@dataclass(frozen=True)
class _RateRows:
    """Regressors and targets ``D²/W`` of the variance-rate fit for one robot."""

    rows_v: Array
    rhs_v: Array
    rows_w: Array
    rhs_w: Array


def _rate_rows(
    s: _RobotSamples, tau: float, lag: float, sv: float, sw: float, integration_s: float
) -> _RateRows:
    """Windowed integrated errors of the calibrated commands against the ground truth's path
    length and total turn over contiguous, valid windows of ``integration_s`` (module doc,
    step 3)."""
    steps = max(round(integration_s / GRID_DT_S), 1)
    n_win = s.t.size // steps
    tw = s.t[: n_win * steps].reshape(n_win, steps)
    contiguous = np.isclose(tw[:, -1] - tw[:, 0], (steps - 1) * GRID_DT_S)
    edges = np.concatenate([tw, tw[:, -1:] + GRID_DT_S], axis=1)
    g = s.robot.groundtruth.at(edges.reshape(-1))
    x, y, theta = (np.reshape(a, (n_win, steps + 1)) for a in (g.x, g.y, g.theta))
    ok = contiguous & g.valid.reshape(n_win, steps + 1).all(axis=1)
    vcw, wcw = command_response(s.robot.odometry.at, tw.reshape(-1), tau, lag)
    vcw = sv * vcw.reshape(n_win, steps)
    wcw = sw * wcw.reshape(n_win, steps)
    turns = np.asarray(wrap_angle(np.diff(theta, axis=1)))
    mid = theta[:, :-1] + 0.5 * turns
    path = np.sum(np.cos(mid) * np.diff(x, axis=1) + np.sin(mid) * np.diff(y, axis=1), axis=1)
    d_v = path - vcw.sum(axis=1) * GRID_DT_S
    d_w = turns.sum(axis=1) - wcw.sum(axis=1) * GRID_DT_S
    speed, turn = np.abs(vcw).mean(axis=1), np.abs(wcw).mean(axis=1)
    W = GRID_DT_S * steps
    return _RateRows(
        rows_v=np.column_stack([np.ones(ok.sum()), speed[ok]]),
        rhs_v=d_v[ok] ** 2 / W,
        rows_w=np.column_stack([np.ones(ok.sum()), turn[ok], speed[ok]]),
        rhs_w=d_w[ok] ** 2 / W,
    )


def fit_odometry_model(
    ds: MrclamDataset, window: CalibrationWindow, integration_s: float
) -> OdometryModelFit:
    """Latency, per-robot scales and variance rates of every robot's odometry on ``window``
    (module docstring); the rates are fitted over ``integration_s``-long windows. A robot
    without commanded motion in the window, or with a scale ≤ 0, is refused (DataError naming
    it); a robot without samples in the window keeps scales of 1 and is listed in
    ``unfitted_robots``; too few whole integration windows for the rates are refused
    (DataError naming the window). Ground truth and commands are finite by construction
    (:class:`~relloc.datasets.mrclam.GroundTruth`, :class:`~relloc.datasets.mrclam.Odometry`)."""
    from scipy.optimize import nnls

    if not (np.isfinite(integration_s) and integration_s > 0):
        raise ConfigError(f"fit_odometry_model: integration_s must be > 0, got {integration_s}")
    samples = [_robot_samples(ds.robot(rid), window, integration_s) for rid in ds.robot_ids]
    if not any(s.t.size for s in samples):
        spans = {rid: _fit_span(ds.robot(rid), window) for rid in ds.robot_ids}
        lengths = {rid: hi - lo for rid, (lo, hi) in spans.items()}
        longest = max(lengths, key=lambda rid: lengths[rid])
        raise window.too_little(
            "to fit the odometry on, a robot needs more than three integration windows "
            f"({3.0 * integration_s:.3g} s) from 1 s after its first command to 1 s before its "
            f"last ground truth; the longest is robot {longest}'s, "
            f"{max(lengths[longest], 0.0):.3g} s"
        )
    tau, lag = _latency_and_lag(samples)
    scale_v, scale_w, rows, unfitted = [], [], [], []
    for s in samples:
        if s.t.size == 0:
            scale_v.append(1.0)
            scale_w.append(1.0)
            unfitted.append(int(s.robot.subject))
            continue
        commands = command_response(s.robot.odometry.at, s.t, tau, lag, DIFFERENCE_STEP_S)
        sv, sw = _scales(s, commands, window)
        scale_v.append(sv)
        scale_w.append(sw)
        rows.append(_rate_rows(s, tau, lag, sv, sw, integration_s))
    rows_w = np.vstack([r.rows_w for r in rows])
    if rows_w.shape[0] < rows_w.shape[1]:
        raise window.too_little(
            f"{rows_w.shape[0]} whole {integration_s:g} s integration windows with valid ground "
            f"truth, fewer than the {rows_w.shape[1]} variance-rate coefficients to fit"
        )
    cv, _ = nnls(np.vstack([r.rows_v for r in rows]), np.concatenate([r.rhs_v for r in rows]))
    cw, _ = nnls(rows_w, np.concatenate([r.rhs_w for r in rows]))
    return OdometryModelFit(
        calibration_window=window,
        latency_s=tau,
        time_constant_s=lag,
        scale_v=tuple(scale_v),
        scale_w=tuple(scale_w),
        q_v0=max(float(cv[0]), RATE_FLOOR),
        k_v=float(cv[1]),
        q_w0=max(float(cw[0]), RATE_FLOOR),
        k_w=float(cw[1]),
        k_wv=float(cw[2]),
        odometry_window_s=float(integration_s),
        unfitted_robots=tuple(unfitted),
    )


def calibrated_commands(
    od: Odometry, latency_s: float, scale_v: float, scale_w: float, time_constant_s: float = 0.0
) -> Odometry:
    """``od`` as a calibrated model sees it: forward speed and turn rate scaled (``s_v v_x``,
    ``s_ω ω_z``) and re-stamped by when they act (``t + τ``); with ``T > 0`` the lagged
    response of :func:`command_response` on a ``GRID_DT_S`` grid from the first command to
    ``SETTLE_TIME_CONSTANTS · T`` after the last (held from then on)."""
    if time_constant_s > 0.0 and od.t.size:
        n = int((od.t[-1] - od.t[0] + SETTLE_TIME_CONSTANTS * time_constant_s) / GRID_DT_S) + 1
        t = od.t[0] + GRID_DT_S * np.arange(n)

        def held(tq: Array) -> tuple[Array, Array]:
            u = od.held_at(tq)
            return u[:, 0], u[:, 3]

        velocity = np.zeros((n, 4))
        velocity[:, 0], velocity[:, 3] = command_response(held, t, 0.0, time_constant_s)
        od = replace(od, t=t, velocity=velocity)
    velocity = np.array(od.velocity)
    velocity[:, 0] *= scale_v
    velocity[:, 3] *= scale_w
    return replace(od, t=od.t + latency_s, velocity=velocity, where=f"{od.where} calibrated")


def unfitted_note(unfitted: Sequence[int]) -> str:
    """The report's sentence on the robots an odometry fit left unfitted (``unfitted_robots``
    of :class:`OdometryModelFit`); empty when every robot was fitted."""
    if not unfitted:
        return ""
    names = ", ".join(str(r) for r in unfitted)
    return (
        f" Not fitted: robot{'s' if len(unfitted) > 1 else ''} {names} had no odometry with "
        "ground truth in the calibration window, so its scales are the placeholder 1."
    )


def calibrated_team(odometry: Sequence[Odometry], fit: OdometryModelFit) -> tuple[Odometry, ...]:
    """Every robot's commands calibrated with ``fit`` (:func:`calibrated_commands`): the team's
    latency and time constant, robot ``i``'s scales ``fit.scale_v[i]``, ``fit.scale_w[i]``
    (``odometry`` in the ``ds.robot_ids`` order the fit was made in)."""
    if len(odometry) != len(fit.scale_v):
        raise ConfigError(
            f"calibrated_team: {len(odometry)} robots' odometry, {len(fit.scale_v)} fitted scales"
        )
    return tuple(
        calibrated_commands(od, fit.latency_s, fit.scale_v[i], fit.scale_w[i], fit.time_constant_s)
        for i, od in enumerate(odometry)
    )


# ----------------------------------------------------------------------------------------------
# Best linear filter of the commands (what no calibration of them can explain)
# ----------------------------------------------------------------------------------------------

#: Lags (s) of the turn-rate commands in :func:`fit_command_fir`: from −0.2 s (commands after
#: the motion) to 1.18 s every ``GRID_DT_S`` — past every latency and lag the fit searches.
FIR_LAGS_S: tuple[float, ...] = tuple(round(GRID_DT_S * k, 10) for k in range(-10, 60))
#: Lags (s) of the speed commands (every fifth turn-rate lag).
FIR_SPEED_LAGS_S: tuple[float, ...] = FIR_LAGS_S[::5]


@dataclass(frozen=True)
class CommandFir:
    """The turn-rate model ``ω(t) ≈ Σ_k a_k c_ω(t − ℓ_k) + Σ_k b_k c_v(t − ℓ'_k) + c₀`` of one
    robot (module docstring), fitted on ``calibration_window`` over ``samples`` grid times:
    ``lags_w_s`` ``ℓ`` with ``coef_w`` ``a`` (dimensionless), ``lags_v_s`` ``ℓ'`` with ``coef_v``
    ``b`` (rad/m), ``constant`` ``c₀`` (rad/s)."""

    lags_w_s: tuple[float, ...]
    coef_w: tuple[float, ...]
    lags_v_s: tuple[float, ...]
    coef_v: tuple[float, ...]
    constant: float
    calibration_window: CalibrationWindow
    samples: int

    @property
    def dc_gain(self) -> float:
        """``Σ a_k``: the turn the filter makes of a steady turn-rate command."""
        return float(sum(self.coef_w))

    @property
    def centroid_lag_s(self) -> float:
        """``Σ a_k ℓ_k / Σ a_k``: the filter's mean delay (s)."""
        return float(np.dot(self.coef_w, self.lags_w_s)) / self.dc_gain

    def predict(self, commands: Commands, t: Array) -> Array:
        """The modelled turn rate at times ``t`` of ``commands`` (zero-order hold)."""
        coef = np.concatenate([self.coef_w, self.coef_v, [self.constant]])
        return _fir_design(commands, np.asarray(t, dtype=np.float64), self) @ coef

    def to_dict(self) -> dict[str, object]:
        """JSON-ready summary (the taps by their sum and centroid, not one by one)."""
        return {
            "turn_rate_taps": len(self.lags_w_s),
            "turn_rate_lags_s": [self.lags_w_s[0], self.lags_w_s[-1]],
            "speed_taps": len(self.lags_v_s),
            "dc_gain": self.dc_gain,
            "centroid_lag_s": self.centroid_lag_s,
            "speed_gain_rad_per_m": float(sum(self.coef_v)),
            "constant_rad_s": self.constant,
            "samples": self.samples,
            "calibration_window": self.calibration_window.to_dict(),
        }


def _fir_design(
    commands: Commands,
    t: Array,
    lags: CommandFir | tuple[tuple[float, ...], tuple[float, ...]],
) -> Array:
    """Columns ``c_ω(t − ℓ_k)``, ``c_v(t − ℓ'_k)`` and 1 of the FIR regression."""
    lags_w, lags_v = (lags.lags_w_s, lags.lags_v_s) if isinstance(lags, CommandFir) else lags
    cols = [commands.at(t - lag)[1] for lag in lags_w]
    cols += [commands.at(t - lag)[0] for lag in lags_v]
    cols.append(np.ones_like(t))
    return np.column_stack(cols)


def fit_command_fir(
    robot: RobotData,
    window: CalibrationWindow,
    *,
    lags_w_s: tuple[float, ...] = FIR_LAGS_S,
    lags_v_s: tuple[float, ...] = FIR_SPEED_LAGS_S,
) -> CommandFir:
    """The least-squares :class:`CommandFir` of ``robot``'s true turn rate (central
    differences, :func:`ground_truth_velocities`) on its commands inside ``window`` (the
    ``GRID_DT_S`` grid of :func:`fit_odometry_model`, ground-truth gaps left out): minimises
    ``Σ_t (ω(t) − x(t)·β)²`` over ``β = (a, b, c₀)`` with ``x(t)`` the lagged commands and 1
    (ConfigError naming a lag that is not a finite number).
    Collinear lags (commands held longer than a grid step) get the minimum-norm solution, which
    leaves the fitted values — and so the residual — unchanged. DataError naming the window
    when it holds fewer than ten samples per coefficient, and naming the robot when its
    turn-rate commands there have an RMS below ``MIN_COMMAND_RMS`` (module docstring)."""
    if not lags_w_s:
        raise ConfigError("fit_command_fir: needs at least one turn-rate lag")
    for name, lags in (("lags_w_s", lags_w_s), ("lags_v_s", lags_v_s)):
        for i, lag in enumerate(lags):
            number(lag, f"fit_command_fir: {name}[{i}]")
    s = _robot_samples(robot, window, GRID_DT_S)
    n_coef = len(lags_w_s) + len(lags_v_s) + 1
    if s.t.size < 10 * n_coef:
        raise window.too_little(
            f"robot {robot.subject}: {s.t.size} ground-truth samples for {n_coef} FIR coefficients"
        )
    _command_energy(robot, robot.odometry.at(s.t)[1], "turn-rate filter", "rad/s", window)
    design = _fir_design(robot.odometry, s.t, (lags_w_s, lags_v_s))
    beta, *_ = np.linalg.lstsq(design, s.w, rcond=None)
    nw = len(lags_w_s)
    return CommandFir(
        lags_w_s=tuple(float(x) for x in lags_w_s),
        coef_w=tuple(float(x) for x in beta[:nw]),
        lags_v_s=tuple(float(x) for x in lags_v_s),
        coef_v=tuple(float(x) for x in beta[nw:-1]),
        constant=float(beta[-1]),
        calibration_window=window,
        samples=int(s.t.size),
    )


# ----------------------------------------------------------------------------------------------
# Equivalent white noise of one robot
# ----------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class OdometryNoiseFit:
    """Equivalent white-noise standard deviations of one robot's odometry channels.

    ``sigma_v`` (forward speed), ``sigma_lateral`` (sideways speed a unicycle reports as 0) in
    m/s and ``sigma_w`` (yaw rate) in rad/s, for noise drawn independently at every step of a
    ``rate_hz`` propagation; ``bias_v``, ``bias_w`` are the mean errors (true − reported);
    ``window_s`` is the integration-window length (the one asked for, rounded to whole steps of
    ``1/rate_hz``: the σ and the biases divide by it) and ``n_windows`` how many were used.
    """

    sigma_v: float
    sigma_lateral: float
    sigma_w: float
    bias_v: float
    bias_w: float
    rate_hz: float
    window_s: float
    n_windows: int
    calibration_window: CalibrationWindow

    def to_dict(self) -> dict[str, object]:
        """JSON-ready record (the window as ``calibration_window``)."""
        return {**asdict(self), "calibration_window": self.calibration_window.to_dict()}


def fit_odometry_noise(
    robot: RobotData,
    window: CalibrationWindow,
    *,
    rate_hz: float = 100.0,
    window_s: float = 1.0,
    latency_s: float = 0.0,
    scale_v: float = 1.0,
    scale_w: float = 1.0,
    time_constant_s: float = 0.0,
) -> OdometryNoiseFit:
    """Fit the white-noise level that explains the odometry's drift over ``window_s`` seconds
    inside ``window`` (module docstring). The real errors are correlated over seconds (command
    lag, scale errors), so a σ fitted for one integration length is only right at that time
    scale. With ``latency_s``, ``scale_v``, ``scale_w``, ``time_constant_s`` (a fitted
    :class:`OdometryModelFit`'s) the commands are first calibrated, ``s · c_τ,T``
    (:func:`command_response`): the fit is then the noise left after that calibration.

    ConfigError naming the parameter unless ``rate_hz``, ``window_s`` and the scales are finite
    and > 0, the grid holds at most :data:`MAX_GRID_SAMPLES` samples, ``window_s`` holds at
    least one step ``1/rate_hz`` and is no longer than
    ``window``, and ``latency_s``, ``time_constant_s`` lie in ``[0, MAX_LATENCY_S]``, ``[0,
    MAX_TIME_CONSTANT_S]`` (what :func:`fit_odometry_model` can fit; the commands lead the
    motion, so neither is negative). DataError naming the window when it holds fewer than two
    whole integration windows of valid ground truth."""
    for name, value in (
        ("rate_hz", rate_hz),
        ("window_s", window_s),
        ("scale_v", scale_v),
        ("scale_w", scale_w),
    ):
        positive(value, f"fit_odometry_noise: {name}")
    if window.duration_s * rate_hz > MAX_GRID_SAMPLES:
        raise ConfigError(
            f"fit_odometry_noise: rate_hz {rate_hz:g} over {window.describe()} is more than "
            f"{MAX_GRID_SAMPLES} samples"
        )
    if not 1.0 / rate_hz <= window_s <= window.duration_s:
        raise ConfigError(
            f"fit_odometry_noise: window_s must lie between one step (1/rate_hz = "
            f"{1.0 / rate_hz:g} s) and the length of the calibration window "
            f"{window.describe()}, got {window_s:g} s"
        )
    for name, value, most in (
        ("latency_s", latency_s, MAX_LATENCY_S),
        ("time_constant_s", time_constant_s, MAX_TIME_CONSTANT_S),
    ):
        if not 0.0 <= value <= most:
            raise ConfigError(
                f"fit_odometry_noise: {name} must lie in [0, {most:g}] s (what "
                f"fit_odometry_model fits), got {value}"
            )
    dt = 1.0 / rate_hz
    steps = max(round(window_s * rate_hz), 1)
    length = steps * dt  # the windows' real length: window_s on the grid
    n_windows = int((window.end_s - window.start_s) // length)
    if n_windows < 2:
        raise window.too_little(
            f"robot {robot.subject}: fewer than two {window_s:g} s windows for the odometry fit"
        )
    t = np.asarray(window.start_s + dt * np.arange(n_windows * steps + 1), dtype=np.float64)
    q = robot.groundtruth.at(t)
    v_cmd, w_cmd = command_response(robot.odometry.at, t[:-1], latency_s, time_constant_s)
    v_cmd, w_cmd = scale_v * v_cmd, scale_w * w_cmd
    c, s = np.cos(q.theta[:-1]), np.sin(q.theta[:-1])
    dx, dy = np.diff(q.x), np.diff(q.y)
    dth = np.diff(np.unwrap(q.theta))
    err = np.stack(
        [c * dx + s * dy - v_cmd * dt, -s * dx + c * dy, dth - w_cmd * dt], axis=-1
    ).reshape(n_windows, steps, 3)
    ok = q.valid[:-1].reshape(n_windows, steps).all(axis=1) & q.valid[steps::steps]
    if ok.sum() < 2:
        raise window.too_little(f"robot {robot.subject}: ground truth has gaps in every window")
    D = err[ok].sum(axis=1)
    sigma = np.sqrt(np.mean(D * D, axis=0) / (dt * length))
    bias = D.mean(axis=0) / length
    return OdometryNoiseFit(
        sigma_v=float(sigma[0]),
        sigma_lateral=float(sigma[1]),
        sigma_w=float(sigma[2]),
        bias_v=float(bias[0]),
        bias_w=float(bias[2]),
        rate_hz=float(rate_hz),
        window_s=float(length),
        n_windows=int(ok.sum()),
        calibration_window=window,
    )


def noise_lengths(lengths_s: Sequence[float], window: CalibrationWindow) -> list[float]:
    """The integration lengths of ``lengths_s`` that fit twice into ``window`` (DataError,
    naming the window, when none does)."""
    lengths = [float(w) for w in lengths_s if 2 * w <= window.duration_s]
    if not lengths:
        raise window.too_little(f"no noise window of {tuple(lengths_s)} s fits twice")
    return lengths


def fit_largest_odometry_noise(
    robot: RobotData,
    window: CalibrationWindow,
    lengths_s: Sequence[float] = NOISE_WINDOWS_S,
    *,
    rate_hz: float = 100.0,
    latency_s: float = 0.0,
    scale_v: float = 1.0,
    scale_w: float = 1.0,
    time_constant_s: float = 0.0,
) -> OdometryNoiseFit:
    """:func:`fit_odometry_noise` at every length of ``lengths_s`` that fits twice into
    ``window`` (:func:`noise_lengths`), and of those fits the one with the largest ``σ_ω``
    (module docstring); its ``window_s`` says which length it is. A length at which the ground
    truth has gaps in all windows but one has no fit and is left out (long windows are the
    first to touch a Vicon gap); when no length has a fit, the shortest length's error is
    raised."""
    fits: list[OdometryNoiseFit] = []
    first_error: DataError | None = None
    for length in noise_lengths(lengths_s, window):
        try:
            fits.append(
                fit_odometry_noise(
                    robot,
                    window,
                    rate_hz=rate_hz,
                    window_s=length,
                    latency_s=latency_s,
                    scale_v=scale_v,
                    scale_w=scale_w,
                    time_constant_s=time_constant_s,
                )
            )
        except DataError as error:
            first_error = first_error or error
    if not fits:
        assert first_error is not None  # noise_lengths gives at least one length
        raise first_error
    return max(fits, key=lambda f: f.sigma_w)
