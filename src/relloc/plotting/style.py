"""Conventions every relloc figure shares: legends outside the data, plain numbers on
logarithmic axes, integer ticks on axes of counts. Functions act on a given ``Axes``."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike


def legend_outside(ax: Any, **kwargs: Any) -> None:
    """The axes' legend to the right of it, outside the data."""
    handles, labels = ax.get_legend_handles_labels()
    if handles:
        ax.legend(
            handles,
            labels,
            loc="upper left",
            bbox_to_anchor=(1.01, 1.0),
            borderaxespad=0.0,
            fontsize="small",
            **kwargs,
        )


def any_positive(*values: ArrayLike) -> bool:
    """Whether some value of ``values`` is > 0 (NaN is not). A logarithmic axis needs one:
    with none matplotlib cannot scale the axis (it warns, and may fail while saving), so a
    figure keeps that axis linear. Non-positive values among positive ones need no masking
    here: matplotlib leaves them out of a logarithmic axis itself."""
    return any(bool(np.any(np.asarray(v, dtype=float) > 0)) for v in values)


def plain_log_ticks(ax: Any, axes: str = "y") -> None:
    """Ticks of each logarithmic axis named in ``axes`` (``"x"``, ``"y"`` or ``"xy"``) at
    1, 2, 5 × 10^k written as plain numbers (0.5, 2, 10)."""
    from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

    for name in axes:
        axis = getattr(ax, f"{name}axis")
        axis.set_major_locator(LogLocator(base=10.0, subs=(1.0, 2.0, 5.0)))
        axis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
        axis.set_minor_formatter(NullFormatter())


def integer_ticks(axis: Any) -> None:
    """Only integer ticks on an axis of counts (``ax.xaxis`` or ``ax.yaxis``)."""
    from matplotlib.ticker import MaxNLocator

    axis.set_major_locator(MaxNLocator(integer=True))
