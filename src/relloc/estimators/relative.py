"""Relative-pose filters for one observer–observed pair: shared predict, TEKF and PLKF updates.

State ``RelPose4 = (x, y, z, φ)`` (see :mod:`relloc.models.motion`), measurement
``z = (r, θ, α)`` (see :mod:`relloc.models.measurement`). Both filters share one predict
(seed 000 Eq. 7, with the exact zero-order-hold discretisation)::

    x⁻ = f_d(x, u_l, u_c, dt),   P⁻ = F P Fᵀ + G Σ_u Gᵀ

and differ only in the update (seed 000 Eq. 8), computed in Joseph form::

    S = H P⁻ Hᵀ + R,   K = P⁻ Hᵀ S⁻¹,   x⁺ = x⁻ + K ν,   P⁺ = (I − KH) P⁻ (I − KH)ᵀ + K R Kᵀ

* TEKF ("traditional EKF"): ``H = ∂h/∂x`` at ``x⁻``, ``ν = z − h(x⁻)`` with the azimuth
  (and elevation) residual wrapped to [−π, π), ``R = diag(σ_r², σ_θ², σ_α²)``.
* PLKF (pseudo-linear KF, seed 000 §3.3): ``H = H_pmo(θ̃, α̃)`` from the *measured* bearings,
  ``ν = [r̃, 0, 0] − H x⁻``, ``R = R_pmo`` (Eq. 6 simplified, or the full ``J Σ Jᵀ`` of Eqs. 4–5).
* Bias-compensated PLKF (``update_plkf_bc``): the measured bearings inside ``H`` correlate the
  gain with the pseudo-linear noise, and the pseudo-linear noise itself has a non-zero mean
  (``u_r(θ̃, α̃)·p = r cos γ < r`` for a bearing error ``γ``), so ``E[K ν_pm] ≠ 0`` and the
  plain PLKF pushes the estimate outwards (range over-estimated). Following the
  bias-compensated pseudolinear estimator of Doğançay (IEEE Trans. Signal Process. 54(1),
  2006) and its Kalman-filter form, the BC-PLKF of Nguyen & Doğançay ("Improved pseudolinear
  Kalman filter algorithms for bearing-only target tracking", IEEE Trans. Signal Process.
  65(23), 2017), the update subtracts an estimate of the bias it injects::

      x⁺_BC = x⁺ − b̂,   b̂ = E_ν[ K(ẑ + ν) · ([r̂ + ν_r, 0, 0] − H_pmo(θ̂ + ν_θ, α̂ + ν_α) p̂⁺) ]

  evaluated at the uncompensated estimate ``p̂⁺`` (``ẑ = h(p̂⁺)``). Nguyen & Doğançay write the
  expectation in closed form for 2-D bearings; here it is evaluated, for the 3-D range and
  bearing sensor, with the third-degree spherical cubature rule (6 points ``±√3 σ`` along each
  noise axis, Arasaratnam & Haykin 2009), which is exact for the second-order terms that make
  up the bias. The covariance is the plain PLKF's.

Every array function broadcasts over a leading batch dimension (``mean (..., 4)``,
``cov (..., 4, 4)``, ``z (..., 3)``) so many pairs update in one numpy call; the
:class:`~relloc.core.Gaussian` wrappers are the single-pair API.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from relloc.core.angles import wrap_angle
from relloc.core.gaussian import Gaussian
from relloc.errors import ConfigError, DataError, ModelError
from relloc.models.measurement import (
    PSEUDO_LINEAR_COVARIANCES,
    PseudoLinearCovariance,
    RangeBearingNoise,
    pseudo_linear_covariance,
    pseudo_linear_matrix,
    pseudo_linear_measurement,
    range_bearing,
    range_bearing_jacobian,
)
from relloc.models.motion import (
    VelocityNoise,
    process_noise,
    relative_jacobians,
    relative_step,
)

Array = NDArray[np.float64]
UpdateKind = Literal["plkf", "plkf_bc", "tekf"]
UPDATE_KINDS: tuple[str, ...] = ("plkf", "plkf_bc", "tekf")


@dataclass(frozen=True)
class Innovation:
    """What an update saw: residual ``ν (..., m)``, its covariance ``S``, ``nis = νᵀS⁻¹ν``, and
    the measurement covariance ``R`` used (for conditioning checks, seed 000 §7.3).

    For a single pair ``nis`` is a float; for a batch it is an array ``(...,)``.
    """

    residual: Array
    cov: Array
    nis: float | Array
    meas_cov: Array


def _swap(M: Array) -> Array:
    return np.swapaxes(M, -1, -2)


def _check_finite(name: str, value: ArrayLike, last: int, where: str) -> Array:
    arr = np.asarray(value, dtype=float)
    if arr.ndim == 0 or arr.shape[-1] != last:
        raise DataError(f"{where or 'relative filter'}: {name} must have last dimension {last}")
    if not np.all(np.isfinite(arr)):
        raise DataError(f"{where or 'relative filter'}: {name} contains NaN or inf: {arr}")
    return arr


def kalman_update(
    mean: Array, cov: Array, residual: Array, H: Array, R: Array, *, where: str = ""
) -> tuple[Array, Array, Innovation]:
    """Batched Joseph-form Kalman update given ``ν``, ``H`` and ``R`` (shared by every update).

    Raises :class:`ModelError` naming ``where`` if some ``S`` cannot be factorised.
    """
    PHt = cov @ _swap(H)
    S = H @ PHt + R
    S = 0.5 * (S + _swap(S))
    try:
        L = np.linalg.cholesky(S)
    except np.linalg.LinAlgError as exc:
        raise ModelError(
            f"innovation covariance is not positive definite{' at ' + where if where else ''}"
        ) from exc
    # K = P Hᵀ S⁻¹ via the Cholesky factor: S⁻¹ = L⁻ᵀ L⁻¹
    eye = np.broadcast_to(np.eye(S.shape[-1]), S.shape)
    L_inv = np.linalg.solve(L, eye)
    S_inv = _swap(L_inv) @ L_inv
    K = PHt @ S_inv
    w = np.einsum("...ij,...j->...i", L_inv, residual)
    nis = np.einsum("...i,...i->...", w, w)
    new_mean = mean + np.einsum("...ij,...j->...i", K, residual)
    A = np.eye(cov.shape[-1]) - K @ H
    new_cov = A @ cov @ _swap(A) + K @ R @ _swap(K)
    new_cov = 0.5 * (new_cov + _swap(new_cov))
    return new_mean, new_cov, Innovation(residual=residual, cov=S, nis=nis, meas_cov=R)


# --------------------------------------------------------------------------- array (batched) API


def predict_arrays(
    mean: ArrayLike,
    cov: ArrayLike,
    u_l: ArrayLike,
    u_c: ArrayLike,
    dt: float,
    noise: VelocityNoise,
    *,
    where: str = "",
) -> tuple[Array, Array]:
    """Shared predict ``x⁻ = f_d(x, u)``, ``P⁻ = F P Fᵀ + G Σ_u Gᵀ`` (batched)."""
    mean = _check_finite("mean", mean, 4, where)
    cov = np.asarray(cov, dtype=float)
    u_l = _check_finite("observer input u_l", u_l, 4, where)
    u_c = _check_finite("observed input u_c", u_c, 4, where)
    F, G = relative_jacobians(mean, u_l, u_c, dt)
    new_cov = F @ cov @ _swap(F) + process_noise(G, noise)
    return relative_step(mean, u_l, u_c, dt), 0.5 * (new_cov + _swap(new_cov))


def _check_measurement(z: ArrayLike, where: str) -> Array:
    z = _check_finite("measurement z", z, 3, where)
    if np.any(z[..., 0] <= 0.0):
        raise DataError(f"{where or 'relative filter'}: measured range must be > 0: {z}")
    return z


def update_tekf_arrays(
    mean: ArrayLike, cov: ArrayLike, z: ArrayLike, noise: RangeBearingNoise, *, where: str = ""
) -> tuple[Array, Array, Innovation]:
    """TEKF update with ``h(x) = (r, θ, α)`` linearised at the prior (batched)."""
    mean = _check_finite("mean", mean, 4, where)
    cov = np.asarray(cov, dtype=float)
    z = _check_measurement(z, where)
    residual = z - range_bearing(mean)
    residual[..., 1:] = wrap_angle(residual[..., 1:])
    H = range_bearing_jacobian(mean)
    R = np.broadcast_to(noise.covariance, (*H.shape[:-2], 3, 3))
    return kalman_update(mean, cov, residual, H, R, where=where)


def update_plkf_arrays(
    mean: ArrayLike,
    cov: ArrayLike,
    z: ArrayLike,
    noise: RangeBearingNoise,
    *,
    covariance: PseudoLinearCovariance = "simplified",
    where: str = "",
) -> tuple[Array, Array, Innovation]:
    """PLKF update with ``H_pmo`` from the measured bearings and ``y = [r̃, 0, 0]`` (batched)."""
    mean = _check_finite("mean", mean, 4, where)
    cov = np.asarray(cov, dtype=float)
    z = _check_measurement(z, where)
    H = pseudo_linear_matrix(z)
    residual = pseudo_linear_measurement(z) - np.einsum("...ij,...j->...i", H, mean)
    R = pseudo_linear_covariance(mean, z, noise, covariance)
    return kalman_update(mean, cov, residual, H, R, where=where)


def _cubature_offsets(noise: RangeBearingNoise) -> Array:
    """The 6 points ``±√3 σ_i e_i`` of the third-degree spherical cubature rule (weights 1/6)."""
    scaled = np.sqrt(3.0) * np.sqrt(noise.variances)
    return np.concatenate([np.diag(scaled), -np.diag(scaled)])


def plkf_bias_estimate(
    prior_mean: Array,
    prior_cov: Array,
    posterior_mean: Array,
    z: Array,
    noise: RangeBearingNoise,
    covariance: PseudoLinearCovariance,
) -> Array:
    """``b̂ = E_ν[K ν_pm]`` of one PLKF update, evaluated at ``posterior_mean`` (batched).

    The gain of each cubature point uses the same prior (and the same state-dependent ``R_pmo``
    recipe) as the PLKF update; only the sensor noise is integrated out.
    """
    z_hat = range_bearing(posterior_mean)
    offsets = _cubature_offsets(noise)  # (6, 3)
    zs = z_hat[..., None, :] + offsets  # (..., 6, 3)
    H = pseudo_linear_matrix(zs)  # (..., 6, 3, 4)
    R = pseudo_linear_covariance(prior_mean[..., None, :], zs, noise, covariance)
    P = prior_cov[..., None, :, :]
    PHt = P @ _swap(H)
    S = H @ PHt + R
    K = _swap(np.linalg.solve(S, _swap(PHt)))  # S symmetric
    nu = pseudo_linear_measurement(zs) - np.einsum(
        "...ij,...j->...i", H, posterior_mean[..., None, :]
    )
    return np.einsum("...kij,...kj->...i", K, nu) / offsets.shape[0]


def update_plkf_bc_arrays(
    mean: ArrayLike,
    cov: ArrayLike,
    z: ArrayLike,
    noise: RangeBearingNoise,
    *,
    covariance: PseudoLinearCovariance = "simplified",
    where: str = "",
) -> tuple[Array, Array, Innovation]:
    """Bias-compensated PLKF update: the PLKF update minus its estimated bias (batched)."""
    mean = _check_finite("mean", mean, 4, where)
    cov = np.asarray(cov, dtype=float)
    z = _check_measurement(z, where)
    new_mean, new_cov, innovation = update_plkf_arrays(
        mean, cov, z, noise, covariance=covariance, where=where
    )
    bias = plkf_bias_estimate(mean, cov, new_mean, z, noise, covariance)
    return new_mean - bias, new_cov, innovation


# --------------------------------------------------------------------------- single-pair API


def predict(
    belief: Gaussian,
    u_l: ArrayLike,
    u_c: ArrayLike,
    dt: float,
    noise: VelocityNoise,
    *,
    where: str = "",
) -> Gaussian:
    """Shared predict for one pair (see :func:`predict_arrays`)."""
    mean, cov = predict_arrays(belief.mean, belief.cov, u_l, u_c, dt, noise, where=where)
    return Gaussian(mean=mean, cov=cov)


def _single(result: tuple[Array, Array, Innovation]) -> tuple[Gaussian, Innovation]:
    mean, cov, inn = result
    return Gaussian(mean=mean, cov=cov), Innovation(
        residual=inn.residual, cov=inn.cov, nis=float(inn.nis), meas_cov=np.array(inn.meas_cov)
    )


def update_tekf(
    belief: Gaussian, z: ArrayLike, noise: RangeBearingNoise, *, where: str = ""
) -> tuple[Gaussian, Innovation]:
    """TEKF update of one pair with a measurement ``z = (r, θ, α)``."""
    return _single(update_tekf_arrays(belief.mean, belief.cov, z, noise, where=where))


def update_plkf(
    belief: Gaussian,
    z: ArrayLike,
    noise: RangeBearingNoise,
    *,
    covariance: PseudoLinearCovariance = "simplified",
    where: str = "",
) -> tuple[Gaussian, Innovation]:
    """PLKF update of one pair with a measurement ``z = (r, θ, α)``."""
    return _single(
        update_plkf_arrays(belief.mean, belief.cov, z, noise, covariance=covariance, where=where)
    )


def update_plkf_bc(
    belief: Gaussian,
    z: ArrayLike,
    noise: RangeBearingNoise,
    *,
    covariance: PseudoLinearCovariance = "simplified",
    where: str = "",
) -> tuple[Gaussian, Innovation]:
    """Bias-compensated PLKF update of one pair with a measurement ``z = (r, θ, α)``."""
    return _single(
        update_plkf_bc_arrays(belief.mean, belief.cov, z, noise, covariance=covariance, where=where)
    )


BatchUpdate = Callable[..., tuple[Array, Array, Innovation]]

#: Batched update function of each filter kind (``covariance=`` is ignored by the TEKF).
BATCH_UPDATES: dict[str, BatchUpdate] = {
    "plkf": update_plkf_arrays,
    "plkf_bc": update_plkf_bc_arrays,
    "tekf": update_tekf_arrays,
}


@dataclass(frozen=True, kw_only=True)
class FilterSettings:
    """Which update a relative filter uses and its noise models.

    ``kind``: ``"plkf"`` (seed 000), ``"plkf_bc"`` (bias-compensated PLKF) or ``"tekf"``;
    ``pseudo_linear_covariance``: ``"simplified"`` (Eq. 6) or ``"full"`` (Eqs. 4–5), PLKF only.
    """

    kind: UpdateKind = "plkf"
    motion_noise: VelocityNoise
    sensor_noise: RangeBearingNoise
    pseudo_linear_covariance: PseudoLinearCovariance = "simplified"

    def __post_init__(self) -> None:
        if self.kind not in UPDATE_KINDS:
            raise ConfigError(f"FilterSettings.kind: one of {UPDATE_KINDS}, got {self.kind!r}")
        if self.pseudo_linear_covariance not in PSEUDO_LINEAR_COVARIANCES:
            raise ConfigError(
                "FilterSettings.pseudo_linear_covariance: one of "
                f"{PSEUDO_LINEAR_COVARIANCES}, got {self.pseudo_linear_covariance!r}"
            )
        if not isinstance(self.motion_noise, VelocityNoise):
            raise ConfigError("FilterSettings.motion_noise: must be a VelocityNoise")
        if not isinstance(self.sensor_noise, RangeBearingNoise):
            raise ConfigError("FilterSettings.sensor_noise: must be a RangeBearingNoise")

    def update_arrays(
        self, mean: ArrayLike, cov: ArrayLike, z: ArrayLike, *, where: str = ""
    ) -> tuple[Array, Array, Innovation]:
        """The configured batched update."""
        if self.kind == "tekf":
            return update_tekf_arrays(mean, cov, z, self.sensor_noise, where=where)
        return BATCH_UPDATES[self.kind](
            mean, cov, z, self.sensor_noise, covariance=self.pseudo_linear_covariance, where=where
        )


class RelativeTracker:
    """Thin stateful wrapper: holds one pair's :class:`Gaussian` and applies the pure functions.

    ``label`` names the pair in error messages (e.g. ``"l1->c3"``).
    """

    def __init__(self, belief: Gaussian, settings: FilterSettings, *, label: str = "") -> None:
        if belief.dim != 4:
            raise ModelError(f"RelativeTracker {label}: belief must be a RelPose4 (4 states)")
        self._belief = belief
        self.settings = settings
        self.label = label

    @property
    def belief(self) -> Gaussian:
        """Current belief over ``(x, y, z, φ)``."""
        return self._belief

    def predict(self, u_l: ArrayLike, u_c: ArrayLike, dt: float) -> Gaussian:
        """Propagate by ``dt`` with both robots' body velocities; returns the new belief."""
        self._belief = predict(
            self._belief, u_l, u_c, dt, self.settings.motion_noise, where=self.label
        )
        return self._belief

    def update(self, z: ArrayLike) -> Innovation:
        """Fuse one measurement ``z = (r, θ, α)``; returns the innovation."""
        mean, cov, innovation = self.settings.update_arrays(
            self._belief.mean, self._belief.cov, z, where=self.label
        )
        self._belief, innovation = _single((mean, cov, innovation))
        return innovation
