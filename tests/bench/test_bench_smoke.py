"""``relloc bench NAME`` for observability, multihypothesis, cooperative, runtime and secure on
tiny workloads: each ``run(quiet=True)`` finishes, reports every documented key with finite
numbers, measures its named baseline, and its own correctness checks hold.

Speed itself is never asserted (no timed unit tests): only that the timings exist and are
finite and positive. The sizes are shrunk through the modules' size constants
(``monkeypatch.setattr``), through ``functools.partial`` where a size is a function's default
argument, and through ``BenchSize`` for ``cooperative``, whose measurement runs in a child
process that a monkeypatch cannot reach. The runtime and secure benchmarks start real robot
processes over loopback Zenoh (extra ``runtime``).
"""

from __future__ import annotations

import functools
import math
from typing import Any

import pytest

from relloc.bench import cooperative, multihypothesis, observability, runtime, secure
from relloc.cli.extras import EXTRA_MODULES
from relloc.errors import ConfigError


def _positive(value: Any) -> bool:
    return isinstance(value, int | float) and math.isfinite(value) and value > 0


def _non_negative(value: Any) -> bool:
    return isinstance(value, int | float) and math.isfinite(value) and value >= 0


def _needs_runtime() -> None:
    for module in EXTRA_MODULES["runtime"]:
        pytest.importorskip(module, reason="extra 'runtime' is needed for this benchmark")


def test_observability_tiny(monkeypatch: pytest.MonkeyPatch) -> None:
    # the team sizes 5/10/20, the PCRLB horizons and the 3-robot symbolic build are fixed in
    # run(); together they take about 1.5 s, so only the model list and the large team shrink
    keep = ("relative-pseudo-linear case 1", "relative-pseudo-linear case 2")
    models = {name: observability.SYMBOLIC_MODELS[name] for name in keep}
    monkeypatch.setattr(observability, "SYMBOLIC_MODELS", models)
    monkeypatch.setattr(observability, "LARGE_TEAM", 6)
    result = observability.run(quiet=True)
    assert set(result) >= {"symbolic", "teams", "symbolic_team_build_s", "pcrlb_s"}
    assert set(result["symbolic"]) == set(keep)
    for name, v in result["symbolic"].items():
        assert 1 <= v["rank"] <= 4, name  # the built-in relative models have 4 states
        assert v["rank"] <= v["rows_pruned"] <= v["rows_unpruned"], name
        assert _positive(v["symbolic_s"]) and _positive(v["unpruned_rows_s"]), name
    assert set(result["teams"]) == {"5", "10", "20", "6_complete"}
    for n_r, v in result["teams"].items():
        # the numerical rank is the graph formula's (run() now raises if not)
        assert v["rank"] == v["expected_rank"], n_r
        assert v["edges"] > 0 and _positive(v["team_matrix_s"]), n_r
    large = result["teams"]["6_complete"]
    assert large["rank"] == 3 * 6 and large["edges"] == 6 * 5 + 6 * 2  # everyone sees all
    assert _positive(large["peak_mb"]) and _positive(large["assembled_mb"])
    assert _positive(result["symbolic_team_build_s"])  # the baseline of team_matrix_s
    assert set(result["pcrlb_s"]) == {"relative_pair_2000_steps", "team_5_robots_200_steps"}
    assert all(_positive(v) for v in result["pcrlb_s"].values())


def test_multihypothesis_tiny(monkeypatch: pytest.MonkeyPatch) -> None:
    # the headline point (10 teammates, 100× clutter) must be among the points measured
    monkeypatch.setattr(multihypothesis, "TEAM_SIZES", (2, 10))
    monkeypatch.setattr(multihypothesis, "CLUTTER_FACTORS", (1, 100))
    monkeypatch.setattr(multihypothesis, "WARMUP_S", 0.5)
    monkeypatch.setattr(multihypothesis, "TIMED_S", 1.0)
    result = multihypothesis.run(quiet=True)
    assert result["benchmark"] == "multihypothesis"
    assert result["timed_seconds_of_data"] == 1.0
    points = result["points"]
    assert [(p["teammates"], p["clutter_factor"]) for p in points] == [
        (2, 1),
        (2, 100),
        (10, 1),
        (10, 100),
    ]
    for p in points:
        for key in (
            "expected_clutter_per_scan",
            "ms_per_scan",
            "ms_per_predict",
            "realtime_factor",
            "baseline_ms_per_scan",  # the known-correspondence EKF, same data
        ):
            assert _positive(p[key]), (p["teammates"], p["clutter_factor"], key)
        # every teammate has a belief with at least one component at every timed scan
        assert 1.0 <= p["components_mean"] <= p["components_max"]
    assert points[1]["expected_clutter_per_scan"] == pytest.approx(
        100 * points[0]["expected_clutter_per_scan"]
    )
    assert result["realtime_10x100"] == points[3]["realtime_factor"]
    assert result["realtime_required"] == 1.0


def test_cooperative_tiny() -> None:
    size = cooperative.BenchSize(sizes=(5, 10), steps=5, repeats=2)
    result = cooperative.run(quiet=True, size=size)  # measured in a child process
    assert result["benchmark"] == "cooperative"
    assert result["steps"] == 5 and result["rate_hz"] == 10.0
    assert result["blas_threads"] == "1"  # the child runs with single-threaded BLAS
    rows = result["sizes"]
    assert rows and [r["n"] for r in rows] == [5, 10][: len(rows)]
    for r in rows:
        assert r["state_dim"] == 3 * r["n"]
        for key in ("rows_per_step", "eif_ms_per_step", "eif_realtime_factor"):
            assert _positive(r[key]), (r["n"], key)
    # the EKF baseline runs on the first size at least, and agrees with the EIF (run() raises
    # otherwise; the difference is reported)
    assert _positive(rows[0]["ekf_ms_per_step"]) and _positive(rows[0]["ekf_realtime_factor"])
    for r in rows:
        if r["ekf_ms_per_step"] is not None:
            assert 0.0 <= r["max_mean_diff_eif_ekf"] < cooperative.EQUIVALENCE_TOL, r["n"]
    assert result["realtime_at_50"] is None  # 50 was not measured
    limit = result["realtime_limit_n"]
    assert limit is None or 5 <= limit <= 10


def test_cooperative_bad_size_names_the_field() -> None:
    with pytest.raises(ConfigError, match="sizes"):
        cooperative.BenchSize(sizes=(1,))
    with pytest.raises(ConfigError, match="repeats"):
        cooperative.BenchSize(repeats=0)


def test_runtime_tiny(monkeypatch: pytest.MonkeyPatch) -> None:
    _needs_runtime()
    # DURATION_S is bound as run_team_size's default argument and monte_carlo_speedup's sizes
    # are its defaults: shrink them through partials of the real functions
    monkeypatch.setattr(runtime, "TEAM_SIZES", (2,))
    monkeypatch.setattr(
        runtime, "run_team_size", functools.partial(runtime.run_team_size, duration_s=2.0)
    )
    monkeypatch.setattr(
        runtime,
        "monte_carlo_speedup",
        functools.partial(runtime.monte_carlo_speedup, runs=2, duration_s=2.0),
    )
    result = runtime.run(quiet=True)
    (team,) = result["team_sizes"]
    assert team["robots"] == 2
    # the transport lost nothing on loopback and no robot missed a barrier; the rate itself
    # (keeps_rates) depends on the machine's load and is not asserted
    assert team["transport_loss_rate"] == 0.0
    assert team["ack_timeouts"] == 0
    assert team["data_messages_sent"] > 0
    assert _positive(team["achieved_rate_fraction"]) and _non_negative(team["max_tick_lag_s"])
    assert result["largest_team_keeping_rates"] == (2 if team["keeps_rates"] else None)
    for key in ("latency_us_p50", "latency_us_p99"):
        assert _positive(team[key]), key
    assert team["latency_us_p50"] <= team["latency_us_p99"]
    assert result["latency_us"] == {"p50": team["latency_us_p50"], "p99": team["latency_us_p99"]}
    cpu = result["cpu_per_robot_process"]
    assert _positive(cpu["observer_cpu_s_per_sim_s"])
    assert _positive(cpu["teammate_cpu_s_per_sim_s"])
    mc = result["monte_carlo"]
    assert mc["runs"] == 2 and mc["scenario_duration_s"] == 2.0
    for key in ("wall_s_1_worker", "wall_s_2_workers", "speedup_2_vs_1"):
        assert _positive(mc[key]), key
    assert mc["identical_results"] is True  # 2 workers give the 1-worker results exactly


def test_secure_tiny(monkeypatch: pytest.MonkeyPatch) -> None:
    _needs_runtime()
    monkeypatch.setattr(secure, "ROBOTS", 2)
    monkeypatch.setattr(secure, "DURATION_S", 2.0)
    monkeypatch.setattr(secure, "REPETITIONS", 1)
    result = secure.run(quiet=True)
    assert result["robots"] == 2 and result["simulated_s"] == 2.0 and result["repetitions"] == 1
    assert [len(result["runs"][mode]) for mode in ("plain", "secure")] == [1, 1]
    for mode in ("plain", "secure"):
        assert set(result["median"][mode]) == set(secure.METRICS)
        for key, value in result["median"][mode].items():
            assert _positive(value), (mode, key)
    assert set(result["secure_over_plain"]) == set(secure.METRICS)
    for key, ratio in result["secure_over_plain"].items():
        assert _positive(ratio), key
        plain, sec = result["median"]["plain"][key], result["median"]["secure"][key]
        assert ratio == pytest.approx(sec / plain), key
    assert result["identical_estimates"] is True  # same seed: TLS must not change estimates
