"""``longest_non_decreasing``: ascending row indices of a longest ordered subsequence, and which
of two equally long ones each ``prefer`` keeps (module docstring of
:mod:`relloc.datasets.time_order`)."""

from __future__ import annotations

import pytest

from relloc.datasets.time_order import longest_non_decreasing


@pytest.mark.parametrize(
    ("stamps", "later", "earlier"),
    [
        # a swapped pair: 20 or 15 can go
        ([10.0, 20.0, 15.0, 30.0], [0, 2, 3], [0, 1, 3]),
        # a far-future stamp first, then an ordered run
        ([99.0, 1.0, 2.0, 3.0], [1, 2, 3], [1, 2, 3]),
        # two ordered runs of equal length
        ([5.0, 6.0, 1.0, 2.0], [2, 3], [0, 1]),
        # equal stamps are in order
        ([3.0, 3.0, 1.0, 3.0], [0, 1, 3], [0, 1, 3]),
    ],
)
def test_indices_are_ascending_and_prefer_picks_among_ties(stamps, later, earlier):
    assert longest_non_decreasing(stamps) == later
    assert longest_non_decreasing(stamps, prefer="later") == later
    assert longest_non_decreasing(stamps, prefer="earlier") == earlier


def test_no_stamps_keep_no_rows():
    assert longest_non_decreasing([]) == []
    assert longest_non_decreasing([], prefer="earlier") == []
