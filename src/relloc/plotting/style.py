"""Conventions every relloc figure shares: legends outside the data, plain numbers on
logarithmic axes, integer ticks on axes of counts. Functions act on a given ``Axes``."""

from __future__ import annotations

from typing import Any


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
