"""Positions from distances: classical multidimensional scaling, rigid alignment, and
multilateration — the geometry a range-only team needs before (and instead of) a filter.

- :func:`classical_mds` — points ``X (n, d)`` whose distances best match a full distance
  matrix ``D``: the top-``d`` eigenpairs of ``B = −½ J D² J`` (``J = I − 11ᵀ/n``),
  ``X = V_d Λ_d^{½}``; defined up to a rigid motion and a reflection. Missing distances (NaN)
  are first filled by shortest paths through the known ones (an upper bound).
- :func:`rigid_alignment` — the rotation ``R`` and translation ``t`` (no scale) minimising
  ``Σ ‖R aᵢ + t − bᵢ‖²`` (Kabsch / Umeyama without scale): with centred ``A, B`` and the SVD
  ``AᵀB = U S Vᵀ``, ``R = V diag(1, …, det(VUᵀ)) Uᵀ``; ``reflection=True`` drops the
  determinant correction (distances cannot tell a configuration from its mirror image).
- :func:`multilaterate` — least-squares points from any set of measured distances between
  free points and fixed ones (Gauss–Newton via ``scipy.optimize.least_squares``).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from relloc.errors import DataError

Array = NDArray[np.float64]


def fill_by_shortest_paths(D: Array) -> Array:
    """``D`` with NaN entries replaced by shortest-path lengths (Floyd–Warshall) and zeros on the
    diagonal; every measured distance stays as measured, even one longer than a path through
    other points (noisy ranges break the triangle inequality; MDS fits them all in least
    squares). DataError if some points are not connected."""
    D = np.array(D, dtype=float)
    n = D.shape[0]
    G = np.where(np.isnan(D), np.inf, D)
    np.fill_diagonal(G, 0.0)
    for k in range(n):
        G = np.minimum(G, G[:, k : k + 1] + G[k : k + 1, :])
    if not np.isfinite(G).all():
        i = int(np.argwhere(~np.isfinite(G))[0][0])
        raise DataError(f"classical_mds: point {i} has no chain of distances to the others")
    out = np.where(np.isnan(D), G, D)
    np.fill_diagonal(out, 0.0)
    return out


def classical_mds(D: Array, dim: int = 2) -> Array:
    """Points ``(n, dim)`` whose distances match ``D (n, n)`` (module docstring); a ``D`` that
    is not square is a DataError."""
    D = np.asarray(D, dtype=float)
    if D.ndim != 2 or D.shape[0] != D.shape[1]:
        raise DataError(f"classical_mds: the distance matrix must be square (n, n), got {D.shape}")
    G = fill_by_shortest_paths(0.5 * (D + D.T))
    n = G.shape[0]
    J = np.eye(n) - np.ones((n, n)) / n
    B = -0.5 * J @ (G**2) @ J
    w, V = np.linalg.eigh(B)
    top = np.argsort(w)[::-1][:dim]
    return np.asarray(V[:, top] * np.sqrt(np.clip(w[top], 0.0, None)))


def rigid_alignment(a: Array, b: Array, *, reflection: bool = False) -> tuple[Array, Array]:
    """``(R, t)`` with ``R a_i + t ≈ b_i`` in least squares (module docstring).

    ``a`` and ``b`` must be finite point sets of one shape ``(n, d)``, ``n ≥ 1``, else
    DataError (a NaN point has no alignment)."""
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    if a.ndim != 2 or a.shape != b.shape or a.shape[0] == 0:
        raise DataError(
            f"rigid_alignment: needs two point sets of one shape (n ≥ 1, d), got {a.shape} "
            f"and {b.shape}"
        )
    if not (np.isfinite(a).all() and np.isfinite(b).all()):
        raise DataError("rigid_alignment: the points are not all finite")
    ca, cb = a.mean(axis=0), b.mean(axis=0)
    U, _, Vt = np.linalg.svd((a - ca).T @ (b - cb))
    d = np.ones(a.shape[1])
    if not reflection:
        d[-1] = np.sign(np.linalg.det(Vt.T @ U.T)) or 1.0
    R = Vt.T @ np.diag(d) @ U.T
    return R, cb - R @ ca


def multilaterate(
    initial: Array,
    fixed: Array,
    pairs: Sequence[tuple[int, int]],
    distances: Array,
) -> Array:
    """Least-squares free points ``(n, 2)`` from ``distances[k]`` between the ends of
    ``pairs[k]``; index ``i < n`` is free point ``i``, ``i ≥ n`` is ``fixed[i − n]``.

    DataError for: an index outside ``[0, n + len(fixed))`` or a pair joining a point to
    itself, a number of distances other than of pairs, or a non-finite distance, initial or
    fixed point. Geometry that leaves a point ambiguous (one anchor, collinear anchors: the
    mirror image fits as well) is not detected; the solution nearest ``initial`` is returned.
    """
    from scipy.optimize import least_squares

    x0 = np.asarray(initial, dtype=float)
    n = x0.shape[0]
    fixed = np.asarray(fixed, dtype=float).reshape(-1, x0.shape[1])
    ij = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
    d = np.asarray(distances, dtype=float).reshape(-1)
    n_points = n + fixed.shape[0]
    if ij.size and (ij.min() < 0 or ij.max() >= n_points or np.any(ij[:, 0] == ij[:, 1])):
        raise DataError(f"multilaterate: pairs must join two different points of 0…{n_points - 1}")
    if d.size != ij.shape[0]:
        raise DataError(f"multilaterate: {d.size} distances for {ij.shape[0]} pairs")
    for name, arr in (("distances", d), ("initial", x0), ("fixed", fixed)):
        if not np.isfinite(arr).all():
            raise DataError(f"multilaterate: not every value of {name} is finite")

    def points(x: Array) -> Array:
        return np.vstack([x.reshape(n, -1), fixed])

    def residual(x: Array) -> Array:
        p = points(x)
        return np.linalg.norm(p[ij[:, 0]] - p[ij[:, 1]], axis=1) - d

    if n == 0 or ij.shape[0] == 0:
        return x0
    return np.asarray(
        least_squares(residual, x0.ravel(), method="lm" if d.size >= x0.size else "trf").x.reshape(
            n, -1
        )
    )
