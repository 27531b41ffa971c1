"""``relloc reproduce NAME --mcap/--tum``: each exporting experiment writes the run it says, and
the exported numbers are the ones that run scored (short scenarios, seeded)."""

from __future__ import annotations

import dataclasses
import json
from collections import defaultdict
from pathlib import Path

import numpy as np
import pytest
from export_files import check_mcap, check_tum

from relloc.cli import main
from relloc.experiments import registry
from relloc.pipeline.evaluation import evaluate
from relloc.pipeline.export import ExportRequest, export_estimates
from relloc.pipeline.montecarlo import spawn_seeds

pytest.importorskip("mcap", reason="extra 'ros' is not installed")


def test_exporting_experiments_state_their_run():
    exporting = {n for n in registry.available() if registry.exported_run(n) is not None}
    assert exporting == {
        "wanasinghe2014",
        "sharma2013",
        "mrclam-cl",
        "desilva2015",
        "mrclam-association",
        "guler2023",
    }


def test_an_experiment_without_estimates_refuses_mcap(tmp_path, capsys):  # type: ignore[no-untyped-def]
    code = main(
        ["reproduce", "wanasinghe-observability", "--out", str(tmp_path / "o"),
         "--mcap", str(tmp_path / "x.mcap")]
    )  # fmt: skip
    assert code == 2
    assert "does not export estimates; experiments that do: " in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


def test_wanasinghe2014_exports_the_accuracy_filters_of_team_draw_0(tmp_path):  # type: ignore[no-untyped-def]
    from relloc.experiments.wanasinghe2014_sim import SimSettings, accuracy_run, team_task
    from relloc.sim.scenario import default_scenario

    settings = SimSettings(
        scenario=dataclasses.replace(default_scenario(), duration_s=6.0), n_poses=3
    )
    seed = spawn_seeds(5, 2)[0]
    estimates, recording = accuracy_run(seed, settings)
    by_subject = {e.subject: e for e in evaluate(estimates, recording, at_updates=True)}
    team = team_task(seed, 0, settings)["accuracy"]  # the batch that also runs Table 1
    assert set(by_subject) == set(team)
    for name, e in team.items():
        np.testing.assert_allclose(by_subject[name].error, e.error, rtol=0, atol=1e-12)
    section = export_estimates(ExportRequest(tum=tmp_path), estimates, recording, run="draw 0")
    assert {s["frame_id"] for s in section["series"].values()} == {"observer/base_link"}


def test_sharma2013_cli_exports_run_0_of_the_two_landmark_case(tmp_path, monkeypatch):  # type: ignore[no-untyped-def]
    """Through the CLI (5 s runs, symbolic ranks off as in the experiment's own smoke test):
    the exported world poses' RMSE per robot is the summary's two-landmark ``pos_rmse_m``."""
    from relloc.experiments import sharma2013

    monkeypatch.setattr(sharma2013, "DURATION_S", 5.0)
    out = tmp_path / "s"
    code = main(
        ["reproduce", "sharma2013", "--out", str(out), "--runs", "1", "--executor", "serial",
         "--quiet", "--mcap", str(tmp_path / "s.mcap"), "--tum", str(tmp_path / "tum")]
    )  # fmt: skip
    assert code == 0
    summary = json.loads((out / "summary.json").read_text())
    export = summary["export"]
    assert export["run"].startswith("run 0 of 1 (seed 2026)")
    expected = summary["cases"]["two_landmarks"]["pos_rmse_m"]
    assert set(export["series"]) == {f"team->{r}" for r in "12345"}
    for robot in "12345":
        s = export["series"][f"team->{robot}"]
        assert s["topic"] == f"/team/estimates/r{robot}" and s["frame_id"] == "map"
        assert s["position_rmse_m"] == pytest.approx(expected[robot], rel=1e-12)
    assert Path(export["mcap"]["path"]).stat().st_size == export["mcap"]["bytes"]


def test_desilva2015_exports_the_dominant_tracks_of_run_0(tmp_path):  # type: ignore[no-untyped-def]
    from relloc.experiments.desilva2015 import RunConfig, _task, export_run0
    from relloc.experiments.registry import ReproduceArgs
    from relloc.sim.multihypothesis import DeSilvaScenario

    config = RunConfig(scenario=DeSilvaScenario(duration=3.0))
    args = ReproduceArgs(out_dir=tmp_path, seed=3, export=ExportRequest(tum=tmp_path / "tum"))
    section = export_run0(args, 2, config)
    scores = _task(spawn_seeds(3, 2)[0], 0, config)
    robots = ("L1", "L2", "P1", "P2", "P3")
    for label, s in section["series"].items():
        owner, subject = label.split("->")
        assert s["frame_id"] == f"{owner}/base_link"
        err = scores.pos_err[robots.index(owner), :, robots.index(subject)]
        err = err[np.isfinite(err)]
        assert s["records_with_truth"] == err.size
        assert s["position_rmse_m"] == pytest.approx(float(np.sqrt(np.mean(err**2))), rel=1e-12)
    assert len(section["series"]) >= 4


def test_guler2023_exports_the_followers_common_frame_beliefs(tmp_path):  # type: ignore[no-untyped-def]
    from relloc.experiments.guler2023 import (
        EXPORTED_CASE,
        build_cases,
        run_scenario_once,
        simulate_case,
    )
    from relloc.models.uwb_noise import UwbNoiseModel

    model = UwbNoiseModel(  # a TIERS-like fit
        bias=0.35, spread=0.075, outlier_rate=0.04, outlier_excess_mean=0.15, correlation_time=1.2
    )
    case = build_cases(model)[EXPORTED_CASE].with_scenario(duration=3.0)
    seed = spawn_seeds(4, 1)[0]
    run, _ = simulate_case(case, np.random.default_rng(seed))
    section = export_estimates(
        ExportRequest(mcap=tmp_path / "g.mcap"), run.estimates, run.recording, run="run 0"
    )
    scored = run_scenario_once(seed, 1, case, False)
    followers = list(run.priors)
    for k, owner in enumerate(followers):
        s = section["series"][f"{owner}->R_0"]
        assert s["frame_id"] == f"{owner}/common"
        assert s["position_rmse_m"] == pytest.approx(float(np.hypot(*scored.rmse[k])), rel=1e-12)
    topics = section["mcap"]["topics"]
    assert all(f"/{f}/estimates/R_0/observer_heading" in topics for f in followers)


def test_desilva2015_cli_writes_the_files_its_summary_states(tmp_path, monkeypatch):  # type: ignore[no-untyped-def]
    """``relloc reproduce desilva2015 --tum DIR --mcap FILE`` (3 s runs, one per setting, the
    sweeps cut to the point the report names): the leaders' dominant tracks of run 0 in both
    formats, row for row the records its summary counts and scores."""
    from relloc.experiments import desilva2015

    for name, value in (("DURATION_S", 3.0), ("STEADY_FROM_S", 1.0), ("FINAL_WINDOW_S", 1.0)):
        monkeypatch.setattr(desilva2015, name, value)
    monkeypatch.setattr(desilva2015, "KIDNAP", (3, 1.5, 3.0, -2.0, 2.0))
    monkeypatch.setattr(desilva2015, "CLUTTER_FACTORS", (1, 100))  # the report's λ × 100
    monkeypatch.setattr(desilva2015, "PD_VALUES", (0.95,))
    # no figures (half the time; test_cli_multihypothesis draws them)
    monkeypatch.setattr(desilva2015, "_figures", lambda *args: defaultdict(lambda: "none.png"))
    out, tum, mcap = tmp_path / "d", tmp_path / "tum", tmp_path / "d.mcap"
    code = main(
        ["reproduce", "desilva2015", "--out", str(out), "--runs", "1", "--seed", "3",
         "--executor", "serial", "--quiet", "--tum", str(tum), "--mcap", str(mcap)]
    )  # fmt: skip
    assert code == 0
    export = json.loads((out / "summary.json").read_text())["export"]
    assert export["run"] == f"run 0 of 1 (seed 3): {desilva2015.EXPORTED_RUN}"
    robots = {"L1", "L2", "P1", "P2", "P3"}
    for label, s in export["series"].items():
        owner, subject = label.split("#")[0].split("->")
        assert owner in {"L1", "L2"} and subject in robots - {owner}, label
        assert s["frame_id"] == f"{owner}/base_link"
    assert len(export["series"]) >= 4
    check_tum(export, tum)
    check_mcap(export, mcap)


def test_guler2023_cli_writes_the_files_its_summary_states(  # type: ignore[no-untyped-def]
    tmp_path, monkeypatch, guler2023_short_plan
):
    """``relloc reproduce guler2023 --tum DIR --mcap FILE`` on a short plan (5 % durations, one
    run per block): every follower's common-frame belief of the leader in run 0 of
    ``two_drones``, as TUM pairs and MCAP poses (and its own heading, MCAP only)."""
    from relloc.experiments import guler2023

    monkeypatch.setattr(guler2023, "default_plan", lambda runs: guler2023_short_plan)
    # no figures (half the time; test_sim_and_cli draws them)
    monkeypatch.setattr(guler2023, "_figures", lambda *args: defaultdict(lambda: "none.png"))
    out, tum, mcap = tmp_path / "g", tmp_path / "tum", tmp_path / "g.mcap"
    code = main(
        ["reproduce", "guler2023", "--out", str(out), "--seed", "7", "--executor", "serial",
         "--quiet", "--tum", str(tum), "--mcap", str(mcap)]
    )  # fmt: skip
    assert code == 0
    export = json.loads((out / "summary.json").read_text())["export"]
    assert export["run"] == (f"run 0 of 1 of two_drones (master seed 7): {guler2023.EXPORTED_RUN}")
    followers = ("R_1", "R_2", "R_3", "R_4")
    assert set(export["series"]) == {f"{f}->R_0" for f in followers}
    for f in followers:
        assert export["series"][f"{f}->R_0"]["frame_id"] == f"{f}/common"
        assert f"/{f}/estimates/R_0/observer_heading" in export["mcap"]["topics"]
    check_tum(export, tum)
    check_mcap(export, mcap)
