"""Air-ground team models of Güler, Yıldırım & Alabay (seed 003).

**Follower relative model (Eq. 3).** Follower ``R_i`` tracks the state
``x = [r_x, r_y, θ_i, θ_0]`` where ``r = p_0 − p_i`` is the leader's position relative to the
follower *in the common frame* ``F_G`` (the drones' fixed heading ψ̄ defines its x-axis), θ_i its
own heading and θ_0 the leader's, with inputs ``u = [v_i, ω_i, v_0, ω_0]`` (both robots' unicycle
commands, Eqs. 1–2; the leader broadcasts its own). The paper writes the Euler step; like
:mod:`relloc.models.unicycle` we use the midpoint heading, which has no yaw bias under turning::

    θ̄_i = θ_i + ω_i T/2,   θ̄_0 = θ_0 + ω_0 T/2
    r⁺ = r + T [v_0 cos θ̄_0 − v_i cos θ̄_i,  v_0 sin θ̄_0 − v_i sin θ̄_i]
    θ_i⁺ = θ_i + ω_i T,     θ_0⁺ = θ_0 + ω_0 T

**Measurements (Eq. 4).** ``d = ‖r‖`` (UWB), bearing ``φ = atan2(r_y, r_x)`` (from R_i toward R_0,
measured by a drone, or derived from the triangle of Fig. 3 — :mod:`relloc.geometry.triangle`),
headings θ_i and θ_0 (drone camera). The three switching modes stack them as
``sw=1: [d, φ, θ_i, θ_0]``, ``sw=2: [d, φ̄, θ_0]``, ``sw=3: [d]``; the components are also exposed
one by one so the filter can update block by block (multi-rate).

**Drone kinematics.** A drone holds a constant heading ψ̄ (so its body x–y plane *is* F_G) and
is moved on the plane by a saturated proportional controller with an optional velocity
feed-forward: ``ṗ_d = sat_{v_max}(v_ff + k_p (p_cmd − p_d))``.
"""

from __future__ import annotations

from enum import IntEnum

import numpy as np
from numpy.typing import NDArray

from relloc.errors import ConfigError, DataError

Array = NDArray[np.float64]

#: State layout of a follower's relative filter.
RX, RY, TH_I, TH_0 = 0, 1, 2, 3
STATE_DIM = 4


class Mode(IntEnum):
    """Measurement mode ``sw`` of Eq. 4."""

    PAIR_SEEN = 1  # {R_0, R_i} detected: d, φ, θ_i, θ_0
    OTHER_PAIR_SEEN = 2  # another pair detected: d, triangle bearing φ̄, θ_0
    NONE_SEEN = 3  # no pair detected: d only


def relative_step(x: Array, u: Array, dt: float) -> Array:
    """Midpoint discretisation of Eq. 3; ``x (..., 4)``, ``u (..., 4) = [v_i, ω_i, v_0, ω_0]``."""
    x = np.asarray(x, dtype=float)
    u = np.asarray(u, dtype=float)
    vi, wi, v0, w0 = u[..., 0], u[..., 1], u[..., 2], u[..., 3]
    ti = x[..., TH_I] + 0.5 * wi * dt
    t0 = x[..., TH_0] + 0.5 * w0 * dt
    out = np.array(x, copy=True)
    out[..., RX] = x[..., RX] + dt * (v0 * np.cos(t0) - vi * np.cos(ti))
    out[..., RY] = x[..., RY] + dt * (v0 * np.sin(t0) - vi * np.sin(ti))
    out[..., TH_I] = x[..., TH_I] + wi * dt
    out[..., TH_0] = x[..., TH_0] + w0 * dt
    return out


def relative_jacobians(x: Array, u: Array, dt: float) -> tuple[Array, Array]:
    """Exact Jacobians of :func:`relative_step`: ``F = ∂x⁺/∂x`` and ``G = ∂x⁺/∂u`` (4×4 each)."""
    x = np.asarray(x, dtype=float)
    u = np.asarray(u, dtype=float)
    vi, wi, v0, w0 = u[..., 0], u[..., 1], u[..., 2], u[..., 3]
    ti = x[..., TH_I] + 0.5 * wi * dt
    t0 = x[..., TH_0] + 0.5 * w0 * dt
    ci, si, c0, s0 = np.cos(ti), np.sin(ti), np.cos(t0), np.sin(t0)
    batch = x.shape[:-1]
    F = np.broadcast_to(np.eye(STATE_DIM), (*batch, 4, 4)).copy()
    F[..., RX, TH_I] = dt * vi * si
    F[..., RY, TH_I] = -dt * vi * ci
    F[..., RX, TH_0] = -dt * v0 * s0
    F[..., RY, TH_0] = dt * v0 * c0
    G = np.zeros((*batch, 4, 4))
    G[..., RX, 0] = -dt * ci
    G[..., RY, 0] = -dt * si
    G[..., RX, 1] = 0.5 * dt * dt * vi * si
    G[..., RY, 1] = -0.5 * dt * dt * vi * ci
    G[..., RX, 2] = dt * c0
    G[..., RY, 2] = dt * s0
    G[..., RX, 3] = -0.5 * dt * dt * v0 * s0
    G[..., RY, 3] = 0.5 * dt * dt * v0 * c0
    G[..., TH_I, 1] = dt
    G[..., TH_0, 3] = dt
    return F, G


def process_noise(
    x: Array, u: Array, dt: float, sigma_v: float, sigma_w: float
) -> tuple[Array, Array]:
    """``(F, Q)`` with ``Q = G diag(σ_v², σ_ω², σ_v², σ_ω²) Gᵀ`` (input noise on both robots)."""
    F, G = relative_jacobians(x, u, dt)
    S = np.diag([sigma_v**2, sigma_w**2, sigma_v**2, sigma_w**2])
    return F, G @ S @ np.swapaxes(G, -1, -2)


def range_h(x: Array) -> tuple[float, Array]:
    """UWB range ``d = ‖r‖`` and its 1×4 Jacobian ``[r_x/d, r_y/d, 0, 0]``."""
    d = float(np.hypot(x[RX], x[RY]))
    H = np.zeros((1, STATE_DIM))
    if d > 0.0:
        H[0, RX], H[0, RY] = x[RX] / d, x[RY] / d
    return d, H


def bearing_h(x: Array) -> tuple[float, Array]:
    """Bearing ``φ = atan2(r_y, r_x)`` and its 1×4 Jacobian ``[−r_y/d², r_x/d², 0, 0]``."""
    d2 = float(x[RX] ** 2 + x[RY] ** 2)
    H = np.zeros((1, STATE_DIM))
    if d2 > 0.0:
        H[0, RX], H[0, RY] = -x[RY] / d2, x[RX] / d2
    return float(np.arctan2(x[RY], x[RX])), H


def heading_h(x: Array, index: int) -> tuple[float, Array]:
    """Heading state ``x[index]`` (θ_i or θ_0) and its 1×4 selector Jacobian."""
    H = np.zeros((1, STATE_DIM))
    H[0, index] = 1.0
    return float(x[index]), H


def mode_measurement(x: Array, mode: Mode) -> tuple[Array, Array, tuple[bool, ...]]:
    """Stacked Eq. 4 for one mode: ``(h(x), H, is_angle)`` with components in paper order.
    ``mode`` must be a :class:`Mode` (a plain ``1`` would not be ``Mode.PAIR_SEEN``): ConfigError
    otherwise; ``x`` a finite state of shape (4,): DataError otherwise."""
    if not isinstance(mode, Mode):
        raise ConfigError(f"mode_measurement: mode must be a Mode, got {mode!r:.40}")
    try:
        finite = np.shape(x) == (STATE_DIM,) and bool(np.isfinite(np.asarray(x, float)).all())
    except (TypeError, ValueError):  # strings
        finite = False
    if not finite:
        raise DataError(f"mode_measurement: x must be a finite state (4,), got {x!r:.60}")
    parts = [range_h(x)]
    angles: tuple[bool, ...]
    if mode is Mode.PAIR_SEEN:
        parts += [bearing_h(x), heading_h(x, TH_I), heading_h(x, TH_0)]
        angles = (False, True, True, True)
    elif mode is Mode.OTHER_PAIR_SEEN:
        parts += [bearing_h(x), heading_h(x, TH_0)]
        angles = (False, True, True)
    else:
        angles = (False,)
    z = np.array([p[0] for p in parts])
    H = np.vstack([p[1] for p in parts])
    return z, H, angles


def drone_velocity(
    position: Array,
    command: Array,
    *,
    gain: float,
    v_max: float,
    feedforward: Array | None = None,
) -> Array:
    """The planar drone's saturated P controller: ``v = sat_{v_max}(v_ff + k_p (p_cmd − p))``
    (what the drone commands; :func:`drone_step` also moves it)."""
    p = np.asarray(position, dtype=float)
    v = gain * (np.asarray(command, dtype=float) - p)
    if feedforward is not None:
        v = v + np.asarray(feedforward, dtype=float)
    speed = float(np.hypot(v[0], v[1]))
    if speed > v_max > 0.0:
        v = v * (v_max / speed)
    return v


def drone_step(
    position: Array,
    command: Array,
    dt: float,
    *,
    gain: float,
    v_max: float,
    feedforward: Array | None = None,
) -> tuple[Array, Array]:
    """One step of the planar drone with constant heading and a saturated P controller.

    ``v`` of :func:`drone_velocity`, ``p⁺ = p + v dt``. Returns ``(p⁺, v)``.
    """
    v = drone_velocity(position, command, gain=gain, v_max=v_max, feedforward=feedforward)
    return np.asarray(position, dtype=float) + v * dt, v
