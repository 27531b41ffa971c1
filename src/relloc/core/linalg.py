"""PSD-safe linear algebra shared by every estimator.

All functions are pure and accept a leading batch dimension where stated.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from relloc.errors import ModelError

Array = NDArray[np.float64]


def symmetrise(P: Array) -> Array:
    """Return ``(P + Pᵀ)/2`` (works on a stack ``(..., n, n)``). An exactly symmetric ``P``
    comes back unchanged (``(a + a)/2 = a`` in floating point)."""
    S = np.asarray(P + np.swapaxes(P, -1, -2), dtype=float)
    S *= 0.5  # (in place: one temporary less than 0.5 * (P + Pᵀ), the same numbers)
    return S


#: Relative asymmetry ``|P_ij − P_ji| / √(P_ii P_jj)`` up to which a covariance counts as
#: symmetric (rounding of a symmetric computation stays many orders below it).
SYMMETRY_RTOL = 1e-9


def symmetric_within(P: Array, rtol: float = SYMMETRY_RTOL) -> bool:
    """Whether every covariance of the stack ``P (..., n, n)`` is symmetric: ``|P_ij − P_ji| ≤
    rtol · √(P_ii P_jj)`` for every entry. A received or hand-built covariance is checked with it
    before use: a Cholesky factorisation or ``eigvalsh`` reads one triangle only, so an upper
    triangle unlike the lower one would pass them and reach the filter, which symmetrises, as a
    different and possibly indefinite matrix. Call it on matrices with a positive diagonal."""
    P = np.asarray(P, dtype=float)
    diag = np.diagonal(P, 0, -2, -1)
    tolerance = rtol * np.sqrt(diag[..., :, None] * diag[..., None, :])
    return not bool(np.any(np.abs(P - np.swapaxes(P, -1, -2)) > tolerance))


def cholesky(P: Array, *, where: str = "", symmetric: bool = False) -> Array:
    """Lower Cholesky factor of ``P``; raises :class:`ModelError` naming ``where`` if ``P`` is not
    finite and positive definite (works on a stack ``(..., n, n)``).

    ``P`` is symmetrised first unless ``symmetric`` says it is exactly symmetric already (the
    output of :func:`symmetrise`, whose symmetrisation would change nothing). Where every
    eigenvalue is positive but the factorisation still fails, the message gives the condition
    number: the matrix is positive definite only beyond double precision. On a stack the
    message names the first bad matrix (the worst-conditioned one in that case) and gives its
    eigenvalues only.
    """
    S = P if symmetric else symmetrise(P)
    L: Array | None
    try:
        L = np.asarray(np.linalg.cholesky(S), dtype=float)
    except np.linalg.LinAlgError:
        L = None
    # numpy factors a NaN matrix without complaint; a NaN or infinity in S reaches its factor
    if L is not None and np.isfinite(L).all():
        return L
    at = f" at {where}" if where else ""
    stack = S.shape[:-2]
    flat = S.reshape(-1, *S.shape[-2:])
    finite = np.isfinite(flat).all(axis=(1, 2))
    if not finite.all():
        raise ModelError(f"covariance is not finite{at}{_which(stack, int(np.argmin(finite)))}")
    eigenvalues = np.linalg.eigvalsh(flat)
    if np.all(eigenvalues > 0):  # positive, but too ill-conditioned for the factorisation
        ratios = eigenvalues.max(axis=1) / eigenvalues.min(axis=1)
        k = int(np.argmax(ratios))
        raise ModelError(
            f"covariance is not positive definite in double precision{at}{_which(stack, k)}: its "
            f"condition number λmax/λmin, {ratios[k]:.3g}, is beyond what a Cholesky "
            f"factorisation resolves; eigenvalues: {eigenvalues[k]}"
        )
    k = int(np.argmax(eigenvalues.min(axis=1) <= 0))
    raise ModelError(
        f"covariance is not positive definite{at}{_which(stack, k)}; eigenvalues: {eigenvalues[k]}"
    )


def _which(stack: tuple[int, ...], k: int) -> str:
    """`` (matrix i of a stack of shape …)`` for the ``k``-th matrix of a stack (row-major), so
    that an error names the one bad covariance of a series instead of printing them all;
    nothing for a single matrix."""
    if not stack:
        return ""
    return f" (matrix {tuple(int(i) for i in np.unravel_index(k, stack))} of a stack {stack})"


def solve_psd(S: Array, B: Array, *, where: str = "") -> Array:
    """Solve ``S X = B`` for symmetric positive definite ``S`` (``ModelError`` if not PD)."""
    L = cholesky(S, where=where)
    Y = np.linalg.solve(L, B)
    return np.linalg.solve(np.swapaxes(L, -1, -2), Y)


def mahalanobis_sq(residual: Array, S: Array, *, where: str = "") -> float:
    """Squared Mahalanobis distance ``νᵀ S⁻¹ ν`` (NIS/NEES building block)."""
    nu = np.asarray(residual, dtype=float).reshape(-1)
    return float(nu @ solve_psd(S, nu, where=where))


def condition_log10(M: Array) -> float:
    """Covariance conditioning ``log10(λmax/λmin)`` of a symmetric matrix (inf if λmin ≤ 0).

    ``M`` must be a square matrix ``(n, n)`` with ``n ≥ 1``: an empty, non-square or
    non-2-D ``M`` has no conditioning and is a :class:`ModelError`."""
    A = np.asarray(M, dtype=float)
    if A.ndim != 2 or A.shape[0] != A.shape[1] or A.shape[0] == 0:
        raise ModelError(f"condition_log10: expected a square matrix (n, n), n ≥ 1, got {A.shape}")
    eig = np.linalg.eigvalsh(symmetrise(A))
    if eig[0] <= 0.0:
        return float("inf")
    return float(np.log10(eig[-1] / eig[0]))
