"""Bearing of an undetected follower from the formation triangle (seed 003, Fig. 3, sw = 2).

A drone sees the pair {R_0, R_j} and broadcasts the bearing φ_j of ``r_j = p_0 − p_j``. The UWB
radios give the three side lengths of the triangle (R_0, R_j, R_i): ``a = d_0j``, ``b = d_0i``,
``c = d_ij``. The interior angle at R_0 follows from the law of cosines,

    cos α_0 = (a² + b² − c²) / (2ab),

and because the ray R_0→R_i is the ray R_0→R_j turned by ±α_0, the bearing of ``r_i = p_0 − p_i``
(the ray R_i→R_0) is

    φ̄_i = φ_j + s α_0,   s = sign((p_j − p_0) × (p_i − p_0)) ∈ {+1, −1}.

The paper writes the same as ``β_i = β_j + π − α_1 − α_2`` (its α_1, α_2 are the angles at R_j and
R_i, and α_1 + α_2 = π − α_0); ``s`` says on which side of the line R_0R_j the follower R_i sits
(the paper's right/left half-planes of l_i). Distances alone cannot tell the side, so it is
supplied by the caller (from the formation's known layout).

Near-collinear triangles (α_0 close to 0 or π) are refused: there ``∂α_0/∂d`` blows up like
``1/sin α_0`` and the side sign flips under noise. Side lengths that violate the triangle
inequality beyond a tolerance (range outliers) are refused too.

Partial derivatives (for the measurement covariance), with ``S = sin α_0``:

    ∂α_0/∂a = −(a² − b² + c²) / (2a²b S),  ∂α_0/∂b = −(b² − a² + c²) / (2ab² S),
    ∂α_0/∂c = c / (ab S).
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass

from relloc.core import checks
from relloc.core.angles import wrap_angle
from relloc.errors import ConfigError, DataError


@dataclass(frozen=True, kw_only=True)
class TriangleBearing:
    """A derived bearing, or a refusal with its reason (``bearing is None``).

    ``d_bearing`` holds ``∂φ̄/∂(φ_j, d_0j, d_0i, d_ij)`` for covariance propagation.
    """

    bearing: float | None
    reason: str = ""
    d_bearing: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 0.0)
    interior_angle: float = float("nan")

    @property
    def ok(self) -> bool:
        """True when a bearing was derived."""
        return self.bearing is not None


def side_of(p0: tuple[float, float], pj: tuple[float, float], pi: tuple[float, float]) -> int:
    """``sign((p_j − p_0) × (p_i − p_0))``: +1 if R_i is left of the ray R_0→R_j or on its line
    (a collinear triangle is refused by :func:`triangle_bearing` anyway), else −1."""
    cross = (pj[0] - p0[0]) * (pi[1] - p0[1]) - (pj[1] - p0[1]) * (pi[0] - p0[0])
    return 1 if cross >= 0.0 else -1


def triangle_bearing(
    phi_j: float,
    d_0j: float,
    d_0i: float,
    d_ij: float,
    side: int,
    *,
    min_sin: float = 0.2,
    inequality_tol: float = 0.05,
) -> TriangleBearing:
    """φ̄_i from φ_j and the three UWB ranges (module docstring); refuses bad geometry.

    ``min_sin``: refuse when ``sin α_0 < min_sin`` (near-collinear); ``inequality_tol`` (m): how
    far noisy sides may break the triangle inequality before the triple is refused (within the
    tolerance γ is clipped to [−1, 1], which then falls under the collinearity refusal).
    ``min_sin`` outside (0, 1) or ``inequality_tol`` not a finite number ≥ 0 is a ConfigError
    naming the argument; a bearing or side that is not a number (a string, None, a bool) is a
    DataError naming it, while a NaN or infinite one is refused in the result. Sides so small
    that their products underflow to 0 are refused like a degenerate triangle.
    """
    if isinstance(side, bool) or side not in (1, -1):
        raise ConfigError(f"triangle_bearing.side: must be +1 or -1, got {side!r}")
    checks.number(
        min_sin, "triangle_bearing.min_sin", low=0.0, high=1.0, open_low=True, open_high=True
    )
    checks.number(inequality_tol, "triangle_bearing.inequality_tol", low=0.0)
    values = {"phi_j": phi_j, "d_0j": d_0j, "d_0i": d_0i, "d_ij": d_ij}
    for name, value in values.items():
        if isinstance(value, bool) or not isinstance(value, numbers.Real):
            raise DataError(f"triangle_bearing.{name}: expected a number, got {value!r:.40}")
        if not math.isfinite(value):
            return TriangleBearing(bearing=None, reason=f"{name} is not finite ({value})")
    a, b, c = d_0j, d_0i, d_ij
    if min(a, b, c) <= 0.0:
        return TriangleBearing(
            bearing=None, reason=f"non-positive side (d_0j={a:.3g}, d_0i={b:.3g}, d_ij={c:.3g})"
        )
    slack = min(a + b - c, a + c - b, b + c - a)
    if slack < -inequality_tol:
        return TriangleBearing(
            bearing=None,
            reason=(
                f"ranges break the triangle inequality by {-slack:.3g} m "
                f"(d_0j={a:.3g}, d_0i={b:.3g}, d_ij={c:.3g})"
            ),
        )
    try:
        raw_gamma = (a * a + b * b - c * c) / (2.0 * a * b)
        alpha = math.acos(min(1.0, max(-1.0, raw_gamma)))
        sin_a = math.sin(alpha)
        if sin_a < min_sin:
            limit = (
                " (the ranges sit at the triangle-inequality limit)" if abs(raw_gamma) >= 1 else ""
            )
            return TriangleBearing(
                bearing=None,
                reason=(
                    f"near-collinear robots: angle at R_0 is {math.degrees(alpha):.1f}° "
                    f"(sin {sin_a:.3f} < {min_sin}){limit}"
                ),
                interior_angle=alpha,
            )
        da = -(a * a - b * b + c * c) / (2.0 * a * a * b * sin_a)
        db = -(b * b - a * a + c * c) / (2.0 * a * b * b * sin_a)
        dc = c / (a * b * sin_a)
    except ZeroDivisionError:
        return TriangleBearing(
            bearing=None,
            reason=f"sides too small to resolve (d_0j={a:.3g}, d_0i={b:.3g}, d_ij={c:.3g})",
        )
    return TriangleBearing(
        bearing=float(wrap_angle(phi_j + side * alpha)),
        d_bearing=(1.0, side * da, side * db, side * dc),
        interior_angle=alpha,
    )
