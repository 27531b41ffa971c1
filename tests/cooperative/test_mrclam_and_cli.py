"""MRCLAM loader + cooperative localization smoke tests, and CLI smoke tests."""

import json
import re
from pathlib import Path

import numpy as np
import pytest

from relloc.cli import main
from relloc.datasets.paths import default_mrclam_dataset

MODES = ("dead_reckoning", "bearing", "range_bearing")
ANCHORS = ("none", "2_landmarks", "all_landmarks", "gps_robot1")


def test_mrclam_cl_cli_on_a_synthetic_mrclam_folder(
    synthetic_mrclam, tmp_path, capsys, monkeypatch
):
    monkeypatch.setenv("COLUMNS", "80")
    monkeypatch.chdir(tmp_path)  # a short --out, as typed (a path is never split)
    out = Path("out")
    code = main(
        [
            "reproduce",
            "mrclam-cl",
            "--out",
            str(out),
            "--dataset",
            str(synthetic_mrclam),
            "--executor",
            "serial",
        ]
    )
    assert code == 0
    # every figure the report shows is rendered (non-empty) and listed on the console
    printed = capsys.readouterr().out
    assert max(len(line) for line in printed.splitlines()) <= 80
    figures = re.findall(r"!\[[^\]]*\]\(([^)]+\.png)\)", (out / "report.md").read_text())
    assert len(figures) >= 4
    for name in figures:
        assert (out / name).stat().st_size > 1000
        assert name in printed
    assert "pos RMSE" in printed  # the headline table, laid out for the terminal
    summary = json.loads((out / "summary.json").read_text())
    assert {"experiment", "seed", "runs", "cases", "fit", "targets"} <= set(summary)
    assert set(summary["cases"]) == {f"{m}/{a}" for m in MODES for a in ANCHORS}
    for case in summary["cases"].values():
        for key in ("pos_rmse_m", "heading_rmse_rad"):
            assert set(case[key]) == {"1", "2", "3", "4", "5", "mean"}
            assert all(np.isfinite(v) for v in case[key].values())
        assert {"nees_pct_beyond", "used", "rejected"} <= set(case)
    rb = summary["cases"]["range_bearing/all_landmarks"]
    assert rb["used"] > 0
    assert rb["counts"]["unknown_barcodes"] == 1  # the stray barcode 99 is counted
    dr = summary["cases"]["dead_reckoning/none"]["pos_rmse_m"]["mean"]
    assert rb["pos_rmse_m"]["mean"] < dr
    assert (out / "report.md").is_file() and (out / "pos_rmse.png").is_file()
    # every target is judged on the held-out window, which starts where the fit's window ends;
    # the whole-run (in-sample) figures are only shown beside
    held, fitted = summary["scored_on"], summary["fit"]["calibration_window"]
    assert held["start_s"] == fitted["end_s"] and held["end_s"] > held["start_s"]
    dr_held = summary["cases"]["dead_reckoning/none"]["heldout"]["pos_rmse_m"]
    for mode in ("range_bearing", "bearing"):
        target, case = summary["targets"][mode], summary["cases"][f"{mode}/all_landmarks"]
        for key in ("pos_rmse_m", "heading_rmse_rad", "nees_pct_beyond"):
            assert target[key] == case["heldout"][key]
        assert target["improvement_over_dead_reckoning"] == dr_held / target["pos_rmse_m"]
        assert target["in_sample"]["pos_rmse_m"] == case["pos_rmse_m"]["mean"]
    assert "judged on the held-out window" in (out / "report.md").read_text()


def test_mrclam_cl_calibrated_on_the_second_half_scores_the_first(synthetic_mrclam, tmp_path):
    out = tmp_path / "out"
    args = ["reproduce", "mrclam-cl", "--out", str(out), "--dataset", str(synthetic_mrclam)]
    assert (
        main([*args, "--executor", "serial", "--quiet", "--calibration-window", "second-half"]) == 0
    )
    summary = json.loads((out / "summary.json").read_text())
    held, fitted = summary["scored_on"], summary["fit"]["calibration_window"]
    assert summary["calibration_window_choice"] == "second-half"
    assert held["end_s"] == fitted["start_s"] and held["start_s"] < held["end_s"]
    assert fitted["end_s"] > fitted["start_s"]
    report = (out / "report.md").read_text()
    assert f"Scored on [{held['start_s']:.0f}, {held['end_s']:.0f}] s" in report
    assert "--calibration-window second-half" in report
    for mode in ("range_bearing", "bearing"):
        case = summary["cases"][f"{mode}/all_landmarks"]
        assert np.isfinite(case["heldout"]["pos_rmse_m"])
        # the held-out figure is over the first half only, so it differs from the whole run's
        assert case["heldout"]["pos_rmse_m"] != case["pos_rmse_m"]["mean"]


def test_mrclam_cl_bad_calibration_window_is_a_config_error(synthetic_mrclam, tmp_path, capsys):
    args = ["reproduce", "mrclam-cl", "--out", str(tmp_path / "o"), "--dataset"]
    code = main([*args, str(synthetic_mrclam), "--quiet", "--calibration-window", "500:"])
    assert code == 2
    err = capsys.readouterr().err
    assert "--calibration-window '500:'" in err and "strictly inside" in err


def test_mrclam_cl_cut_after_the_last_output_time_is_a_config_error(
    synthetic_mrclam, tmp_path, capsys
):
    """The 12 s folder is scored every 0.5 s up to 11.5 s: a cut at 11.75 s is inside the run's
    span but leaves the scoring window [11.75, 12] s without an output time."""
    args = ["reproduce", "mrclam-cl", "--out", str(tmp_path / "o"), "--dataset"]
    code = main([*args, str(synthetic_mrclam), "--quiet", "--calibration-window", ":11.75"])
    assert code == 2
    err = capsys.readouterr().err
    assert (
        "--calibration-window ':11.75': the scoring window [11.75, 12.00] s holds no span of the "
        "output times" in err
    )
    assert "(every 0.5 s from 0.00 to 11.50 s)" in err


@pytest.mark.parametrize("split", ["first-half", "second-half"])
def test_mrclam_cl_on_a_cut_of_run6_states_its_windows(mrclam_run6_cut, tmp_path, split):
    """Another run of the same layout: three of run 6's robots, its first 120 s."""
    folder = mrclam_run6_cut(tmp_path / "cut", robots=(2, 4, 5), keep_s=120.0)
    out = tmp_path / "out"
    args = ["reproduce", "mrclam-cl", "--out", str(out), "--dataset", str(folder)]
    assert main([*args, "--executor", "serial", "--quiet", "--calibration-window", split]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["robots"] == [2, 4, 5]
    held, fitted = summary["scored_on"], summary["fit"]["calibration_window"]
    assert (
        0.0 <= min(held["start_s"], fitted["start_s"])
        and max(held["end_s"], fitted["end_s"]) <= 120.5
    )
    cut_at = fitted["end_s"] if split == "first-half" else fitted["start_s"]
    assert cut_at == pytest.approx(60.0, abs=1.0)
    assert (held["start_s"] if split == "first-half" else held["end_s"]) == cut_at
    # either half fits the models: the report states half the run in-sample (it said "half"
    # whatever the window, also for a quarter)
    report = (out / "report.md").read_text()
    assert "the whole-run figures, 50% of the run in-sample" in report
    # the rows the loader and the conversion skipped are in report.md too, not only in
    # summary.json's load_report
    skipped = summary["load_report"]["n_skipped"]
    assert (
        f"Input rows of the dataset skipped (not used): {skipped} (" in report
        if skipped
        else "Input rows: every data row of the dataset was used." in report
    )
    for case in summary["cases"].values():
        assert set(case["pos_rmse_m"]) == {"2", "4", "5", "mean"}
        held_share = case["heldout"].pop("nees_beyond_interval")
        assert held_share["percent"] == case["heldout"]["nees_pct_beyond"]
        assert all(np.isfinite(v) for v in case["heldout"].values())
    for target in summary["targets"].values():
        assert np.isfinite(target["pos_rmse_m"]) and np.isfinite(target["nees_pct_beyond"])
        # the held-out share's interval by batch means: the same share, inside its interval
        share = target["nees_beyond_interval"]
        assert share["percent"] == target["nees_pct_beyond"] and share["clusters"] == 10
        assert share["clustering"] == "time blocks" and share["runs"] == 1
        assert share["interval"][0] <= share["percent"] <= share["interval"][1]
        assert share["verdict"] in {"consistent", "conservative", "over-confident", "inconclusive"}
        assert (
            f"{share['interval'][0]:.1f}–{share['interval'][1]:.1f} {share['verdict']}"
            in (out / "report.md").read_text()
        )
    inflation = summary["fit"]["odometry_inflation"]
    assert inflation["cases"] == ["range_bearing/all_landmarks", "bearing/all_landmarks"]
    report = (out / "report.md").read_text()
    if split == "first-half":  # 30 s from the start, the robots' first command included: too
        assert inflation["k"] == 1.0 and not inflation["tried"]  # little odometry to fit on
        assert "odometry" in inflation["not_fitted"]
        assert "no factor on it could be fitted" in report
    else:
        assert not inflation["not_fitted"] and inflation["tried"][-1]["k"] == inflation["k"]
        assert f"odometry σ multiplied by {inflation['k']:g}" in report
    # the factor is checked on the second half of the calibration window, not on the scored part
    assert inflation["fitted_on"]["start_s"] == fitted["start_s"]
    assert inflation["fitted_on"]["end_s"] == inflation["checked_on"]["start_s"]
    assert inflation["checked_on"]["end_s"] == fitted["end_s"]
    assert f"Scored on [{held['start_s']:.0f}, {held['end_s']:.0f}] s" in report
    assert f"calibration window [{fitted['start_s']:.0f}, {fitted['end_s']:.0f}] s" in report
    # the ratio to dead reckoning states the drift it divides and the window's end it grew to
    dr = summary["cases"]["dead_reckoning/none"]["heldout"]["pos_rmse_m"]
    assert f"held-out position RMSE of dead reckoning ({dr:.2f} m)" in report
    start = min(fitted["start_s"], held["start_s"])  # the run's start, where DR starts
    assert f"the window ends {held['end_s'] - start:.0f} s after it" in report


def test_mrclam_cl_scores_up_to_the_last_ground_truth_and_needs_two_landmarks(
    mrclam_run6_cut, tmp_path, capsys
):
    """One measurement row stamped 500 s after the rest once put the held-out half where no
    robot has ground truth (a traceback); a landmark table of one landmark, an IndexError."""
    folder = mrclam_run6_cut(tmp_path / "cut", robots=(2, 4, 5), keep_s=120.0)
    path = folder / "Robot2_Measurement.dat"
    rows = path.read_text().splitlines()
    stray = rows[-1].split()
    stray[0] = f"{float(stray[0]) + 500.0:.3f}"
    path.write_text("\n".join([*rows, "\t".join(stray)]) + "\n")
    out = tmp_path / "out"
    args = ["reproduce", "mrclam-cl", "--dataset", str(folder), "--executor", "serial", "--quiet"]
    assert main([*args, "--out", str(out)]) == 0
    held = json.loads((out / "summary.json").read_text())["scored_on"]
    assert 60.0 < held["end_s"] <= 120.5
    landmarks = folder / "Landmark_Groundtruth.dat"
    lines = landmarks.read_text().splitlines()
    landmarks.write_text("\n".join(lines[:5]) + "\n")  # the header and one landmark
    assert main([*args, "--out", str(tmp_path / "one")]) == 3
    assert "on two landmarks; Landmark_Groundtruth.dat has 1" in capsys.readouterr().err


def test_mrclam_cl_figures_do_not_depend_on_the_world_frame_clock_or_barcodes(
    mrclam_run6_cut, mrclam_run6_moved, tmp_path
):
    """Another run in every respect a pipeline could wrongly depend on: the same 120 s of three
    robots recorded in a world frame turned by 2 rad and shifted, on a clock 123456.789 s later
    and with other robot barcodes (``tests/conftest.py``). Ranges, bearings and odometry are
    body-frame readings, so the fitted models and every held-out figure must agree; they differ
    only by the files' rounding of the poses (1e-8 m, 1e-8 rad;
    :mod:`relloc.datasets.mrclam_move`)."""
    cut = mrclam_run6_cut(tmp_path / "cut", robots=(1, 3, 5), keep_s=120.0)
    summaries = []
    for name, folder in (("cut", cut), ("moved", mrclam_run6_moved(cut, tmp_path / "moved"))):
        out = tmp_path / f"out_{name}"
        args = ["reproduce", "mrclam-cl", "--out", str(out), "--dataset", str(folder)]
        assert (
            main([*args, "--executor", "serial", "--quiet", "--calibration-window", "second-half"])
            == 0
        )
        summaries.append(json.loads((out / "summary.json").read_text()))
    here, moved = summaries
    assert moved["robots"] == here["robots"] == [1, 3, 5]
    for edge in ("start_s", "end_s"):
        assert moved["scored_on"][edge] == here["scored_on"][edge]
    assert moved["fit"]["odometry_inflation"]["k"] == here["fit"]["odometry_inflation"]["k"]
    for key in ("scale_v", "scale_w"):
        np.testing.assert_allclose(moved["fit"][key], here["fit"][key], rtol=1e-6)
    for mode, target in here["targets"].items():
        other = moved["targets"][mode]
        for figure in ("pos_rmse_m", "heading_rmse_rad", "improvement_over_dead_reckoning"):
            assert other[figure] == pytest.approx(target[figure], rel=1e-5), (mode, figure)
        assert other["nees_pct_beyond"] == target["nees_pct_beyond"]
        assert other["nees_beyond_interval"] == target["nees_beyond_interval"]


def test_odometry_inflation_reads_the_calibration_window_only(mrclam_run6_cut, tmp_path):
    """The factor on the odometry noise is chosen by replaying the calibration window alone:
    two recordings that share their first 60 s and differ after it (one stops at 60 s, one goes
    on to 120 s) give the same factor, tried the same way, for a window inside those 60 s
    (models fitted on its first half, replayed over its second)."""
    from relloc.calibration.window import CalibrationWindow
    from relloc.datasets.mrclam import load_mrclam
    from relloc.experiments.mrclam_cl import ODOMETRY_INFLATION_GRID, fit_models

    fits = []
    for keep_s in (60.0, 120.0):
        ds = load_mrclam(mrclam_run6_cut(tmp_path / f"cut{keep_s:g}", keep_s=keep_s))
        t0 = max(float(ds.robot(r).groundtruth.t[0]) for r in ds.robot_ids)
        fits.append(fit_models(ds, CalibrationWindow(t0, 55.0, "cut")).odometry_inflation)
    assert fits[0] == fits[1]
    tried = [k for k, _ in fits[0].tried]
    assert tried == list(ODOMETRY_INFLATION_GRID[: len(tried)]) and fits[0].k == tried[-1]


def test_mrclam_missing_file_is_a_data_error(synthetic_mrclam, tmp_path, capsys):
    broken = tmp_path / "broken"
    broken.mkdir()
    for f in synthetic_mrclam.iterdir():
        if f.name != "Robot3_Odometry.dat":
            (broken / f.name).write_text(f.read_text())
    assert (
        main(
            [
                "reproduce",
                "mrclam-cl",
                "--out",
                str(tmp_path / "o"),
                "--dataset",
                str(broken),
                "--quiet",
            ]
        )
        == 3
    )
    assert "Robot3_Odometry.dat" in capsys.readouterr().err


@pytest.mark.skipif(
    not default_mrclam_dataset().is_dir(), reason="shared MRCLAM_Dataset6 not available here"
)
def test_loader_and_cooperative_localization_on_real_mrclam():
    from relloc.calibration.window import CalibrationWindow
    from relloc.datasets.mrclam import load_mrclam
    from relloc.experiments.mrclam_cl import (
        build_recording,
        case_settings,
        evaluate,
        fit_models,
        run_filter,
    )

    ds = load_mrclam(default_mrclam_dataset())
    fit = fit_models(ds, CalibrationWindow(0.0, 100.0, str(ds.path)))
    prepared = build_recording(ds, fit, np.random.default_rng(0))
    out_t = prepared.out_t[prepared.out_t <= 30.0]
    n_lm = prepared.recording.landmarks.shape[0]
    result = {}
    for mode, anchors in (("dead_reckoning", "none"), ("range_bearing", "all_landmarks")):
        settings = case_settings(mode, anchors, fit, prepared.two_landmarks, n_lm)
        run = run_filter(prepared, settings, out_t)
        result[mode] = (evaluate(run, ds, out_t, 0.0), run["counts"])
    cl, counts = result["range_bearing"]
    assert counts["used"] > 100 and np.isfinite(cl["pos_rmse_m"]["mean"])
    assert cl["pos_rmse_m"]["mean"] < 0.2
    assert cl["pos_rmse_m"]["mean"] < result["dead_reckoning"][0]["pos_rmse_m"]["mean"]


def test_sharma2013_cli_writes_the_acceptance_keys(tmp_path, monkeypatch):
    """Short (5 s) run, with the symbolic ranks at run 0's mid-run graph (about 4 s)."""
    from relloc.experiments import sharma2013

    monkeypatch.setattr(sharma2013, "DURATION_S", 5.0)
    out = tmp_path / "s"
    assert (
        main(
            [
                "reproduce",
                "sharma2013",
                "--out",
                str(out),
                "--runs",
                "1",
                "--executor",
                "serial",
                "--quiet",
            ]
        )
        == 0
    )
    summary = json.loads((out / "summary.json").read_text())
    assert summary["runs"] == 1 and summary["seed"] == 2026
    assert set(summary["cases"]) == {"no_landmark", "one_landmark", "two_landmarks", "gps_robot1"}
    for case in summary["cases"].values():
        assert set(case["pos_rmse_m"]) == {"1", "2", "3", "4", "5", "mean"}
        assert set(case["heading_rmse_rad"]) == {"1", "2", "3", "4", "5", "mean"}
        assert isinstance(case["bounded"], bool)
        share = case["nees_beyond_interval"]
        assert share["percent"] == case["nees_pct_beyond"] and share["samples"] > 0
        assert share["clustering"] == "time blocks"  # one run: its blocks of time
        assert case["nees_pct_beyond_per_run"] == [pytest.approx(share["percent"])]
    aware = summary["observability_aware"]
    assert set(aware["nees_beyond_interval"]) == {"no_landmark", "one_landmark"}
    share = aware["nees_beyond_interval"]["no_landmark"]
    assert share == summary[aware["block"]]["no_landmark"]["nees_beyond_interval"]
    lo, hi = share["interval"]
    assert f"{lo:.1f}–{hi:.1f} {share['verdict']}" in (out / "report.md").read_text()
    assert (out / "fig3_topology.png").is_file() and (out / "report.md").is_file()
    # the final NEES along the unobservable directions: d = 3, 1, none, none
    for block in ("cases", "cases_first_estimates", "cases_observability_constrained"):
        frame = {case: c["frame_nees"] for case, c in summary[block].items()}
        assert frame["two_landmarks"] is None and frame["gps_robot1"] is None
        for case, dof in (("no_landmark", 3), ("one_landmark", 1)):
            f = frame[case]
            assert f["dof"] == dof and len(f["per_run"]) == 1 and f["mean"] == f["per_run"][0]
            assert f["band"][0] < dof < f["band"][1]
            assert f["verdict"] in ("consistent", "over-confident", "conservative")
    assert (
        aware["frame_nees"]["no_landmark"] == summary[aware["block"]]["no_landmark"]["frame_nees"]
    )
    report = (out / "report.md").read_text()
    assert "the final frame NEES" in report and "Along the unobservable directions" in report
    # Theorems 2-4 for five robots on a connected graph: 3(n-1) unanchored, 3n-1 with one
    # landmark, full rank 3n with two or with GPS on robot 1
    ranks = {case: c["observability_rank"] for case, c in summary["cases"].items()}
    assert {case: r["rank"] for case, r in ranks.items()} == {
        "no_landmark": 12,
        "one_landmark": 14,
        "two_landmarks": 15,
        "gps_robot1": 15,
    }
    assert [r["landmark_edges"] for r in ranks.values()] == [0, 1, 2, 0]
    assert all(r["robot_edges"] == 4 and r["state_dim"] == 15 for r in ranks.values())
    assert all(r["full_rank"] == (r["rank"] == 15) for r in ranks.values())
