"""Observability-constrained Jacobians (OC-EKF/EIF) for the team filter.

Huang, Mourikis & Roumeliotis (2010, observability-based rules for consistent EKF estimators;
Huang, Trawny, Mourikis & Roumeliotis 2011 for cooperative localization) keep the linearised
system's unobservable subspace equal to the nonlinear one's not by moving the linearisation
point, as first-estimates Jacobians do (:mod:`relloc.estimators.first_estimates`, where the
subspace and the failure of the standard filter are derived), but by linearising at the latest
estimates and then changing the Jacobians as little as possible so that they obey the
constraint. This module holds that choice for
:class:`relloc.estimators.cooperative.CooperativeEstimator`
(``CooperativeSettings.linearisation = "observability_constrained"``).

The constraint
--------------
With ``N_k (3n × d)`` the unobservable directions at epoch ``k`` (columns of
:func:`unobservable_directions`), the linearised team has the nonlinear team's unobservable
subspace when, for every ``k``,

    Φ_k N_k = N_{k+1},        H_k N_k = 0.

``N_k`` is evaluated at the estimate every Jacobian of epoch ``k`` sees first, the prior
``X̂_{k|k−1}`` (the update at ``k`` cannot enter ``N_k``: the update depends on ``H_k``, which
must already annihilate ``N_k``).

Minimal change
--------------
Both conditions are linear in the Jacobian: ``A* N = B`` with ``(A, B) = (Φ_k, N_{k+1})`` or
``(H_k, 0)``. The closest such ``A*`` in the Frobenius norm solves
``min ½‖A* − A‖²_F`` s.t. ``A* N = B``; the Lagrangian ``½‖A* − A‖²_F + tr Λᵀ(A* N − B)``
is stationary at ``A* = A − Λ Nᵀ``, and the constraint gives ``Λ = (A N − B)(NᵀN)⁻¹``:

    A* = A − (A N − B)(NᵀN)⁻¹ Nᵀ.

- Transition (:func:`constrained_transition`): ``A = Φ_k``, the standard composite Jacobian of
  the steps since the last epoch (at the latest, updated, estimate ``X̂_{k|k}``),
  ``B = N(X̂_{k+1|k})``. Translation already satisfies the constraint; for the rotation the
  residual ``Φ_k N_k − N_{k+1}`` is, per robot, ``[J (p̂_{k|k−1} − p̂_{k|k}); 0]`` (the update's
  correction, :mod:`relloc.estimators.first_estimates`). The change is minimal over the whole
  ``3n × 3n`` matrix, so ``Φ*`` is dense: the correction is spread over every robot's states
  instead of being put into each robot's own heading column. (Restricted to block-diagonal
  transitions the constraint leaves no freedom without landmarks: each robot's ``N_i`` is an
  invertible 3 × 3 matrix, so ``Φ*_i = N_i(X̂_{k+1|k}) N_i(X̂_{k|k−1})⁻¹``, the first-estimates
  transition; the dense solution is what makes this filter a different one.)
- Measurement (:func:`constrained_rows`): ``A = H_k`` at the latest estimate, ``B = 0``:
  ``H* = H (I − N (NᵀN)⁻¹ Nᵀ)``, the row projected off the unobservable directions. A row is kept
  within its sparsity pattern (its observer's and target's blocks; the rows of ``N`` of those
  blocks, ``N_S``): ``h* = h − (h N_S) N_S⁺``, the minimal change among rows of that pattern
  (``N_S⁺`` the pseudo-inverse). A row linearised at ``X̂_{k|k−1}`` itself already satisfies
  ``h N_k = 0`` and is unchanged; rows differ only at a second epoch at the same instant, whose
  latest estimate is the first epoch's update.

Residuals ``z − h(X̂)`` and the mean propagation stay at the latest estimate; the input
Jacobian and the process noise are the standard ones (they do not enter ``N``).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from relloc.models.planar_measurement import LinearisedRows

Array = NDArray[np.float64]

_J = np.array([[0.0, -1.0], [1.0, 0.0]])


def unobservable_directions(X: Array, anchors_xy: Array, fixed: bool) -> Array:
    """The nonlinear team's unobservable directions ``N (3n, d)`` at the team mean ``X (n, 3)``.

    ``anchors_xy (a, 2)``: the known landmarks the filter uses; ``fixed``: absolute pose fixes
    are used. No anchor and no fix: global translation (2) and rotation about the origin
    (``[J p_i; 1]`` per robot), ``d = 3``; one anchor: rotation about it, ``d = 1``; two or more
    anchors or fixes: none, ``d = 0`` (seed 001 Theorems 2–4).
    """
    X = np.asarray(X, dtype=float)
    n = X.shape[0]
    if fixed or anchors_xy.shape[0] >= 2:
        return np.zeros((3 * n, 0))
    centre = anchors_xy[0] if anchors_xy.shape[0] == 1 else np.zeros(2)
    rotation = np.column_stack([(X[:, :2] - centre) @ _J.T, np.ones(n)])  # (n, 3)
    if anchors_xy.shape[0] == 1:
        return rotation.reshape(3 * n, 1)
    translation = np.tile(np.vstack([np.eye(2), np.zeros((1, 2))]), (n, 1))  # (3n, 2)
    return np.column_stack([translation, rotation.reshape(-1)])


def constrained_transition(F_blocks: Array, N_before: Array, N_after: Array) -> Array:
    """The dense ``Φ* (3n, 3n)`` closest to ``diag(F_blocks)`` with ``Φ* N_before = N_after``."""
    n = F_blocks.shape[0]
    F4 = np.zeros((n, 3, n, 3))
    F4[np.arange(n), :, np.arange(n), :] = F_blocks
    F = F4.reshape(3 * n, 3 * n)
    if N_before.shape[1] == 0:
        return F
    residual = F @ N_before - N_after
    return F - residual @ np.linalg.solve(N_before.T @ N_before, N_before.T)


def constrained_rows(lin: LinearisedRows, N: Array) -> LinearisedRows:
    """``lin`` with each row's blocks changed least so that the row annihilates ``N (3n, d)``,
    within the row's sparsity pattern (``h* = h − (h N_S) N_S⁺``)."""
    d = N.shape[1]
    m = lin.blocks.shape[0]
    if d == 0 or m == 0:
        return lin
    N3 = N.reshape(-1, 3, d)
    present = lin.block_index >= 0  # (m, 2)
    NS = N3[np.maximum(lin.block_index, 0)] * present[:, :, None, None]  # (m, 2, 3, d)
    NS = NS.reshape(m, 6, d)
    h = lin.blocks.reshape(m, 6)
    hN = np.einsum("ms,msd->md", h, NS)
    h_star = h - np.einsum("md,mds->ms", hN, np.linalg.pinv(NS))
    blocks = (h_star.reshape(m, 2, 3)) * present[:, :, None]
    return LinearisedRows(
        residual=lin.residual,
        blocks=blocks,
        block_index=lin.block_index,
        sigma=lin.sigma,
        group=lin.group,
    )
