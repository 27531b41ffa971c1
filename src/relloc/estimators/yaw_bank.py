"""A bank of relative-yaw hypotheses: relloc's initialisation for an unknown relative yaw.

Why. The relative yaw φ of seed 000 Eq. 1 is observed only through the observed robot's
motion: the predicted displacement ``R(φ̂) v_c dt`` is compared with the measured one. The
correction a single Kalman filter makes is, to first order, proportional to ``sin(φ − φ̂)``,
which vanishes at an error of π. From a yaw guess near the wrong side of the circle both the
TEKF and the PLKF therefore sit near this unstable equilibrium for a long time (seed 000
Table 1 reports 263 TEKF updates in case 4; single runs can take far longer).

What. The prior over φ is replaced by a Gaussian sum whose ``K`` components sit evenly on the
circle, ``φ_k = φ̂₀ + 2πk/K`` (``k = 0 … K−1``), each with standard deviation
``σ_c = π/K`` (half the spacing) and the prior's position block. Every component is a full
relative filter run with the shared predict and the configured update of
:mod:`relloc.estimators.relative` (the PLKF by default). After each measurement the weights
follow Bayes' rule with the component's innovation likelihood (a Gaussian-sum filter,
Alspach & Sorenson, IEEE TAC 17(4), 1972)::

    w_k ← w_k · N(ν_k; 0, S_k),   log w_k ← log w_k − ½ (ν_kᵀ S_k⁻¹ ν_k + log det S_k)

(the constant ``−(m/2) log 2π`` is common to all components and dropped), then

* **pruning**: a component whose weight falls below ``prune_ratio`` times the largest weight
  is dropped;
* **merging**: neighbouring hypotheses that have converged onto the best one (yaw within
  ``merge_sigmas`` standard deviations of the difference, ``|φ_k − φ_best| ≤ n √(P_k,φφ +
  P_best,φφ)``) are absorbed into it (their weights added), so duplicates of the winning
  hypothesis do not keep the bank from collapsing;
* **collapse**: once one component holds at least ``collapse_weight`` of the total weight the
  bank keeps only that component and is an ordinary single filter from then on.

The estimate is the highest-weight component (its mean and covariance); a moment-matched
mean would average headings that are far apart on the circle and sit between the modes.

Batching. A bank is a :class:`~relloc.core.gaussian.GaussianMixture` in the rectangular layout,
with any leading batch shape: ``means (..., K, 4)``, ``covs (..., K, 4, 4)``,
``weights (..., K)``. Bayes' rule runs on the log weights (the likelihoods of far-off
hypotheses underflow) and is shifted so that the best weight is 1 before going back to weights.
A dropped component keeps its slot (the arrays stay rectangular so many banks update in one
numpy call): its weight is 0 and its state is overwritten with the surviving best component, so
it costs arithmetic but can never be chosen, revived or make an update fail.

A prior whose yaw standard deviation is below ``spread_above`` is not spread: the bank is that
single filter (``K = 1``), so known-yaw cases run unchanged.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from relloc.association.mixture_reduction import absorb_weights, heaviest_mask, prune_mask
from relloc.core.angles import angle_diff
from relloc.core.checks import number, positive, probability
from relloc.core.gaussian import Gaussian, GaussianMixture
from relloc.core.kalman import Innovation
from relloc.errors import ConfigError, ModelError
from relloc.estimators.relative import FilterSettings, predict_arrays
from relloc.models.motion import VelocityNoise

Array = NDArray[np.float64]

YAW = 3


@dataclass(frozen=True, kw_only=True)
class YawBankSettings:
    """How the bank is spread and reduced.

    Attributes:
        n_components: hypotheses ``K`` spread evenly over the circle.
        spread_above: a prior yaw σ (rad) below this is kept as one component.
        prune_ratio: drop components with weight < ``prune_ratio`` × the largest weight.
        merge_sigmas: absorb components whose yaw is this many σ of the difference from the
            best one.
        collapse_weight: keep only the best component once its weight reaches this fraction.
    """

    n_components: int = 12
    spread_above: float = 0.5
    prune_ratio: float = 1e-3
    merge_sigmas: float = 1.0
    collapse_weight: float = 0.99

    def __post_init__(self) -> None:
        if not isinstance(self.n_components, int) or not 2 <= self.n_components <= 64:
            raise ConfigError(
                f"YawBankSettings.n_components: an integer in [2, 64], got {self.n_components!r}"
            )
        positive(self.spread_above, "YawBankSettings.spread_above")
        probability(self.prune_ratio, "YawBankSettings.prune_ratio")
        number(self.merge_sigmas, "YawBankSettings.merge_sigmas", low=0.0)
        number(
            self.collapse_weight,
            "YawBankSettings.collapse_weight",
            low=0.5,
            high=1.0,
            open_low=True,
        )

    @property
    def component_sigma(self) -> float:
        """σ_c = π/K: half the spacing 2π/K between neighbouring hypotheses."""
        return math.pi / self.n_components


def spread_yaw_bank(
    prior_mean: ArrayLike, prior_cov: ArrayLike, settings: YawBankSettings
) -> GaussianMixture:
    """Bank for a prior ``N(prior_mean, prior_cov)`` over ``(x, y, z, φ)`` (batched).

    If every prior yaw σ is at least ``spread_above`` the bank has ``K`` components at
    ``φ̂₀ + 2πk/K`` with σ_c = π/K, the yaw–position cross-covariance removed (each component
    fixes φ) and equal weights; otherwise it is the prior as a single component.
    """
    mean = np.asarray(prior_mean, dtype=float)
    cov = np.asarray(prior_cov, dtype=float)
    if mean.shape[-1:] != (4,) or cov.shape != (*mean.shape, 4):
        raise ModelError(f"spread_yaw_bank: prior shapes {mean.shape}, {cov.shape}")
    sigma_yaw = np.sqrt(cov[..., YAW, YAW])
    if np.all(sigma_yaw < settings.spread_above):
        return GaussianMixture(
            means=mean[..., None, :],
            covs=cov[..., None, :, :],
            weights=np.ones((*mean.shape[:-1], 1)),
        )
    if np.any(sigma_yaw < settings.spread_above):
        raise ModelError(
            "spread_yaw_bank: a batch must be all unknown-yaw or all known-yaw priors "
            f"(yaw σ {sigma_yaw.min():.3g} … {sigma_yaw.max():.3g}, threshold "
            f"{settings.spread_above})"
        )
    K = settings.n_components
    offsets = 2.0 * math.pi * np.arange(K) / K
    means = np.repeat(mean[..., None, :], K, axis=-2)
    yaw = mean[..., None, YAW] + offsets
    means[..., YAW] = np.arctan2(np.sin(yaw), np.cos(yaw))  # construction, not a state wrap
    covs = np.repeat(cov[..., None, :, :], K, axis=-3)
    covs[..., YAW, :] = 0.0
    covs[..., :, YAW] = 0.0
    covs[..., YAW, YAW] = settings.component_sigma**2
    return GaussianMixture(means=means, covs=covs, weights=np.ones((*mean.shape[:-1], K)))


def predict_yaw_bank(
    bank: GaussianMixture,
    u_l: ArrayLike,
    u_c: ArrayLike,
    dt: float,
    noise: VelocityNoise,
    *,
    where: str = "yaw bank",
) -> GaussianMixture:
    """Shared predict of every component (inputs broadcast over the component axis); an error
    names ``where`` (a track manager passes its pair)."""
    u_l = np.asarray(u_l, dtype=float)[..., None, :]
    u_c = np.asarray(u_c, dtype=float)[..., None, :]
    means, covs = predict_arrays(bank.means, bank.covs, u_l, u_c, dt, noise, where=where)
    return GaussianMixture(means=means, covs=covs, weights=bank.weights)


def reweight(weights: Array, innovation: Innovation) -> Array:
    """Bayes' rule on the weights: ``log w_k − ½ (NIS_k + log det S_k)``, shifted so that the
    best weight of each bank is 1; empty slots stay 0."""
    _, logdet = np.linalg.slogdet(innovation.cov)
    with np.errstate(divide="ignore"):
        log_w = np.log(weights)
    lw = log_w - 0.5 * (np.asarray(innovation.nis) + logdet)
    lw = np.where(np.isfinite(log_w), lw, -np.inf)
    return np.asarray(np.exp(lw - np.max(lw, axis=-1, keepdims=True)))


def reduce_bank(bank: GaussianMixture, settings: YawBankSettings) -> GaussianMixture:
    """Merge into the best component, prune below ``prune_ratio`` × best, collapse if dominant.

    The steps are those of :mod:`relloc.association.mixture_reduction`, along the component
    axis: merge by weight (:func:`absorb_weights`) into the best component
    (:func:`heaviest_mask`), prune with a relative threshold (:func:`prune_mask`), and keep only
    the best component of a bank where it holds ``collapse_weight``. Dropped slots get weight 0
    and the best component's state (see module docstring).
    """
    is_best = heaviest_mask(bank.weights)
    mean, cov = bank.heaviest()
    w = bank.weights / np.max(bank.weights, axis=-1, keepdims=True)
    d_yaw = np.abs(angle_diff(bank.means[..., YAW], mean[..., None, YAW]))
    spread = np.sqrt(bank.covs[..., YAW, YAW] + cov[..., None, YAW, YAW])
    w = absorb_weights(w, is_best, d_yaw <= settings.merge_sigmas * spread)
    keep = prune_mask(w, settings.prune_ratio * np.max(w, axis=-1, keepdims=True))
    w = np.where(keep, w, 0.0)
    w = w / w.sum(axis=-1, keepdims=True)
    dominant = np.max(w, axis=-1) >= settings.collapse_weight
    keep = np.where(dominant[..., None], is_best, keep)
    new_w = np.where(keep, w, 0.0)
    if keep.all():
        return GaussianMixture(means=bank.means, covs=bank.covs, weights=new_w)
    means = np.where(keep[..., None], bank.means, mean[..., None, :])
    covs = np.where(keep[..., None, None], bank.covs, cov[..., None, :, :])
    return GaussianMixture(means=means, covs=covs, weights=new_w)


def update_yaw_bank(
    bank: GaussianMixture,
    z: ArrayLike,
    filter_settings: FilterSettings,
    settings: YawBankSettings,
    *,
    where: str = "yaw bank",
) -> tuple[GaussianMixture, Innovation]:
    """Update every component with ``z (..., 3)``, reweight, prune and collapse.

    Returns the new bank and the innovation of every component (shapes ``(..., K, ...)``); an
    error names ``where``.
    """
    z = np.asarray(z, dtype=float)[..., None, :]
    means, covs, innovation = filter_settings.update_arrays(bank.means, bank.covs, z, where=where)
    updated = GaussianMixture(means=means, covs=covs, weights=reweight(bank.weights, innovation))
    return reduce_bank(updated, settings), innovation


class YawBankTracker:
    """Stateful single-pair wrapper around a yaw bank (same interface as
    :class:`relloc.estimators.relative.RelativeTracker`): ``predict``, ``update``, ``belief``."""

    def __init__(
        self,
        prior: Gaussian,
        filter_settings: FilterSettings,
        settings: YawBankSettings | None = None,
        *,
        label: str = "",
    ) -> None:
        if prior.dim != 4:
            raise ModelError(f"YawBankTracker {label}: prior must be a RelPose4 (4 states)")
        self.settings = settings or YawBankSettings()
        self.filter_settings = filter_settings
        self.label = label
        self._bank = spread_yaw_bank(prior.mean, prior.cov, self.settings)

    @property
    def bank(self) -> GaussianMixture:
        """The current Gaussian sum."""
        return self._bank

    @property
    def n_alive(self) -> int:
        """Hypotheses still in the bank."""
        return int(self._bank.alive.sum())

    @property
    def belief(self) -> Gaussian:
        """The highest-weight hypothesis."""
        mean, cov = self._bank.heaviest()
        return Gaussian(mean=mean, cov=cov)

    def predict(self, u_l: ArrayLike, u_c: ArrayLike, dt: float) -> Gaussian:
        """Propagate every hypothesis by ``dt``; returns the best one."""
        self._bank = predict_yaw_bank(self._bank, u_l, u_c, dt, self.filter_settings.motion_noise)
        return self.belief

    def update(self, z: ArrayLike) -> Innovation:
        """Fuse ``z = (r, θ, α)``; returns the innovation of the (new) best hypothesis."""
        self._bank, innovation = update_yaw_bank(self._bank, z, self.filter_settings, self.settings)
        k = int(self._bank.heaviest_index)
        return Innovation(
            residual=innovation.residual[k],
            cov=innovation.cov[k],
            nis=float(np.asarray(innovation.nis)[k]),
            meas_cov=innovation.meas_cov[k],
        )
