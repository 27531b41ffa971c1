"""The run-averaged NEES test on data with no usable instant or beyond the band on both
sides, and the convergence counts' refusals of empty or mismatched series."""

from __future__ import annotations

import numpy as np
import pytest

from relloc.errors import DataError
from relloc.metrics.consistency import run_average_band
from relloc.metrics.convergence import updates_to_converge, updates_to_converge_per_state


def test_run_average_band_without_a_complete_instant_has_no_verdict() -> None:
    nees = np.full((3, 5), np.nan)
    nees[0] = 1.0  # one run alone never makes an instant's average
    out = run_average_band(nees, dof=2)
    assert out["verdict"] is None and out["instants"] == 0 and out["runs"] == 3
    assert out["reason"] == "no instant with a value in every run"
    assert np.isnan(out["in_band_percent"])  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("pattern", "verdict"),
    [((0.0, 0.0, 100.0), "conservative"), ((0.0, 100.0, 100.0), "over-confident")],
)
def test_run_average_band_beyond_on_both_sides_takes_the_larger_share(
    pattern: tuple[float, ...], verdict: str
) -> None:
    """Every block of three instants holds the same values, far below (0) and far above
    (100) the band of two runs of χ²(1): both shares are significant, with no spread over the
    blocks, and the verdict is the side holding two of every three instants."""
    nees = np.tile(np.array(pattern), (2, 10))
    out = run_average_band(nees, dof=1)
    below = 100.0 * pattern.count(0.0) / 3
    assert out["below_band_percent"] == pytest.approx(below)
    assert out["above_band_percent"] == pytest.approx(100.0 - below)
    assert out["verdict"] == verdict


def test_convergence_counts_refuse_empty_or_mismatched_series() -> None:
    with pytest.raises(DataError, match="updates_to_converge: empty error series"):
        updates_to_converge([], 1.0)
    with pytest.raises(
        DataError, match=r"updates_to_converge_per_state: series \(4, 3\) needs 2 state columns"
    ):
        updates_to_converge_per_state(np.zeros((4, 3)), [1.0, 1.0])
