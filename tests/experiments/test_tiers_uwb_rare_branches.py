"""tiers-uwb's rarer outcomes: a held-out window without readings, a team case skipped for want
of anchors (and its report row), a stretch with no robot estimated, a mirror image no closer to
motion capture, and the shipped bags found under the shared data folder."""

from __future__ import annotations

import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from relloc.calibration.uwb_bag import heldout_errors
from relloc.datasets.bag_mapping import load_mapping
from relloc.datasets.rosbag import load_bag
from relloc.experiments import tiers_uwb, tiers_uwb_team
from relloc.experiments.registry import ReproduceArgs
from relloc.experiments.tiers_uwb_team import TeamTrack, score_positions, team_case


def test_a_held_out_window_without_readings_counts_no_rows(tmp_path: Path) -> None:
    sys.path.insert(0, str(Path(__file__).parent))
    from tiers_synthetic import synth

    bag = load_bag(synth(tmp_path / "moving", duration=3.0), load_mapping("tiers_relative"))
    assert heldout_errors(bag, None, 10.0, 20.0) == {"rows": 0}  # type: ignore[arg-type]


def test_an_anchored_case_with_fewer_than_two_anchors_is_skipped_and_reported() -> None:
    rec = SimpleNamespace(n_robots=3)
    got = team_case(rec, rec, 0.0, 1.0, [2], None, anchored=True)  # type: ignore[arg-type]
    assert got == {"skipped": "needs ≥ 2 anchors, the bag has 1"}
    fit = dict.fromkeys(
        ("bias_m", "spread_m", "link_bias_std_m", "outlier_rate", "correlation_time_s"), 0.1
    )
    summary = {
        "bags": {
            "b": {
                "calibration": {
                    "fit": fit,
                    "window": {"source": "w", "start_s": 0.0, "end_s": 1.0},
                    "source": "b",
                    "bias_drift_m": 0.0,
                    "range_sigma_m": 0.1,
                    "heldout": {"rows": 0},
                },
                "scored_window_s": [1.0, 2.0],
                "team": {"anchored": got},
                "pairs": {},
                "loader": {
                    "skips": {"rows_skipped": 0, "by_reason": {}},
                    "stamp_offset_s": {"bag": 0.0},
                    "unknown_topics": [],
                    "uwb_readings_not_in_recording": {},
                },
            }
        }
    }
    text = tiers_uwb.report(summary)
    assert "| team anchored | — | — | — | — | — | — | needs ≥ 2 anchors, the bag has 1 |" in text
    assert "Held-out range error" not in text


def test_a_stretch_with_no_robot_estimated_scores_no_records() -> None:
    grid = np.arange(3.0)
    est = np.full((3, 2, 2), np.nan)
    truth = np.zeros((3, 2, 2))
    got = score_positions(grid, est, None, truth, [0, 1], align=False)
    assert got == {"pos_rmse_m": None, "records": 0}


def test_a_mirror_image_no_closer_to_motion_capture_is_not_taken(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    line = np.array([[0.0, 0.0], [1.0, 0.0]])  # the anchors on the x axis
    truth = np.array([[[0.0, 0.0], [1.0, 0.0], [0.5, 2.0]]])
    monkeypatch.setattr(tiers_uwb_team, "_anchor_positions", lambda rec, anchors, t: line)
    monkeypatch.setattr(tiers_uwb_team, "truth_xy", lambda rec, t: truth)
    cov = np.tile(np.eye(2), (1, 3, 1, 1))
    right = TeamTrack(np.zeros(1), truth + np.array([0.0, 0.0, 0.1])[:, None], cov)
    assert tiers_uwb_team._best_mirror(None, right, [0, 1], [2], 0.0) == (right, False)  # type: ignore[arg-type]
    wrong = TeamTrack(np.zeros(1), truth * [1.0, -1.0], cov)
    flipped, taken = tiers_uwb_team._best_mirror(None, wrong, [0, 1], [2], 0.0)  # type: ignore[arg-type]
    assert taken
    np.testing.assert_allclose(flipped.mean[0, 2], [0.5, 2.0])


def test_without_bag_the_shipped_bags_of_the_shared_folder_are_scored(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    (tmp_path / "tiers").mkdir()
    monkeypatch.setattr(tiers_uwb, "shared_data_dir", lambda: tmp_path)
    got = tiers_uwb._bags(ReproduceArgs(out_dir=tmp_path / "out"))
    assert [path for path, _ in got] == [
        tmp_path / "tiers" / "cooperative_shortbag",
        tmp_path / "tiers" / "relative_case4_test1",
    ]
    assert [m.name for _, m in got] == ["tiers-cooperative", "tiers-relative"]
