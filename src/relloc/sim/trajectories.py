"""True robot motion: body-velocity commands and their exact integration.

Each robot's motion is a sequence of body-velocity commands ``u_k = (v_x, v_y, v_z, ω_z)``
held over ``[t_k, t_k + Δt)`` at the propagation rate. The true pose is the *exact* integral of
that piecewise-constant body velocity (a circular arc in the plane for ω ≠ 0):

    ψ_{k+1} = ψ_k + ω Δt
    p_{k+1} = p_k + Rz(ψ_k) · M(ωΔt) · [v_x, v_y]ᵀ Δt,  z_{k+1} = z_k + v_z Δt,

    M(a) = [[sin a / a, −(1 − cos a)/a], [(1 − cos a)/a, sin a / a]]   (M(0) = I).

so a filter fed the noise-free commands propagates without model error beyond its own
discretisation. Way-point paths are periodic (or natural, if open) cubic splines through the
points, re-parametrised by arc length so the robot moves at constant speed; the command of step
``k`` is the path's speed and curvature-driven yaw rate at the step's midpoint time.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from scipy.interpolate import CubicSpline

from relloc.errors import ConfigError
from relloc.sim.scenario import RobotSpec, VelocityMotion, WaypointMotion

Array = NDArray[np.float64]

_ARC_SAMPLES_PER_SEGMENT = 400


def integrate_body_velocities(pose0: Array, commands: Array, dt: float) -> Array:
    """Exact poses ``(N+1, 4)`` from ``pose0 = (x, y, z, ψ)`` under held commands ``(N, 4)``."""
    commands = np.asarray(commands, dtype=float)
    n = commands.shape[0]
    a = commands[:, 3] * dt
    yaw = pose0[3] + np.concatenate([[0.0], np.cumsum(a)])
    sinc = np.sinc(a / np.pi)  # sin(a)/a
    half = 0.5 * a
    one_minus_cos_over_a = np.sin(half) * np.sinc(half / np.pi)  # (1 − cos a)/a
    vx, vy = commands[:, 0] * dt, commands[:, 1] * dt
    bx = sinc * vx - one_minus_cos_over_a * vy
    by = one_minus_cos_over_a * vx + sinc * vy
    c, s = np.cos(yaw[:-1]), np.sin(yaw[:-1])
    out = np.empty((n + 1, 4))
    out[0] = pose0
    out[1:, 0] = pose0[0] + np.cumsum(c * bx - s * by)
    out[1:, 1] = pose0[1] + np.cumsum(s * bx + c * by)
    out[1:, 2] = pose0[2] + np.cumsum(commands[:, 2] * dt)
    out[1:, 3] = yaw[1:]
    return out


class SplinePath:
    """A planar spline through way-points, evaluated by arc length ``s``."""

    def __init__(self, points: tuple[tuple[float, float], ...], *, closed: bool) -> None:
        pts = np.asarray(points, dtype=float)
        if closed:
            pts = np.vstack([pts, pts[:1]])
        chord = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(pts, axis=0), axis=1))])
        self._spline = CubicSpline(chord, pts, bc_type="periodic" if closed else "natural")
        self.closed = closed
        u = np.linspace(0.0, chord[-1], _ARC_SAMPLES_PER_SEGMENT * (len(pts) - 1) + 1)
        speed = np.linalg.norm(self._spline(u, 1), axis=1)
        # Arc length by the trapezoidal rule on a dense grid of the spline parameter.
        self._u = u
        self._s = np.concatenate([[0.0], np.cumsum(0.5 * (speed[1:] + speed[:-1]) * np.diff(u))])
        self.length = float(self._s[-1])

    def _param(self, s: Array) -> Array:
        s = np.mod(s, self.length) if self.closed else np.clip(s, 0.0, self.length)
        return np.interp(s, self._s, self._u)

    def position(self, s: Array) -> Array:
        return np.asarray(self._spline(self._param(s)))

    def heading_and_curvature(self, s: Array) -> tuple[Array, Array]:
        """Tangent heading atan2(y', x') and signed curvature (x'y'' − y'x'')/|p'|³."""
        u = self._param(s)
        d1 = self._spline(u, 1)
        d2 = self._spline(u, 2)
        heading = np.arctan2(d1[:, 1], d1[:, 0])
        norm = np.linalg.norm(d1, axis=1)
        with np.errstate(divide="ignore", invalid="ignore"):  # a cusp: NaN, named by simulate()
            curvature = (d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]) / norm**3
        return heading, curvature


def _waypoint_commands(
    spec: RobotSpec, motion: WaypointMotion, t: Array, dt: float
) -> tuple[Array, Array]:
    path = SplinePath(motion.points, closed=motion.closed)
    t_mid = t[:-1] + 0.5 * dt
    s_mid = motion.speed * t_mid
    moving = np.ones_like(t_mid) if motion.closed else (s_mid < path.length).astype(float)
    heading0, _ = path.heading_and_curvature(np.array([0.0]))
    heading_mid, curvature_mid = path.heading_and_curvature(s_mid)
    commands = np.zeros((t_mid.size, 4))
    if motion.heading == "tangent":
        commands[:, 0] = motion.speed * moving
        commands[:, 3] = motion.speed * curvature_mid * moving
        yaw0 = float(heading0[0])
    else:
        # Fixed yaw: the world-frame velocity along the path, expressed in the body frame.
        # Because ψ is constant, Rz(ψ)ᵀ v_world is exact over the step.
        yaw0 = motion.yaw_rad
        vw = motion.speed * moving
        vx_w, vy_w = vw * np.cos(heading_mid), vw * np.sin(heading_mid)
        c, s = np.cos(yaw0), np.sin(yaw0)
        commands[:, 0] = c * vx_w + s * vy_w
        commands[:, 1] = -s * vx_w + c * vy_w
    # Vertical oscillation: the held climb rate that reproduces z(t) exactly at the samples.
    z = spec.height + motion.z_amplitude * np.sin(2.0 * np.pi * t / motion.z_period_s)
    commands[:, 2] = np.diff(z) / dt
    start = path.position(np.array([0.0]))[0]
    pose0 = np.array([start[0], start[1], z[0], yaw0])
    return pose0, commands


def _velocity_commands(
    spec: RobotSpec, motion: VelocityMotion, t: Array, dt: float
) -> tuple[Array, Array]:
    t_mid = (t[:-1] + 0.5 * dt)[:, None]
    mean = np.asarray(motion.mean)
    amp = np.asarray(motion.amplitude)
    period = np.asarray(motion.period_s)
    phase = np.asarray(motion.phase_rad)
    commands = mean + amp * np.sin(2.0 * np.pi * t_mid / period + phase)
    if spec.initial_pose is None:  # RobotSpec validation already requires it
        raise ConfigError(f"{spec.name}.initial_pose: required with velocity commands")
    x0, y0, yaw0 = spec.initial_pose
    return np.array([x0, y0, spec.height, yaw0]), commands


def robot_motion(spec: RobotSpec, t: Array) -> tuple[Array, Array]:
    """True poses ``(N+1, 4)`` at times ``t`` and the held commands ``(N, 4)`` that produce them.

    ``t`` is the uniform propagation grid ``0, Δt, …, NΔt``.
    """
    dt = float(t[1] - t[0])
    motion = spec.motion
    if isinstance(motion, WaypointMotion):
        pose0, commands = _waypoint_commands(spec, motion, t, dt)
    else:
        pose0, commands = _velocity_commands(spec, motion, t, dt)
    return integrate_body_velocities(pose0, commands, dt), commands
