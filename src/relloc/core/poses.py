"""Pose algebra with Jacobians: SE(2) poses ``(x, y, θ)`` and 4-DOF poses ``(x, y, z, φ)``.

The 4-DOF pose is a planar rotation about z plus a 3-D translation (hovering aerial robots
and ground robots, seed 000 §3.2). Composition ⊕ and inversion ⊖ follow Smith–Self–Cheeseman:

    a ⊕ b = [x_a + cφ_a x_b − sφ_a y_b,  y_a + sφ_a x_b + cφ_a y_b,  (z_a + z_b),  φ_a + φ_b]
    ⊖ a   = [−cφ x − sφ y,  sφ x − cφ y,  (−z),  −φ]

Headings are *not* wrapped in the result (states are never wrapped silently); wrap residuals.
Both functions accept 3-vectors (SE(2)) or 4-vectors (4-DOF); the layout decides.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from relloc.core.checks import floats
from relloc.errors import ModelError

Array = NDArray[np.float64]


def _check(p: Array, name: str) -> Array:
    """``p`` as a flat float pose of 3 or 4 entries (else ModelError naming ``name``). Values
    are not checked for NaN: these run at every step, on states the filters keep finite."""
    p = floats(p, name, ModelError).reshape(-1)
    if p.size not in (3, 4):
        raise ModelError(f"{name}: a pose has 3 (x, y, θ) or 4 (x, y, z, φ) entries, got {p.size}")
    return p


def compose(a: Array, b: Array) -> tuple[Array, Array, Array]:
    """Return ``(a ⊕ b, ∂(a⊕b)/∂a, ∂(a⊕b)/∂b)``; ``a`` and ``b`` must have the same layout."""
    a = _check(a, "compose(a)")
    b = _check(b, "compose(b)")
    if a.size != b.size:
        raise ModelError(f"compose: pose sizes differ ({a.size} vs {b.size})")
    n = a.size
    h = n - 1  # heading index
    c, s = np.cos(a[h]), np.sin(a[h])
    out = a + b
    out[0] = a[0] + c * b[0] - s * b[1]
    out[1] = a[1] + s * b[0] + c * b[1]
    Ja = np.eye(n)
    Ja[0, h] = -s * b[0] - c * b[1]
    Ja[1, h] = c * b[0] - s * b[1]
    Jb = np.eye(n)
    Jb[:2, :2] = [[c, -s], [s, c]]
    return out, Ja, Jb


def inverse(a: Array) -> tuple[Array, Array]:
    """Return ``(⊖a, ∂(⊖a)/∂a)``."""
    a = _check(a, "inverse")
    n = a.size
    h = n - 1
    c, s = np.cos(a[h]), np.sin(a[h])
    x, y = a[0], a[1]
    out = -a
    out[0] = -c * x - s * y
    out[1] = s * x - c * y
    J = -np.eye(n)
    J[:2, :2] = [[-c, -s], [s, -c]]
    J[0, h] = s * x - c * y
    J[1, h] = c * x + s * y
    return out, J


def relative(a: Array, b: Array) -> tuple[Array, Array, Array]:
    """Pose of ``b`` seen from ``a``: ``⊖a ⊕ b`` with Jacobians w.r.t. ``a`` and ``b``."""
    inv_a, J_inv = inverse(a)
    out, J1, J2 = compose(inv_a, b)
    return out, J1 @ J_inv, J2
