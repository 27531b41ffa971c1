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
from relloc.errors import DataError

Array = NDArray[np.float64]


def estimates_error(where: str, *estimates: tuple[Array, Array]) -> DataError:
    """The DataError, naming ``where`` and the estimate, for fusion inputs ``(x, P)`` that are
    not a finite mean ``(n,)`` with a covariance ``(n, n)``, one ``n`` for all.

    The fusions call it only once their arithmetic has failed (numpy's ``ValueError`` on
    mismatched shapes) or given a non-finite mean, so valid input pays no check; a non-finite
    or non-PD covariance is refused before, ModelError, by
    :func:`relloc.core.linalg.solve_psd`."""
    n = np.shape(estimates[0][0])[-1] if np.ndim(estimates[0][0]) else 0
    for k, (x, P) in enumerate(estimates):
        if np.shape(x) != (n,) or np.shape(P) != (n, n):
            return DataError(
                f"{where}: estimate {k} has mean {np.shape(x)} and covariance {np.shape(P)}; "
                f"expected ({n},) and ({n}, {n}), n from the first mean"
            )
        if not np.isfinite(x).all():
            return DataError(f"{where}: the mean of estimate {k} is not finite: {x}")
    return DataError(f"{where}: the fused mean is not finite (values beyond float range)")


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
    """Fuse the new information of a received track into ``N(x_i, P_i)`` (module docstring).

    Means and covariances of mismatched shapes, or a non-finite mean, are a DataError
    (:func:`estimates_error`)."""
    n = x_i.size
    eye = np.eye(n)
    try:
        dY = information_increment(P_post, P_prior)
        Y_prior = solve_psd(P_prior, eye, where="decorrelation(prior)")
        Y = symmetrise(solve_psd(P_i, eye, where="decorrelation(local)") + dY)
        P = symmetrise(solve_psd(Y, eye, where="decorrelation(fused)"))
        shift = dY @ pose_difference(x_post, x_i, angle_index) + Y_prior @ pose_difference(
            x_post, x_prior, angle_index
        )
        x = x_i + P @ shift
    except ValueError as exc:
        raise estimates_error(
            "decorrelated_fusion", (x_i, P_i), (x_post, P_post), (x_prior, P_prior)
        ) from exc
    if not np.isfinite(x).all():
        raise estimates_error(
            "decorrelated_fusion", (x_i, P_i), (x_post, P_post), (x_prior, P_prior)
        )
    return x, P
