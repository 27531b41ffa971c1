"""Figures of cooperative localization (seed 001 Figs. 3–10, MRCLAM comparisons).

Every function draws into the matplotlib ``Axes`` it is given and returns nothing.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from relloc.plotting.style import any_positive, legend_outside


def plot_topology(
    ax: Any,
    true_xy: ArrayLike,
    estimate_xy: ArrayLike,
    sigma_xy: ArrayLike,
    landmarks_xy: ArrayLike,
    edges: Sequence[tuple[int, int]],
    landmark_edges: Sequence[tuple[int, int]] = (),
) -> None:
    """Initial RPMG (seed 001 Fig. 3): true positions, estimates with 3σ circles, edges.

    ``edges (i, j)``: robot ``i`` sees robot ``j``; ``landmark_edges (i, k)``: robot ``i`` sees
    landmark ``k``.
    """
    true_xy = np.asarray(true_xy, dtype=float)
    est = np.asarray(estimate_xy, dtype=float)
    sig = np.asarray(sigma_xy, dtype=float)
    lm = np.asarray(landmarks_xy, dtype=float).reshape(-1, 2)
    for i, j in edges:
        ax.plot(*np.stack([true_xy[i], true_xy[j]]).T, ls="--", color="tab:blue", lw=0.7)
    for i, k in landmark_edges:
        ax.plot(*np.stack([true_xy[i], lm[k]]).T, ls=":", color="tab:green", lw=0.7)
    angle = np.linspace(0.0, 2.0 * np.pi, 64)
    for i in range(true_xy.shape[0]):
        r = 3.0 * float(np.max(sig[i]))
        ax.plot(est[i, 0] + r * np.cos(angle), est[i, 1] + r * np.sin(angle), color="k", lw=0.8)
        ax.annotate(str(i + 1), true_xy[i], textcoords="offset points", xytext=(4, 4))
    ax.plot(true_xy[:, 0], true_xy[:, 1], "o", mfc="none", color="tab:red", label="true")
    ax.plot(est[:, 0], est[:, 1], "kD", ms=4, label="estimate (3σ circle)")
    ax.plot(lm[:, 0], lm[:, 1], "s", color="tab:green", ms=8, label="landmark")
    for k, p in enumerate(lm):
        ax.annotate(f"L{k + 1}", p, textcoords="offset points", xytext=(5, -10))
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.grid(True, alpha=0.3)
    legend_outside(ax)


def plot_case_series(
    ax: Any,
    t: ArrayLike,
    series: Mapping[str, ArrayLike],
    *,
    ylabel: str,
    log: bool = False,
) -> None:
    """One quantity (an error or a 3σ bound) over time for several cases (seed 001 Figs. 6–10).
    ``log`` takes effect only if some value is positive (:func:`relloc.plotting.style.
    any_positive`)."""
    t = np.asarray(t, dtype=float)
    for label, values in series.items():
        ax.plot(t, np.asarray(values, dtype=float), lw=1.0, label=label)
    if log and any_positive(*series.values()):
        ax.set_yscale("log")
    else:
        ax.axhline(0.0, color="0.6", lw=0.5)
    ax.set_xlabel("time (s)")
    ax.set_ylabel(ylabel)
    ax.grid(True, alpha=0.3, which="both")
    legend_outside(ax)


def plot_grouped_bars(
    ax: Any,
    groups: Sequence[str],
    series: Mapping[str, Sequence[float]],
    *,
    ylabel: str,
    log: bool = True,
    reference: float | None = None,
    reference_label: str = "",
) -> None:
    """Bars of ``series[label][g]`` for every group ``g`` (e.g. RMSE per mode and anchor set);
    ``None`` is a missing bar. ``log`` takes effect only if some bar or the reference is
    positive (:func:`relloc.plotting.style.any_positive`)."""
    x = np.arange(len(groups))
    width = 0.8 / max(len(series), 1)
    bars = []
    for k, (label, values) in enumerate(series.items()):
        vals = np.asarray([np.nan if v is None else v for v in values], dtype=float)
        ax.bar(x + (k - (len(series) - 1) / 2) * width, vals, width, label=label)
        bars.append(vals)
    if reference is not None:
        ax.axhline(reference, color="k", ls="--", lw=0.8, label=reference_label)
        bars.append(np.array([reference], dtype=float))
    ax.set_xticks(x, groups, rotation=20)
    if log and any_positive(*bars):
        ax.set_yscale("log")
    ax.set_ylabel(ylabel)
    ax.grid(True, alpha=0.3, axis="y", which="both")
    legend_outside(ax)
