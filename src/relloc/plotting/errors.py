"""Estimation-error figures: error with ±3σ bounds, errors of several robots, trajectories.

Every function draws into the matplotlib ``Axes`` it is given (never creates figures) and
returns nothing; callers arrange axes and save figures (see
:func:`relloc.pipeline.output.save_figure`). Seed 000 Figs. 3–4 are drawn with
:func:`plot_error_with_bounds` and :func:`plot_robot_errors`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from relloc.plotting.style import legend_outside


def break_gaps(t: ArrayLike, *series: ArrayLike) -> tuple[np.ndarray, ...]:
    """Insert a NaN row wherever the time step exceeds 1.5× its median, so a line is not drawn
    across an interval without data (e.g. while a track did not exist)."""
    t = np.asarray(t, dtype=float)
    arrays = [np.asarray(y, dtype=float) for y in series]
    if t.size < 3:
        return (t, *arrays)
    dt = np.diff(t)
    gaps = np.flatnonzero(dt > 1.5 * np.median(dt)) + 1
    if gaps.size == 0:
        return (t, *arrays)
    t_out = np.insert(t, gaps, np.nan)
    return (t_out, *(np.insert(y, gaps, np.nan, axis=0) for y in arrays))


#: Axis labels of the ``RelPose4`` states.
STATE_LABELS: tuple[str, ...] = ("x (m)", "y (m)", "z (m)", "φ (rad)")


def plot_error_with_bounds(
    ax: Any,
    t: ArrayLike,
    error: ArrayLike,
    sigma: ArrayLike,
    *,
    n_sigma: float = 3.0,
    ylabel: str = "",
    label: str = "error",
    color: str = "tab:blue",
    bound_color: str = "tab:cyan",
) -> None:
    """One state's error over time with the ``±n_sigma·σ`` envelope of the filter (lines are
    broken where samples are missing)."""
    t, e, s = break_gaps(t, error, n_sigma * np.asarray(sigma, dtype=float))
    ax.plot(t, e, color=color, lw=1.0, label=label)
    ax.plot(t, s, color=bound_color, lw=0.9, label=f"±{n_sigma:g}σ")
    ax.plot(t, -s, color=bound_color, lw=0.9)
    ax.axhline(0.0, color="0.6", lw=0.5)
    if ylabel:
        ax.set_ylabel(ylabel)
    ax.grid(True, alpha=0.3)


def plot_pose_errors_with_bounds(
    axes: Sequence[Any],
    t: ArrayLike,
    errors: ArrayLike,
    sigmas: ArrayLike,
    *,
    n_sigma: float = 3.0,
) -> None:
    """All four ``(x, y, z, φ)`` errors ``(K, 4)`` with their bounds, one state per axis."""
    e = np.asarray(errors, dtype=float)
    s = np.asarray(sigmas, dtype=float)
    for i, ax in enumerate(axes):
        plot_error_with_bounds(ax, t, e[:, i], s[:, i], n_sigma=n_sigma, ylabel=STATE_LABELS[i])
    legend_outside(axes[0])
    axes[-1].set_xlabel("time (s)")


def plot_robot_errors(
    axes: Sequence[Any],
    series: Mapping[str, tuple[ArrayLike, ArrayLike]],
) -> None:
    """Errors ``(K, 4)`` of several robots overlaid, one state per axis (seed 000 Fig. 4).

    ``series`` maps a label (e.g. the observed robot's name) to ``(t, errors)``.
    """
    for label, (t_raw, err) in series.items():
        t, e = break_gaps(t_raw, err)
        for i, ax in enumerate(axes):
            ax.plot(t, e[:, i], lw=0.9, label=label)
    for i, ax in enumerate(axes):
        ax.set_ylabel(STATE_LABELS[i])
        ax.axhline(0.0, color="0.6", lw=0.5)
        ax.grid(True, alpha=0.3)
    legend_outside(axes[0])
    axes[-1].set_xlabel("time (s)")


def plot_trajectories(
    ax: Any,
    paths: Mapping[str, ArrayLike],
    *,
    arena: tuple[tuple[float, float], tuple[float, float]] | None = None,
    markers: Mapping[str, str] | None = None,
) -> None:
    """Planar paths ``(K, ≥2)`` of several robots, with start markers (in the legend) and the
    arena outline; the legend sits outside the data. An empty path (``K = 0``) keeps its
    legend entry and has no start marker."""

    for k, (name, path) in enumerate(paths.items()):
        p = np.asarray(path, dtype=float)
        (line,) = ax.plot(p[:, 0], p[:, 1], lw=1.2, label=name)
        if not p.shape[0]:
            continue
        marker = (markers or {}).get(name, "o")
        start = "start" if k == 0 and not markers else None
        ax.plot(p[0, 0], p[0, 1], marker=marker, color=line.get_color(), ms=6, ls="", label=start)
    if arena is not None:
        (x0, x1), (y0, y1) = arena
        ax.plot([x0, x1, x1, x0, x0], [y0, y0, y1, y1, y0], color="0.3", lw=1.0)
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.grid(True, alpha=0.3)
    legend_outside(ax)
