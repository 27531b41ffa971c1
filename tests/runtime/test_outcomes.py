"""How a team's headline figures are compared with the in-process run's."""

from __future__ import annotations

import math

import pytest

from relloc.runtime.outcomes import difference_cell, figure_agreement, figure_difference


@pytest.mark.parametrize(
    ("a", "b", "expected"),
    [
        (0.5, 0.25, 0.25),
        (None, 0.25, None),  # a figure missing: nothing to compare
        (math.nan, math.nan, None),  # undefined in both (no steady-state samples)
    ],
)
def test_figure_difference(a, b, expected):
    assert figure_difference(a, b) == expected


@pytest.mark.parametrize(
    ("difference", "cell"),
    [(0.25, 0.25), (None, None), (math.nan, "differs"), (math.inf, "differs")],
)
def test_a_difference_that_is_not_finite_shows_as_differs(difference, cell):
    assert difference_cell(difference) == cell


def test_a_figure_undefined_in_one_run_only_is_a_disagreement():
    diff = figure_difference(math.nan, 0.1)
    assert diff is not None and math.isnan(diff)
    verdict = figure_agreement(
        0.0, True, {"pos_rmse_m": diff}, belief_tolerance=1e-6, figure_tolerance=1e-6
    )
    assert not verdict["agreement"]["within_tolerance"]
    both = figure_agreement(
        0.0,
        True,
        {"pos_rmse_m": figure_difference(math.nan, math.nan), "success_rate": 0.0},
        belief_tolerance=1e-6,
        figure_tolerance=1e-6,
    )
    assert both["agreement"]["within_tolerance"]


def test_a_fault_outcome_reads_as_one_console_line():
    """The console shows a windowed fault's RMSEs before → during → after with units and its
    track counts, figures at four significant digits ("—" where there are no samples), not
    the outcome's raw JSON."""
    from relloc.runtime.team import fault_outcome_text

    kill = {
        "fault": "kill ground1@10, restart @20",
        "window_s": [10.0, 20.0],
        "affected_pairs": ["observer->ground1"],
        "position_rmse_before_m": 0.0123456789,
        "position_rmse_during_m": None,
        "position_rmse_after_m": 0.5,
        "yaw_rmse_before_rad": 0.01,
        "yaw_rmse_during_rad": math.nan,
        "yaw_rmse_after_rad": 0.2,
        "tracks_kept": 2,
        "tracks_deleted": 1,
        "tracks_lost_with_process": 0,
        "tracks_refound": 3,
        "restarted": True,
    }
    assert fault_outcome_text(kill) == (
        "fault kill ground1@10, restart @20 (10–20 s): position RMSE 0.01235 → — → 0.5 m, "
        "yaw RMSE 0.01 → — → 0.2 rad (before → during → after); tracks kept 2, deleted 1, "
        "lost with process 0, re-found 3"
    )
    network = {
        "fault": "network drop=0.1",
        "window_s": [0.0, 30.0],
        "position_rmse_during_m": 0.02,
        "yaw_rmse_during_rad": 0.013,
        "tracks_created": 4,
        "tracks_deleted": 0,
        "tracks_refound": 0,
        "note": "whole run",
    }
    assert fault_outcome_text(network) == (
        "fault network drop=0.1 (0–30 s): position RMSE 0.02 m, yaw RMSE 0.013 rad; "
        "tracks created 4, deleted 0, re-found 0; whole run"
    )


def test_the_agreement_line_names_the_tolerance_and_the_verdict():
    blocks = figure_agreement(
        2.5e-7, True, {"pos_rmse_m": 0.0}, belief_tolerance=1e-6, figure_tolerance=1e-6
    )
    from relloc.runtime.outcomes import agreement_text

    assert agreement_text(blocks) == (
        "largest |Δ| of a belief entry 2.5e-07 (tolerance 1e-06; within tolerance)"
    )
    blocks = figure_agreement(
        0.003, False, {"pos_rmse_m": 0.0}, belief_tolerance=1e-6, figure_tolerance=1e-6
    )
    assert agreement_text(blocks).endswith("(tolerance 1e-06; NOT within tolerance)")
