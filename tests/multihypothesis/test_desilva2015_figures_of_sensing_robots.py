"""Seed 002's Fig. 4 and Fig. 5 analogues are drawn for the robots that sense
(``relloc.experiments.desilva2015._figures``): with ``--sensing`` another team than the paper's
two leaders, each panel is one sensing robot's filters, named after it; one sensing robot
draws one panel."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest
from test_desilva2015_figures_over_runs_and_leaders import _blank

from relloc.experiments import desilva2015 as ds

SWEEP = {"success_rate": 1.0, "wrong_association_rate": 0.0}


def _drawn(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path, observers: tuple[int, ...]
) -> dict[str, list[tuple[str, list[str]]]]:
    """The figures of one run of ``observers`` whose every filter has a track (1 m, 0.1 rad
    off, one component): per figure, each panel's title and the labels of what it draws."""
    run = _blank(observers)
    run.pos_err[:] = 1.0
    run.yaw_err[:] = 0.1
    run.components[:] = 1
    run.estimate_xy[:] = 1.0
    run.truth_xy[:] = 2.0
    drawn: dict[str, list[tuple[str, list[str]]]] = {}
    real = ds.save_figure

    def keep(fig: Any, out: Path, name: str, **kw: Any) -> str:
        drawn[name] = [(ax.get_title(), [ln.get_label() for ln in ax.lines]) for ax in fig.axes]
        return real(fig, out, name, **kw)

    monkeypatch.setattr(ds, "save_figure", keep)
    files = ds._figures(tmp_path, [run], [run], {"1": SWEEP}, {"0.95": SWEEP})
    assert all((tmp_path / f).is_file() for f in files.values())
    return drawn


def test_the_panels_are_those_of_the_sensing_robots(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    """L2 and P2 sense (``--sensing P2,L2``): Fig. 4 shows the teammates in L2's frame and in
    P2's (each robot at its own origin, its four teammates drawn), Fig. 5 one column each with
    the series of its four teammates."""
    drawn = _drawn(monkeypatch, tmp_path, (1, 3))
    fig4 = drawn["fig4_paths_and_estimates"]
    assert [title for title, _ in fig4[1:]] == [
        "dominant tracks in the L2 frame",
        "dominant tracks in the P2 frame",
    ]
    l2, p2 = (labels for _, labels in fig4[1:])
    assert "L2 (origin)" in l2 and "L2 true" not in l2 and "L1 true" in l2
    assert "P2 (origin)" in p2 and "P2 true" not in p2 and "L2 true" in p2
    for tag in ("fig5", "fig5_no_sharing"):
        panels = drawn[tag]
        assert [panels[0][0], panels[1][0]] == ["L2 (1 runs)", "P2 (1 runs)"]
        assert all(len(labels) == 4 for _, labels in panels), tag


def test_one_sensing_robot_draws_one_panel(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    """``--sensing L1``, which the flag accepts: one frame in Fig. 4, one column in Fig. 5."""
    drawn = _drawn(monkeypatch, tmp_path, (0,))
    assert [title for title, _ in drawn["fig4_paths_and_estimates"]] == [
        "world paths (run 0)",
        "dominant tracks in the L1 frame",
    ]
    assert drawn["fig5"][0][0] == "L1 (1 runs)"
    assert len(drawn["fig5"]) == 3 and np.all([len(lb) == 4 for _, lb in drawn["fig5"]])
