"""Angle helpers. Angles are wrapped in residuals and errors, never silently in states."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray


def wrap_angle(angle: ArrayLike) -> NDArray[np.float64] | float:
    """Wrap angles to [-π, π).

    Uses ``(a + π) mod 2π − π``, exact for all finite inputs. Scalars stay scalars.
    """
    a = np.asarray(angle, dtype=float)
    wrapped = np.mod(a + np.pi, 2.0 * np.pi) - np.pi
    if wrapped.ndim == 0:
        return float(wrapped)
    return wrapped


def angle_diff(a: ArrayLike, b: ArrayLike) -> NDArray[np.float64] | float:
    """Smallest signed difference ``a − b`` wrapped to [-π, π)."""
    return wrap_angle(np.asarray(a, dtype=float) - np.asarray(b, dtype=float))


def circular_interp(
    t: ArrayLike, t_known: ArrayLike, angle_known: ArrayLike
) -> NDArray[np.float64]:
    """Interpolate angles on the circle: unwrap, interpolate linearly, wrap back."""
    unwrapped = np.unwrap(np.asarray(angle_known, dtype=float))
    t_query = np.asarray(t, dtype=float)
    t_grid = np.asarray(t_known, dtype=float)
    return np.asarray(wrap_angle(np.interp(t_query, t_grid, unwrapped)), dtype=float)
