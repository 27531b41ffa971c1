"""The longest time-ordered subset of a file's rows, for loaders that skip only the rows out of
order (:mod:`relloc.datasets.mrclam`, :mod:`relloc.datasets.uwb`).

:func:`longest_non_decreasing` keeps a longest non-decreasing subsequence of the stamps
``t₁ … tₙ`` (rows ``i₁ < … < iₖ`` with ``t_{i₁} ≤ … ≤ t_{iₖ}``, ``k`` as large as possible) by
patience sorting, ``O(n log n)``. Of the equally long ones it keeps one of two, as asked:

- ``prefer="later"``: reading forward, ``tails[k]`` is the smallest last stamp of an ordered run
  of length ``k + 1`` so far and ``ends[k]`` its row; a later row with an equal-length run
  replaces the tail, so of two swapped rows the earlier is dropped;
- ``prefer="earlier"``: the same on the stamps read from the last row back, negated (a run that
  is non-decreasing in file order is non-decreasing in ``−t`` read backwards); following the
  links from the top pile then picks at each step the earliest row that can still complete a
  longest run, the lexicographically first one — where skipping every row earlier than the
  latest kept before it already leaves a longest run, exactly those rows.
"""

from __future__ import annotations

import bisect
from collections.abc import Sequence
from typing import Literal


def longest_non_decreasing(
    t: Sequence[float], prefer: Literal["earlier", "later"] = "later"
) -> list[int]:
    """Indices, ascending, of a longest non-decreasing subsequence of ``t`` (module docstring
    for which one ``prefer`` picks)."""
    if prefer == "earlier":
        n = len(t)
        backward = _patience([-x for x in reversed(t)])
        return [n - 1 - j for j in reversed(backward)]
    return _patience(t)


def _patience(t: Sequence[float]) -> list[int]:
    """The forward patience sort of :func:`longest_non_decreasing` (``prefer="later"``)."""
    tails: list[float] = []
    ends: list[int] = []
    back: list[int] = []
    for i, value in enumerate(t):
        k = bisect.bisect_right(tails, value)
        back.append(ends[k - 1] if k else -1)
        if k == len(tails):
            tails.append(value)
            ends.append(i)
        else:
            tails[k] = value
            ends[k] = i
    keep: list[int] = []
    i = ends[-1] if ends else -1
    while i >= 0:
        keep.append(i)
        i = back[i]
    return keep[::-1]
