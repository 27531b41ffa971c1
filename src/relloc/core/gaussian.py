"""Belief containers: Gaussian (moment form), InformationState and GaussianMixture.

All are frozen dataclasses; estimators return new instances instead of mutating.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from relloc.core.linalg import solve_psd, symmetrise
from relloc.errors import ModelError

Array = NDArray[np.float64]


def _as_state(mean: Array, cov: Array, what: str) -> tuple[Array, Array]:
    m = np.asarray(mean, dtype=float).reshape(-1)
    P = np.asarray(cov, dtype=float)
    if P.shape != (m.size, m.size):
        raise ModelError(f"{what}: covariance shape {P.shape} does not match state size {m.size}")
    if not (np.all(np.isfinite(m)) and np.all(np.isfinite(P))):
        raise ModelError(f"{what}: non-finite mean or covariance")
    return m, symmetrise(P)


@dataclass(frozen=True)
class Gaussian:
    """N(mean, cov). ``mean`` has shape (n,), ``cov`` (n, n)."""

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

    @property
    def dim(self) -> int:
        return int(self.info_vector.size)

    def to_gaussian(self) -> Gaussian:
        """Moment form: ``P = Y⁻¹``, ``x = P y``."""
        P = solve_psd(self.info_matrix, np.eye(self.dim), where="InformationState.to_gaussian")
        return Gaussian(mean=P @ self.info_vector, cov=symmetrise(P))


@dataclass(frozen=True)
class GaussianMixture:
    """Σ_k w_k N(means[k], covs[k]); weights are normalised on construction.

    ``means`` (K, n), ``covs`` (K, n, n), ``weights`` (K,). ``labels`` are optional per-component
    tags (e.g. track ids) that estimators may carry along.
    """

    means: Array
    covs: Array
    weights: Array
    labels: tuple[object, ...] = field(default=())

    def __post_init__(self) -> None:
        means = np.atleast_2d(np.asarray(self.means, dtype=float))
        covs = np.asarray(self.covs, dtype=float).reshape(means.shape[0], means.shape[1], -1)
        w = np.asarray(self.weights, dtype=float).reshape(-1)
        if covs.shape[1:] != (means.shape[1], means.shape[1]) or w.size != means.shape[0]:
            raise ModelError(
                f"GaussianMixture: shapes means {means.shape}, covs {covs.shape}, weights {w.shape}"
            )
        if np.any(w < 0) or not np.isfinite(w).all() or w.sum() <= 0:
            raise ModelError(f"GaussianMixture: weights must be finite, ≥ 0, not all 0: {w}")
        if self.labels and len(self.labels) != w.size:
            raise ModelError("GaussianMixture: one label per component is required")
        object.__setattr__(self, "means", means)
        object.__setattr__(self, "covs", symmetrise(covs))
        object.__setattr__(self, "weights", w / w.sum())

    @property
    def size(self) -> int:
        return int(self.weights.size)

    def moments(self) -> Gaussian:
        """Moment-matched single Gaussian: mean Σ w m, cov Σ w (P + (m − m̄)(m − m̄)ᵀ)."""
        mean = self.weights @ self.means
        d = self.means - mean
        cov = np.einsum("k,kij->ij", self.weights, self.covs) + np.einsum(
            "k,ki,kj->ij", self.weights, d, d
        )
        return Gaussian(mean=mean, cov=cov)
