"""Arguments of :func:`relloc.pipeline.replay.replay` that once did the wrong thing silently
or ran out of memory are refused, naming the argument."""

from __future__ import annotations

import numpy as np
import pytest

from relloc.core.recording import Odometry, Recording, measurement_rows
from relloc.errors import ConfigError
from relloc.estimators.uwb_range import RangeTeamFilter, RangeTeamSettings
from relloc.pipeline.replay import MAX_RECORDS, record_grid, replay


def _recording() -> Recording:
    still = Odometry(t=np.zeros(0), velocity=np.zeros((0, 4)), sigma=(0, 0, 0, 0))
    rows = measurement_rows("range", t=np.arange(30) * 0.1, observer=1, target=0, value=np.ones(30))
    return Recording(
        robots=("a", "b"), platforms=("ground",) * 2, odometry=(still, still), measurements=rows
    )


def _filter() -> RangeTeamFilter:
    return RangeTeamFilter(("a", "b"), [[0.0, 0.0], [1.0, 0.0]], RangeTeamSettings(), anchors=(0,))


def test_one_estimator_given_twice_is_refused():
    """It was advanced and fed twice (58 records instead of 29)."""
    f = _filter()
    with pytest.raises(ConfigError, match="replay: one estimator given twice"):
        replay(_recording(), [f, f])


def test_record_times_of_an_owner_without_an_estimator_are_refused():
    """A misspelt owner recorded nothing, without a word."""
    rec = _recording()
    with pytest.raises(ConfigError, match=r"record_times of \['zz'\], who own no estimator"):
        replay(rec, [_filter()], record_times={"zz": np.array([0.0, 1.0])})
    f = _filter()
    est = replay(rec, [f], record_times={f.owner: np.array([0.0, 1.0])})
    assert est.series(f.owner, "b").t.tolist() == [0.0, 1.0]


def test_a_record_grid_too_large_to_hold_is_refused():
    """``record_grid(0, 1e12, 10)`` once asked for 73 TiB; ``inf`` overflowed."""
    for t1, rate in ((1e12, 10.0), (np.inf, 1.0), (10.0, 1e7)):
        with pytest.raises(ConfigError, match=f"more than {MAX_RECORDS} record times"):
            record_grid(0.0, t1, rate)
    assert record_grid(0.0, 1.0, 10.0).size == 11
