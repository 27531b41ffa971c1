"""Odometry error models fitted against ground truth: latency, scale and noise.

Two fits, for two ways of driving a filter with recorded commands.

**Latency, scales and velocity-dependent variance rates** (:func:`fit_odometry_model`, a team,
used by the cooperative EIF of mrclam-cl). On a ``GRID_DT_S`` grid inside the window (1 s in
from each robot's first command and last ground-truth sample) the ground truth gives the true
forward speed and turn rate by central differences (:func:`ground_truth_velocities`).

1. *Latency* ``τ`` (one for the team; the commands lead the motion): a grid search over
   ``LATENCY_GRID_S`` minimising ``Σ_robots Σ_{v,ω} ‖m − s c_τ‖² / ‖m‖²`` with ``m`` the true
   velocity, ``c_τ(t) = c(t − τ)`` the delayed command and ``s`` its least-squares scale — the
   share of the velocity the delayed, scaled command cannot explain, normalised per robot and
   channel so that no robot dominates.
2. *Scales* ``s_v, s_ω`` per robot: ``s = m·c_τ / c_τ·c_τ`` at that ``τ`` (1 for a robot with
   no samples in the window).
3. *Variance rates*: the calibrated commands are integrated over consecutive windows of
   ``integration_s = W`` seconds and compared with the ground-truth displacement (no
   differentiation noise): ``D_v = Δs_fwd − Σ s_v c_v dt``, ``D_ω = Δθ − Σ s_ω c_ω dt``.
   White input noise of variance rate ``q`` accumulates ``E[D²] = q W``, and the rates are
   modelled as ``q_v = q_v0 + k_v |v|``, ``q_ω = q_ω0 + k_ω |ω| + k_ωv |v|`` (mean |command| over
   the window), fitted by non-negative least squares on ``D²/W`` (rates cannot be negative).
   The constant terms are floored at ``RATE_FLOOR`` so that a still robot keeps some noise.
   ``W`` sets the time scale the rates are right at: the real errors are correlated over
   seconds, so the caller picks the horizon its filter must bridge.

:func:`calibrated_commands` applies a fit to a recording's odometry: every command re-stamped
by when it acts (``t + τ``) and scaled (``s_v v``, ``s_ω ω``).

**Equivalent white noise** (:func:`fit_odometry_noise`, one robot, used where the filter's
input noise is one σ per channel and propagation step). On a ``rate_hz`` grid the held commands
are integrated over windows of ``window_s = W`` seconds and compared with the ground-truth
body-frame increments ``cos θ Δx + sin θ Δy`` (forward), ``−sin θ Δx + cos θ Δy`` (lateral, which
a unicycle reports as 0) and ``Δθ``. White noise of σ held over each step ``dt`` accumulates a
displacement variance ``σ² dt W``, so the equivalent ``σ = √(mean(D²) / (dt W))`` with ``D`` the
windowed error — bias included, which makes the fit conservative; the bias itself is reported as
``mean(D)/W``. Windows touching a ground-truth gap are left out.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, replace

import numpy as np
from numpy.typing import NDArray

from relloc.calibration.window import CalibrationWindow
from relloc.core.angles import wrap_angle
from relloc.core.recording import Odometry
from relloc.datasets.mrclam import GroundTruth, MrclamDataset, RobotData
from relloc.errors import ConfigError

Array = NDArray[np.float64]

#: Resampling step (s) of the latency/scale/rate fit.
GRID_DT_S = 0.02
#: Latencies (s) searched by :func:`fit_odometry_model`.
LATENCY_GRID_S = np.arange(0.0, 0.5001, 0.01)
#: Half-step (s) of the central differences of the ground truth.
DIFFERENCE_STEP_S = 0.05
#: Floor of the fitted constant variance rates ``q_v0``, ``q_ω0``.
RATE_FLOOR = 1e-6
#: Guard on ``c·c`` and ``m·m`` in the scale fit and the latency cost.
_TINY = 1e-12


# ----------------------------------------------------------------------------------------------
# Latency, scales and variance rates of a team (mrclam-cl)
# ----------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class OdometryModelFit:
    """Latency (s), per-robot scales (in ``ds.robot_ids`` order) and variance rates: ``q_v0``
    (m²/s), ``k_v`` (m), ``q_w0`` (rad²/s), ``k_w`` (rad), ``k_wv`` (rad²/m), fitted over
    ``odometry_window_s``-long integration windows inside ``calibration_window``."""

    calibration_window: CalibrationWindow
    latency_s: float
    scale_v: tuple[float, ...]
    scale_w: tuple[float, ...]
    q_v0: float
    k_v: float
    q_w0: float
    k_w: float
    k_wv: float
    odometry_window_s: float

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


def _robot_samples(
    robot: RobotData, window: CalibrationWindow, integration_s: float
) -> _RobotSamples:
    """The ``GRID_DT_S`` grid from 1 s after the first command (or the window start) to 1 s
    before the last ground truth (or the window end); empty when shorter than three
    integration windows or when the robot has no odometry or no ground truth."""
    odo, gt = robot.odometry.t, robot.groundtruth.t
    t = np.zeros(0)
    if len(odo) and len(gt):
        lo = max(window.start_s, float(odo[0]) + 1.0)
        hi = min(window.end_s, float(gt[-1]) - 1.0)
        if hi > lo + 3 * integration_s:
            t = np.arange(lo, hi, GRID_DT_S)
    v, w, ok = ground_truth_velocities(robot.groundtruth, t)
    return _RobotSamples(robot, t[ok], v[ok], w[ok])


def _scale(measured: Array, command: Array) -> float:
    """Least-squares ``s`` of ``measured ≈ s · command``."""
    return float(measured @ command) / max(float(command @ command), _TINY)


def _latency(samples: list[_RobotSamples]) -> float:
    """Grid-search latency ``τ`` minimising the normalised unexplained velocity (module doc)."""
    cost = np.zeros(LATENCY_GRID_S.size)
    for k, tau in enumerate(LATENCY_GRID_S):
        for s in samples:
            if s.t.size == 0:
                continue
            vc, wc = s.robot.odometry.at(s.t - tau)
            for meas, cmd in ((s.v, vc), (s.w, wc)):
                residual = meas - _scale(meas, cmd) * cmd
                cost[k] += np.sum(residual**2) / max(float(meas @ meas), _TINY)
    return float(LATENCY_GRID_S[int(np.argmin(cost))])


@dataclass(frozen=True)
class _RateRows:
    """Regressors and targets ``D²/W`` of the variance-rate fit for one robot."""

    rows_v: Array
    rhs_v: Array
    rows_w: Array
    rhs_w: Array


def _rate_rows(
    s: _RobotSamples, tau: float, sv: float, sw: float, integration_s: float
) -> _RateRows:
    """Windowed integrated errors of the calibrated commands against the ground-truth
    displacement over contiguous, valid windows of ``integration_s`` (module doc, step 3)."""
    steps = max(round(integration_s / GRID_DT_S), 1)
    n_win = s.t.size // steps
    tw = s.t[: n_win * steps].reshape(n_win, steps)
    contiguous = np.isclose(tw[:, -1] - tw[:, 0], (steps - 1) * GRID_DT_S)
    t0, t1 = tw[:, 0], tw[:, -1] + GRID_DT_S
    g0, g1 = s.robot.groundtruth.at(t0), s.robot.groundtruth.at(t1)
    ok = contiguous & g0.valid & g1.valid
    vcw, wcw = s.robot.odometry.at(tw.reshape(-1) - tau)
    vcw = sv * vcw.reshape(n_win, steps)
    wcw = sw * wcw.reshape(n_win, steps)
    dtheta = np.asarray(wrap_angle(g1.theta - g0.theta))
    mid = g0.theta + 0.5 * dtheta
    fwd = np.cos(mid) * (g1.x - g0.x) + np.sin(mid) * (g1.y - g0.y)
    d_v = fwd - vcw.sum(axis=1) * GRID_DT_S
    d_w = dtheta - wcw.sum(axis=1) * GRID_DT_S
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
    (module docstring); the rates are fitted over ``integration_s``-long windows."""
    from scipy.optimize import nnls

    if not (np.isfinite(integration_s) and integration_s > 0):
        raise ConfigError(f"fit_odometry_model: integration_s must be > 0, got {integration_s}")
    samples = [_robot_samples(ds.robot(rid), window, integration_s) for rid in ds.robot_ids]
    if not any(s.t.size for s in samples):
        raise window.too_little("no odometry overlapping ground truth to fit the odometry on")
    tau = _latency(samples)
    scale_v, scale_w, rows = [], [], []
    for s in samples:
        if s.t.size == 0:
            scale_v.append(1.0)
            scale_w.append(1.0)
            continue
        vc, wc = s.robot.odometry.at(s.t - tau)
        sv, sw = _scale(s.v, vc), _scale(s.w, wc)
        scale_v.append(sv)
        scale_w.append(sw)
        rows.append(_rate_rows(s, tau, sv, sw, integration_s))
    cv, _ = nnls(np.vstack([r.rows_v for r in rows]), np.concatenate([r.rhs_v for r in rows]))
    cw, _ = nnls(np.vstack([r.rows_w for r in rows]), np.concatenate([r.rhs_w for r in rows]))
    return OdometryModelFit(
        calibration_window=window,
        latency_s=tau,
        scale_v=tuple(scale_v),
        scale_w=tuple(scale_w),
        q_v0=max(float(cv[0]), RATE_FLOOR),
        k_v=float(cv[1]),
        q_w0=max(float(cw[0]), RATE_FLOOR),
        k_w=float(cw[1]),
        k_wv=float(cw[2]),
        odometry_window_s=float(integration_s),
    )


def calibrated_commands(od: Odometry, latency_s: float, scale_v: float, scale_w: float) -> Odometry:
    """``od`` as a calibrated model sees it: every command re-stamped by when it acts
    (``t + τ``) and its forward speed and turn rate scaled (``s_v v_x``, ``s_ω ω_z``)."""
    velocity = np.array(od.velocity)
    velocity[:, 0] *= scale_v
    velocity[:, 3] *= scale_w
    return replace(od, t=od.t + latency_s, velocity=velocity, where=f"{od.where} calibrated")


# ----------------------------------------------------------------------------------------------
# Equivalent white noise of one robot
# ----------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class OdometryNoiseFit:
    """Equivalent white-noise standard deviations of one robot's odometry channels.

    ``sigma_v`` (forward speed), ``sigma_lateral`` (sideways speed a unicycle reports as 0) in
    m/s and ``sigma_w`` (yaw rate) in rad/s, for noise drawn independently at every step of a
    ``rate_hz`` propagation; ``bias_v``, ``bias_w`` are the mean errors (true − reported);
    ``window_s`` is the integration-window length and ``n_windows`` how many were used.
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
) -> OdometryNoiseFit:
    """Fit the white-noise level that explains the odometry's drift over ``window_s`` seconds
    inside ``window`` (module docstring). The real errors are correlated over seconds (command
    lag, scale errors), so a σ fitted for one integration length is only right at that time
    scale. With ``latency_s``, ``scale_v``, ``scale_w`` (a fitted :class:`OdometryModelFit`'s)
    the commands are first calibrated, ``(s_v v(t − τ), s_ω ω(t − τ))``: the fit is then the
    noise left after that calibration."""
    if not (rate_hz > 0 and window_s > 0):
        raise ConfigError(
            f"fit_odometry_noise: need rate_hz > 0 and window_s > 0; got {rate_hz}, {window_s}"
        )
    dt = 1.0 / rate_hz
    steps = max(round(window_s * rate_hz), 1)
    n_windows = int((window.end_s - window.start_s) // (steps * dt))
    if n_windows < 2:
        raise window.too_little(
            f"robot {robot.subject}: fewer than two {window_s:g} s windows for the odometry fit"
        )
    t = window.start_s + dt * np.arange(n_windows * steps + 1)
    q = robot.groundtruth.at(t)
    v_cmd, w_cmd = robot.odometry.at(t[:-1] - latency_s)
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
    sigma = np.sqrt(np.mean(D * D, axis=0) / (dt * window_s))
    bias = D.mean(axis=0) / window_s
    return OdometryNoiseFit(
        sigma_v=float(sigma[0]),
        sigma_lateral=float(sigma[1]),
        sigma_w=float(sigma[2]),
        bias_v=float(bias[0]),
        bias_w=float(bias[2]),
        rate_hz=float(rate_hz),
        window_s=float(window_s),
        n_windows=int(ok.sum()),
        calibration_window=window,
    )
