"""Seed 001's scoring helpers (``relloc.experiments.sharma2013``) on hand-made inputs: the
frame-NEES times, the spanning tree of the robot graph, the growth ratios, the frame-NEES
verdict and the choice of the headline observability-aware filter."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from relloc.experiments.sharma2013 import (
    _growth,
    _spanning_edges,
    frame_nees_summary,
    frame_times,
    headline_aware,
)


def test_frame_times_are_every_30_s_after_the_start_and_the_last() -> None:
    np.testing.assert_array_equal(frame_times(np.arange(0.0, 100.0, 0.5)), [30, 60, 90, 99.5])
    np.testing.assert_array_equal(frame_times(np.arange(10.0, 75.1, 2.5)), [40, 70, 75])
    np.testing.assert_array_equal(frame_times(np.arange(0.0, 60.5, 1.0)), [30, 60])
    # no 30-s mark inside the run: the last time only
    np.testing.assert_array_equal(frame_times(np.array([0.0, 7.0, 29.0])), [29.0])
    # a time a rounding error short of the 30-s mark is that mark
    np.testing.assert_array_equal(
        frame_times(np.array([0.0, 30.0 - 1e-9, 50.0])), [30.0 - 1e-9, 50.0]
    )


def test_spanning_tree_of_robot_0s_component_keeps_the_first_measured_direction() -> None:
    """Robots 0-1 seen both ways (1 → 0 first), 2 sees 1, 1 sees 3 twice; 4-5 form another
    component."""
    edges = [(1, 0), (0, 1), (2, 1), (1, 3), (1, 3), (4, 5)]
    assert _spanning_edges(edges, 6) == [(1, 0), (2, 1), (1, 3)]
    assert _spanning_edges([(3, 2)], 4) == []


def test_growth_compares_the_last_quarter_with_the_second() -> None:
    """Eight records, one run, one robot: position errors 5, 5, 1, 1, 1, 1, 2, 2 m (second
    quarter 1 m, last 2 m) and 1σ bounds 9, 9, 1, 1, 1, 1, 3, 3 m: ratios 2 and 3."""
    e = np.array([5, 5, 1, 1, 1, 1, 2, 2], dtype=float)
    errors = np.zeros((1, 8, 1, 3))
    errors[0, :, 0, 1] = e  # along y only
    s = np.array([9, 9, 1, 1, 1, 1, 3, 3], dtype=float)
    cov = np.zeros((1, 8, 1, 3, 3))
    cov[0, :, 0, 0, 0] = cov[0, :, 0, 1, 1] = s**2 / 2
    assert _growth(errors, cov) == {"error_ratio": pytest.approx(2.0), "sigma_ratio": 3.0}


def test_frame_nees_summary_of_two_runs() -> None:
    times = np.array([30.0, 45.0])
    series = [(np.array([1.0, 2.0]), 2), (np.array([3.0, 2.5]), 2)]
    s = frame_nees_summary(series, times)
    assert s is not None
    assert s["dof"] == 2 and s["per_run"] == [2.0, 2.5] and s["mean"] == 2.25
    assert s["verdict"] == "consistent"
    assert s["along_the_run"]["t"] == [30.0, 45.0]
    assert s["along_the_run"]["mean_over_runs"] == [2.0, 2.25]
    high = frame_nees_summary([(np.array([40.0]), 2), (np.array([50.0]), 2)], times[:1])
    low = frame_nees_summary([(np.array([0.01]), 2), (np.array([0.02]), 2)], times[:1])
    assert high is not None and high["verdict"] == "over-confident"
    assert low is not None and low["verdict"] == "conservative"
    assert frame_nees_summary([series[0], None], times) is None
    assert frame_nees_summary([], times) is None


def _filter(worst: float, rmse: float) -> dict[str, Any]:
    return {
        c: {
            "nees_pct_beyond": worst if c == "one_landmark" else 1.0,
            "pos_rmse_m": {"mean": rmse},
            "nees_beyond_interval": c,
            "nees_pct_beyond_per_run": [c],
            "frame_nees": None,
        }
        for c in ("no_landmark", "one_landmark")
    }


PLAIN = {c: {"pos_rmse_m": {"mean": 1.0}} for c in ("no_landmark", "one_landmark")}


def test_the_headline_filter_meets_the_target_before_having_the_smaller_nees_share() -> None:
    """FEJ: worst NEES share 8 % but a position RMSE above the plain EIF's; OC: 10 % (the
    limit) and the plain EIF's RMSE: only OC meets the target and is the headline."""
    aware = {
        "cases_first_estimates": _filter(8.0, 1.1),
        "cases_observability_constrained": _filter(10.0, 1.0),
    }
    h = headline_aware(PLAIN, aware)
    assert h["block"] == "cases_observability_constrained" and h["target_met"] is True
    assert h["meets_target"] == {
        "cases_first_estimates": False,
        "cases_observability_constrained": True,
    }
    assert h["worst_nees_pct_beyond"] == {
        "cases_first_estimates": 8.0,
        "cases_observability_constrained": 10.0,
    }
    assert h["nees_pct_beyond_per_run"] == {
        "no_landmark": ["no_landmark"],
        "one_landmark": ["one_landmark"],
    }


def test_without_a_filter_meeting_the_target_the_smaller_nees_share_is_the_headline() -> None:
    aware = {
        "cases_first_estimates": _filter(12.0, 0.5),
        "cases_observability_constrained": _filter(11.0, 1.5),
    }
    h = headline_aware(PLAIN, aware)
    assert h["block"] == "cases_observability_constrained" and h["target_met"] is False
