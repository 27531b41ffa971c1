"""Consistency figures: NEES / NIS against χ² bounds, covariance conditioning over time.

A single run's NEES (NIS) is compared with the one-sided bound ``χ²_n(p)`` (seed 000 Eq. 34,
Fig. 10); an average over ``N`` Monte-Carlo runs with the two-sided band of the mean of ``N``
χ²(n) values (Bar-Shalom et al. 2001 §5.4), from :mod:`relloc.metrics.consistency`.
Functions draw into a given ``Axes``.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from relloc.metrics.conditioning import ILL_CONDITIONED_LOG10
from relloc.metrics.consistency import chi2_upper, mean_chi2_band
from relloc.plotting.style import legend_outside


def plot_chi2_series(
    ax: Any,
    t: ArrayLike,
    values: ArrayLike,
    dof: int,
    *,
    n_runs: int = 1,
    p: float = 0.95,
    label: str = "NEES",
    color: str | None = None,
    show_bound: bool = True,
    normalise: bool = False,
) -> None:
    """NEES/NIS over time with its χ² acceptance region.

    ``n_runs = 1``: ``values`` are single-run values and the line is ``χ²_dof(p)``.
    ``n_runs > 1``: ``values`` are averages over ``n_runs`` runs and the band is the two-sided
    ``p`` region of such an average. Several series can share one axes: pass
    ``show_bound=False`` for all but one. ``normalise`` divides values and bounds by ``dof``
    (ANEES / ANIS, ideal 1), as the report tables print them.
    """
    t = np.asarray(t, dtype=float)
    scale = 1.0 / dof if normalise else 1.0
    v = np.asarray(values, dtype=float) * scale
    ax.plot(t, v, color=color, lw=0.9, label=label)
    if show_bound and n_runs <= 1:
        bound = chi2_upper(dof, p) * scale
        ax.axhline(
            bound, color="k", lw=1.0, label=f"χ²({dof}, {p:g}){'/' + str(dof) if normalise else ''}"
        )
    elif show_bound:
        lo, hi = mean_chi2_band(dof, n_runs, p)
        ax.axhspan(
            lo * scale, hi * scale, color="0.85", zorder=0, label=f"{p:.0%} band, {n_runs} runs"
        )
        ax.axhline(dof * scale, color="0.5", lw=0.6, ls="--")
    ax.set_yscale("log")
    ax.grid(True, alpha=0.3, which="both")
    legend_outside(ax)


def plot_conditioning(
    ax: Any,
    series: Mapping[str, tuple[ArrayLike, ArrayLike]],
    *,
    threshold: float = ILL_CONDITIONED_LOG10,
) -> None:
    """``log10(λmax/λmin)`` of covariances over time (seed 000 §7.3) with the ill-conditioning
    threshold; ``series`` maps a label (``P``, ``R``, ``S`` …) to ``(t, values)``."""
    for label, (t, c) in series.items():
        ax.plot(np.asarray(t, dtype=float), np.asarray(c, dtype=float), lw=0.9, label=label)
    ax.axhline(threshold, color="tab:red", lw=0.8, ls="--", label="ill-conditioned")
    ax.set_ylabel("log10 condition number")
    ax.set_xlabel("time (s)")
    ax.grid(True, alpha=0.3)
    legend_outside(ax)
