"""Numeric rank of observability matrices: double precision SVD and an mpmath cross-check.

Rows of an observability matrix have wildly different scales (gradients of higher-order Lie
derivatives carry powers of ranges and speeds), so every non-zero row is normalised to unit
length before the SVD; the rank is the number of singular values above ``rtol · σ_max``.
Normalising rows does not change the rank.

Every tolerance is *relative*, so the rank of ``c·M`` is that of ``M`` for any ``c > 0`` (a
matrix whose entries are all 1e-13 is as full-rank as the identity): a row is dropped as zero
when its norm is at most :data:`ROW_RTOL` times the largest row norm (or exactly zero), and a
singular value counts when it exceeds :data:`RANK_RTOL` times the largest one. Noise at the
1e-12 level on a rank-deficient matrix stays below :data:`RANK_RTOL` and does not raise the
rank. Column (state-unit) scaling is *not* undone: a state whose column is 1e-8 times smaller
than the others, in every row, reads as unobservable; express states in comparable units.

The mpmath variant repeats the computation with ``dps`` significant digits so that a rank
decision does not hinge on double rounding.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable

import numpy as np
from numpy.typing import NDArray

from relloc.errors import ModelError

Array = NDArray[np.float64]

#: Singular values below ``RANK_RTOL · σ_max`` count as zero in double precision.
RANK_RTOL = 1e-8
#: Rows with norm ≤ ``ROW_RTOL ·`` (largest row norm) are treated as zero rows (module doc).
ROW_RTOL = 1e-12


def normalise_rows(M: Array) -> Array:
    """Drop (numerically) zero rows and scale the others to unit Euclidean norm.

    A row is zero when its norm is ``≤ ROW_RTOL ·`` the largest row norm: relative, so the
    decision does not depend on the overall scale of ``M`` (module doc). Non-finite entries are
    a :class:`ModelError`.
    """
    A, keep = unit_rows(M)
    return A[keep]


def unit_rows(M: Array) -> tuple[Array, NDArray[np.bool_]]:
    """Every row of ``M`` scaled to unit norm (zero rows left as they are) and the mask of the
    rows :func:`normalise_rows` keeps (same rule; row indices preserved)."""
    M = np.asarray(M, dtype=float)
    if not np.all(np.isfinite(M)):
        raise ModelError(
            "observability matrix has non-finite entries (a singular configuration, e.g. two "
            "bodies at one point, or values beyond double precision)"
        )
    top = float(np.max(np.abs(M), initial=0.0))
    if top > 0.0:  # rescale first: row norms neither overflow nor underflow
        M = M / top
    norms = np.linalg.norm(M, axis=1)
    keep = norms > ROW_RTOL * float(norms.max(initial=0.0))
    return M / np.where(keep, norms, 1.0)[:, None], keep


def singular_values(M: Array) -> Array:
    """Singular values of the row-normalised matrix (length ``n``, zeros padded)."""
    M = np.asarray(M, dtype=float)
    return padded_singular_values(normalise_rows(M), M.shape[1])


def padded_singular_values(A: Array, n: int) -> Array:
    """Singular values (length ``n``, zeros padded) of ``A``, taken as already row-normalised
    (or an orthogonal transform of such rows, e.g. a triangular factor): no rescaling here."""
    A = np.asarray(A, dtype=float).reshape(-1, n)
    out = np.zeros(n)
    if A.shape[0]:
        if A.shape[0] > 2 * n:  # tall: the triangular factor has the same singular values
            A = np.asarray(np.linalg.qr(A, mode="r"), dtype=float)
        sv = np.linalg.svd(A, compute_uv=False)
        out[: sv.size] = sv[:n]
    return out


def stacked_singular_values(chunks: Iterable[Array], n: int) -> Array:
    """Singular values (length ``n``, zeros padded) of the rows of every chunk ``(k_i, n)``
    stacked, without stacking them: the running triangular factor ``R ← qr([R; chunk])`` is an
    orthogonal transform of all rows so far, so its singular values are theirs, while memory
    stays a few chunks (the chunk, its copy under ``R`` and the QR's working copy) instead of
    all rows (rows taken as already normalised, as in :func:`padded_singular_values`). A chunk
    that is not ``(k, n)`` is a :class:`ModelError`."""
    R = np.zeros((0, n))
    for chunk in chunks:
        rows = np.asarray(chunk, dtype=float)
        if rows.ndim != 2 or rows.shape[1] != n:
            raise ModelError(
                f"stacked_singular_values: a chunk of shape {rows.shape} for {n} columns"
            )
        R = np.vstack([R, rows]) if R.shape[0] else rows
        if R.shape[0] > n:
            R = np.asarray(np.linalg.qr(R, mode="r"), dtype=float)
    return padded_singular_values(R, n)


def rank_from_singular_values(sv: Array, *, rtol: float = RANK_RTOL) -> int:
    """Number of singular values above ``rtol · σ_max``."""
    if sv.size == 0 or sv[0] == 0.0:
        return 0
    return int(np.count_nonzero(sv > rtol * sv[0]))


def numeric_rank(M: Array, *, rtol: float = RANK_RTOL) -> int:
    """Rank of ``M`` after row normalisation (module doc)."""
    return rank_from_singular_values(singular_values(M), rtol=rtol)


def null_space(M: Array, rank: int) -> Array:
    """Orthonormal basis ``(n − rank, n)`` of the numeric null space of ``M``."""
    A = normalise_rows(M)
    n = np.asarray(M).shape[1]
    if A.shape[0] == 0:
        return np.eye(n)
    _, _, Vt = np.linalg.svd(A, full_matrices=True)
    return Vt[rank:]


def precise_rank(
    evaluator: Callable[..., object], state: Array, params: Array, *, dps: int = 50
) -> int:
    """Rank with ``dps``-digit arithmetic (mpmath); threshold ``10^(−dps/2)``."""
    import mpmath

    with mpmath.workdps(dps):
        args = [mpmath.mpf(float(v)) for v in state], [mpmath.mpf(float(v)) for v in params]
        M = mpmath.matrix(evaluator(*args))
        rows = []
        for i in range(M.rows):
            row = [M[i, j] for j in range(M.cols)]
            norm = mpmath.sqrt(sum(v * v for v in row))
            if norm > mpmath.mpf(10) ** (-dps // 2):
                rows.append([v / norm for v in row])
        if not rows:
            return 0
        sv = mpmath.svd_r(mpmath.matrix(rows), compute_uv=False)
        top = max(abs(s) for s in sv)
        return int(sum(1 for s in sv if abs(s) > top * mpmath.mpf(10) ** (-dps // 2)))
