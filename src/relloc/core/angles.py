"""Angle helpers. Angles are wrapped in residuals and errors, never silently in states."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from relloc.core.checks import floats
from relloc.errors import DataError


def wrap_angle(angle: ArrayLike) -> NDArray[np.float64] | float:
    """Wrap angles to [-π, π).

    Uses ``(a + π) mod 2π − π``. Where ``a + π`` rounds to a tiny negative number (``a`` just
    below −π) the modulo rounds up to 2π and the result to π: that one case is set to −π, the
    same angle, so the result stays inside [-π, π). Scalars stay scalars.
    """
    a = np.asarray(angle, dtype=float)
    wrapped = np.mod(a + np.pi, 2.0 * np.pi) - np.pi
    if wrapped.ndim == 0:
        return -math.pi if wrapped >= math.pi else float(wrapped)
    wrapped[wrapped >= np.pi] = -np.pi
    return wrapped


def angle_diff(a: ArrayLike, b: ArrayLike) -> NDArray[np.float64] | float:
    """Smallest signed difference ``a − b`` wrapped to [-π, π)."""
    return wrap_angle(np.asarray(a, dtype=float) - np.asarray(b, dtype=float))


def circular_interp(
    t: ArrayLike, t_known: ArrayLike, angle_known: ArrayLike, *, assume_sorted: bool = False
) -> NDArray[np.float64]:
    """Interpolate angles on the circle: unwrap, interpolate linearly, wrap back.

    ``t_known`` must be a non-empty 1-D array of finite, strictly increasing times (unsorted or
    repeated times make ``np.interp`` return a wrong angle without a word), ``angle_known`` of
    the same length and finite, the query times ``t`` not NaN; otherwise (strings included) a
    :class:`~relloc.errors.DataError`. Queries outside the known times get the end angles (no
    extrapolation). ``assume_sorted`` skips these O(N) checks of the values (only the shapes
    are checked) for samples and queries already validated, e.g. by a
    :class:`~relloc.core.recording.GroundTruth`.
    """
    t_grid = floats(t_known, "circular_interp: t_known")
    angles = floats(angle_known, "circular_interp: angle_known")
    t_query = floats(t, "circular_interp: t")
    if t_grid.ndim != 1 or t_grid.size == 0 or angles.shape != t_grid.shape:
        raise DataError(
            f"circular_interp: expected 1-D sample times and angles of one length ≥ 1, got "
            f"{t_grid.shape} and {angles.shape}"
        )
    if not assume_sorted:
        if not (t_grid[1:] > t_grid[:-1]).all():  # (NaN times too)
            raise DataError("circular_interp: the sample times must be strictly increasing")
        # (increasing: only the first or last time can be infinite)
        if not (np.isfinite(t_grid[[0, -1]]).all() and np.isfinite(angles).all()):
            raise DataError("circular_interp: a sample time or angle is not finite")
        if np.isnan(t_query).any():
            raise DataError("circular_interp: a query time is NaN")
    unwrapped = np.unwrap(angles)
    return np.asarray(wrap_angle(np.interp(t_query, t_grid, unwrapped)), dtype=float)
