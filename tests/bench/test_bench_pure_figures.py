"""The small computations behind the benchmarks' numbers, on hand-made inputs: the real-time
limit's log-log crossing, the agreement check of ``bench filters``, the secure benchmark's
start-up time, the team scenario the runtime benchmarks launch, the interval benchmark's
correlation time, coverage test and baseline, and the size checks. Nothing is timed."""

from __future__ import annotations

import math
import tomllib

import numpy as np
import pytest

from relloc.bench import cooperative, intervals, runtime, secure
from relloc.errors import ConfigError, ModelError, RellocError
from relloc.metrics.consistency import BeyondShare
from relloc.runtime.keys import CLOCK_ID

# -- cooperative: where the real-time factor crosses 1 (log-log interpolation) --------------


def test_the_crossing_halfway_in_log_factor_lies_at_the_geometric_mean() -> None:
    # factors 2 and 0.5: log 2 and −log 2, so 1 lies halfway, at √(5 · 10) = 5√2
    assert cooperative._crossing([5, 10], [2.0, 0.5]) == pytest.approx(5 * math.sqrt(2))


def test_the_crossing_of_a_later_interval_and_at_a_measured_size() -> None:
    assert cooperative._crossing([10, 20, 40], [4.0, 2.0, 0.5]) == pytest.approx(20 * math.sqrt(2))
    # a factor of exactly 1 at a measured size: the limit is that size
    assert cooperative._crossing([5, 10], [1.0, 0.5]) == pytest.approx(5.0)
    assert cooperative._crossing([5, 10, 20], [2.0, 1.0, 0.5]) == pytest.approx(10.0)
    # a quarter of the way in log factor: 8 → 1 → 1/2 is 3 of 4 halvings, n = 10 · 2^(3/4)
    assert cooperative._crossing([10, 20], [8.0, 0.5]) == pytest.approx(10 * 2**0.75)


def test_no_crossing_when_every_size_keeps_real_time_or_one_size_only() -> None:
    assert cooperative._crossing([5, 10, 25], [9.0, 3.0, 1.5]) is None
    # a factor of exactly 1 is still real time: the last size has not fallen below it
    assert cooperative._crossing([5, 10], [2.0, 1.0]) is None
    assert cooperative._crossing([5], [0.5]) is None
    assert cooperative._crossing([], []) is None


def test_a_team_size_list_without_one_or_repeats_is_refused() -> None:
    with pytest.raises(ConfigError, match="at least one team size"):
        cooperative.BenchSize(sizes=())
    with pytest.raises(ConfigError, match="steps"):
        cooperative.BenchSize(steps=0)
    assert cooperative.BenchSize(sizes=[2, 3]).sizes == (2, 3)  # a list is kept as a tuple


# -- filters: the agreement check run before anything is timed -------------------------------


def test_the_filters_agreement_check_returns_the_largest_difference() -> None:
    pytest.importorskip("filterpy", reason="filterpy (extra 'bench') is needed")
    from relloc.bench.filters import _check_same

    mean, cov = np.zeros(4), np.zeros((4, 4))
    cov_b = cov.copy()
    cov_b[2, 3] = 1e-8  # on the bound: still the same
    assert _check_same((mean, cov), (mean + 5e-9, cov_b), "x") == pytest.approx(1e-8)
    with pytest.raises(ModelError, match=r"bench filters: means disagree by 2e-08"):
        _check_same((mean, cov), (mean - 2e-8, cov), "means")
    cov_b[0, 0] = -3e-6  # the covariance counts as much as the mean
    with pytest.raises(ModelError, match=r"covs disagree by 3e-06; timings would be unfair"):
        _check_same((mean, cov), (mean, cov_b), "covs")


def test_a_batch_as_long_as_the_sequence_is_refused_one_shorter_is_not() -> None:
    pytest.importorskip("filterpy", reason="filterpy (extra 'bench') is needed")
    from relloc.bench.filters import BenchSize

    assert BenchSize(steps=6, batch_steps=5).batch_steps == 5
    with pytest.raises(ConfigError, match="must be smaller than steps"):
        BenchSize(steps=6, batch_steps=6)
    with pytest.raises(ConfigError, match="repeats"):
        BenchSize(repeats=0)


# -- secure: start-up time ---------------------------------------------------------------------


def _presence(member: str, token: str, event: str, wall_s: float) -> dict[str, object]:
    return {"member": member, "token": token, "event": event, "wall_s": wall_s}


def test_startup_is_the_clocks_first_join_plus_its_wait() -> None:
    presence = [
        _presence("observer", "alive", "joined", 0.1),  # a robot, not the clock
        _presence(CLOCK_ID, "ready", "joined", 0.2),  # another token
        _presence(CLOCK_ID, "alive", "left", 0.3),  # leaving is no join
        _presence(CLOCK_ID, "alive", "joined", 0.5),
        _presence(CLOCK_ID, "alive", "joined", 0.9),  # a later join does not count
    ]
    assert secure.startup_wall_s(presence, 1.25) == pytest.approx(1.75)


def test_startup_without_the_clocks_join_is_an_error() -> None:
    presence = [_presence(CLOCK_ID, "alive", "left", 0.3), _presence("r1", "alive", "joined", 1)]
    with pytest.raises(RellocError, match="the clock's liveliness token never reached"):
        secure.startup_wall_s(presence, 1.0)


# -- runtime: the launched team ----------------------------------------------------------------


def test_the_team_scenario_places_teammates_on_an_arc_in_front_of_the_observer() -> None:
    doc = tomllib.loads(runtime.team_toml(3, 8.0))
    assert doc["name"] == "bench-3" and doc["duration_s"] == 8.0
    names = [r["name"] for r in doc["robots"]]
    assert names == ["observer", "r1", "r2"]
    observer, r1, r2 = doc["robots"]
    assert observer["kind"] == "ground" and observer["initial_pose"][:2] == [20.0, 2.0]
    # r1: −30° at radius 10 → (20 − 5, 2 + 5√3); r2: +30° at radius 14 → (27, 2 + 7√3)
    assert r1["initial_pose"] == pytest.approx([15.0, 2.0 + 5 * math.sqrt(3), 0.0])
    assert r2["initial_pose"] == pytest.approx([27.0, 2.0 + 7 * math.sqrt(3), 0.0])
    assert (r1["height"], r2["height"]) == pytest.approx((1.1, 1.2))
    assert r1["motion"]["period_s"] == [10.0, 12.0, 10.0, 9.0]
    assert r2["motion"]["period_s"] == [10.0, 12.0, 10.0, 10.0]
    heights = [r["height"] for r in tomllib.loads(runtime.team_toml(7, 1.0))["robots"][1:]]
    assert heights == pytest.approx([1.1, 1.2, 1.3, 1.4, 1.0, 1.1])  # 1 + 0.1 · (i mod 5)
    # a pair: the single teammate straight ahead, 10 m away
    pair = tomllib.loads(runtime.team_toml(2, 1.5))
    assert pair["robots"][1]["initial_pose"] == pytest.approx([20.0, 12.0, 0.0])
    assert len(pair["robots"]) == 2 and pair["duration_s"] == 1.5


# -- intervals ---------------------------------------------------------------------------------


def test_the_nees_correlation_time_by_hand() -> None:
    assert intervals.correlation_time(0.0) == 1.0  # independent values
    assert intervals.correlation_time(0.5) == pytest.approx(1.25 / 0.75)
    assert intervals.correlation_time(0.9) == pytest.approx(1.81 / 0.19)


def test_an_interval_holds_the_true_share_with_its_ends_included() -> None:
    assert not intervals._holds(None)
    assert intervals._holds((4.0, 5.0)) and intervals._holds((5.0, 6.0))
    assert intervals._holds((0.0, 100.0))
    assert not intervals._holds((5.01, 6.0)) and not intervals._holds((3.0, 4.99))


def test_the_baseline_takes_every_value_as_its_own_run() -> None:
    values = np.zeros((4, 5))
    values[1, 2] = 100.0  # one value of 20 beyond χ²₃(0.95) ≈ 7.81
    share = intervals._independent_baseline(values)
    assert share.percent == pytest.approx(5.0)
    assert share.samples == 20 and share.runs == 20


def test_an_interval_size_out_of_range_names_the_field() -> None:
    with pytest.raises(ConfigError, match=r"IntervalBenchSize\.draws"):
        intervals.IntervalBenchSize(draws=1)
    with pytest.raises(ConfigError, match=r"IntervalBenchSize.runs_rho \(a ρ\)"):
        intervals.IntervalBenchSize(runs_rho=1.0)
    with pytest.raises(ConfigError, match=r"IntervalBenchSize\.subject_shares"):
        intervals.IntervalBenchSize(subject_shares=(0.5, 1.01))
    with pytest.raises(ConfigError, match="at least one ρ"):
        intervals.IntervalBenchSize(rhos=())
    full = intervals.IntervalBenchSize(subject_shares=(1.0,), rhos=(0.0,))  # both ends allowed
    assert full.subject_shares == (1.0,) and full.rhos == (0.0,)


def _share(interval: tuple[float, float] | None, effective: float | None) -> BeyondShare:
    return BeyondShare(
        percent=5.0,
        interval=interval,
        samples=100,
        effective_samples=effective,
        clustering="runs",
        clusters=10,
        runs=10,
        batch_s=None,
        correlation_time_s=None,
        correlation_samples=None,
        expected_percent=5.0,
        confidence=0.95,
        batch_means_interval=interval,
    )


def test_a_draw_without_an_interval_is_left_out_of_the_mean_effective_samples() -> None:
    """Two draws: one interval [2, 8] % from 40 effective samples, one share without an
    interval (too few clusters): the mean is 40, not (40 + 0)/2; coverage counts both draws."""
    draws = iter([(_share((2.0, 8.0), 40.0),) * 2, (_share(None, None),) * 2])
    out = intervals._coverage(2, lambda: next(draws))
    assert out["mean_effective_samples"] == 40.0
    assert out["coverage"] == 0.5 and out["mean_width_pct"] == 6.0
