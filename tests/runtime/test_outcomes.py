"""How a team's headline figures are compared with the in-process run's."""

from __future__ import annotations

import math

import pytest

from relloc.runtime.outcomes import figure_agreement, figure_difference


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
