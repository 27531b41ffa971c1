"""Estimation errors with angle wrapping and RMSE over Monte-Carlo runs.

Error ``e = x̂ − x`` per state, with the entries listed in ``angle_indices`` wrapped to
[−π, π) (for ``RelPose4 = (x, y, z, φ)`` that is index 3). RMSE per state over ``N`` runs at
each time is ``√(1/N Σ_i e_i²)`` (seed 000 Fig. 5, Table 3). The radial error ``‖p̂‖ − ‖p‖``
measures the range bias of pseudo-linear filters.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from relloc.core import checks
from relloc.core.angles import wrap_angle
from relloc.errors import ConfigError, DataError

Array = NDArray[np.float64]

#: Index of the yaw in a ``RelPose4`` state.
RELPOSE4_ANGLES: tuple[int, ...] = (3,)


def state_errors(
    estimate: ArrayLike, truth: ArrayLike, angle_indices: Sequence[int] = RELPOSE4_ANGLES
) -> Array:
    """``x̂ − x`` with the angle entries wrapped; any matching shapes ``(..., n)``.

    Shapes that differ, or infinite entries (NaN ones, missing records, give NaN errors), are a
    :class:`DataError`; ``angle_indices`` must be a sequence (or an array) of integers in
    ``[−n, n)`` (:class:`ConfigError` otherwise — a bare integer, a float index, an index
    beyond the state).
    """
    est = checks.floats(estimate, "state_errors: estimate")
    tru = checks.floats(truth, "state_errors: truth")
    if est.shape != tru.shape:
        raise DataError(f"state_errors: estimate shape {est.shape} != truth shape {tru.shape}")
    for name, x in (("estimate", est), ("truth", tru)):
        if np.isinf(x).any():
            raise DataError(
                f"state_errors: {np.count_nonzero(np.isinf(x))} infinite {name} entries"
            )
    if isinstance(angle_indices, (str, bytes)) or not isinstance(angle_indices, Iterable):
        raise ConfigError(
            f"state_errors: angle_indices must be a sequence of state indices, got "
            f"{angle_indices!r:.40}"
        )
    n = est.shape[-1] if est.ndim else 0
    angles = [
        checks.count(i, f"state_errors: angle_indices[{k}]", low=-n)
        for k, i in enumerate(angle_indices)
    ]
    for k, i in enumerate(angles):
        if i >= n:
            raise ConfigError(
                f"state_errors: angle_indices[{k}] = {i} is beyond the {n} entries of a state"
            )
    err = est - tru
    for i in angles:
        err[..., i] = wrap_angle(err[..., i])
    return err


def rmse(errors: ArrayLike, axis: int | tuple[int, ...] | None = 0) -> Array:
    """Root-mean-square of ``errors`` along ``axis`` (default: over runs, the first axis).

    ``errors (runs, time, n)`` → RMSE per time and state ``(time, n)``; use
    ``axis=(0, 1)`` for one number per state over runs and time. NaN entries (e.g. no estimate
    while a track did not exist) are ignored; an all-NaN slice gives NaN. Finite errors whose
    squares overflow (beyond about 1.3e154) are a :class:`DataError`.

    ``axis`` is an integer or a tuple of distinct integers in ``[−ndim, ndim)`` (negative ones
    count from the end), or ``None`` for all axes; anything else is a :class:`ConfigError`.
    """
    e = checks.floats(errors, "rmse: errors")
    axes = tuple(range(e.ndim)) if axis is None else axis if isinstance(axis, tuple) else (axis,)
    if not axes and e.ndim:
        raise ConfigError("rmse: axis must name at least one axis, got ()")
    seen: set[int] = set()
    for a in axes:
        k = checks.count(a, "rmse: axis", low=-e.ndim)
        if k >= e.ndim:
            raise ConfigError(f"rmse: axis {k} is beyond the {e.ndim} axes of the errors")
        if k % e.ndim in seen:
            raise ConfigError(f"rmse: axis {axis} names axis {k % e.ndim} twice")
        seen.add(k % e.ndim)
    with np.errstate(over="ignore"):
        sq = np.square(e)
    if np.any(np.isinf(sq) & np.isfinite(e)):
        raise DataError("rmse: errors beyond 1.3e154 in magnitude overflow their squares")
    count = np.sum(np.isfinite(sq), axis=axis)
    total = np.nansum(sq, axis=axis)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.sqrt(np.where(count > 0, total / np.maximum(count, 1), np.nan))


def radial_errors(estimate: ArrayLike, truth: ArrayLike) -> Array:
    """Range error ``‖p̂‖ − ‖p‖`` of the positions (first three entries) ``(..., ≥3)`` → ``(...)``.

    Its mean over runs is the radial bias (positive: the robot is placed too far away, as the
    plain PLKF does with a noisy bearing sensor).
    """
    est = checks.floats(estimate, "radial_errors: estimate")
    tru = checks.floats(truth, "radial_errors: truth")
    if est.shape != tru.shape or est.ndim == 0 or est.shape[-1] < 3:
        raise DataError(f"radial_errors: shapes {est.shape} and {tru.shape} must match, ≥ 3 wide")
    return np.linalg.norm(est[..., :3], axis=-1) - np.linalg.norm(tru[..., :3], axis=-1)
