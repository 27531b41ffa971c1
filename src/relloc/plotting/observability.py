"""Observability and accuracy-limit figures.

Every function draws into the matplotlib ``Axes`` it is given and returns nothing.

- :func:`plot_case_ranks`: rank vs state dimension per analysed case, coloured by agreement
  with the paper;
- :func:`plot_subset_ranks`: rank for every set of excited input groups (one row per case);
- :func:`plot_beta_sigma`: seed 001 Fig. 2 — β connectivity and σ_min of the observability
  matrix over time (σ_min on a twin axis);
- :func:`plot_team_snapshot`: robots, landmarks and RPMG edges at one instant.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from relloc.plotting.style import legend_outside

_AGREE_COLOURS = {True: "tab:green", False: "tab:red", None: "tab:gray"}


def plot_case_ranks(
    ax: Any,
    names: Sequence[str],
    ranks: Sequence[int],
    state_dims: Sequence[int],
    agrees: Sequence[bool | None],
) -> None:
    """Horizontal bars of the rank found per case, with the state dimension as a tick mark."""
    y = np.arange(len(names))
    colours = [_AGREE_COLOURS[a] for a in agrees]
    ax.barh(y, ranks, color=colours, alpha=0.8)
    ax.scatter(state_dims, y, marker="|", s=300, color="k", label="state dimension")
    ax.set_yticks(y)
    ax.set_yticklabels(names, fontsize=8)
    ax.invert_yaxis()
    ax.set_xlabel("rank of the observability matrix")
    for colour, text in (
        ("tab:green", "agrees"),
        ("tab:red", "disagrees"),
        ("tab:gray", "no claim"),
    ):
        ax.barh([np.nan], [np.nan], color=colour, label=text)
    legend_outside(ax)


def plot_subset_ranks(ax: Any, table: Mapping[str, Mapping[str, int]]) -> None:
    """Heat map: rows are cases, columns the excited input-group sets, cells the rank."""
    cases = list(table)
    subsets = list(dict.fromkeys(k for row in table.values() for k in row))
    M = np.full((len(cases), len(subsets)), np.nan)
    for i, c in enumerate(cases):
        for j, s in enumerate(subsets):
            if s in table[c]:
                M[i, j] = table[c][s]
    im = ax.imshow(M, aspect="auto", cmap="viridis", vmin=0)
    for i in range(len(cases)):
        for j in range(len(subsets)):
            if np.isfinite(M[i, j]):
                ax.text(j, i, f"{int(M[i, j])}", ha="center", va="center", color="w", fontsize=7)
    ax.set_yticks(range(len(cases)))
    ax.set_yticklabels(cases, fontsize=8)
    ax.set_xticks(range(len(subsets)))
    ax.set_xticklabels(subsets, rotation=70, ha="right", fontsize=7)
    ax.set_xlabel("inputs that are non-zero")
    ax.figure.colorbar(im, ax=ax, label="rank")


def plot_beta_sigma(ax: Any, t: ArrayLike, beta: ArrayLike, sigma_min: ArrayLike) -> None:
    """β(G) as a dashed red step and σ_min as a solid blue line on a twin axis (Fig. 2)."""
    t = np.asarray(t, dtype=float)
    ax.step(t, np.asarray(beta, dtype=float), where="post", color="tab:red", ls="--", label="β")
    ax.set_ylim(-0.05, 1.15)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("β(G) connectivity", color="tab:red")
    twin = ax.twinx()
    twin.plot(t, np.asarray(sigma_min, dtype=float), color="tab:blue", lw=1.2, label="σ_min")
    twin.set_ylabel("σ_min of the observability matrix", color="tab:blue")
    twin.set_ylim(bottom=0.0)


def plot_team_snapshot(
    ax: Any,
    poses: ArrayLike,
    landmarks: ArrayLike,
    edges: Sequence[tuple[int, int]],
    *,
    trails: Sequence[ArrayLike] | None = None,
    title: str = "",
) -> None:
    """Robots (arrows), landmarks (squares) and RPMG edges; optional position trails."""
    P = np.asarray(poses, dtype=float)
    L = np.asarray(landmarks, dtype=float).reshape(-1, 2)
    n = P.shape[0]
    targets = np.vstack([P[:, :2], L])
    if trails is not None:
        for tr in trails:
            tr = np.asarray(tr, dtype=float)
            ax.plot(tr[:, 0], tr[:, 1], lw=0.7, color="0.7")
    for i, j in edges:
        ax.plot(*zip(P[i, :2], targets[j], strict=True), color="tab:blue", ls=":", lw=0.8)
    ax.quiver(P[:, 0], P[:, 1], np.cos(P[:, 2]), np.sin(P[:, 2]), color="tab:red", width=0.004)
    for i in range(n):
        ax.annotate(f"R{i + 1}", P[i, :2], textcoords="offset points", xytext=(4, 4), fontsize=8)
    ax.scatter(L[:, 0], L[:, 1], marker="s", color="k")
    for k in range(L.shape[0]):
        ax.annotate(f"L{k + 1}", L[k], textcoords="offset points", xytext=(4, -10), fontsize=8)
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    if title:
        ax.set_title(title)
