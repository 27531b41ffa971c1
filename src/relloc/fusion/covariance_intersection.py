"""Covariance intersection (Julier & Uhlmann), the conservative fusion alternative.

For two estimates with unknown cross-correlation,

    P⁻¹ = ω P_a⁻¹ + (1 − ω) P_b⁻¹,    P⁻¹ x = ω P_a⁻¹ x_a + (1 − ω) P_b⁻¹ x_b,

is consistent for every ω ∈ [0, 1]; ω is chosen to minimise ``log det P``
(``scipy.optimize.minimize_scalar`` on the bounded interval). Fusing an estimate with a copy of
itself returns it unchanged for any ω — CI never double counts.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import minimize_scalar

from relloc.core.linalg import solve_psd, symmetrise
from relloc.fusion.decorrelation import estimates_error

Array = NDArray[np.float64]


def covariance_intersection(
    x_a: Array, P_a: Array, x_b: Array, P_b: Array
) -> tuple[Array, Array, float]:
    """Fuse ``N(x_a, P_a)`` and ``N(x_b, P_b)``; returns ``(x, P, ω)``.

    ``x_b`` must already be expressed next to ``x_a`` (headings aligned by the caller).
    Means and covariances of mismatched shapes, or a non-finite mean, are a DataError
    (:func:`relloc.fusion.decorrelation.estimates_error`); a covariance that is not positive
    definite is a ModelError.
    """
    n = x_a.size
    eye = np.eye(n)
    try:
        Y_a = solve_psd(P_a, eye, where="covariance_intersection(P_a)")
        Y_b = solve_psd(P_b, eye, where="covariance_intersection(P_b)")

        def neg_logdet_info(omega: float) -> float:
            sign, logdet = np.linalg.slogdet(omega * Y_a + (1.0 - omega) * Y_b)
            return -logdet if sign > 0 else np.inf

        res = minimize_scalar(neg_logdet_info, bounds=(0.0, 1.0), method="bounded")
        omega = float(np.clip(res.x, 0.0, 1.0))
        for candidate in (0.0, 1.0):
            if neg_logdet_info(candidate) < neg_logdet_info(omega):
                omega = candidate
        Y = symmetrise(omega * Y_a + (1.0 - omega) * Y_b)
        P = symmetrise(solve_psd(Y, eye, where="covariance_intersection(fused)"))
        x = P @ (omega * Y_a @ x_a + (1.0 - omega) * Y_b @ x_b)
    except ValueError as exc:
        raise estimates_error("covariance_intersection", (x_a, P_a), (x_b, P_b)) from exc
    if not np.isfinite(x).all():
        raise estimates_error("covariance_intersection", (x_a, P_a), (x_b, P_b))
    return x, P, omega
