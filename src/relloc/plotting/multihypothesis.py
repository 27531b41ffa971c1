"""Figures of the multi-hypothesis (seed 002) experiments.

Every function draws into the matplotlib ``Axes`` it is given and returns nothing (seed 002
Fig. 4: paths and relative estimates; Fig. 5: hypotheses over time and log RMS errors).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from relloc.plotting.style import legend_outside


def plot_world_paths(ax: Any, truth: ArrayLike, names: Sequence[str]) -> None:
    """World paths ``truth (T, n, ≥2)`` of every robot, start marked with a dot."""
    tr = np.asarray(truth, dtype=float)
    for j, name in enumerate(names):
        (line,) = ax.plot(tr[:, j, 0], tr[:, j, 1], lw=1.0, label=name)
        ax.plot(tr[0, j, 0], tr[0, j, 1], "o", color=line.get_color(), ms=4)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_aspect("equal", adjustable="datalim")
    legend_outside(ax)


def plot_relative_estimates(
    ax: Any,
    estimate: ArrayLike,
    truth: ArrayLike,
    names: Sequence[str],
    observer: int,
) -> None:
    """Estimated (dots) and true (lines) positions of the teammates in ``observer``'s frame.

    ``estimate`` and ``truth`` are ``(S, n, ≥2)``; the observer's own column is skipped.
    """
    est = np.asarray(estimate, dtype=float)
    tru = np.asarray(truth, dtype=float)
    for j, name in enumerate(names):
        if j == observer:
            continue
        (line,) = ax.plot(tru[:, j, 0], tru[:, j, 1], lw=0.8, label=f"{name} true")
        ax.plot(est[:, j, 0], est[:, j, 1], ".", ms=1.5, color=line.get_color())
    ax.plot(0.0, 0.0, "k^", ms=6, label=f"{names[observer]} (origin)")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_aspect("equal", adjustable="datalim")
    legend_outside(ax)


def plot_series(
    ax: Any,
    t: ArrayLike,
    series: Mapping[str, ArrayLike],
    *,
    ylabel: str,
    log10: bool = False,
    legend: bool = True,
) -> None:
    """Several named time series against ``t``.

    ``log10``: draw ``log10(y)`` on a linear axis (seed 002 Fig. 5 plots log RMS errors);
    ``legend``: label the lines.
    """
    tt = np.asarray(t, dtype=float)
    for label, y in series.items():
        yy = np.asarray(y, dtype=float)
        if log10:
            with np.errstate(divide="ignore", invalid="ignore"):
                yy = np.log10(yy)
        ax.plot(tt, yy, lw=1.0, label=label)
    ax.set_xlabel("time (s)")
    ax.set_ylabel(f"log10 {ylabel}" if log10 else ylabel)
    ax.grid(alpha=0.3)
    if legend:
        legend_outside(ax)


def plot_sweep(
    ax: Any,
    x: Sequence[float],
    curves: Mapping[str, Sequence[float]],
    *,
    xlabel: str,
    ylabel: str,
    logx: bool = False,
) -> None:
    """Figures of merit against a swept setting (one line per named curve)."""
    for label, y in curves.items():
        ax.plot(list(x), list(y), "o-", lw=1.0, label=label)
    if logx:
        ax.set_xscale("log")
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.grid(alpha=0.3)
    legend_outside(ax)
