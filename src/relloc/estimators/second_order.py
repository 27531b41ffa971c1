"""Second-order measurement terms for the team filter's bearing and range rows.

A linearised update treats ``h(X)`` as linear over the prior's spread. For a bearing or a range
between two robots (or a robot and a landmark) that fails when the relative position's
uncertainty is comparable with the distance: with 5 m initial errors on two robots 6 m apart,
the bearing between them is almost uniform over the circle under the prior, yet the linearised
filter predicts it with a small variance and then moves both robots as if the Jacobian held
over metres. Such updates remove information along directions the data do not constrain (the
formation's scale, while the robots move in parallel) and the damage lasts: an error along an
unobservable direction is never corrected later.

The Gaussian second-order filter (Athans, Wishner & Bertolini 1968; Bar-Shalom, Li &
Kirubarajan 2001, §10.3) keeps the next term of the Taylor expansion. A row depends on the
relative position ``d = p_t − p_o`` (target minus observer) only through its nonlinear part
(the observer's heading enters a bearing linearly), so with ``H_d`` the Hessian of the row with
respect to ``d`` and ``P_d`` the covariance of ``d`` under the prior,

    E[h] ≈ h(X̂) + ½ tr(H_d P_d),        var[h] ≈ J P Jᵀ + ½ tr(H_d P_d H_d P_d),

and :func:`second_order_rows` subtracts the mean term from the residual and adds the variance
term to the row's noise variance. ``P_d = P_tt + P_oo − P_ot − P_to`` (position blocks) for a
robot target and ``P_oo`` for a landmark. With ``Δ = (Δx, Δy) = d``, ``q = Δx² + Δy²``,
``ρ = √q``:

    bearing:  H_d = [[2ΔxΔy, Δy² − Δx²], [Δy² − Δx², −2ΔxΔy]] / q²    (eigenvalues ±1/q),
    range:    H_d = [[Δy², −ΔxΔy], [−ΔxΔy, Δx²]] / ρ³                  (eigenvalues 0, 1/ρ).

For an isotropic ``P_d = s² I`` the bearing's extra variance is ``(s²/q)²``: negligible once the
relative uncertainty is small against the distance (``s/ρ = 0.05`` adds 6·10⁻⁶ rad²), dominant
when it is not (``s/ρ = 1`` adds 1 rad²) — the row is then de-weighted by the amount its
linearisation is wrong, with nothing to tune. The extra noise does not touch the Jacobian, so a
row that annihilates the unobservable directions (:mod:`relloc.estimators.first_estimates`,
:mod:`relloc.estimators.observability_constrained`) still does. This is the variance of the
quadratic part alone; the fourth-order terms that pair first with third derivatives are left
out (for a bearing they add about as much again, for a range they can reduce the variance:
``tests/cooperative/test_second_order.py`` compares both with sampling). The two rows of one
range-and-bearing detection also get a second-order cross term, ``½ tr(H_b P_d H_r P_d)``; it is
zero for isotropic ``P_d`` and is left out (each row keeps its own noise).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from numpy.typing import NDArray

from relloc.models.planar_measurement import LinearisedRows, RowKind, ScalarRows

Array = NDArray[np.float64]


def relative_position_hessians(d: Array) -> tuple[Array, Array]:
    """Hessians ``(m, 2, 2)`` of the bearing and of the range with respect to the relative
    position ``d (m, 2)`` (module docstring)."""
    dx, dy = d[:, 0], d[:, 1]
    q = dx * dx + dy * dy
    rho3 = q * np.sqrt(q)
    bearing = np.empty((d.shape[0], 2, 2))
    bearing[:, 0, 0] = 2.0 * dx * dy / q**2
    bearing[:, 1, 1] = -bearing[:, 0, 0]
    bearing[:, 0, 1] = bearing[:, 1, 0] = (dy * dy - dx * dx) / q**2
    rng = np.empty((d.shape[0], 2, 2))
    rng[:, 0, 0] = dy * dy / rho3
    rng[:, 1, 1] = dx * dx / rho3
    rng[:, 0, 1] = rng[:, 1, 0] = -dx * dy / rho3
    return bearing, rng


def relative_position_covariance(
    P: Array, observer: NDArray[np.int64], target: NDArray[np.int64]
) -> Array:
    """``P_d (m, 2, 2)`` of ``d = p_target − p_observer`` from the joint ``P (3n, 3n)``; a
    negative ``target`` is a known landmark (``P_d = P_oo``)."""
    n = P.shape[0] // 3
    P4 = P.reshape(n, 3, n, 3)
    Pd = P4[observer, :2, observer, :2].copy()
    robot = target >= 0
    o, t = observer[robot], target[robot]
    Pd[robot] += P4[t, :2, t, :2] - P4[o, :2, t, :2] - P4[t, :2, o, :2]
    return Pd


def second_order_rows(lin: LinearisedRows, rows: ScalarRows, X: Array, P: Array) -> LinearisedRows:
    """``lin`` (the rows ``rows`` linearised at the team mean ``X (n, 3)``, prior covariance
    ``P``) with the second-order mean removed from each bearing and range residual and the
    second-order variance added to its noise (module docstring)."""
    rel = np.flatnonzero((rows.kind == RowKind.BEARING) | (rows.kind == RowKind.RANGE))
    if rel.size == 0:
        return lin
    observer, target = rows.observer[rel], rows.target[rel]
    target_xy = np.where(
        (target >= 0)[:, None], X[np.maximum(target, 0), :2], rows.landmark_xy[rel]
    )
    H_bearing, H_range = relative_position_hessians(target_xy - X[observer, :2])
    is_bearing = (rows.kind[rel] == RowKind.BEARING)[:, None, None]
    HP = np.where(is_bearing, H_bearing, H_range) @ relative_position_covariance(
        P, observer, target
    )
    residual = lin.residual.copy()
    sigma = lin.sigma.copy()
    residual[rel] -= 0.5 * np.trace(HP, axis1=1, axis2=2)
    sigma[rel] = np.sqrt(sigma[rel] ** 2 + 0.5 * np.einsum("mab,mba->m", HP, HP))
    return replace(lin, residual=residual, sigma=sigma)
