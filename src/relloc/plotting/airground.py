"""Figures of the air-ground reproduction (seed 003 Figs. 4, 5, 7, 8, 9): traces, relative
estimates over a detection-timeline background, sweeps, UWB error histogram.

Every function draws into the Axes it is given; nothing here is imported by core code.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from relloc.core.recording import Recording

Array = NDArray[np.float64]

#: Background colour of "pair {R_0, R_i} detected" per follower (paper: green, blue, black, cyan).
PAIR_COLOURS = ("#8fd18f", "#8fb3ff", "#ffd27f", "#8fe3e3", "#d9a3ff", "#c8c8c8")
MULTI_COLOUR = "#404040"
NONE_COLOUR = "#f7c6c6"


def detection_codes(detected: NDArray[np.bool_]) -> NDArray[np.int64]:
    """Per tick: −1 no pair detected, −2 several pairs, else the 0-based follower index."""
    count = detected.sum(axis=1)
    return np.where(count == 0, -1, np.where(count > 1, -2, np.argmax(detected, axis=1)))


def plot_detection_background(ax: Any, t: Array, detected: NDArray[np.bool_]) -> None:
    """Shade the time axis by which pairs the drones detect (Figs. 4, 7, 9 colour code).

    One ``fill_between`` per colour (not one span per segment), so flickering detections stay
    cheap to draw.
    """
    codes = detection_codes(detected)
    n = detected.shape[1]
    styles = [(-1, NONE_COLOUR, 0.35), (-2, MULTI_COLOUR, 0.2)]
    styles += [(i, PAIR_COLOURS[i % len(PAIR_COLOURS)], 0.35) for i in range(n)]
    transform = ax.get_xaxis_transform()
    for code, colour, alpha in styles:
        mask = codes == code
        if mask.any():
            ax.fill_between(
                t,
                0,
                1,
                where=mask,
                step="post",
                color=colour,
                alpha=alpha,
                lw=0,
                transform=transform,
            )


def detection_legend_handles(n_followers: int, *, lines: bool = False) -> list[Any]:
    """Legend patches for :func:`plot_detection_background`; ``lines`` adds the true (dashed)
    and estimated (solid) line styles of :func:`plot_component`."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    handles: list[Any] = []
    if lines:
        handles += [
            Line2D([], [], color="k", ls="--", lw=1.0, label="true"),
            Line2D([], [], color="tab:blue", lw=1.2, label="estimate"),
        ]
    handles += [
        Patch(color=PAIR_COLOURS[i % len(PAIR_COLOURS)], alpha=0.35, label=f"{{R0,R{i + 1}}}")
        for i in range(n_followers)
    ]
    handles.append(Patch(color=MULTI_COLOUR, alpha=0.2, label="several pairs"))
    handles.append(Patch(color=NONE_COLOUR, alpha=0.35, label="no pair"))
    return handles


def plot_traces(ax: Any, recording: Recording) -> None:
    """Paths of every robot of ``recording``: UGVs solid (the leader, robot 0, thick), drones
    dashed; a dot marks each UGV's start."""
    truth = recording.require_truth("plot_traces")
    for i, (name, platform, gt) in enumerate(
        zip(recording.robots, recording.platforms, truth, strict=True)
    ):
        x, y = gt.pose[:, 0], gt.pose[:, 1]
        if platform == "aerial":
            ax.plot(x, y, "k--", lw=0.7, label=name)
            continue
        ax.plot(x, y, lw=2.2 if i == 0 else 1.2, label=f"{name} (leader)" if i == 0 else name)
        ax.plot(x[0], y[0], "ko", ms=3)
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0)


def plot_component(
    ax: Any,
    t: Array,
    estimate: Array,
    truth: Array,
    detected: NDArray[np.bool_],
    label: str,
) -> None:
    """One state component, estimate (solid) against truth (dashed), over the detection shading."""
    plot_detection_background(ax, t, detected)
    ax.plot(t, truth, "k--", lw=1.0, label=f"{label} true")
    ax.plot(t, estimate, color="tab:blue", lw=1.2, label=f"{label} est.")
    ax.set_ylabel(label)
    ax.margins(x=0)


def plot_sweep(
    ax: Any,
    xs: Sequence[float],
    series: dict[str, Sequence[float]],
    xlabel: str,
    bound: float | None = None,
    *,
    integer_x: bool = False,
) -> None:
    """Lines of a parameter sweep; an optional horizontal bound (the paper's); ``integer_x``
    for a count (ticks only at integers). The legend sits below the axes."""
    from relloc.plotting.style import integer_ticks

    for name, ys in series.items():
        ax.plot(xs, ys, "o-", label=name)
    if bound is not None:
        ax.axhline(bound, color="r", ls=":", label=f"paper bound {bound} m")
    if integer_x:
        integer_ticks(ax.xaxis)
    ax.set_xlabel(xlabel)
    ax.set_ylabel("RMSE [m]")
    ax.set_ylim(bottom=0.0)
    ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.2), ncol=3)
    ax.grid(alpha=0.3)


def plot_uwb_errors(ax: Any, residuals: Array, spread: float, threshold: float) -> None:
    """Histogram of within-link UWB residuals with the fitted Gaussian core and outlier gate."""
    ax.hist(residuals, bins=80, density=True, alpha=0.6, label="TIERS UWB − mocap (per link)")
    x = np.linspace(float(residuals.min()), float(residuals.max()), 400)
    ax.plot(
        x,
        np.exp(-0.5 * (x / spread) ** 2) / (spread * np.sqrt(2 * np.pi)),
        "k",
        lw=1.2,
        label=f"fitted core σ = {spread:.3f} m",
    )
    for k, s in enumerate((-threshold, threshold)):
        label = f"outlier gate ±{threshold:.3f} m" if k == 0 else None
        ax.axvline(s, color="r", ls=":", lw=1, label=label)
    ax.set_xlabel("range residual [m]")
    ax.set_ylabel("density [1/m]")
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0)
