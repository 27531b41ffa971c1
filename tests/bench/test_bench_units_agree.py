"""``relloc bench cooperative``'s per-size figures in their documented units: milliseconds per
0.1 s step and the real-time factor (simulated time over wall time) are two readings of one
timing, so their product is always 100 ms (one step of simulated time), for the EIF and for
the EKF baseline alike. Nothing about speed is asserted."""

from __future__ import annotations

import pytest

from relloc.bench import cooperative


def test_ms_per_step_times_the_realtime_factor_is_one_step_of_simulated_time() -> None:
    result = cooperative.run(quiet=True, size=cooperative.BenchSize(sizes=(5,), steps=3, repeats=1))
    (row,) = result["sizes"]
    assert row["n"] == 5 and result["steps"] == 3
    assert row["eif_ms_per_step"] * row["eif_realtime_factor"] == pytest.approx(100.0)
    assert row["ekf_ms_per_step"] * row["ekf_realtime_factor"] == pytest.approx(100.0)
    # rows per step: the bearings used over the epochs; a 5-robot grid sees 4 to 5 a robot
    assert 5 <= row["rows_per_step"] <= 5 * 4 + 2 * 5


def test_the_filters_ratios_are_read_the_documented_way_round() -> None:
    pytest.importorskip("filterpy", reason="filterpy (extra 'bench') is needed")
    from relloc.bench.filters import BenchSize, run

    result = run(quiet=True, size=BenchSize(steps=12, pairs=4, batch_steps=3, repeats=1))
    per = result["per_update_us"]
    # "filterpy's time over relloc's TEKF time", the same figure under both keys
    assert result["ratio_vs_filterpy"] == result["ratio_vs_filterpy_by_filter"]["tekf"]
    assert result["ratio_vs_filterpy"] == pytest.approx(per["filterpy_ekf"] / per["tekf"])
    assert result["ratio_vs_filterpy_by_filter"]["plkf"] == pytest.approx(
        per["filterpy_ekf"] / per["plkf"]
    )
    assert result["ratio_vs_filterpy_algebra_only"] == pytest.approx(
        per["filterpy_ekf_algebra_only"] / per["tekf"]
    )
    # the same pair-updates done both ways: the speed-up is the ratio of the two rates
    assert result["batched_speedup_vs_loop"] == pytest.approx(
        result["batched_pair_updates_per_s"] / result["loop_pair_updates_per_s"]
    )
    assert result["setup"]["pairs"] == 4 and result["setup"]["batched_steps"] == 3
