"""Global nearest-neighbour assignment of measurements to targets.

The Gaussian-sum filters of one fuser weigh every association hypothesis separately; when a
single decision is needed (which teammate produced which bearing, for the association-accuracy
figures) the fuser solves the 2-D assignment problem

    min Σ_t c[t, a(t)]   over one-to-one maps a: targets → measurements ∪ {missed},

where ``c[t, r] = −log(P_D N(z_r; ẑ_t, S_t) / κ)`` and a missed target costs
``−log(1 − P_D P_G)``. It is solved with ``scipy.optimize.linear_sum_assignment`` on the matrix
augmented by one private "missed" column per target.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import linear_sum_assignment

from relloc.errors import ModelError

Array = NDArray[np.float64]

#: Finite stand-in for a forbidden pairing (linear_sum_assignment rejects infeasible rows).
_FORBIDDEN = 1e12


def assign(cost: Array, miss_cost: Array) -> NDArray[np.int64]:
    """Best one-to-one assignment; returns for each target the measurement index or −1.

    Args:
        cost: (T, M) assignment costs, ``inf`` where a pairing is not allowed (outside gate).
        miss_cost: (T,) cost of leaving each target without a measurement.

    A NaN or ``−inf`` cost (no pairing is infinitely good) or a non-finite miss cost is a
    ModelError; a row of ``inf`` leaves its target missed.
    """
    cost = np.asarray(cost, dtype=float)
    miss_cost = np.asarray(miss_cost, dtype=float).reshape(-1)
    if cost.ndim != 2 or miss_cost.size != cost.shape[0]:
        raise ModelError(f"assign: cost {cost.shape} and miss_cost {miss_cost.shape} disagree")
    if np.isnan(cost).any() or np.isneginf(cost).any() or not np.isfinite(miss_cost).all():
        raise ModelError("assign: NaN cost, −inf cost or non-finite miss cost")
    n_t, n_m = cost.shape
    big = np.full((n_t, n_m + n_t), _FORBIDDEN)
    big[:, :n_m] = np.where(np.isfinite(cost), cost, _FORBIDDEN)
    big[np.arange(n_t), n_m + np.arange(n_t)] = miss_cost
    rows, cols = linear_sum_assignment(big)
    out = np.full(n_t, -1, dtype=np.int64)
    for t, c in zip(rows, cols, strict=True):
        if c < n_m and big[t, c] < _FORBIDDEN:
            out[t] = c
    return out
