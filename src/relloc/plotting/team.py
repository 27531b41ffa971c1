"""Figures of a team run (``relloc run``, ``relloc team up``): paths, gaps, convergence.

Every function draws into the ``Axes`` it is given. Conventions shared by the team figures:
legends sit outside the data and logarithmic axes carry plain numbers
(:mod:`relloc.plotting.style`), intervals in which a pair had no track are shaded
(:func:`shade_gaps`).

The estimated path of a teammate in the world frame (:func:`estimated_world_path`) is the
observed robot's true position plus the filter's error rotated out of the observer's body
frame: with ``e = x̂ − x`` the error of the relative pose ``(x, y, z, φ)`` (seed 000 Eq. 1),
``p̂_j = p_j + R_z(ψ_i) e_{xyz}`` — the estimate the observer would draw on a map if it knew
its own pose.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from relloc.plotting.errors import break_gaps
from relloc.plotting.style import legend_outside

Array = NDArray[np.float64]


def track_gaps(
    events: Sequence[Any], owner: str, subject: str, t_end: float
) -> list[tuple[float, float]]:
    """Intervals ``(deleted, re-created)`` in which ``owner`` held no track of ``subject``
    (to ``t_end`` if it was never re-created), from :class:`relloc.core.contract.TrackEvent`s."""
    mine = sorted((e.t, e.kind) for e in events if (e.owner, e.subject) == (owner, subject))
    gaps: list[tuple[float, float]] = []
    start: float | None = None
    for t, kind in mine:
        if kind == "deleted" and start is None:
            start = t
        elif kind in ("created", "recreated") and start is not None:
            gaps.append((start, t))
            start = None
    if start is not None:
        gaps.append((start, t_end))
    return gaps


def shade_gaps(ax: Any, gaps: Sequence[tuple[float, float]], *, label: bool = True) -> None:
    """Shade the intervals without a track (labelled once)."""
    for k, (a, b) in enumerate(gaps):
        ax.axvspan(a, b, color="0.88", zorder=0, label="no track" if label and k == 0 else None)


def steady_limits(
    ax: Any, t: ArrayLike, values: ArrayLike, t_from: float, margin: float = 1.3
) -> None:
    """Scale the y axis to the values at ``t ≥ t_from`` (a start-up transient is clipped)."""
    t = np.asarray(t, dtype=float)
    v = np.abs(np.asarray(values, dtype=float))
    keep = (t >= t_from) & np.isfinite(v)
    if keep.any() and float(np.max(v[keep])) > 0:
        half = margin * float(np.max(v[keep]))
        ax.set_ylim(-half, half)


def _interp_path(t_path: Array, path: Array, t: Array) -> Array:
    """A true path ``(K, 4)`` = x, y, z, ψ at times ``t`` (ψ interpolated unwrapped)."""
    cols = [np.interp(t, t_path, path[:, i]) for i in range(3)]
    cols.append(np.interp(t, t_path, np.unwrap(path[:, 3])))
    return np.column_stack(cols)


def estimated_world_path(
    t_path: ArrayLike,
    owner_path: ArrayLike,
    subject_path: ArrayLike,
    t: ArrayLike,
    error: ArrayLike,
) -> Array:
    """World position ``(K, 3)`` of the relative estimate at times ``t`` (module docstring)."""
    tp = np.asarray(t_path, dtype=float)
    tt = np.asarray(t, dtype=float)
    e = np.asarray(error, dtype=float)
    owner = _interp_path(tp, np.asarray(owner_path, dtype=float), tt)
    subject = _interp_path(tp, np.asarray(subject_path, dtype=float), tt)
    c, s = np.cos(owner[:, 3]), np.sin(owner[:, 3])
    dx = c * e[:, 0] - s * e[:, 1]
    dy = s * e[:, 0] + c * e[:, 1]
    return np.column_stack([subject[:, 0] + dx, subject[:, 1] + dy, subject[:, 2] + e[:, 2]])


def plot_team_paths(
    ax_xy: Any,
    ax_z: Any,
    t_path: ArrayLike,
    paths: Mapping[str, ArrayLike],
    estimates: Mapping[str, tuple[ArrayLike, ArrayLike, str]],
    *,
    views: Mapping[str, tuple[float, float]] | None = None,
    arena: tuple[tuple[float, float], tuple[float, float]] | None = None,
) -> None:
    """True paths (solid) with labelled start markers, estimated paths (dashed), each
    observer's field of view at its start pose, and the heights over time.

    ``paths``: robot → ``(K, 4)`` true x, y, z, ψ at ``t_path``; ``estimates``: pair label →
    ``(t, (M, 3) world position, subject)``; ``views``: observer → ``(fov_deg, max_range)``.
    A robot with an empty true path (``K = 0``) keeps its legend entry but has no start marker
    and no field of view (both are drawn at its first pose).
    """
    from matplotlib.patches import Wedge

    tp = np.asarray(t_path, dtype=float)
    colors: dict[str, str] = {}
    for name, path in paths.items():
        p = np.asarray(path, dtype=float)
        (line,) = ax_xy.plot(p[:, 0], p[:, 1], lw=1.2, label=f"{name} (true)")
        colors[name] = line.get_color()
        ax_z.plot(tp, p[:, 2], lw=1.2, color=colors[name], label=f"{name} (true)")
        if not p.shape[0]:
            continue
        ax_xy.plot(p[0, 0], p[0, 1], "o", color=colors[name], ms=6)
        ax_xy.annotate(
            f"{name} start",
            (p[0, 0], p[0, 1]),
            xytext=(4, 4),
            textcoords="offset points",
            fontsize="x-small",
            color=colors[name],
        )
    for label, (t, xyz, subject) in estimates.items():
        tt, q = break_gaps(t, xyz)
        color = colors.get(subject)
        ax_xy.plot(q[:, 0], q[:, 1], ls="--", lw=0.9, color=color, label=f"{label} (estimate)")
        ax_z.plot(tt, q[:, 2], ls="--", lw=0.9, color=color, label=f"{label} (estimate)")
    for name, (fov_deg, max_range) in (views or {}).items():
        p = np.asarray(paths[name], dtype=float)
        if not p.shape[0]:
            continue
        heading = float(np.degrees(p[0, 3]))
        ax_xy.add_patch(
            Wedge(
                (p[0, 0], p[0, 1]),
                max_range,
                heading - fov_deg / 2,
                heading + fov_deg / 2,
                alpha=0.12,
                color=colors[name],
                label=f"{name} field of view at start",
            )
        )
    if arena is not None:
        (x0, x1), (y0, y1) = arena
        ax_xy.plot([x0, x1, x1, x0, x0], [y0, y0, y1, y1, y0], color="0.3", lw=1.0, label="arena")
        ax_xy.set_xlim(x0 - 0.5, x1 + 0.5)
        ax_xy.set_ylim(y0 - 0.5, y1 + 0.5)
    ax_xy.set_aspect("equal", adjustable="box")
    ax_xy.set_xlabel("x (m)")
    ax_xy.set_ylabel("y (m)")
    ax_xy.grid(True, alpha=0.3)
    legend_outside(ax_xy)
    ax_z.set_xlabel("time (s)")
    ax_z.set_ylabel("z (m)")
    ax_z.grid(True, alpha=0.3)


def plot_convergence(
    ax: Any, times: Mapping[str, Sequence[float | None]], *, t_max: float | None = None
) -> None:
    """Share of runs converged by time ``t`` after the track started, one step curve per pair
    (``None`` = a run that never converged; the curve then ends below 100 %)."""
    for label, per_run in times.items():
        n = len(per_run)
        done = np.sort([float(v) for v in per_run if v is not None])
        if n == 0:
            continue
        end = t_max if t_max is not None else (float(done[-1]) if done.size else 1.0)
        x = np.concatenate([[0.0], done, [max(end, float(done[-1]) if done.size else 0.0)]])
        y = np.concatenate([[0.0], np.arange(1, done.size + 1) / n, [done.size / n]]) * 100
        ax.step(x, y, where="post", lw=1.2, label=f"{label} ({done.size}/{n} runs)")
    ax.set_xlabel("time since the track started (s)")
    ax.set_ylabel("runs converged (%)")
    ax.set_ylim(-2, 102)
    ax.grid(True, alpha=0.3)
    legend_outside(ax)
