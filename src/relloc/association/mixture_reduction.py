"""Reduction of a Gaussian mixture: low-weight pruning, Mahalanobis merging and a size cap.

Seed 002 §II-D.5 limits the growth of hypotheses by deleting tracks of low weight and
combining tracks that lie within a Mahalanobis distance of each other. Merging here is greedy
and moment preserving (Salmond's joining, as in the GM-PHD filter): the heaviest remaining
component ``a`` absorbs every component ``b`` with

    (m_b − m_a)ᵀ P_a⁻¹ (m_b − m_a) ≤ U,

and, symmetrically, ``(m_a − m_b)ᵀ P_b⁻¹ (m_a − m_b) ≤ U`` (so a broad component — e.g. a new
track whose yaw is still uniform — is not averaged into a sharp one it merely overlaps), and
the group ``G`` is replaced by the single Gaussian with the same first two moments::

    w = Σ_G w_b,   m = Σ_G w_b m_b / w,   P = Σ_G w_b (P_b + (m_b − m)(m_b − m)ᵀ) / w.

Headings are not wrapped in states; before merging, the heading of each member is moved by a
multiple of 2π next to the heading of ``a`` (``angle_index``), so the merge happens on the
circle's local chart and the moments above are exact for the aligned values.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from relloc.core.angles import wrap_angle
from relloc.errors import ModelError

Array = NDArray[np.float64]
IntArray = NDArray[np.int64]


def align_angles(means: Array, reference: Array, angle_index: int | None) -> Array:
    """Copy of ``means`` whose heading entries lie within π of ``reference``'s heading."""
    if angle_index is None:
        return means
    out = np.array(means, dtype=float, copy=True)
    ref = reference[..., angle_index]
    out[..., angle_index] = ref + wrap_angle(out[..., angle_index] - ref)
    return out


def pairwise_mahalanobis(means: Array, covs: Array, *, angle_index: int | None = None) -> Array:
    """``D[a, b] = max(d_abᵀ P_a⁻¹ d_ab, d_abᵀ P_b⁻¹ d_ab)`` with ``d_ab = m_b − m_a``."""
    d = means[None, :, :] - means[:, None, :]
    if angle_index is not None:
        d[..., angle_index] = wrap_angle(d[..., angle_index])
    inv = np.linalg.inv(covs)
    d2_a = np.einsum("abi,aij,abj->ab", d, inv, d)
    d2_b = np.einsum("abi,bij,abj->ab", d, inv, d)
    return np.maximum(d2_a, d2_b)


def merge_groups(
    means: Array,
    covs: Array,
    weights: Array,
    threshold: float,
    *,
    angle_index: int | None = None,
    groups: IntArray | None = None,
) -> list[IntArray]:
    """Greedy Mahalanobis grouping (module docstring); groups listed heaviest first.

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

    The first index of ``group`` is the reference for heading alignment.
    """
    w = weights[group]
    total = float(w.sum())
    if total <= 0.0:
        raise ModelError("merge_moments: the group has zero total weight")
    m = align_angles(means[group], means[group[0]], angle_index)
    mean = (w @ m) / total
    d = m - mean
    cov = (np.einsum("k,kij->ij", w, covs[group]) + np.einsum("k,ki,kj->ij", w, d, d)) / total
    return mean, 0.5 * (cov + cov.T), total


def heaviest_mask(weights: Array, groups: IntArray | None = None) -> NDArray[np.bool_]:
    """``True`` at the heaviest component of each group (of the whole mixture if ``None``)."""
    mask = np.zeros(weights.size, dtype=bool)
    if weights.size == 0:
        return mask
    if groups is None:
        mask[int(np.argmax(weights))] = True
        return mask
    order = np.lexsort((-weights, groups))
    first = np.ones(order.size, dtype=bool)
    first[1:] = groups[order][1:] != groups[order][:-1]
    mask[order[first]] = True
    return mask


def prune_mask(
    weights: Array, threshold: float, groups: IntArray | None = None
) -> NDArray[np.bool_]:
    """Components to keep: weight ≥ threshold, and always the heaviest one (of each group)."""
    return np.asarray((weights >= threshold) | heaviest_mask(weights, groups))


def cap_indices(weights: Array, max_components: int) -> IntArray:
    """Indices of the ``max_components`` heaviest components (heaviest first)."""
    if max_components < 1:
        raise ModelError(f"cap_indices: max_components must be ≥ 1, got {max_components}")
    order = np.argsort(-weights, kind="stable")
    return np.asarray(order[:max_components], dtype=np.int64)
