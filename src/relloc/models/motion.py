"""4-DOF relative motion model of an observed robot in an observing robot's body frame.

State layout ``RelPose4 = (x, y, z, φ)``: position of the observed robot *c* expressed in the
body frame of the observing robot *l*, and relative yaw ``φ = ψ_c − ψ_l``. Inputs are the body
velocities of both robots, ``u = (v_x, v_y, v_z, ω_z)`` (hovering aerial robots and ground
robots: roll and pitch are held level, seed 000 §3.1 assumption 6).

Continuous model (seed 000 Eq. 1, derived from ``p = R(ψ_l)ᵀ (p_c − p_l)``; the paper's last
row has a typo and must read ``ω_c − ω_l``)::

    ẋ = v_xc cos φ − v_yc sin φ − v_xl + ω_l y
    ẏ = v_xc sin φ + v_yc cos φ − v_yl − ω_l x
    ż = v_zc − v_zl
    φ̇ = ω_c − ω_l

Discretisation (exact for inputs held constant over ``dt``, i.e. zero-order hold). Each robot
moves on a circular arc; ``∫₀^dt R(ωs) ds = dt·sinc(ω dt/2)·R(ω dt/2)`` with
``sinc(a) = sin(a)/a``. In the observer's frame at the start of the step, with ``R(·)`` the planar
rotation and all vectors the (x, y) parts::

    d_c = dt · sinc(ω_c dt/2) · R(φ + ω_c dt/2) v_c          (observed robot's displacement)
    d_l = dt · sinc(ω_l dt/2) · R(ω_l dt/2) v_l              (observer's displacement)
    p⁺  = R(−ω_l dt) (p + d_c − d_l)
    z⁺  = z + dt (v_zc − v_zl)
    φ⁺  = φ + dt (ω_c − ω_l)

This is the midpoint (second-order) rule times the ``sinc`` arc-length factor, so it carries
none of the ``ω·dt/2`` heading lag a forward-Euler step has. Jacobians ``F = ∂x⁺/∂x`` and
``G = ∂x⁺/∂[u_l, u_c]`` are exact for this map; ``Q = G Σ_u Gᵀ`` propagates the odometry
(body-velocity) noise. Every function accepts a leading batch dimension: states ``(..., 4)``,
inputs ``(..., 4)``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from relloc.core.checks import number, sequence, time_step
from relloc.errors import ConfigError

Array = NDArray[np.float64]

#: Names of the ``RelPose4`` state entries and of the body-velocity inputs, in order.
STATE_NAMES: tuple[str, str, str, str] = ("x", "y", "z", "phi")
INPUT_NAMES: tuple[str, str, str, str] = ("v_x", "v_y", "v_z", "omega_z")

#: Below this |a| the series of sinc and its derivative are used (relative truncation error
#: below 2e-19 for sinc and 4e-15 for its derivative).
SINC_SERIES_LIMIT = 1e-3


@dataclass(frozen=True, kw_only=True)
class VelocityNoise:
    """Standard deviations of the body-velocity (odometry) noise of both robots.

    ``observer`` and ``observed`` are ``(σ_vx, σ_vy, σ_vz, σ_ω)`` in m/s and rad/s. The noise is
    white and held constant over one propagation step, so ``Σ_u = diag(observer², observed²)``.
    """

    observer: tuple[float, float, float, float]
    observed: tuple[float, float, float, float]

    def __post_init__(self) -> None:
        for name in ("observer", "observed"):
            given = getattr(self, name)
            if isinstance(given, str) or np.ndim(given) != 1 or len(given) != 4:
                raise ConfigError(f"VelocityNoise.{name}: needs 4 sigmas {INPUT_NAMES}")
            values = tuple(number(v, f"VelocityNoise.{name}", low=0.0) for v in given)
            object.__setattr__(self, name, values)

    @classmethod
    def of(cls, observer: ArrayLike, observed: ArrayLike) -> VelocityNoise:
        """From any four-element sequences or 1-D arrays (an odometry's stated ``sigma``);
        anything else (a string, ``None``, a scalar, a 2-D array) is a ConfigError naming it."""
        what = f"4 sigmas {INPUT_NAMES}"
        return cls(
            observer=tuple(sequence(observer, "VelocityNoise.observer", what, length=4)),  # type: ignore[arg-type]
            observed=tuple(sequence(observed, "VelocityNoise.observed", what, length=4)),  # type: ignore[arg-type]
        )

    @property
    def covariance(self) -> Array:
        """``Σ_u`` (8 × 8) ordered as ``[u_l, u_c]``."""
        return np.diag(np.square(np.array(self.observer + self.observed)))


def _rot(angle: Array) -> Array:
    """Planar rotation matrices ``R(angle)`` with shape ``(..., 2, 2)``."""
    c, s = np.cos(angle), np.sin(angle)
    return np.stack([np.stack([c, -s], axis=-1), np.stack([s, c], axis=-1)], axis=-2)


def sinc_and_derivative(a: ArrayLike) -> tuple[Array, Array]:
    """``sinc(a) = sin(a)/a`` and ``d sinc/da = (a cos a − sin a)/a²``, series near 0."""
    a = np.asarray(a, dtype=float)
    small = np.abs(a) < SINC_SERIES_LIMIT
    safe = np.where(small, 1.0, a)
    a2 = a * a
    sinc = np.where(small, 1.0 - a2 / 6.0 + a2 * a2 / 120.0, np.sin(safe) / safe)
    dsinc = np.where(
        small,
        -a / 3.0 + a * a2 / 30.0,
        (safe * np.cos(safe) - np.sin(safe)) / (safe * safe),
    )
    return sinc, dsinc


def _mv(M: Array, v: Array) -> Array:
    """Batched matrix–vector product ``M v`` for ``(..., 2, 2) × (..., 2)``."""
    return np.einsum("...ij,...j->...i", M, v)


def relative_derivative(x: ArrayLike, u_l: ArrayLike, u_c: ArrayLike) -> Array:
    """Continuous-time ``ẋ = f(x, u_l, u_c)`` of seed 000 Eq. 1 (with ``φ̇ = ω_c − ω_l``)."""
    x = np.asarray(x, dtype=float)
    u_l = np.asarray(u_l, dtype=float)
    u_c = np.asarray(u_c, dtype=float)
    c, s = np.cos(x[..., 3]), np.sin(x[..., 3])
    w_l = u_l[..., 3]
    return np.stack(
        [
            u_c[..., 0] * c - u_c[..., 1] * s - u_l[..., 0] + w_l * x[..., 1],
            u_c[..., 0] * s + u_c[..., 1] * c - u_l[..., 1] - w_l * x[..., 0],
            u_c[..., 2] - u_l[..., 2],
            u_c[..., 3] - u_l[..., 3],
        ],
        axis=-1,
    )


def relative_step(x: ArrayLike, u_l: ArrayLike, u_c: ArrayLike, dt: float) -> Array:
    """Exact zero-order-hold step ``x⁺ = f_d(x, u_l, u_c, dt)`` (see module docstring)."""
    dt = time_step(dt, "relative motion")
    x = np.asarray(x, dtype=float)
    u_l = np.asarray(u_l, dtype=float)
    u_c = np.asarray(u_c, dtype=float)
    x, u_l, u_c = np.broadcast_arrays(x, u_l, u_c)
    w_l, w_c = u_l[..., 3], u_c[..., 3]
    sinc_l, _ = sinc_and_derivative(0.5 * w_l * dt)
    sinc_c, _ = sinc_and_derivative(0.5 * w_c * dt)
    d_c = (dt * sinc_c)[..., None] * _mv(_rot(x[..., 3] + 0.5 * w_c * dt), u_c[..., :2])
    d_l = (dt * sinc_l)[..., None] * _mv(_rot(0.5 * w_l * dt), u_l[..., :2])
    out = np.empty_like(x)
    out[..., :2] = _mv(_rot(-w_l * dt), x[..., :2] + d_c - d_l)
    out[..., 2] = x[..., 2] + dt * (u_c[..., 2] - u_l[..., 2])
    out[..., 3] = x[..., 3] + dt * (w_c - w_l)
    return out


def relative_jacobians(
    x: ArrayLike, u_l: ArrayLike, u_c: ArrayLike, dt: float
) -> tuple[Array, Array]:
    """Exact Jacobians of :func:`relative_step`.

    Returns ``F = ∂x⁺/∂x`` with shape ``(..., 4, 4)`` and ``G = ∂x⁺/∂[u_l, u_c]`` with shape
    ``(..., 4, 8)`` (columns ``v_xl, v_yl, v_zl, ω_l, v_xc, v_yc, v_zc, ω_c``). With
    ``J = [[0, −1], [1, 0]]`` (so ``dR(a)/da = J R(a)``) and ``R_l = R(−ω_l dt)``::

        ∂p⁺/∂p = R_l,                         ∂p⁺/∂φ = R_l J d_c
        ∂p⁺/∂v_l = −dt sinc_l R_l R(ω_l dt/2), ∂p⁺/∂v_c = dt sinc_c R_l R(φ + ω_c dt/2)
        ∂p⁺/∂ω_l = −dt J p⁺ − R_l (dt²/2)(sinc'_l I + sinc_l J) R(ω_l dt/2) v_l
        ∂p⁺/∂ω_c = R_l (dt²/2)(sinc'_c I + sinc_c J) R(φ + ω_c dt/2) v_c
    """
    dt = time_step(dt, "relative motion")
    x = np.asarray(x, dtype=float)
    u_l = np.asarray(u_l, dtype=float)
    u_c = np.asarray(u_c, dtype=float)
    x, u_l, u_c = np.broadcast_arrays(x, u_l, u_c)
    batch = x.shape[:-1]
    w_l, w_c = u_l[..., 3], u_c[..., 3]
    sinc_l, dsinc_l = sinc_and_derivative(0.5 * w_l * dt)
    sinc_c, dsinc_c = sinc_and_derivative(0.5 * w_c * dt)
    R_lstep = _rot(-w_l * dt)
    Rv_c = _mv(_rot(x[..., 3] + 0.5 * w_c * dt), u_c[..., :2])  # R(φ + ω_c dt/2) v_c
    Rv_l = _mv(_rot(0.5 * w_l * dt), u_l[..., :2])  # R(ω_l dt/2) v_l
    d_c = (dt * sinc_c)[..., None] * Rv_c
    d_l = (dt * sinc_l)[..., None] * Rv_l
    p_next = _mv(R_lstep, x[..., :2] + d_c - d_l)

    def perp(v: Array) -> Array:  # J v
        return np.stack([-v[..., 1], v[..., 0]], axis=-1)

    F = np.zeros((*batch, 4, 4))
    F[..., :2, :2] = R_lstep
    F[..., :2, 3] = _mv(R_lstep, perp(d_c))
    F[..., 2, 2] = 1.0
    F[..., 3, 3] = 1.0

    half_dt2 = 0.5 * dt * dt
    G = np.zeros((*batch, 4, 8))
    # observer inputs
    G[..., :2, :2] = -(dt * sinc_l)[..., None, None] * (R_lstep @ _rot(0.5 * w_l * dt))
    G[..., 2, 2] = -dt
    dd_l = half_dt2 * (dsinc_l[..., None] * Rv_l + sinc_l[..., None] * perp(Rv_l))
    G[..., :2, 3] = -dt * perp(p_next) - _mv(R_lstep, dd_l)
    G[..., 3, 3] = -dt
    # observed inputs
    G[..., :2, 4:6] = (dt * sinc_c)[..., None, None] * (R_lstep @ _rot(x[..., 3] + 0.5 * w_c * dt))
    G[..., 2, 6] = dt
    dd_c = half_dt2 * (dsinc_c[..., None] * Rv_c + sinc_c[..., None] * perp(Rv_c))
    G[..., :2, 7] = _mv(R_lstep, dd_c)
    G[..., 3, 7] = dt
    return F, G


def process_noise(G: Array, noise: VelocityNoise) -> Array:
    """Discrete process noise ``Q = G Σ_u Gᵀ`` (``G`` from :func:`relative_jacobians`)."""
    G = np.asarray(G, dtype=float)
    var = np.square(np.array(noise.observer + noise.observed))
    Q = (G * var) @ np.swapaxes(G, -1, -2)
    return 0.5 * (Q + np.swapaxes(Q, -1, -2))
