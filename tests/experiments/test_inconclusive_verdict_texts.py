"""The reports state an "inconclusive" verdict (an interval that holds the expected share but
reaches above twice it, :data:`relloc.metrics.consistency.EQUIVALENCE_FACTOR`) and define it."""

from __future__ import annotations

import numpy as np

from relloc.experiments.wanasinghe2014_pairs import VERDICT_MARKS
from relloc.metrics import percent_beyond_interval
from relloc.pipeline.output import interval_text


def test_an_inconclusive_share_in_a_table_cell_and_its_mark() -> None:
    # nothing beyond in ten time blocks: 0 of 10, interval 0.0–30.8 %
    share = percent_beyond_interval(np.zeros(300), np.arange(300.0), 1.0).to_dict()
    assert share["verdict"] == "inconclusive"
    assert interval_text(share) == "0.0–30.8 inconclusive"
    assert VERDICT_MARKS["inconclusive"] == "?"
    assert "consistent" not in VERDICT_MARKS  # a consistent share stays unmarked
