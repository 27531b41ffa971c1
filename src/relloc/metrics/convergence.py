"""Convergence time: how many measurement updates until an error series stays below a threshold.

Seed 000 §5.1 counts the measurement updates after which each state's RMSE stays under a
threshold. Eq. 32 ties the threshold to the known-initialisation case (case 1)::

    x_th = 1.05 · max_k RMSE_x,case1(k)        (and likewise for y, z, φ)

The fixed-threshold rule uses absolute limits instead (default 0.05 m, 0.1 rad), which do not
move when the odometry noise changes the case-1 RMSE.

A series ``e`` is indexed by update: ``e[0]`` is the error after the first update. The number
of updates to converge is ``k + 1`` for the first ``k`` with ``e[j] < threshold`` for all
``j ≥ k``; ``None`` if the series never settles below the threshold.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from relloc.core.checks import floats, positive
from relloc.errors import ConfigError, DataError

Array = NDArray[np.float64]

#: Fixed-rule thresholds for ``(x, y, z, φ)``: 0.05 m and 0.1 rad.
FIXED_THRESHOLDS: tuple[float, float, float, float] = (0.05, 0.05, 0.05, 0.1)
#: Seed 000 Eq. 32 margin over the known-initialisation maximum RMSE.
PAPER_MARGIN = 1.05


def paper_thresholds(known_init_rmse: ArrayLike, margin: float = PAPER_MARGIN) -> Array:
    """Eq. 32: ``margin · max_k RMSE(k)`` per state from the case-1 RMSE series ``(time, n)``,
    NaN entries (no estimate) skipped. ``margin`` is a finite number > 0 (``ConfigError``); a
    negative or infinite RMSE, or a state with no finite one, is a :class:`DataError`."""
    margin = positive(margin, "paper_thresholds: margin")
    rmse = floats(known_init_rmse, "paper_thresholds: known_init_rmse")
    if rmse.ndim != 2 or rmse.shape[0] == 0:
        raise DataError(f"paper_thresholds: expected an RMSE series (time, n), got {rmse.shape}")
    if np.any(rmse < 0.0) or np.isinf(rmse).any():
        raise DataError("paper_thresholds: known_init_rmse has negative or infinite entries")
    missing = np.flatnonzero(np.isnan(rmse).all(axis=0))
    if missing.size:
        raise DataError(f"paper_thresholds: known_init_rmse has no value in columns {missing}")
    return margin * np.nanmax(rmse, axis=0)


def updates_to_converge(series: ArrayLike, threshold: float) -> int | None:
    """Number of updates after which ``|series|`` stays strictly below ``threshold``: one
    series ``(updates,)`` (:class:`DataError` for more dimensions), a finite ``threshold`` > 0
    (``ConfigError``)."""
    threshold = positive(threshold, "updates_to_converge: threshold")
    raw = floats(series, "updates_to_converge: series")
    if raw.ndim > 1:
        raise DataError(
            f"updates_to_converge: series {raw.shape} must be one series (updates,); "
            "updates_to_converge_per_state takes (updates, n)"
        )
    e = np.abs(raw.reshape(-1))
    if e.size == 0:
        raise DataError("updates_to_converge: empty error series")
    above = ~(e < threshold)  # NaN counts as not converged
    if not above.any():
        return 1
    last_above = int(np.flatnonzero(above)[-1])
    if last_above == e.size - 1:
        return None
    return last_above + 2


def updates_to_converge_per_state(
    series: ArrayLike, thresholds: Sequence[float] | ArrayLike
) -> list[int | None]:
    """:func:`updates_to_converge` for each column of ``series (updates, n)``; each threshold
    a finite number > 0 (``ConfigError`` naming it)."""
    e = floats(series, "updates_to_converge_per_state: series")
    th = floats(thresholds, "updates_to_converge_per_state: thresholds", ConfigError).reshape(-1)
    if e.ndim != 2 or e.shape[1] != th.size:
        raise DataError(
            f"updates_to_converge_per_state: series {e.shape} needs {th.size} state columns"
        )
    limits = [
        positive(x, f"updates_to_converge_per_state: thresholds[{i}]") for i, x in enumerate(th)
    ]
    return [updates_to_converge(e[:, i], limits[i]) for i in range(th.size)]
