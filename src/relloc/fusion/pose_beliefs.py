"""Pose composition of Gaussian beliefs (sensor registration, seed 002 Eqs. 9 and 11).

With ``relloc.core.poses`` giving ``a ⊕ b`` and ``⊖a`` with their Jacobians, first-order
propagation gives

    ⊖N(a, P_a)           ≈ N(⊖a, J P_a Jᵀ),                       J = ∂(⊖a)/∂a      (Eq. 9)
    N(a, P_a) ⊕ N(b, P_b) ≈ N(a ⊕ b, J_a P_a J_aᵀ + J_b P_b J_bᵀ)  (independent a, b; Eq. 11)

Used with ``a = x^(j,i)`` (``j``'s belief about ``i``) the inverse is a belief of ``x^(i,j)``;
with ``a = x^(i,l)`` and ``b = x^(l,j)`` the composition is a belief of ``x^(i,j)``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from relloc.core.poses import compose, inverse

Array = NDArray[np.float64]


def invert_beliefs(means: Array, covs: Array) -> tuple[Array, Array]:
    """``⊖`` applied to each belief of a stack: means (K, n), covs (K, n, n)."""
    out_m = np.empty_like(means)
    out_P = np.empty_like(covs)
    for k in range(means.shape[0]):
        m, J = inverse(means[k])
        out_m[k] = m
        out_P[k] = J @ covs[k] @ J.T
    return out_m, 0.5 * (out_P + np.swapaxes(out_P, -1, -2))


def compose_beliefs(
    mean_a: Array, cov_a: Array, means_b: Array, covs_b: Array
) -> tuple[Array, Array, Array]:
    """``N(a, P_a) ⊕ N(b_k, P_b,k)`` for every ``k`` of a stack of ``b``.

    Returns ``(means (K, n), covs (K, n, n), J_a P_a J_aᵀ (K, n, n))``; the last term is the
    part contributed by ``a`` alone, needed to register a prior with the same ``a``.
    """
    out_m = np.empty_like(means_b)
    out_P = np.empty_like(covs_b)
    from_a = np.empty_like(covs_b)
    for k in range(means_b.shape[0]):
        m, Ja, Jb = compose(mean_a, means_b[k])
        out_m[k] = m
        from_a[k] = Ja @ cov_a @ Ja.T
        out_P[k] = from_a[k] + Jb @ covs_b[k] @ Jb.T
    return out_m, 0.5 * (out_P + np.swapaxes(out_P, -1, -2)), from_a


def register_prior(
    mean_a: Array, means_b: Array, covs_b: Array, from_a: Array
) -> tuple[Array, Array]:
    """Compose prior beliefs ``b`` with the same registration ``a`` (its covariance ``from_a``)."""
    out_m = np.empty_like(means_b)
    out_P = np.empty_like(covs_b)
    for k in range(means_b.shape[0]):
        m, _, Jb = compose(mean_a, means_b[k])
        out_m[k] = m
        out_P[k] = from_a[k] + Jb @ covs_b[k] @ Jb.T
    return out_m, 0.5 * (out_P + np.swapaxes(out_P, -1, -2))
