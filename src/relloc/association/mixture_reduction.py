"""Reduction of Gaussian mixtures: pruning, merging and a size cap (seed 002 §II-D.5).

One module reduces both kinds of mixture in relloc: the Gaussian-sum fuser's filters
(:mod:`relloc.estimators.gaussian_sum`) and the yaw-hypothesis banks
(:mod:`relloc.estimators.yaw_bank`). Both store many mixtures in one set of arrays
(:class:`relloc.core.gaussian.GaussianMixture`): either as a rectangular batch, one mixture per
leading index with its ``K`` components on the last axis (``weights (..., K)``), or as one flat
list of components labelled by ``groups (K,)`` (components with equal labels form one mixture).
Every function below takes either layout (``groups=None``: the last axis) and never mixes
components of different mixtures.

* **Prune**: keep the components whose weight reaches a threshold, and always the heaviest one
  of each mixture (:func:`prune_mask`). The threshold may be per mixture (a relative threshold
  is ``ratio × max w``).
* **Cap**: keep the ``max_components`` heaviest components of each mixture (:func:`cap_mask`).
* **Merge**, moment preserving (Salmond's joining, as in the GM-PHD filter): greedily, the
  heaviest remaining component ``a`` absorbs every component ``b`` with

      (m_b − m_a)ᵀ P_a⁻¹ (m_b − m_a) ≤ U,

  and, symmetrically, ``(m_a − m_b)ᵀ P_b⁻¹ (m_a − m_b) ≤ U`` (so a broad component — e.g. a new
  track whose yaw is still uniform — is not averaged into a sharp one it merely overlaps), and
  the group ``G`` is replaced by the single Gaussian with the same first two moments
  (:func:`merge_groups`, :func:`merge_moments`)::

      w = Σ_G w_b,   m = Σ_G w_b m_b / w,   P = Σ_G w_b (P_b + (m_b − m)(m_b − m)ᵀ) / w.

  Headings are not wrapped in states; before merging, the heading of each member is moved by a
  multiple of 2π next to the heading of ``a`` (``angle_index``), so the merge happens on the
  circle's local chart and the moments above are exact for the aligned values.
* **Merge by weight** into the heaviest component (:func:`absorb_weights`): the members' weights
  are added to it and its mean and covariance stay. This is the merge for duplicates of a
  hypothesis that has already won (a yaw bank's neighbours that converged onto its best
  component), where averaging the states would only blur the winner.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from relloc.core.angles import wrap_angle
from relloc.core.checks import count
from relloc.errors import ConfigError, ModelError

Array = NDArray[np.float64]
IntArray = NDArray[np.int64]
BoolArray = NDArray[np.bool_]


def align_angles(means: Array, reference: Array, angle_index: int | None) -> Array:
    """Copy of ``means`` whose heading entries lie within π of ``reference``'s heading."""
    if angle_index is None:
        return means
    out = np.array(means, dtype=float, copy=True)
    ref = reference[..., angle_index]
    out[..., angle_index] = ref + wrap_angle(out[..., angle_index] - ref)
    return out


def pairwise_mahalanobis(means: Array, covs: Array, *, angle_index: int | None = None) -> Array:
    """``D[a, b] = max(d_abᵀ P_a⁻¹ d_ab, d_abᵀ P_b⁻¹ d_ab)`` with ``d_ab = m_b − m_a``.

    A singular covariance (``np.linalg.inv`` fails: a component with no spread along some
    direction) has no inverse; its component is a degenerate Gaussian supported on
    ``m + range(P)``, and the distance to it is taken as ``0`` from an identical mean
    (``d_ab = 0``) and ``∞`` otherwise, so it merges only with exact duplicates.
    """
    d = means[None, :, :] - means[:, None, :]
    if angle_index is not None:
        d[..., angle_index] = wrap_angle(d[..., angle_index])
    try:
        inv = np.linalg.inv(covs)
        singular = None
    except np.linalg.LinAlgError:
        inv, singular = _inverses_or_zero(covs)
    d2_a = np.einsum("abi,aij,abj->ab", d, inv, d)
    d2_b = np.einsum("abi,bij,abj->ab", d, inv, d)
    out = np.maximum(d2_a, d2_b)
    if singular is not None:
        involved = singular[:, None] | singular[None, :]
        same = ~np.any(d != 0.0, axis=-1)
        out[involved] = np.where(same[involved], 0.0, np.inf)
    return out


def _inverses_or_zero(covs: Array) -> tuple[Array, BoolArray]:
    """Per-matrix inverses of ``covs (K, n, n)``, zeros where one is singular, and which are."""
    inv = np.zeros_like(covs, dtype=float)
    singular = np.zeros(covs.shape[0], dtype=bool)
    for k in range(covs.shape[0]):
        try:
            inv[k] = np.linalg.inv(covs[k])
        except np.linalg.LinAlgError:
            singular[k] = True
    return inv, singular


def merge_groups(
    means: Array,
    covs: Array,
    weights: Array,
    threshold: float,
    *,
    angle_index: int | None = None,
    groups: IntArray | None = None,
) -> list[IntArray]:
    """Greedy Mahalanobis grouping of flat components (module docstring); heaviest first.

    ``groups`` labels independent mixtures sharing the arrays: components of different
    mixtures are never merged.
    """
    if threshold < 0.0 or not np.isfinite(threshold):
        raise ModelError(f"merge_groups: threshold must be finite and ≥ 0, got {threshold}")
    close = pairwise_mahalanobis(means, covs, angle_index=angle_index) <= threshold
    if groups is not None:
        close &= groups[:, None] == groups[None, :]
    free = np.ones(weights.size, dtype=bool)
    out: list[IntArray] = []
    for a in np.argsort(-weights, kind="stable"):
        if not free[a]:
            continue
        members = np.flatnonzero(close[a] & free)
        members = np.concatenate([[a], members[members != a]]).astype(np.int64)
        free[members] = False
        out.append(members)
    return out


def merge_moments(
    means: Array,
    covs: Array,
    weights: Array,
    group: IntArray,
    *,
    angle_index: int | None = None,
) -> tuple[Array, Array, float]:
    """Moment-preserving merge of the components ``group`` → ``(mean, cov, weight)``.

    The first index of ``group`` is the reference for heading alignment. The moments depend
    only on the ratios ``w_b / Σ w``, so they are computed with the weights scaled by a power
    of two, ``2⁻ᵉ w`` with ``2ᵉ⁻¹ ≤ Σ w < 2ᵉ`` (``max w`` in place of ``Σ w`` when the sum
    overflows). That scaling is exact in floating point: every product and quotient is the
    unscaled one, bit for bit, wherever that neither underflows nor overflows; and weights
    near the subnormal range (whose products with the means underflow to 0) or near overflow
    (whose sum is ∞) still give the right moments. The returned weight is the unscaled
    ``Σ w``; a group whose total is not > 0, or holding an infinite weight, is a ModelError.
    """
    w = weights[group]
    total = float(w.sum())
    if not total > 0.0:
        raise ModelError(f"merge_moments: the group's total weight must be > 0, got {total}")
    if math.isfinite(total):
        e = math.frexp(total)[1]
        w = np.ldexp(w, -e)
        scaled_total = math.ldexp(total, -e)
    else:
        largest = float(np.max(w))
        if not math.isfinite(largest):
            raise ModelError(f"merge_moments: a weight is not finite ({largest})")
        w = np.ldexp(w, -math.frexp(largest)[1])
        scaled_total = float(w.sum())
    m = align_angles(means[group], means[group[0]], angle_index)
    mean = (w @ m) / scaled_total
    d = m - mean
    cov = (
        np.einsum("k,kij->ij", w, covs[group]) + np.einsum("k,ki,kj->ij", w, d, d)
    ) / scaled_total
    return mean, 0.5 * (cov + cov.T), total


def absorb_weights(weights: Array, into: BoolArray, members: BoolArray) -> Array:
    """Merge by weight along the last axis (module docstring).

    ``into`` marks one component per mixture (``(..., K)``, usually :func:`heaviest_mask`); it
    takes the summed weight of the components ``members`` marks, whose weights become 0.
    """
    absorbed = members & ~into
    total = np.sum(np.where(absorbed, weights, 0.0), axis=-1, keepdims=True)
    return np.asarray(np.where(absorbed, 0.0, np.where(into, weights + total, weights)))


def heaviest_mask(weights: Array, groups: IntArray | None = None) -> BoolArray:
    """``True`` at the heaviest component of each mixture (ties: the lowest index).

    ``weights (..., K)`` with ``groups=None`` (one mixture per leading index), or flat
    ``weights (K,)`` labelled by ``groups (K,)``. Only the order of the weights matters, so log
    weights give the same mask.
    """
    if weights.shape[-1] == 0:
        return np.zeros(weights.shape, dtype=bool)
    if groups is None:
        return np.asarray(np.arange(weights.shape[-1]) == np.argmax(weights, axis=-1)[..., None])
    mask = np.zeros(weights.size, dtype=bool)
    order = np.lexsort((-weights, groups))
    first = np.ones(order.size, dtype=bool)
    first[1:] = groups[order][1:] != groups[order][:-1]
    mask[order[first]] = True
    return mask


def prune_mask(
    weights: Array, threshold: float | Array, groups: IntArray | None = None
) -> BoolArray:
    """Components to keep: weight ≥ ``threshold`` (a number, or one per mixture broadcasting
    against ``weights``), and always the heaviest one of each mixture."""
    return np.asarray((weights >= threshold) | heaviest_mask(weights, groups))


def cap_mask(weights: Array, max_components: int, groups: IntArray | None = None) -> BoolArray:
    """Components to keep: the ``max_components`` heaviest of each mixture (ties: the lower
    index first), in either layout (see :func:`heaviest_mask`). ``max_components`` must be an
    integer ≥ 1 (:func:`relloc.core.checks.count`), else ModelError."""
    try:
        count(max_components, "cap_mask: max_components")
    except ConfigError as exc:
        raise ModelError(str(exc)) from exc
    if groups is None:
        order = np.argsort(-weights, axis=-1, kind="stable")
        rank = np.empty_like(order)
        np.put_along_axis(rank, order, np.arange(weights.shape[-1]), axis=-1)
        return np.asarray(rank < max_components)
    order = np.lexsort((-weights, groups))
    sorted_groups = groups[order]
    rank = np.arange(order.size) - np.searchsorted(sorted_groups, sorted_groups, side="left")
    mask = np.zeros(weights.size, dtype=bool)
    mask[order[rank < max_components]] = True
    return mask
