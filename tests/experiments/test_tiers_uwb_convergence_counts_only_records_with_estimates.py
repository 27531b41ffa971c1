"""tiers-uwb's team convergence time by hand: seconds from the first record (a record time at
which every scored robot has an estimate) until the error stays below 0.3 m for good, null when
it never does; a record time without an estimate shows nothing converged."""

from __future__ import annotations

import numpy as np
import pytest

from relloc.experiments.tiers_uwb_team import score_positions

GRID = np.array([0.0, 0.1, 0.2, 0.3])
TRUTH = np.zeros((4, 1, 2))
COV = np.tile(np.eye(2), (4, 1, 1, 1))


def _score(errors_m: list[float]) -> dict[str, object]:
    """One robot whose estimate is ``errors_m[k]`` m east of the truth (NaN: no estimate)."""
    est = np.zeros((4, 1, 2))
    est[:, 0, 0] = errors_m
    return score_positions(GRID, est, COV, TRUTH, [0], align=False)


def test_an_error_above_the_bound_up_to_the_last_estimate_never_converged() -> None:
    got = _score([1.0, 1.0, 1.0, np.nan])
    assert got["records"] == 3
    assert got["converged_after_s"] is None


def test_the_time_counts_from_the_first_record_to_the_first_record_after_the_last_miss() -> None:
    assert _score([np.nan, 1.0, 0.0, 0.0])["converged_after_s"] == pytest.approx(0.1)
    assert _score([1.0, np.nan, 0.1, 0.0])["converged_after_s"] == pytest.approx(0.2)


def test_errors_within_the_bound_throughout_converge_at_once_and_one_at_the_end_never() -> None:
    assert _score([0.1, 0.2, 0.0, 0.29])["converged_after_s"] == 0.0
    assert _score([0.1, 0.2, 0.0, 0.3])["converged_after_s"] is None
    got = _score([2.5, 0.0, 0.0, 0.0])
    assert got["converged_after_s"] == pytest.approx(0.1)
    assert got["pos_rmse_m"] == pytest.approx(1.25)  # √(6.25/4)
    # NEES 6.25 (2.5 m against a 1 m σ) is beyond χ²₂(0.95) ≈ 5.99 (not χ²₃'s 7.81); the
    # three others are 0
    assert got["nees_pct_beyond"] == 25.0


def test_the_team_converges_when_its_last_robot_does() -> None:
    """Robot 0 exact throughout, robot 1 1 m off until 0.2 s."""
    est = np.zeros((4, 2, 2))
    est[:2, 1, 0] = 1.0
    got = score_positions(
        GRID, est, np.tile(np.eye(2), (4, 2, 1, 1)), np.zeros((4, 2, 2)), [0, 1], align=False
    )
    assert got["converged_after_s"] == pytest.approx(0.2)
