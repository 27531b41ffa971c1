"""Data an experiment leaves out are counted where its user reads (summary.json, report.md):
UWB readings kept at radio level only and ranges to surveyed static radios in ``relloc run BAG``,
output times and robots without ground truth in mrclam-cl, the rows the loader skipped in
``relloc team up MRCLAM_DIR``."""

from __future__ import annotations

import math
import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from relloc.errors import DataError

sys.path.insert(0, str(Path(__file__).parents[1] / "datasets"))

S = 1_000_000_000
T0 = 1_000 * S


def _mapping() -> str:
    """The sample bags' mapping with odometry for beta too, so both robots form a pair."""
    from bag_samples import SAMPLE_MAPPING

    text = SAMPLE_MAPPING.replace('name = "beta"\n', 'name = "beta"\nodometry = "/beta/odom"\n', 1)
    assert text != SAMPLE_MAPPING
    return text


def _bag(path: Path) -> Path:
    """Two robots with odometry and motion capture for 2 s; ranges alpha–beta (tracked), to the
    surveyed n_3 (3, used by no filter of ``relloc run``) and to the unsurveyed n_4 (4, kept at
    radio level only)."""
    pytest.importorskip("rosbags")
    from bag_samples import ODOM, POSE, RANGE, mocap, odometry, pose, uwb, write_bag

    msgs = []
    for k in range(21):
        t = T0 + k * S // 10
        a = (1.0 + 0.02 * k, 2.0)
        msgs.append(("/alpha/odom", ODOM, t, odometry(t, 0.2, 0.0)))
        msgs.append(("/beta/odom", ODOM, t, odometry(t, 0.0, 0.0)))
        msgs.append(("/mocap/alpha", POSE, t, mocap(t, pose(a[0], a[1], 0.0, 0.0))))
        msgs.append(("/mocap/beta", POSE, t, mocap(t, pose(3.0, 2.0, 0.0, 0.0))))
        if k % 2:
            r = math.hypot(3.0 - a[0], 0.0)
            msgs.append(("/u/n_1/n_2/d", RANGE, t + 1, uwb(t + 1, r)))
        if k % 7 == 1:
            msgs.append(("/u/n_1/n_3/d", RANGE, t + 2, uwb(t + 2, math.hypot(a[0], 3.0))))
        if k % 5 == 2:
            msgs.append(("/u/n_1/n_4/d", RANGE, t + 3, uwb(t + 3, 4.0)))
    msgs.sort(key=lambda m: m[2])
    return write_bag(path, msgs)


def test_relloc_run_counts_the_uwb_readings_no_filter_uses(tmp_path):
    from relloc.datasets.bag_mapping import parse_mapping
    from relloc.experiments.bag_run import run_bag

    path = _bag(tmp_path / "bag")
    out = tmp_path / "out"
    summary, _ = run_bag(path, parse_mapping(_mapping(), "loss.toml"), out, plots=False)
    loader = summary["loader"]
    assert loader["uwb_readings"] == 10 + 3 + 4
    # the 4 readings to the radio of unknown position never reach the recording: said so
    assert loader["uwb_readings_not_in_recording"] == {"to a static radio of unknown position": 4}
    # the 3 ranges to the surveyed radio are in the recording, but no filter of the run takes them
    assert summary["range_rows_to_static_radios_not_used"] == 3
    report = (out / "report.md").read_text()
    assert "Not used: 3 UWB ranges to static radios of known position" in report
    assert "Not in the recording: 4 of the bag's 17 UWB readings" in report


def test_a_bag_whose_readings_all_reach_the_recording_reports_none_left_out(tmp_path):
    from relloc.datasets.bag_mapping import parse_mapping
    from relloc.datasets.rosbag import load_bag

    path = _bag(tmp_path / "bag")
    surveyed = _mapping().replace('name = "n_4"\n', 'name = "n_4"\nposition = [9.0, 9.0, 0.0]\n')
    bag = load_bag(path, parse_mapping(surveyed, "s.toml"))
    assert bag.to_dict()["uwb_readings_not_in_recording"] == {}
    assert bag.recording.measurements.size == bag.ranges.t.size == 17


def _truth(t: np.ndarray):
    from relloc.datasets.mrclam import GroundTruth

    return GroundTruth(
        t=t, x=np.zeros(t.size), y=np.zeros(t.size), theta=np.zeros(t.size), gap_threshold=0.5
    )


def test_mrclam_cl_names_the_robots_and_times_it_cannot_score():
    """A robot whose ground truth ends before the scored window was dropped from the per-robot
    figures and their mean without a word; times without truth were not counted."""
    from relloc.experiments.mrclam_cl import evaluate

    dense = np.arange(0.0, 20.01, 0.1)
    truths = {1: _truth(dense), 2: _truth(np.arange(0.0, 8.01, 0.1))}
    ds = SimpleNamespace(
        robot_ids=(1, 2), robot=lambda r: SimpleNamespace(groundtruth=truths[r]), path="synthetic"
    )
    out_t = np.arange(0.0, 20.01, 0.5)
    result = {
        "mean": np.full((out_t.size, 2, 3), 0.1),
        "cov": np.tile(np.eye(3) * 0.01, (out_t.size, 2, 1, 1)),
    }
    whole = evaluate(result, ds, out_t, 0.0)
    assert set(whole["pos_rmse_m"]) == {"1", "2", "mean"}
    assert whole["records_without_truth"] == {"2": int(np.count_nonzero(out_t > 8.0 + 1e-9))}
    assert whole["robots_without_truth"] == []
    held = evaluate(result, ds, out_t, 10.0, 20.0)
    assert set(held["pos_rmse_m"]) == {"1", "mean"}  # the figure as before
    assert held["robots_without_truth"] == ["2"]
    assert held["records_without_truth"] == {"2": int(np.count_nonzero(out_t >= 10.0))}
    # no robot with truth in the window: a clear error, not numpy's "need at least one array"
    with pytest.raises(DataError, match=r"synthetic: no robot has ground truth"):
        evaluate(result, ds, out_t, 30.0, 40.0)


def test_mrclam_cl_report_says_which_robots_were_left_out():
    from relloc.experiments.mrclam_cl import _without_truth_text

    case = {
        "records_without_truth": {"2": 24},
        "robots_without_truth": [],
        "heldout_records_without_truth": {"2": 21},
        "heldout_robots_without_truth": ["2"],
    }
    text = _without_truth_text(case)
    assert "whole run: robot 2: 24" in text and "held-out window: robot 2: 21" in text
    assert "(held-out window), without any ground truth there: robots 2." in text
    clean = {
        "records_without_truth": {},
        "robots_without_truth": [],
        "heldout_records_without_truth": {},
        "heldout_robots_without_truth": [],
    }
    assert _without_truth_text(clean).startswith("Every robot has valid ground truth")


def test_team_up_on_an_mrclam_folder_reports_the_rows_the_loader_skipped(tmp_path):
    """``relloc team up MRCLAM_DIR`` wrote no load report: rows the loader skipped (here the
    synthetic folder's stray barcode 99) vanished without a trace."""
    import importlib.util

    from relloc.experiments.mrclam_cl import load_report_line
    from relloc.experiments.mrclam_team import fit_dataset, load_report, prepared_team

    where = Path(__file__).parents[1] / "cooperative" / "conftest.py"
    spec = importlib.util.spec_from_file_location("cooperative_conftest", where)
    assert spec is not None and spec.loader is not None
    helpers = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(helpers)
    folder = helpers.write_mrclam_folder(tmp_path / "Synthetic", duration=12.0)
    ds, fit = fit_dataset(folder)
    prepared, _ = prepared_team(ds, fit, 0, "range_bearing/2_landmarks")
    report = load_report(prepared)
    assert report == {"n_skipped": 1, "by_reason": {"unknown barcode": 1}}
    assert (
        load_report_line(report)
        == "Input rows of the dataset skipped (not used): 1 (1 unknown barcode)."
    )
    assert (
        load_report_line({"n_skipped": 0, "by_reason": {}})
        == "Input rows: every data row of the dataset was used."
    )
