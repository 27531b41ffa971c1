"""Covariance conditioning ``C = log10(λmax / λmin)`` (seed 000 Eq. 36), batched.

The batched counterpart of :func:`relloc.core.condition_log10`: a stack ``(..., n, n)`` gives
``(...,)``; a matrix with ``λmin ≤ 0`` gives ``inf``. Values above 6 indicate ill-conditioning
(seed 000 §7.3).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from relloc.core.checks import floats
from relloc.errors import ModelError

Array = NDArray[np.float64]

#: Conditioning above this is considered ill-conditioned (seed 000 §7.3).
ILL_CONDITIONED_LOG10 = 6.0


def condition_log10_batch(M: ArrayLike) -> Array:
    """``log10(λmax/λmin)`` of each symmetric matrix in a stack ``(..., n, n)``.

    The matrices must be square with ``n ≥ 1`` (a stack of none, ``(0, n, n)``, gives ``(0,)``);
    an empty ``(0, 0)`` matrix, a non-square one or fewer than two axes is a
    :class:`ModelError`; entries that are not real numbers (text, booleans, ``None``) are a
    :class:`~relloc.errors.DataError`."""
    A = floats(M, "condition_log10_batch: M")
    if A.ndim < 2 or A.shape[-1] != A.shape[-2] or A.shape[-1] == 0:
        raise ModelError(
            f"condition_log10_batch: expected square matrices (..., n, n), n ≥ 1, got {A.shape}"
        )
    eig = np.linalg.eigvalsh(0.5 * (A + np.swapaxes(A, -1, -2)))
    lo, hi = eig[..., 0], eig[..., -1]
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(lo > 0.0, np.log10(hi / np.where(lo > 0.0, lo, 1.0)), np.inf)
