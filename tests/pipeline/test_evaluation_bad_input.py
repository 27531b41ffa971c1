"""Bad settings of the evaluation: a ConfigError naming the setting or the series, never a
silently wrong table (records overwriting each other, no steady sample) or a raw numpy error."""

from __future__ import annotations

import numpy as np
import pytest

from relloc.core.estimates import BeliefSeries
from relloc.errors import ConfigError
from relloc.pipeline.evaluation import (
    SeriesEvaluation,
    accuracy_and_consistency,
    at_times,
    nees_band_check,
    run_averaged_nees,
    steady_nees_table,
)

NAN = float("nan")
#: 20 s of records at 10 Hz (the grid's times as a recorder computes them)
T = np.arange(200) / 10.0


def _run(seed: int, t: np.ndarray = T) -> SeriesEvaluation:
    """One run of a 2-state series with χ²(2) NEES values."""
    rng = np.random.default_rng(seed)
    n, z = t.size, np.zeros(0)
    return SeriesEvaluation(
        owner="a",
        subject="b",
        track="",
        platform="ground",
        frame="world_position2",
        t=t,
        error=rng.normal(size=(n, 2)),
        sigma=np.ones((n, 2)),
        nees=rng.chisquare(2, size=n),
        age=t - t[0],
        cond_p=np.zeros(n),
        update_t=z,
        update_age=z,
        nis=z,
        nis_dof=np.zeros(0, dtype=np.int64),
        cond_r=z,
        cond_s=z,
    )


RUNS = [_run(k) for k in range(3)]


def test_the_table_at_the_record_rate_holds_every_record_once() -> None:
    t, table = steady_nees_table(RUNS, rate_hz=10.0, settle_s=1.0)
    np.testing.assert_allclose(t, T[10:], atol=1e-12)
    np.testing.assert_array_equal(table, np.stack([r.nees[10:] for r in RUNS]))


@pytest.mark.parametrize("rate_hz", [0.0, -10.0, NAN, np.inf])
@pytest.mark.parametrize("f", [steady_nees_table, run_averaged_nees, nees_band_check])
def test_a_rate_that_is_not_finite_and_positive_is_refused(f, rate_hz) -> None:
    # 0 collapsed the table to one column, -10 gave an IndexError, NaN a ValueError
    with pytest.raises(ConfigError, match="rate_hz"):
        f(RUNS, rate_hz=rate_hz, settle_s=1.0)


@pytest.mark.parametrize("settle_s", [NAN, -1.0, np.inf])
def test_a_settle_time_that_is_not_finite_and_non_negative_is_refused(settle_s) -> None:
    # NaN left no steady sample, without a word
    for f in (steady_nees_table, run_averaged_nees, nees_band_check):
        with pytest.raises(ConfigError, match="settle_s"):
            f(RUNS, rate_hz=10.0, settle_s=settle_s)
    with pytest.raises(ConfigError, match="accuracy_and_consistency: settle_s"):
        accuracy_and_consistency(RUNS, settle_s=settle_s)


@pytest.mark.parametrize("f", [steady_nees_table, run_averaged_nees, nees_band_check])
def test_records_off_the_grid_or_in_one_cell_are_refused(f) -> None:
    # 1 Hz on a 10 Hz record: ten records to a cell, the last overwriting the others
    with pytest.raises(ConfigError, match=r"a->b: record at t=0\.1 is off the 1\.0 Hz grid"):
        f(RUNS, rate_hz=1.0, settle_s=1.0)
    off = [*RUNS[:2], _run(2, np.append(T, 20.05))]
    with pytest.raises(ConfigError, match=r"t=20\.05 is off the 10\.0 Hz grid"):
        f(off, rate_hz=10.0, settle_s=1.0)
    twice = [*RUNS[:2], _run(2, np.sort(np.append(T, 5.0)))]
    with pytest.raises(ConfigError, match=r"a->b: two records in one cell of the 10\.0 Hz grid"):
        f(twice, rate_hz=10.0, settle_s=1.0)


def test_at_times_refuses_a_nan_time() -> None:
    series = BeliefSeries(
        owner="a",
        subject="b",
        frame="world_position2",
        t=T[:5],
        mean=np.zeros((5, 2)),
        cov=np.broadcast_to(np.eye(2), (5, 2, 2)),
        age=T[:5],
    )
    np.testing.assert_array_equal(at_times(series, T[1:3]).t, T[1:3])
    # NaN > TIME_TOL is False: the last record came back
    with pytest.raises(ConfigError, match="a->b: not recorded"):
        at_times(series, np.array([NAN]))
    with pytest.raises(ConfigError, match="a->b: not recorded"):
        at_times(series, np.array([0.1, NAN]))
