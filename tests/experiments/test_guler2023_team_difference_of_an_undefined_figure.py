"""``relloc team up guler2023``'s ``difference`` block (``largest_difference``): a figure
undefined (NaN) in one run only is a disagreement, wherever it sits in a nested figure, and
the team then does not count as within tolerance."""

from __future__ import annotations

import math

from relloc.experiments.guler2023_team import largest_difference
from relloc.runtime.outcomes import figure_agreement

NAN = float("nan")


def test_a_figure_undefined_in_one_run_only_differs_whatever_its_place() -> None:
    # follower R2's RMSE undefined in the distributed run, 0.2 m in-process; R1 equal
    first = largest_difference({"R1": 0.0, "R2": NAN}, {"R1": 0.0, "R2": 0.2})
    second = largest_difference({"R2": NAN, "R1": 0.0}, {"R2": 0.2, "R1": 0.0})
    assert first == second == math.inf
    assert largest_difference([0.1, NAN], [0.1, 0.3]) == math.inf
    assert largest_difference(NAN, 0.2) == math.inf
    # undefined in both: nothing to compare, as before
    assert largest_difference({"R1": NAN}, {"R1": NAN}) is None


def test_a_nested_undefined_figure_breaks_the_agreement() -> None:
    diff = {
        "rmse_m": largest_difference({"R1": {"x": 0.0, "y": NAN}}, {"R1": {"x": 0.0, "y": 0.1}})
    }
    block = figure_agreement(0.0, True, diff, belief_tolerance=1e-9, figure_tolerance=1e-9)
    assert block["agreement"]["within_tolerance"] is False
