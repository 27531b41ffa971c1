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
* Bias-compensated PLKF (``update_bcplkf``): the measured bearings inside ``H`` correlate the
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

API: array functions (``predict_arrays``, ``update_*_arrays``) broadcast over a leading batch
dimension (``mean (..., 4)``, ``cov (..., 4, 4)``, ``z (..., 3)``) so many pairs update in one
numpy call; the :class:`~relloc.core.Gaussian` wrappers (``predict``, ``update_*``) are the
single-pair API; :class:`RelativeTracker` is the thin stateful wrapper. All of them run the
hand-unrolled kernels of :mod:`relloc.estimators.kernels`, which are tested to equal the general
matrix form (the models' Jacobians and the Joseph-form
:func:`relloc.core.kalman.kalman_update`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from relloc.core.checks import time_step
from relloc.core.contract import Silent
from relloc.core.events import elapsed
from relloc.core.gaussian import Gaussian
from relloc.core.kalman import Innovation, not_positive_definite
from relloc.core.recording import KIND_NAMES, KINDS, Measurements, kind_code
from relloc.errors import ConfigError, DataError, ModelError
from relloc.estimators.kernels import (
    ARRAY_OPS,
    SCALAR_OPS,
    Ops,
    Vec,
    join_symmetric,
    join_vector,
    plkf_bias_kernel,
    plkf_terms,
    predict_kernel,
    split_cov4,
    split_vector,
    tekf_terms,
    update_kernel,
)
from relloc.models.measurement import (
    PSEUDO_LINEAR_COVARIANCES,
    PseudoLinearCovariance,
    RangeBearingNoise,
)
from relloc.models.motion import VelocityNoise

Array = NDArray[np.float64]
UpdateKind = Literal["plkf", "tekf", "bcplkf"]
UPDATE_KINDS: tuple[str, ...] = ("plkf", "tekf", "bcplkf")

#: The reading the relative filters fuse: range, azimuth and elevation of a robot (seed 000
#: Eq. 2), and the degrees of freedom of its NIS.
MEASUREMENT_KIND = "range_bearing_elevation"
MEASUREMENT_DOF = KINDS[MEASUREMENT_KIND].dim
#: The frame of their beliefs (:mod:`relloc.pipeline.frames`).
FRAME = "relative_pose4"
_RBE = kind_code(MEASUREMENT_KIND)


def is_relative_reading(kind: NDArray[np.int64]) -> NDArray[np.bool_]:
    """Which rows of a table's ``kind`` column are :data:`MEASUREMENT_KIND` readings."""
    return np.asarray(kind) == _RBE


def unfusable_reason(batch: Measurements, q: int) -> str:
    """Why row ``q`` of ``batch`` cannot update a relative filter (empty if it can): another
    kind, an unknown target (unknown correspondence or a landmark), or no stated σ."""
    if int(batch.kind[q]) != _RBE:
        return f"rows_of_kind_{KIND_NAMES[int(batch.kind[q])]}"
    if int(batch.target[q]) < 0:
        return "rows_of_unknown_target"
    if not np.all(np.isfinite(batch.sigma[q, :MEASUREMENT_DOF])):
        return "rows_without_sigma"
    return ""


class ObserverClock(Silent):
    """The event clock and the count of unfused rows that a relative estimator of one observing
    robot keeps: ``t`` is the latest event time (``None`` before the first advance)."""

    t: float | None
    _counts: dict[str, int]

    def _start_clock(self) -> None:
        self.t = None
        self._counts = {}

    def _elapsed(self, t: float) -> float | None:
        """``t − t_previous`` (``None`` at the first event, which only sets the clock)."""
        dt = elapsed(self.t, t, f"{type(self).__name__}.advance")
        if dt is None:
            self.t = t
        return dt

    def _now(self, what: str) -> float:
        if self.t is None:
            raise ConfigError(f"{type(self).__name__}.{what}: called before the first advance")
        return self.t

    def _count(self, reason: str) -> None:
        self._counts[reason] = self._counts.get(reason, 0) + 1

    def take_counts(self) -> dict[str, int]:
        """The owner's rows not fused since the previous call, by reason."""
        out, self._counts = self._counts, {}
        return out


def check_finite(name: str, value: ArrayLike, last: int, where: str) -> Array:
    """``value`` as a float array whose last dimension is ``last``; :class:`DataError` naming
    ``where`` and ``name`` if it is not, or if an entry is NaN or infinite."""
    arr = np.asarray(value, dtype=float)
    if arr.ndim == 0 or arr.shape[-1] != last:
        raise DataError(f"{where or 'relative filter'}: {name} must have last dimension {last}")
    if not np.all(np.isfinite(arr)):
        raise DataError(f"{where or 'relative filter'}: {name} contains NaN or inf: {arr}")
    return arr


# --------------------------------------------------------------------------- array (batched) API
#
# The functions below run the hand-unrolled kernels of :mod:`relloc.estimators.kernels` on
# Python floats (one pair) or on numpy arrays holding one entry for every pair. They equal the
# general matrix composition ``relative_step`` / ``relative_jacobians`` / ``process_noise`` and
# :func:`relloc.core.kalman.kalman_update` with the models' ``h``, ``H``, ``R``
# (tests/estimators/test_kernels.py).


def check_cov(cov: ArrayLike, where: str) -> Array:
    """``cov`` as a float array ``(..., 4, 4)`` of finite entries, else :class:`DataError`
    naming ``where``."""
    P = np.asarray(cov, dtype=float)
    if P.ndim < 2 or P.shape[-2:] != (4, 4):
        raise DataError(
            f"{where or 'relative filter'}: covariance must be (..., 4, 4), got {P.shape}"
        )
    if not np.all(np.isfinite(P)):
        raise DataError(f"{where or 'relative filter'}: covariance contains NaN or inf")
    return P


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
    """Shared predict ``x⁻ = f_d(x, u)``, ``P⁻ = F P Fᵀ + G Σ_u Gᵀ`` (batched, broadcasting)."""
    mean = check_finite("mean", mean, 4, where)
    cov = check_cov(cov, where)
    u_l = check_finite("observer input u_l", u_l, 4, where)
    u_c = check_finite("observed input u_c", u_c, 4, where)
    dt = time_step(dt, where or "relative filter")
    single = mean.ndim == 1 and cov.ndim == 2 and u_l.ndim == 1 and u_c.ndim == 1
    ops = SCALAR_OPS if single else ARRAY_OPS
    var = tuple(np.square(noise.observer + noise.observed).tolist())
    new_mean, new_cov = predict_kernel(
        split_vector(mean, single),
        split_cov4(cov, single),
        split_vector(u_l, single),
        split_vector(u_c, single),
        dt,
        var,
        ops,
    )
    return join_vector(new_mean), join_symmetric(new_cov)


def _check_measurement(z: ArrayLike, where: str) -> Array:
    z = check_finite("measurement z", z, 3, where)
    if np.any(z[..., 0] <= 0.0):
        raise DataError(f"{where or 'relative filter'}: measured range must be > 0: {z}")
    return z


Terms = Callable[[Vec, Vec, Ops], tuple[Vec, Vec, Vec]]


def _kernel_update(
    mean: ArrayLike,
    cov: ArrayLike,
    z: ArrayLike,
    terms: Terms,
    where: str,
    bias: Callable[[Vec, Vec, Vec, Ops], Vec | None] | None = None,
) -> tuple[Array, Array, Innovation]:
    """Validate, run ``terms`` (``A``, ``ν``, ``R``) and the Joseph update kernel, re-assemble."""
    mean = check_finite("mean", mean, 4, where)
    cov = check_cov(cov, where)
    z = _check_measurement(z, where)
    single = mean.ndim == 1 and cov.ndim == 2 and z.ndim == 1
    ops = SCALAR_OPS if single else ARRAY_OPS
    m = split_vector(mean, single)
    P = split_cov4(cov, single)
    A, nu, R = terms(m, split_vector(z, single), ops)
    out = update_kernel(m, P, A, nu, R, ops)
    correction = None
    if out is not None and bias is not None:
        correction = bias(m, P, out[0], ops)
        out = None if correction is None else out
    if out is None:
        raise not_positive_definite(where)
    new_mean, new_cov, S, nis = out
    if correction is not None:
        new_mean = tuple(a - b for a, b in zip(new_mean, correction, strict=True))
    S_full = join_symmetric(S)
    innovation = Innovation(
        residual=join_vector(nu),
        cov=S_full,
        nis=float(nis) if single else np.asarray(nis, dtype=float),
        meas_cov=np.broadcast_to(join_symmetric(R), S_full.shape).copy(),
    )
    return join_vector(new_mean), join_symmetric(new_cov), innovation


def update_tekf_arrays(
    mean: ArrayLike, cov: ArrayLike, z: ArrayLike, noise: RangeBearingNoise, *, where: str = ""
) -> tuple[Array, Array, Innovation]:
    """TEKF update with ``h(x) = (r, θ, α)`` linearised at the prior (batched)."""
    var = tuple(noise.variances.tolist())
    return _kernel_update(mean, cov, z, lambda m, zz, ops: tekf_terms(m, zz, var, ops), where)


def _check_covariance_kind(kind: str) -> bool:
    if kind not in PSEUDO_LINEAR_COVARIANCES:
        raise ConfigError(
            f"pseudo-linear covariance: one of {PSEUDO_LINEAR_COVARIANCES}, got {kind!r}"
        )
    return kind == "full"


def _plkf_update(
    mean: ArrayLike,
    cov: ArrayLike,
    z: ArrayLike,
    noise: RangeBearingNoise,
    covariance: PseudoLinearCovariance,
    where: str,
    *,
    compensate_bias: bool,
) -> tuple[Array, Array, Innovation]:
    """The PLKF update, optionally minus its estimated bias ``b̂`` (shared by both variants)."""
    var = tuple(noise.variances.tolist())
    full = _check_covariance_kind(covariance)

    def bias(prior: Vec, P: Vec, post: Vec, ops: Ops) -> Vec | None:
        return plkf_bias_kernel(prior, P, post, var, ops, full_covariance=full)

    return _kernel_update(
        mean,
        cov,
        z,
        lambda m, zz, ops: plkf_terms(m, zz, var, ops, full_covariance=full),
        where,
        bias=bias if compensate_bias else None,
    )


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
    return _plkf_update(mean, cov, z, noise, covariance, where, compensate_bias=False)


def update_bcplkf_arrays(
    mean: ArrayLike,
    cov: ArrayLike,
    z: ArrayLike,
    noise: RangeBearingNoise,
    *,
    covariance: PseudoLinearCovariance = "simplified",
    where: str = "",
) -> tuple[Array, Array, Innovation]:
    """Bias-compensated PLKF update: the PLKF update minus its estimated bias ``b̂`` (batched)."""
    return _plkf_update(mean, cov, z, noise, covariance, where, compensate_bias=True)


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


def update_bcplkf(
    belief: Gaussian,
    z: ArrayLike,
    noise: RangeBearingNoise,
    *,
    covariance: PseudoLinearCovariance = "simplified",
    where: str = "",
) -> tuple[Gaussian, Innovation]:
    """Bias-compensated PLKF update of one pair with a measurement ``z = (r, θ, α)``."""
    return _single(
        update_bcplkf_arrays(belief.mean, belief.cov, z, noise, covariance=covariance, where=where)
    )


BatchUpdate = Callable[..., tuple[Array, Array, Innovation]]

#: Batched update function of each filter kind (``covariance=`` is ignored by the TEKF).
BATCH_UPDATES: dict[str, BatchUpdate] = {
    "plkf": update_plkf_arrays,
    "tekf": update_tekf_arrays,
    "bcplkf": update_bcplkf_arrays,
}


@dataclass(frozen=True, kw_only=True)
class FilterSettings:
    """Which update a relative filter uses and its noise models.

    ``kind``: ``"plkf"`` (seed 000), ``"bcplkf"`` (bias-compensated PLKF) or ``"tekf"``;
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


def _floats(value: ArrayLike, n: int, name: str, where: str) -> tuple[float, ...]:
    """A length-``n`` vector as a tuple of finite floats (the tracker's fast input path)."""
    seq: Any = value.tolist() if isinstance(value, np.ndarray) else value
    try:
        out = tuple(map(float, seq))
    except (TypeError, ValueError) as exc:
        raise DataError(f"{where or 'relative tracker'}: {name} must be {n} numbers") from exc
    if len(out) != n:
        raise DataError(
            f"{where or 'relative tracker'}: {name} must have {n} entries, got {len(out)}"
        )
    if not all(math.isfinite(v) for v in out):
        raise DataError(f"{where or 'relative tracker'}: {name} contains NaN or inf: {out}")
    return out


class RelativeTracker:
    """Thin stateful wrapper around the kernels for one observer–observed pair.

    Holds the belief as plain floats (mean and the upper triangle of ``P``) and applies
    :func:`~relloc.estimators.kernels.predict_kernel` / ``update_kernel`` directly, so one
    predict + update costs microseconds; :attr:`belief` returns it as a :class:`Gaussian`. The
    results equal the pure functions of this module (tests/estimators/test_relative.py).
    ``label`` names the pair in error messages (e.g. ``"l1->c3"``).
    """

    def __init__(self, belief: Gaussian, settings: FilterSettings, *, label: str = "") -> None:
        if belief.dim != 4:
            raise ModelError(f"RelativeTracker {label}: belief must be a RelPose4 (4 states)")
        self.settings = settings
        self.label = label
        self._mean: Vec = tuple(belief.mean.tolist())
        self._cov: Vec = split_cov4(belief.cov, True)
        self._cached: Gaussian | None = belief
        self._var_u = tuple(
            np.square(settings.motion_noise.observer + settings.motion_noise.observed).tolist()
        )
        self._var_z = tuple(settings.sensor_noise.variances.tolist())
        self._full = settings.pseudo_linear_covariance == "full"

    @property
    def belief(self) -> Gaussian:
        """Current belief over ``(x, y, z, φ)``."""
        if self._cached is None:
            self._cached = Gaussian(mean=join_vector(self._mean), cov=join_symmetric(self._cov))
        return self._cached

    def predict(self, u_l: ArrayLike, u_c: ArrayLike, dt: float) -> None:
        """Propagate by ``dt`` with both robots' body velocities (shared predict)."""
        ul = _floats(u_l, 4, "observer input u_l", self.label)
        uc = _floats(u_c, 4, "observed input u_c", self.label)
        dt = time_step(dt, self.label or "relative tracker")
        self._mean, self._cov = predict_kernel(
            self._mean, self._cov, ul, uc, dt, self._var_u, SCALAR_OPS
        )
        self._cached = None

    def update(self, z: ArrayLike) -> Innovation:
        """Fuse one measurement ``z = (r, θ, α)`` with the configured update; returns the
        innovation (residual, ``S``, NIS, ``R``)."""
        zz = _floats(z, 3, "measurement z", self.label)
        if zz[0] <= 0.0:
            raise DataError(f"{self.label or 'relative tracker'}: measured range must be > 0: {zz}")
        kind = self.settings.kind
        if kind == "tekf":
            A, nu, R = tekf_terms(self._mean, zz, self._var_z, SCALAR_OPS)
        else:
            A, nu, R = plkf_terms(
                self._mean, zz, self._var_z, SCALAR_OPS, full_covariance=self._full
            )
        out = update_kernel(self._mean, self._cov, A, nu, R, SCALAR_OPS)
        bias = None
        if out is not None and kind == "bcplkf":
            bias = plkf_bias_kernel(
                self._mean, self._cov, out[0], self._var_z, SCALAR_OPS, full_covariance=self._full
            )
        if out is None or (kind == "bcplkf" and bias is None):
            raise not_positive_definite(self.label or "tracker")
        mean, self._cov, S, nis = out
        if bias is not None:
            mean = tuple(a - b for a, b in zip(mean, bias, strict=True))
        self._mean = mean
        self._cached = None
        s00, s01, s02, s11, s12, s22 = S
        r00, r01, r02, r11, r12, r22 = R
        return Innovation(
            residual=np.array(nu),
            cov=np.array([s00, s01, s02, s01, s11, s12, s02, s12, s22]).reshape(3, 3),
            nis=nis,
            meas_cov=np.array([r00, r01, r02, r01, r11, r12, r02, r12, r22]).reshape(3, 3),
        )
