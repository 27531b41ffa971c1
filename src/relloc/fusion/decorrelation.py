"""Information de-correlation for mutual and indirect fusion (seed 002 Eqs. 10 and 12).

A receiver ``i`` holding ``N(x_i, P_i)`` gets a teammate's current track ``N(x⁺, P⁺)`` and the
same track as it was at the previous broadcast, propagated to now, ``N(x⁻, P⁻)`` (both already
registered into ``i``'s frame). Only the information gained since the last broadcast is new;
the rest was fused before (or stems from the common prior), so in information form

    Y = Y_i + (P⁺⁻¹ − P⁻⁻¹),      Y x = Y_i x_i + (P⁺⁻¹ x⁺ − P⁻⁻¹ x⁻)          (Eq. 10)

(Eq. 12 sums the increments of several senders). Written around ``x_i`` so that only
differences of poses (headings wrapped) appear::

    ΔY = P⁺⁻¹ − P⁻⁻¹,   x = x_i + Y⁻¹ [ΔY (x⁺ − x_i) + P⁻⁻¹ (x⁺ − x⁻)].

Linearisation and registration can make ``ΔY`` slightly indefinite; its negative eigenvalues
are clipped to 0 (information is never removed), so the fused covariance is never larger than
``P_i`` and never smaller than the covariance obtained from the genuinely new information.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from relloc.core.angles import wrap_angle
from relloc.core.linalg import solve_psd, symmetrise

Array = NDArray[np.float64]


def pose_difference(a: Array, b: Array, angle_index: int | None) -> Array:
    """``a − b`` with the heading entry wrapped to [−π, π)."""
    d = np.asarray(a, dtype=float) - np.asarray(b, dtype=float)
    if angle_index is not None:
        d[..., angle_index] = wrap_angle(d[..., angle_index])
    return d


def information_increment(P_post: Array, P_prior: Array) -> Array:
    """PSD part of ``P⁺⁻¹ − P⁻⁻¹`` (negative eigenvalues clipped to 0)."""
    n = P_post.shape[-1]
    eye = np.eye(n)
    dY = symmetrise(
        solve_psd(P_post, eye, where="decorrelation(post)")
        - solve_psd(P_prior, eye, where="decorrelation(prior)")
    )
    vals, vecs = np.linalg.eigh(dY)
    return symmetrise((vecs * np.clip(vals, 0.0, None)) @ vecs.T)


def decorrelated_fusion(
    x_i: Array,
    P_i: Array,
    x_post: Array,
    P_post: Array,
    x_prior: Array,
    P_prior: Array,
    *,
    angle_index: int | None = 3,
) -> tuple[Array, Array]:
    """Fuse the new information of a received track into ``N(x_i, P_i)`` (module docstring)."""
    n = x_i.size
    eye = np.eye(n)
    dY = information_increment(P_post, P_prior)
    Y_prior = solve_psd(P_prior, eye, where="decorrelation(prior)")
    Y = symmetrise(solve_psd(P_i, eye, where="decorrelation(local)") + dY)
    P = symmetrise(solve_psd(Y, eye, where="decorrelation(fused)"))
    shift = dY @ pose_difference(x_post, x_i, angle_index) + Y_prior @ pose_difference(
        x_post, x_prior, angle_index
    )
    return x_i + P @ shift, P
