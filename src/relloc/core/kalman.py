"""The Kalman update and the χ² gate shared by every covariance-form filter.

Update, in Joseph form (seed 000 Eq. 8; seed 001 §2.1; seed 003 Algorithm 1), for a residual
``ν``, a measurement matrix ``H`` and a measurement covariance ``R``::

    S = H P Hᵀ + R,   K = P Hᵀ S⁻¹,   x⁺ = x + K ν,   P⁺ = (I − K H) P (I − K H)ᵀ + K R Kᵀ.

``S⁻¹`` comes from the Cholesky factor ``S = L Lᵀ`` (``S⁻¹ = L⁻ᵀ L⁻¹``), which also gives the
normalised innovation squared ``NIS = νᵀ S⁻¹ ν = ‖L⁻¹ ν‖²``. Every argument may carry leading
batch dimensions (``mean (..., n)``, ``cov (..., n, n)``, ``residual (..., m)``,
``H (..., m, n)``, ``R (..., m, m)``), so many independent updates run in one numpy call.
The trailing dimensions must agree and the leading ones broadcast, and ``S`` and every NIS must
be finite (a NaN or infinity in ``ν``, ``P``, ``H`` or ``R`` reaches them); otherwise
:class:`ModelError` naming ``where``. The checks cost O(m²) per update: the shapes, ``S`` and
the NIS, not every entry of ``P``, and not the prior mean ``x``, which enters neither ``S`` nor
the NIS (a NaN there comes back in ``x⁺``). Its check, one reduction over ``x``, costs about
1 µs, 2–2.5 % of an update of 1 to 30 states, so a mean is checked where it enters an
estimator instead: :class:`~relloc.core.gaussian.Gaussian`,
:class:`~relloc.core.gaussian.GaussianMixture`, the relative filters' array functions
(:func:`relloc.estimators.relative.check_finite`) and the measurement tables
(:class:`~relloc.core.recording.Measurements`) refuse NaN and infinity, and every filter's
state stays one of these or the output of an update from one.

Gate: a measurement block of dimension ``m`` is consistent with the prediction when

    NIS ≤ γ,   γ = F⁻¹_{χ²(m)}(p),

so that a correct measurement is accepted with probability ``p``. :func:`gated_update` computes
``S`` and the NIS first, decides, and forms the gain and the update only for an accepted block.

The hand-unrolled kernels of :mod:`relloc.estimators.kernels` are the same update written out for
the 4-state relative model (tested equal to :func:`kalman_update` in
tests/estimators/test_kernels.py).
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from numpy.typing import ArrayLike, NDArray

from relloc.core.checks import count
from relloc.core.checks import probability as probability_in_01
from relloc.errors import ModelError

Array = NDArray[np.float64]


@dataclass(frozen=True)
class Innovation:
    """What an update saw: residual ``ν (..., m)``, its covariance ``S``, ``nis = νᵀS⁻¹ν``, and
    the measurement covariance ``R`` used (for conditioning checks, seed 000 §7.3).

    For a single update ``nis`` is a float; for a batch it is an array ``(...,)``.
    """

    residual: Array
    cov: Array
    nis: float | Array
    meas_cov: Array


def _at(where: str) -> str:
    return f" at {where}" if where else ""


def not_positive_definite(where: str) -> ModelError:
    """The error of an update whose innovation covariance ``S`` cannot be factorised."""
    return ModelError(f"innovation covariance is not positive definite{_at(where)}")


def _checked(
    mean: ArrayLike, cov: ArrayLike, residual: ArrayLike, H: ArrayLike, R: ArrayLike, where: str
) -> tuple[Array, Array, Array, Array, Array]:
    """The arguments as float arrays; ``ModelError`` naming ``where`` unless their shapes end in
    ``(n,)``, ``(n, n)``, ``(m,)``, ``(m, n)``, ``(m, m)`` and the leading (batch) dimensions
    broadcast."""
    x = np.asarray(mean, dtype=float)
    P = np.asarray(cov, dtype=float)
    nu = np.asarray(residual, dtype=float)
    H_ = np.asarray(H, dtype=float)
    R_ = np.asarray(R, dtype=float)
    n, m = x.shape[-1:], nu.shape[-1:]
    fits = (
        bool(n and m)
        and P.shape[-2:] == n + n
        and H_.shape[-2:] == m + n
        and R_.shape[-2:] == m + m
    )
    batches = (x.shape[:-1], P.shape[:-2], nu.shape[:-1], H_.shape[:-2], R_.shape[:-2])
    if fits and batches.count(batches[0]) != len(batches):  # (equal ones need no broadcasting)
        try:
            np.broadcast_shapes(*batches)
        except ValueError:
            fits = False
    if not fits:
        raise ModelError(
            f"Kalman update{_at(where)}: shapes mean {x.shape}, cov {P.shape}, residual "
            f"{nu.shape}, H {H_.shape}, R {R_.shape} do not fit (..., n), (..., n, n), (..., m), "
            "(..., m, n), (..., m, m)"
        )
    return x, P, nu, H_, R_


def _swap(M: Array) -> Array:
    return np.swapaxes(M, -1, -2)


def _factor(
    cov: Array, residual: Array, H: Array, R: Array, where: str
) -> tuple[Array, Array, Array, Array]:
    """``(S, NIS, P Hᵀ, L⁻¹)``: ``S = H P Hᵀ + R = L Lᵀ``, ``NIS = ‖L⁻¹ ν‖²``, and what the gain
    needs (``ModelError`` naming ``where`` if ``S`` is not positive definite, or ``S`` or a NIS
    not finite)."""
    PHt = cov @ _swap(H)
    S = H @ PHt + R
    S = 0.5 * (S + _swap(S))
    try:
        L = np.linalg.cholesky(S)
    except np.linalg.LinAlgError as exc:
        raise not_positive_definite(where) from exc
    eye = np.broadcast_to(np.eye(S.shape[-1]), S.shape)
    L_inv = np.linalg.solve(L, eye)
    w = np.einsum("...ij,...j->...i", L_inv, residual)
    nis = np.einsum("...i,...i->...", w, w)
    # one scalar test: a NaN or infinity anywhere in S or a NIS makes their sum non-finite
    if not math.isfinite(S.sum() + nis.sum()):
        raise ModelError(
            f"Kalman update{_at(where)}: non-finite NIS or innovation covariance (NaN or "
            "infinity in the residual, the covariance, H or R)"
        )
    return S, nis, PHt, L_inv


def _correct(
    mean: Array, cov: Array, residual: Array, H: Array, R: Array, PHt: Array, L_inv: Array
) -> tuple[Array, Array]:
    """Gain ``K = P Hᵀ L⁻ᵀ L⁻¹``, ``x⁺ = x + K ν`` and the Joseph-form ``P⁺``."""
    K = PHt @ (_swap(L_inv) @ L_inv)
    new_mean = mean + np.einsum("...ij,...j->...i", K, residual)
    A = np.eye(cov.shape[-1]) - K @ H
    new_cov = A @ cov @ _swap(A) + K @ R @ _swap(K)
    return new_mean, 0.5 * (new_cov + _swap(new_cov))


def kalman_update(
    mean: Array, cov: Array, residual: Array, H: Array, R: Array, *, where: str = ""
) -> tuple[Array, Array, Innovation]:
    """Joseph-form Kalman update (module docstring), batched over leading dimensions.

    Returns ``(mean⁺, cov⁺, innovation)``. Raises :class:`ModelError` naming ``where`` if the
    shapes do not fit, or some ``S`` is not finite and positive definite or some NIS not finite
    (module docstring). ``mean`` must be finite: it is not checked here (module docstring).
    """
    mean, cov, residual, H, R = _checked(mean, cov, residual, H, R, where)
    S, nis, PHt, L_inv = _factor(cov, residual, H, R, where)
    new_mean, new_cov = _correct(mean, cov, residual, H, R, PHt, L_inv)
    return new_mean, new_cov, Innovation(residual=residual, cov=S, nis=nis, meas_cov=R)


#: Most degrees of freedom of a χ² quantile: every integer up to it is a float exactly (scipy's
#: quantile fails beyond the int64 range and on integers no float holds).
MAX_CHI2_DOF = 2**53


@lru_cache(maxsize=64)
def chi2_threshold(dim: int, probability: float) -> float:
    """Gate threshold ``γ`` with ``P(χ²(dim) ≤ γ) = probability`` (cached); ``dim`` an integer
    in ``[1, MAX_CHI2_DOF]`` and ``probability`` in (0, 1), else ConfigError."""
    count(dim, "chi2_threshold: dim", high=MAX_CHI2_DOF)
    probability_in_01(probability, "chi2_threshold: probability")
    # scipy.stats is imported here, not at module level: it takes about a second to import and
    # most users of this module (the relative filters) never gate
    from scipy.stats import chi2

    return float(chi2.ppf(probability, dim))


def prepare_gates(dims: Iterable[int], *probabilities: float | None) -> None:
    """Compute (and cache) ``γ = F⁻¹_{χ²(m)}(p)`` for every block dimension ``m`` in ``dims``
    and every gate probability ``p`` (``None``: that gate is off).

    A gating filter calls it when it is built, so that the one-off cost of its first gate
    (importing ``scipy.stats``, about 0.4–0.6 s of CPU) is paid before a process that runs it
    declares itself ready, not inside a timed tick; later gates read the cache
    (:func:`chi2_threshold`). The thresholds are the same either way.
    """
    for p in probabilities:
        if p is not None:
            for m in sorted(set(dims)):
                chi2_threshold(m, p)


def gated_update(
    mean: Array,
    cov: Array,
    residual: Array,
    H: Array,
    R: Array,
    probability: float | None,
    *,
    where: str = "",
) -> tuple[Array, Array, Innovation, bool]:
    """χ²-gated Kalman update of one measurement block (no batch dimension).

    Computes ``S`` and the NIS first; if ``NIS > chi2_threshold(m, probability)`` the block is
    rejected and the prior ``(mean, cov)`` is returned unchanged, otherwise the update is that of
    :func:`kalman_update`. ``probability=None`` disables the gate. Returns
    ``(mean⁺, cov⁺, innovation, accepted)``; the errors are those of :func:`kalman_update` (a
    NaN NIS is refused before the gate, which it would otherwise pass).
    """
    mean, cov, residual, H, R = _checked(mean, cov, residual, H, R, where)
    if residual.ndim != 1:
        raise ModelError(f"gated_update{_at(where)}: one block, residual shape {residual.shape}")
    S, nis_array, PHt, L_inv = _factor(cov, residual, H, R, where)
    nis = float(nis_array)
    innovation = Innovation(residual=residual, cov=S, nis=nis, meas_cov=R)
    if probability is not None and nis > chi2_threshold(residual.size, probability):
        return mean, cov, innovation, False
    new_mean, new_cov = _correct(mean, cov, residual, H, R, PHt, L_inv)
    return new_mean, new_cov, innovation, True
