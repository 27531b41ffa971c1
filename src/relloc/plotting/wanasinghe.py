"""Figures specific to the seed-000 reproduction (Wanasinghe et al. 2014).

Generic error, consistency and conditioning figures come from :mod:`relloc.plotting.errors`
and :mod:`relloc.plotting.consistency`; these add the reproduction's own views: convergence
curves of the Table-1 initial guesses, RMSE against the PCRLB, the odometry-noise sweep and
the PLKF / BC-PLKF / TEKF radial bias. Every function draws into the ``Axes`` it is given.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from relloc.plotting.errors import STATE_LABELS
from relloc.plotting.style import any_positive, legend_outside, plain_log_ticks


def plot_convergence_curves(
    ax: Any,
    rmse: ArrayLike,
    *,
    threshold: float,
    label: str,
    color: str,
    max_updates: int | None = None,
) -> None:
    """RMSE ``(guesses, updates)`` of one state for every initial guess, and the threshold."""
    r = np.asarray(rmse, dtype=float)
    n = r.shape[1] if max_updates is None else min(max_updates, r.shape[1])
    k = np.arange(1, n + 1)
    for g in range(r.shape[0]):
        ax.plot(k, r[g, :n], color=color, lw=0.7, alpha=0.7, label=label if g == 0 else None)
    ax.axhline(threshold, color="k", lw=0.8, ls="--")
    ax.set_yscale("log")
    ax.set_xlabel("measurement update")
    ax.grid(True, alpha=0.3, which="both")


def plot_rmse_vs_bound(
    axes: Sequence[Any], t: ArrayLike, rmse: ArrayLike, bound_sigma: ArrayLike, *, label: str
) -> None:
    """RMSE ``(K, 4)`` over Monte-Carlo runs against ``sqrt(diag PCRLB)`` ``(K, 4)``, each
    state on a logarithmic axis if some value of it is positive
    (:func:`relloc.plotting.style.any_positive`)."""
    t = np.asarray(t, dtype=float)
    r = np.asarray(rmse, dtype=float)
    b = np.asarray(bound_sigma, dtype=float)
    for i, ax in enumerate(axes):
        ax.plot(t, r[:, i], lw=0.9, label=f"{label} RMSE")
        ax.plot(t, b[:, i], lw=0.9, ls="--", label=f"{label} √PCRLB")
        ax.set_ylabel(STATE_LABELS[i])
        if any_positive(r[:, i], b[:, i]):
            ax.set_yscale("log")
        ax.grid(True, alpha=0.3, which="both")
    legend_outside(axes[0])
    axes[-1].set_xlabel("time (s)")


def plot_noise_sweep(
    ax: Any,
    sigma_v: ArrayLike,
    position_rmse: Mapping[str, ArrayLike],
    *,
    paper_band: tuple[float, float],
) -> None:
    """Steady-state position RMSE of each robot against the odometry speed noise σ_v."""
    s = np.asarray(sigma_v, dtype=float)
    for name, values in position_rmse.items():
        ax.plot(s, np.asarray(values, dtype=float), marker="o", lw=1.0, label=name)
    ax.axhspan(*paper_band, color="0.85", zorder=0, label="paper: 5–10 cm")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("odometry σ_v (m/s, white at 100 Hz)")
    ax.set_ylabel("position RMSE (m)")
    ax.grid(True, alpha=0.3, which="both")
    legend_outside(ax)


def plot_bias_comparison(
    ax: Any, values: Mapping[str, Mapping[str, float]], *, ylabel: str
) -> None:
    """Grouped bars: ``values[case][filter]`` (e.g. the radial bias of each filter per case)."""
    cases = list(values)
    filters: list[str] = []
    for per_case in values.values():
        filters.extend(f for f in per_case if f not in filters)
    width = 0.8 / max(len(filters), 1)
    x = np.arange(len(cases))
    for i, name in enumerate(filters):
        heights = [values[c].get(name, np.nan) for c in cases]
        ax.bar(x + (i - (len(filters) - 1) / 2) * width, heights, width, label=name)
    ax.set_xticks(x, cases)
    ax.axhline(0.0, color="0.4", lw=0.6)
    ax.set_ylabel(ylabel)
    ax.grid(True, axis="y", alpha=0.3)
    legend_outside(ax)


def plot_pair_targets(
    axes: Sequence[Any],
    pairs: Sequence[Mapping[str, Any]],
    cases: Sequence[str],
    *,
    yaw_target: float,
    nees_target: float,
) -> None:
    """Per pair record of ``wanasinghe2014-pairs`` and case: the calibrated yaw RMSE against
    the model's √PCRLB of φ (``axes[0]``, log–log, the diagonal RMSE = bound) and the % NEES
    beyond χ²(4, 0.95) per pair (``axes[1]``), each with its target dashed."""
    markers = "osD^v<>"
    names = [f"{p['observer']}→{p['observed']}" for p in pairs]
    x = np.arange(len(pairs))
    width = 0.8 / max(len(cases), 1)
    for k, case in enumerate(cases):
        bound = np.array([p["cases"][case]["yaw_bound_rad"] for p in pairs], dtype=float)
        yaw = np.array([p["cases"][case]["calibrated"]["yaw_rmse_rad"] for p in pairs], dtype=float)
        nees = np.array(
            [p["cases"][case]["calibrated"]["nees_percent_beyond"] for p in pairs], dtype=float
        )
        axes[0].scatter(bound, yaw, marker=markers[k % len(markers)], label=case)
        axes[1].bar(x + (k - (len(cases) - 1) / 2) * width, nees, width, label=case)
    lo = min(axes[0].get_xlim()[0], axes[0].get_ylim()[0])
    hi = max(axes[0].get_xlim()[1], axes[0].get_ylim()[1])
    axes[0].plot([lo, hi], [lo, hi], color="k", lw=0.8)
    axes[0].axhline(yaw_target, color="k", lw=0.8, ls="--")
    axes[0].set_xscale("log")
    axes[0].set_yscale("log")
    plain_log_ticks(axes[0], "xy")
    axes[0].set_xlabel("√PCRLB of φ, calibrated model (rad)")
    axes[0].set_ylabel("calibrated PLKF yaw RMSE (rad)")
    axes[0].grid(True, alpha=0.3, which="both")
    axes[0].legend(fontsize=8)
    axes[1].axhline(nees_target, color="k", lw=0.8, ls="--")
    axes[1].set_xticks(x, names, rotation=45)
    axes[1].set_ylabel("% NEES beyond χ²(4, 0.95)")
    axes[1].grid(True, alpha=0.3, axis="y")
    axes[1].set_ylim(top=1.2 * axes[1].get_ylim()[1])  # room for the legend above the bars
    axes[1].legend(fontsize=8, ncols=len(cases), loc="upper center")
