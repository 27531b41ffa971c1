"""The team report: track a recording with one manager per observer, score it with the one
evaluation, pool runs; rows the trackers could not use are reported; bad calls are ConfigErrors."""

import dataclasses

import numpy as np
import pytest

from relloc.core.recording import Measurements, measurement_rows
from relloc.errors import ConfigError
from relloc.estimators.track_manager import TrackManagerSettings
from relloc.pipeline.evaluation import accuracy_and_consistency
from relloc.pipeline.team_report import (
    build_summary,
    report_markdown,
    score_run,
    summarise,
    track_team,
)
from relloc.sim.scenario import default_scenario
from relloc.sim.simulate import simulate

SCENARIO = dataclasses.replace(default_scenario(), duration_s=8.0)


def _recordings(n=2):
    return [simulate(SCENARIO, np.random.default_rng(seed)) for seed in range(n)]


def test_two_runs_pool_into_the_summary_layout():
    recordings = _recordings()
    estimates = [track_team(r, TrackManagerSettings()) for r in recordings]
    summary, results = build_summary(estimates, recordings, settle_s=2.0)
    assert list(summary["pairs"]) == [f"observer->{n}" for n in SCENARIO.robot_names[1:]]
    pair = summary["pairs"]["observer->aerial1"]
    assert (pair["observer"], pair["observed"], pair["observed_kind"]) == (
        "observer",
        "aerial1",
        "aerial",
    )
    assert pair["track_events"]["created"] == 2  # one per run
    assert len(pair["nees_run_average_band"]) == 2 and 0 <= pair["nees_run_average_in_band_percent"]
    everything = [e for r in results for e in r.evaluations]
    run_of = [k for k, r in enumerate(results) for _ in r.evaluations]
    pooled = accuracy_and_consistency(everything, settle_s=2.0, runs=run_of)
    assert {k: summary["team"][k] for k in pooled} == pooled
    # the NEES share's interval: the two independent runs are its clusters
    share = summary["team"]["nees_beyond_interval"]
    assert share["clustering"] == "runs" and share["clusters"] == share["runs"] == 2
    replayed = accuracy_and_consistency(
        everything, settle_s=2.0, runs=run_of, shared_recording=True
    )["nees_beyond_interval"]
    assert replayed["clustering"] == "runs and time blocks" and replayed["clusters"] == 2
    one_run = accuracy_and_consistency(everything, settle_s=2.0)["nees_beyond_interval"]
    assert one_run["clustering"] == "time blocks" and one_run["clusters"] == 10
    with pytest.raises(ConfigError, match="one per evaluation"):
        accuracy_and_consistency(everything, settle_s=2.0, runs=[0])
    for s in (summary["team"], pair):  # the spread of the per-run RMSE over the two runs
        spread = s["position_rmse_over_runs"]
        assert spread["runs"] == 2 and spread["std"] >= 0.0
        assert spread["interval95"][0] <= spread["mean"] <= spread["interval95"][1]
    assert pair["convergence"]["runs"] == 2
    assert summary["runs"] == 2 and "rows_not_used" not in summary
    assert results[0].paths is not None and results[1].paths is None
    first = summary["events_run0"][0]
    assert set(first) == {"t", "observer", "observed", "kind"} and first["kind"] == "created"


def test_rows_the_trackers_cannot_use_are_reported():
    rec = _recordings(1)[0]
    extra = measurement_rows("range", t=[1.0], observer=0, target=1, value=[3.0], sigma=0.1)
    rec = dataclasses.replace(rec, measurements=Measurements.concatenate([rec.measurements, extra]))
    run = score_run(track_team(rec, TrackManagerSettings()), rec)
    assert run.rows_not_used == {"rows_of_kind_range": 1}
    summary = summarise([run], settle_s=2.0, record_rate_hz=10.0)
    assert summary["rows_not_used"] == {"rows_of_kind_range": 1}
    # and report.md says so (it was only in summary.json)
    report = report_markdown(summary, [], title="t")
    assert "did not use, over all runs, by reason: 1 rows_of_kind_range." in report


def test_bad_calls_are_config_errors():
    rec = _recordings(1)[0]
    with pytest.raises(ConfigError, match="no runs"):
        summarise([], settle_s=1.0, record_rate_hz=10.0)
    with pytest.raises(ConfigError, match="1 estimate sets but 2 recordings"):
        build_summary([track_team(rec, TrackManagerSettings())], [rec, rec])
    blind = dataclasses.replace(rec, measurements=rec.measurements.select(np.zeros(0, int)))
    nothing = track_team(blind, TrackManagerSettings())
    assert nothing.beliefs == () and nothing.updates == ()
    with pytest.raises(ConfigError, match="no results: no observing robot measured"):
        build_summary([nothing], [blind])
