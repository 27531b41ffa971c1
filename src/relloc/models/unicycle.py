"""Unicycle (planar ground robot) kinematics, pose layout ``(x, y, θ)``.

Continuous model: ẋ = v cos θ, ẏ = v sin θ, θ̇ = ω with inputs ``u = (v, ω)``.

Discretisation over ``dt`` uses the midpoint heading (second order, unbiased in θ for constant
inputs up to O(dt³)):

    θ_m = θ + ω dt / 2
    x⁺ = x + v dt cos θ_m,   y⁺ = y + v dt sin θ_m,   θ⁺ = θ + ω dt

Jacobians ``F = ∂x⁺/∂x`` and ``G = ∂x⁺/∂u`` are exact for this discrete map. All functions
accept a leading batch dimension: poses ``(..., 3)``, inputs ``(..., 2)``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]


def unicycle_step(pose: Array, u: Array, dt: float) -> Array:
    """One midpoint step of the unicycle; ``pose (..., 3)``, ``u (..., 2)``."""
    pose = np.asarray(pose, dtype=float)
    u = np.asarray(u, dtype=float)
    v, w = u[..., 0], u[..., 1]
    theta_m = pose[..., 2] + 0.5 * w * dt
    out = np.array(pose, copy=True)
    out[..., 0] = pose[..., 0] + v * dt * np.cos(theta_m)
    out[..., 1] = pose[..., 1] + v * dt * np.sin(theta_m)
    out[..., 2] = pose[..., 2] + w * dt
    return out


def unicycle_jacobians(pose: Array, u: Array, dt: float) -> tuple[Array, Array]:
    """Jacobians of :func:`unicycle_step`: ``F = ∂x⁺/∂x (…,3,3)``, ``G = ∂x⁺/∂u (…,3,2)``."""
    pose = np.asarray(pose, dtype=float)
    u = np.asarray(u, dtype=float)
    v, w = u[..., 0], u[..., 1]
    theta_m = pose[..., 2] + 0.5 * w * dt
    c, s = np.cos(theta_m), np.sin(theta_m)
    batch = pose.shape[:-1]
    F = np.broadcast_to(np.eye(3), (*batch, 3, 3)).copy()
    F[..., 0, 2] = -v * dt * s
    F[..., 1, 2] = v * dt * c
    G = np.zeros((*batch, 3, 2))
    G[..., 0, 0] = dt * c
    G[..., 1, 0] = dt * s
    G[..., 0, 1] = -0.5 * v * dt * dt * s
    G[..., 1, 1] = 0.5 * v * dt * dt * c
    G[..., 2, 1] = dt
    return F, G
