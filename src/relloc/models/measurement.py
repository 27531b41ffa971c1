"""Range / azimuth / elevation measurement of an observed robot and its pseudo-linear form.

Measurement ``z = (r, θ, α)`` of the relative position ``p = (x, y, z)`` of a ``RelPose4`` state
(seed 000 Eq. 2)::

    r = √(x² + y² + z²),   θ = atan2(y, x),   α = atan2(z, ρ),   ρ = √(x² + y²)

Jacobian ``H = ∂h/∂x`` (3 × 4, last column zero)::

    ∂r = [x, y, z]/r
    ∂θ = [−y, x, 0]/ρ²
    ∂α = [−x z/ρ, −y z/ρ, ρ]/r²

Pseudo-linear form (seed 000 Eq. 3). The rows of ``H_pmo(θ, α)`` are the orthonormal unit
vectors ``u_r, u_θ, u_α`` of the measured bearing::

    u_r = [cθ cα, sθ cα, sα],  u_θ = [−sθ, cθ, 0],  u_α = [−cθ sα, −sθ sα, cα]

so ``H_pmo p = [r, 0, 0]`` exactly for the true bearings, and the pseudo-measurement is
``y = [r̃, 0, 0]``. Its noise ``ν_pm = ỹ − H_pmo(θ̃, α̃) p`` depends on the state. Linearised in
the sensor noise ``(ν_r, ν_θ, ν_α)`` it is ``ν_pm ≈ J [ν_r, ν_θ, ν_α]ᵀ`` with (``a = u_θ·p``,
``b = x cθ + y sθ``)::

    J = [[1, −cα a,  sα b − z cα],
         [0,  b,     0          ],
         [0,  sα a,  cα b + z sα]]

and covariance ``R_pmo = J Σ Jᵀ`` (seed 000 Eqs. 4–5; the paper prints ``JᵀΣJ``, which has the
wrong shape convention). At the true position ``a = 0``, ``b = ρ``, ``cα b + z sα = r`` and
``sα b − z cα = 0`` so ``J = diag(1, ρ, r)`` and ``R_pmo`` reduces to the simplified,
state-dependent form of seed 000 Eq. 6, ``diag(σ_r², ρ² σ_θ², r² σ_α²)``. Both forms are
evaluated at the filter's position estimate (the truth is unknown); the full form also uses the
measured bearings. All functions accept a leading batch dimension.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from relloc.core.checks import positive
from relloc.errors import ConfigError

Array = NDArray[np.float64]

MEASUREMENT_NAMES: tuple[str, str, str] = ("range", "azimuth", "elevation")
PseudoLinearCovariance = Literal["simplified", "full"]
PSEUDO_LINEAR_COVARIANCES: tuple[str, ...] = ("simplified", "full")


@dataclass(frozen=True, kw_only=True)
class RangeBearingNoise:
    """Sensor noise standard deviations: range ``sigma_r`` (m), azimuth and elevation (rad).

    Each a finite number > 0 (a string, ``None`` or a bool is a ConfigError naming the field).
    Seed 000 Table 2: precise ``(0.0068, 0.0036, 0.0036)``, noisy ``(0.1466, 0.1, 0.1)``.
    """

    sigma_r: float
    sigma_azimuth: float
    sigma_elevation: float

    def __post_init__(self) -> None:
        for name in ("sigma_r", "sigma_azimuth", "sigma_elevation"):
            value = positive(getattr(self, name), f"RangeBearingNoise.{name}")
            object.__setattr__(self, name, value)

    @property
    def variances(self) -> Array:
        """``(σ_r², σ_θ², σ_α²)``."""
        return np.square(np.array([self.sigma_r, self.sigma_azimuth, self.sigma_elevation]))

    @property
    def covariance(self) -> Array:
        """``Σ = diag(σ_r², σ_θ², σ_α²)`` of the raw measurement."""
        return np.diag(self.variances)


def range_bearing(x: ArrayLike) -> Array:
    """``h(x) = (r, θ, α)`` for states ``(..., 4)`` (or positions ``(..., 3)``)."""
    x = np.asarray(x, dtype=float)
    px, py, pz = x[..., 0], x[..., 1], x[..., 2]
    rho = np.hypot(px, py)
    return np.stack([np.sqrt(rho * rho + pz * pz), np.arctan2(py, px), np.arctan2(pz, rho)], -1)


def range_bearing_jacobian(x: ArrayLike) -> Array:
    """``H = ∂h/∂x`` with shape ``(..., 3, 4)``; singular at ``ρ = 0`` (robot straight above)."""
    x = np.asarray(x, dtype=float)
    px, py, pz = x[..., 0], x[..., 1], x[..., 2]
    rho2 = px * px + py * py
    rho = np.sqrt(rho2)
    r2 = rho2 + pz * pz
    r = np.sqrt(r2)
    H = np.zeros((*x.shape[:-1], 3, 4))
    H[..., 0, 0] = px / r
    H[..., 0, 1] = py / r
    H[..., 0, 2] = pz / r
    H[..., 1, 0] = -py / rho2
    H[..., 1, 1] = px / rho2
    H[..., 2, 0] = -px * pz / (rho * r2)
    H[..., 2, 1] = -py * pz / (rho * r2)
    H[..., 2, 2] = rho / r2
    return H


def pseudo_linear_matrix(z: ArrayLike) -> Array:
    """``H_pmo(θ, α)`` (seed 000 Eq. 3) from measured bearings; shape ``(..., 3, 4)``."""
    z = np.asarray(z, dtype=float)
    ct, st = np.cos(z[..., 1]), np.sin(z[..., 1])
    ca, sa = np.cos(z[..., 2]), np.sin(z[..., 2])
    H = np.zeros((*z.shape[:-1], 3, 4))
    H[..., 0, 0] = ct * ca
    H[..., 0, 1] = st * ca
    H[..., 0, 2] = sa
    H[..., 1, 0] = -st
    H[..., 1, 1] = ct
    H[..., 2, 0] = -ct * sa
    H[..., 2, 1] = -st * sa
    H[..., 2, 2] = ca
    return H


def pseudo_linear_measurement(z: ArrayLike) -> Array:
    """The pseudo-measurement ``y = [r̃, 0, 0]`` for measurements ``(..., 3)``."""
    z = np.asarray(z, dtype=float)
    y = np.zeros(z.shape)
    y[..., 0] = z[..., 0]
    return y


def pseudo_linear_noise_jacobian(x: ArrayLike, z: ArrayLike) -> Array:
    """``J = ∂ν_pm/∂(r, θ, α)`` at position ``x`` and measured bearings ``z``; ``(..., 3, 3)``."""
    x = np.asarray(x, dtype=float)
    z = np.asarray(z, dtype=float)
    ct, st = np.cos(z[..., 1]), np.sin(z[..., 1])
    ca, sa = np.cos(z[..., 2]), np.sin(z[..., 2])
    px, py, pz = x[..., 0], x[..., 1], x[..., 2]
    a = -px * st + py * ct
    b = px * ct + py * st
    J = np.zeros((*np.broadcast_shapes(x.shape[:-1], z.shape[:-1]), 3, 3))
    J[..., 0, 0] = 1.0
    J[..., 0, 1] = -ca * a
    J[..., 0, 2] = sa * b - pz * ca
    J[..., 1, 1] = b
    J[..., 2, 1] = sa * a
    J[..., 2, 2] = ca * b + pz * sa
    return J


def pseudo_linear_covariance(
    x: ArrayLike,
    z: ArrayLike,
    noise: RangeBearingNoise,
    kind: PseudoLinearCovariance = "simplified",
) -> Array:
    """``R_pmo`` at state estimate ``x``: ``"simplified"`` (Eq. 6) or ``"full"`` (``J Σ Jᵀ``)."""
    x = np.asarray(x, dtype=float)
    var = noise.variances
    if kind == "simplified":
        rho2 = x[..., 0] ** 2 + x[..., 1] ** 2
        r2 = rho2 + x[..., 2] ** 2
        R = np.zeros((*x.shape[:-1], 3, 3))
        R[..., 0, 0] = var[0]
        R[..., 1, 1] = rho2 * var[1]
        R[..., 2, 2] = r2 * var[2]
        return R
    if kind == "full":
        J = pseudo_linear_noise_jacobian(x, z)
        return (J * var) @ np.swapaxes(J, -1, -2)
    raise ConfigError(
        f"pseudo-linear covariance: kind must be one of {PSEUDO_LINEAR_COVARIANCES}, got {kind!r}"
    )
