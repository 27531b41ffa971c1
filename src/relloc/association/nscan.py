"""N-scan pruning of track families (seed 002 §II-D.5).

Every track carries the identifiers of its ancestors over the last ``N`` branching scans as a
row ``history = [a_{k−N}, …, a_{k−1}, a_k]``; when a track branches at a scan (false alarm,
detected with each gated measurement, born) every child gets a fresh identifier appended and
the oldest one dropped. Tracks sharing ``a_{k−N}`` descend from the same track ``N`` scans
ago and form a *family*; a family whose summed weight is below a threshold is deleted. The
family of the heaviest track is always kept, so the filter never empties itself.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from relloc.association.mixture_reduction import heaviest_mask
from relloc.core.checks import count
from relloc.errors import ConfigError, ModelError

IntArray = NDArray[np.int64]


def new_history(ids: IntArray, depth: int) -> IntArray:
    """Histories for freshly born tracks: their own id repeated (they are their own root).

    ``depth`` must be an integer ≥ 1 (:func:`relloc.core.checks.count`), else ModelError."""
    try:
        count(depth, "new_history: depth N")
    except ConfigError as exc:
        raise ModelError(str(exc)) from exc
    ids = np.asarray(ids, dtype=np.int64).reshape(-1)
    return np.repeat(ids[:, None], depth + 1, axis=1)


def branch(history: IntArray, parent: IntArray, child_ids: IntArray) -> IntArray:
    """Histories of children: parent's row shifted left, the child's own id appended."""
    rows = history[np.asarray(parent, dtype=np.int64)]
    return np.concatenate([rows[:, 1:], np.asarray(child_ids, dtype=np.int64)[:, None]], axis=1)


def family_keep_mask(
    history: IntArray,
    weights: NDArray[np.float64],
    threshold: float,
    groups: IntArray | None = None,
) -> NDArray[np.bool_]:
    """Tracks whose family (shared ``history[:, 0]``) has total weight ≥ ``threshold``.

    ``groups`` labels independent mixtures sharing the arrays (identifiers must be unique
    across them); the family of each group's heaviest track is always kept.
    """
    if history.ndim != 2 or history.shape[0] != weights.size:
        raise ModelError(
            f"family_keep_mask: one history row per weight is required, got history "
            f"{history.shape} for {weights.size} weights"
        )
    if weights.size == 0:
        return np.zeros(0, dtype=bool)
    roots, inverse = np.unique(history[:, 0], return_inverse=True)
    family_weight = np.bincount(inverse, weights=weights, minlength=roots.size)
    keep_family = family_weight >= threshold
    keep_family[inverse[heaviest_mask(weights, groups)]] = True
    return np.asarray(keep_family[inverse])
