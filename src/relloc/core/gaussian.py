"""Belief containers: Gaussian (moment form), InformationState and GaussianMixture.

All are frozen dataclasses; estimators return new instances instead of mutating.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from relloc.core.checks import floats
from relloc.core.linalg import solve_psd, symmetrise
from relloc.errors import ModelError

Array = NDArray[np.float64]


#: Relative tolerance of the covariance checks: an asymmetry ``|P_ij − P_ji|``, a negative
#: eigenvalue or (in a mixture) a negative variance larger than ``PSD_TOL`` times the largest
#: variance is refused as wrong input; anything smaller is rounding (an asymmetry is then
#: symmetrised away).
PSD_TOL = 1e-6


def _semidefinite(S: Array, tol: float) -> bool:
    """Whether the symmetric ``S`` has no eigenvalue below ``−tol``, i.e. ``S + tol I`` has a
    Cholesky factor: one factorisation of ``S`` (which succeeds for every positive definite one)
    and, only if that fails, one of ``S + tol I``."""
    try:
        np.linalg.cholesky(S)
        return True
    except np.linalg.LinAlgError:
        pass
    try:
        np.linalg.cholesky(S + max(tol, np.finfo(float).tiny) * np.eye(S.shape[-1]))
        return True
    except np.linalg.LinAlgError:
        return False


def _as_state(mean: Array, cov: Array, what: str, *, factored: bool = False) -> tuple[Array, Array]:
    """``(mean (n,), cov (n, n))`` checked for shape and finiteness, and ``cov`` symmetrised and
    checked for symmetry and positive semi-definiteness within ``τ = PSD_TOL · max_i P_ii``
    (:data:`PSD_TOL`) — unless ``factored`` says it is exactly symmetric and known positive
    definite (the caller has just Cholesky-factored it or its inverse): then neither again."""
    m = floats(mean, f"{what}: mean", ModelError).reshape(-1)
    P = floats(cov, f"{what}: covariance", ModelError)
    if P.shape != (m.size, m.size):
        raise ModelError(f"{what}: covariance shape {P.shape} does not match state size {m.size}")
    if not (np.all(np.isfinite(m)) and np.all(np.isfinite(P))):
        raise ModelError(f"{what}: non-finite mean or covariance")
    if factored:  # its factorisation proved it; a negative variance is all that is left to see
        if np.any(P.diagonal() < 0.0):
            raise ModelError(f"{what}: covariance is not positive semi-definite (a variance < 0)")
        return m, P
    S = symmetrise(P)
    tol = PSD_TOL * float(S.diagonal().max(initial=0.0))
    asymmetry = 2.0 * float(np.abs(P - S).max(initial=0.0))
    if asymmetry > tol:
        raise ModelError(f"{what}: covariance is not symmetric (|P_ij − P_ji| = {asymmetry:.3g})")
    if not _semidefinite(S, tol):
        raise ModelError(
            f"{what}: covariance is not positive semi-definite; eigenvalues {np.linalg.eigvalsh(S)}"
        )
    return m, S


@dataclass(frozen=True)
class Gaussian:
    """N(mean, cov). ``mean`` has shape (n,), ``cov`` (n, n): finite, and symmetric and positive
    semi-definite within :data:`PSD_TOL` (else :class:`ModelError`); stored symmetrised."""

    mean: Array
    cov: Array

    def __post_init__(self) -> None:
        m, P = _as_state(self.mean, self.cov, "Gaussian")
        object.__setattr__(self, "mean", m)
        object.__setattr__(self, "cov", P)

    @property
    def dim(self) -> int:
        return int(self.mean.size)

    def to_information(self) -> InformationState:
        """Information form: ``Y = P⁻¹``, ``y = P⁻¹ x``."""
        Y = solve_psd(self.cov, np.eye(self.dim), where="Gaussian.to_information")
        return InformationState(info_vector=Y @ self.mean, info_matrix=symmetrise(Y))


@dataclass(frozen=True)
class InformationState:
    """Canonical (information) form: ``info_matrix`` Y = P⁻¹, ``info_vector`` y = Y x."""

    info_vector: Array
    info_matrix: Array

    def __post_init__(self) -> None:
        y, Y = _as_state(self.info_vector, self.info_matrix, "InformationState")
        object.__setattr__(self, "info_vector", y)
        object.__setattr__(self, "info_matrix", Y)

    @staticmethod
    def from_symmetric(info_vector: Array, info_matrix: Array) -> InformationState:
        """The state of an ``info_matrix`` that is exactly symmetric and known positive definite:
        the caller has just Cholesky-factored it or its inverse (the team filter's ``3n × 3n``
        matrices, every epoch, in :mod:`relloc.estimators.eif`). Checked for shape, finiteness
        and negative variances only: neither symmetrised nor factored again."""
        y, Y = _as_state(info_vector, info_matrix, "InformationState", factored=True)
        state = object.__new__(InformationState)
        object.__setattr__(state, "info_vector", y)
        object.__setattr__(state, "info_matrix", Y)
        return state

    @property
    def dim(self) -> int:
        return int(self.info_vector.size)

    def to_gaussian(self) -> Gaussian:
        """Moment form: ``P = Y⁻¹``, ``x = P y``."""
        P = solve_psd(self.info_matrix, np.eye(self.dim), where="InformationState.to_gaussian")
        return Gaussian(mean=P @ self.info_vector, cov=symmetrise(P))


@dataclass(frozen=True, kw_only=True)
class GaussianMixture:
    """Gaussian mixtures as parallel arrays: ``Σ_k w_k N(means[k], covs[k]) / Σ_k w_k``.

    The weights are ≥ 0 and need not be normalised (:meth:`normalised_weights`). One instance
    holds many mixtures in one of two layouts, both reduced by
    :mod:`relloc.association.mixture_reduction`:

    * **rectangular** (``groups is None``): ``means (..., K, n)``, ``covs (..., K, n, n)``,
      ``weights (..., K)``; each leading index is one mixture of ``K`` slots and a slot of weight
      0 is empty, so that all mixtures stay one array and update in one numpy call (the yaw
      banks of :mod:`relloc.estimators.yaw_bank`). Every mixture has a slot of weight > 0.
    * **flat** (``groups (K,)`` integers): ``means (K, n)``, ``covs (K, n, n)``, ``weights (K,)``
      and components with equal ``groups`` form one mixture, of any size (the Gaussian-sum
      filters of :mod:`relloc.estimators.gaussian_sum`, one per teammate).

    The means and covariances must be finite and no variance negative (beyond
    :data:`PSD_TOL`); unlike :class:`Gaussian`, the covariances are neither factorised nor
    symmetrised, to keep the check of a bank of thousands of slots at O(K n²).
    """

    means: Array
    covs: Array
    weights: Array
    groups: NDArray[np.int64] | None = None

    def __post_init__(self) -> None:
        means = floats(self.means, "GaussianMixture: means", ModelError)
        covs = floats(self.covs, "GaussianMixture: covs", ModelError)
        w = floats(self.weights, "GaussianMixture: weights", ModelError)
        shape = w.shape
        n = means.shape[-1] if means.ndim else -1
        if w.ndim == 0 or means.shape[:-1] != shape or covs.shape != (*shape, n, n):
            raise ModelError(
                f"GaussianMixture: shapes means {means.shape}, covs {covs.shape}, weights "
                f"{shape} must be (..., K, n), (..., K, n, n), (..., K)"
            )
        if w.size and not (w.min() >= 0.0 and w.max() < np.inf):  # NaN fails both
            raise ModelError(f"GaussianMixture: weights must be finite and ≥ 0: {w}")
        if not (np.isfinite(means).all() and np.isfinite(covs).all()):
            raise ModelError("GaussianMixture: non-finite mean or covariance")
        variances = np.diagonal(covs, axis1=-2, axis2=-1)
        # the global minimum first: the per-component reductions are slow on a diagonal view
        if variances.size and variances.min() < 0.0:
            if np.any(variances.min(axis=-1) < -PSD_TOL * variances.max(axis=-1)):
                raise ModelError("GaussianMixture: negative variance in a covariance")
        if self.groups is None:
            if shape[-1] == 0 or not (w > 0.0).any(axis=-1).all():
                raise ModelError("GaussianMixture: every mixture needs a component of weight > 0")
        else:
            groups = np.asarray(self.groups)
            if groups.size and groups.dtype.kind not in "iu":  # 0.5 would become group 0
                raise ModelError(f"GaussianMixture: groups must be integers, got {groups.dtype}")
            groups = groups.astype(np.int64, copy=False)
            if w.ndim != 1 or groups.shape != shape or (groups.size and groups.min() < 0):
                raise ModelError(
                    f"GaussianMixture: groups {groups.shape} must be indices ≥ 0 labelling flat "
                    f"weights {shape}"
                )
            object.__setattr__(self, "groups", groups)
        object.__setattr__(self, "means", means)
        object.__setattr__(self, "covs", covs)
        object.__setattr__(self, "weights", w)

    @property
    def size(self) -> int:
        """Number of components (slots) in all mixtures together."""
        return int(self.weights.size)

    @property
    def alive(self) -> NDArray[np.bool_]:
        """Components of weight > 0 (empty slots are ``False``)."""
        return np.asarray(self.weights > 0.0)

    def normalised_weights(self) -> Array:
        """Weights divided by the total of their mixture (a mixture of total 0 keeps its 0s)."""
        if self.groups is None:
            totals = self.weights.sum(axis=-1, keepdims=True)
            return np.asarray(self.weights / np.where(totals > 0.0, totals, 1.0))
        totals = np.bincount(self.groups, weights=self.weights)
        return np.asarray(self.weights / np.where(totals > 0.0, totals, 1.0)[self.groups])

    @property
    def heaviest_index(self) -> NDArray[np.int64]:
        """Index of the heaviest component of each mixture, ``(...)`` (rectangular layout)."""
        if self.groups is not None:
            raise ModelError("GaussianMixture.heaviest_index: needs the rectangular layout")
        return np.asarray(np.argmax(self.weights, axis=-1))

    def heaviest(self) -> tuple[Array, Array]:
        """Mean ``(..., n)`` and covariance ``(..., n, n)`` of each mixture's heaviest component
        (rectangular layout)."""
        k = self.heaviest_index[..., None, None]
        mean = np.take_along_axis(self.means, k, axis=-2)[..., 0, :]
        cov = np.take_along_axis(self.covs, k[..., None], axis=-3)[..., 0, :, :]
        return mean, cov
