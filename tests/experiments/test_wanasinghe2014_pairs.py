"""``relloc reproduce wanasinghe2014-pairs`` on truncated MRCLAM-layout copies of run 6: the
default pairs, a pair's row against the one-pair reproduction, a pair the data cannot give
(counted and reported, the others still run), and a robot the dataset lacks (refused)."""

from __future__ import annotations

import dataclasses
import json
import re
import shutil
from collections.abc import Callable
from pathlib import Path

import pytest
from wanasinghe_small import small_config

from relloc.errors import ConfigError
from relloc.experiments.wanasinghe2014 import run_reproduction
from relloc.experiments.wanasinghe2014_mrclam import TABLE2
from relloc.experiments.wanasinghe2014_pairs import (
    VERDICT_MARKS,
    chosen_pairs,
    default_pairs,
    run_pairs,
)


@pytest.fixture(scope="module")
def short_dataset(tmp_path_factory: pytest.TempPathFactory, mrclam_run6_cut) -> Path:
    """Robots 1-3, the first 45 s of run 6."""
    return mrclam_run6_cut(tmp_path_factory.mktemp("mrclam") / "MRCLAM_short")


def test_default_pairs_are_each_robot_observing_the_next_two() -> None:
    run6 = {(1, 2), (1, 3), (2, 3), (2, 4), (3, 4), (3, 5), (4, 5), (4, 1), (5, 1), (5, 2)}
    assert set(default_pairs([5, 3, 1, 4, 2])) == run6 and len(default_pairs(range(1, 6))) == 10
    three = default_pairs([7, 2, 9])
    assert sorted(three) == [(2, 7), (2, 9), (7, 2), (7, 9), (9, 2), (9, 7)]
    assert default_pairs([4, 8]) == ((4, 8), (8, 4))


def test_a_pair_naming_a_missing_robot_is_refused(short_dataset: Path) -> None:
    assert chosen_pairs(short_dataset, None) == ((1, 2), (1, 3), (2, 3), (2, 1), (3, 1), (3, 2))
    with pytest.raises(ConfigError, match=r"--pair 1,5: robot\(s\) \[5\] not in .*\[1, 2, 3\]"):
        chosen_pairs(short_dataset, [(1, 2), (1, 5)])


def test_a_row_is_the_one_pair_reproduction(
    short_dataset: Path, tmp_path: Path, states_skipped_rows: Callable[..., bool]
) -> None:
    """The 2 → 1 row carries what ``wanasinghe2014 --pair 2,1`` at the same seed reports."""
    config = small_config(short_dataset)
    summary = run_pairs(
        config, [(2, 1)], tmp_path / "pairs", seed=11, executor="serial", quiet=True
    )
    one = run_reproduction(
        dataclasses.replace(
            config, replay=dataclasses.replace(config.replay, observer=2, observed=1)
        ),
        tmp_path / "one",
        seed=11,
        executor="serial",
        quiet=True,
    )
    (row,) = summary["pairs"]
    assert (row["observer"], row["observed"]) == (2, 1) and summary["skipped"] == []
    assert row["windows"] == one["table3"]["windows"]
    calibration, scored = row["windows"]["calibration"], row["windows"]["scored"]
    assert calibration["start_s"] >= scored["end_s"] or calibration["end_s"] <= scored["start_s"]
    walk = one["turn_rate_residual"]["residual"]["relative"]
    assert row["relative_yaw_random_walk_rad"] == {
        window: walk[window]["calibrated"]["yaw_random_walk_rad"]
        for window in ("calibration", "scored")
    }
    for case in TABLE2:
        cell = row["cases"][case]
        for kind in ("calibrated", "raw"):
            assert cell[kind]["yaw_rmse_rad"] == one["table3"][kind][case]["phi"]["rmse_mean"]
            nees = one["table4"][kind][case]["nees_percent_beyond"]
            assert cell[kind]["nees_percent_beyond"] == nees
            share = one["table4"][kind][case]["nees_beyond_interval"]
            assert cell[kind]["nees_beyond_interval"] == share
        assert cell["yaw_bound_rad"] == one["replay_pcrlb"]["calibrated"][case]["phi"]
        tv = one["replay_pcrlb"]["truth_velocity"][case]["phi"]
        assert cell["truth_velocity_yaw_bound_rad"] == tv
        targets = one["replay_targets"][case]
        assert cell["calibrated"]["position_rmse_m"] == targets["position_rmse_m"]
        assert cell["raw"]["position_rmse_m"] == targets["raw_position_rmse_m"]
        assert cell["met"] == all(targets[k] for k in ("yaw_ok", "nees_ok", "position_ok"))
    # the report's cells mark the share's verdict: ↑ over-confident, ↓ conservative
    report = (tmp_path / "pairs" / "report.md").read_text()
    assert set(summary["loader"]) == {"n_skipped", "skipped_by_reason"}
    assert states_skipped_rows(report, summary["loader"]["n_skipped"])
    for kind in ("calibrated", "raw"):
        c = row["cases"]["case1"][kind]
        mark = VERDICT_MARKS.get(c["nees_beyond_interval"]["verdict"], "")
        text = f"{c['yaw_rmse_rad']:.3f} / {c['nees_percent_beyond']:.1f}{mark}"
        assert re.search(re.escape(text) + r"( ✓)? \|", report)
    on_disk = json.loads((tmp_path / "pairs" / "summary.json").read_text())
    assert on_disk["pairs"][0]["cases"]["case1"]["yaw_bound_rad"] == pytest.approx(
        row["cases"]["case1"]["yaw_bound_rad"]
    )


def test_a_pair_the_data_cannot_give_is_counted_and_the_rest_run(
    short_dataset: Path, tmp_path: Path
) -> None:
    """Robot 3's ground truth cut to its first 8 s: every pair with robot 3 is skipped with the
    replay's reason; 1 → 2 and 2 → 1 still run, and the tally counts only them."""
    cut = tmp_path / "robot3_truth_short"
    shutil.copytree(short_dataset, cut)
    truth = cut / "Robot3_Groundtruth.dat"
    lines = truth.read_text().splitlines()
    rows = [line for line in lines if not line.startswith("#")]
    t0 = float(rows[0].split()[0])
    kept = [line for line in lines if line.startswith("#") or float(line.split()[0]) < t0 + 8.0]
    truth.write_text("\n".join(kept) + "\n")

    out = tmp_path / "out"
    summary = run_pairs(small_config(cut), None, out, seed=3, executor="serial", quiet=True)
    assert [(r["observer"], r["observed"]) for r in summary["pairs"]] == [(1, 2), (2, 1)]
    skipped = {(s["observer"], s["observed"]): s["reason"] for s in summary["skipped"]}
    assert set(skipped) == {(1, 3), (2, 3), (3, 1), (3, 2)}
    assert all("share only" in reason for reason in skipped.values())
    tally = summary["tally"]
    assert (tally["pairs"], tally["cells"]) == (2, 8)
    met = [
        row["cases"][case]["calibrated"]["yaw_rmse_rad"] <= 0.10
        and row["cases"][case]["calibrated"]["nees_percent_beyond"] <= 10.0
        for row in summary["pairs"]
        for case in TABLE2
    ]
    assert tally["cells_meeting_yaw_and_nees"] == sum(met)
    report = (out / "report.md").read_text()
    assert "## Skipped pairs" in report and "- 3 → 1:" in report
    assert f"Met in **{sum(met)} of 8** pair-cases" in report
    assert (out / "pairs_yaw_vs_bound.png").stat().st_size > 0


def test_a_pair_robot_without_calibration_samples_is_refused(short_dataset: Path) -> None:
    """Before: the team fit's placeholder scales of 1 for a robot without samples in the
    calibration window went into the "calibrated" replay as if they were fitted."""
    from relloc.calibration.odometry import OdometryModelFit
    from relloc.calibration.window import CalibrationWindow
    from relloc.datasets.mrclam import load_mrclam
    from relloc.errors import DataError
    from relloc.experiments.wanasinghe2014_mrclam import PairResponse, ReplaySettings

    ds = load_mrclam(short_dataset)
    fit = OdometryModelFit(
        calibration_window=CalibrationWindow(5.0, 20.0, "cut"),
        latency_s=0.1,
        time_constant_s=0.2,
        scale_v=(1.1, 1.0, 0.9),
        scale_w=(1.2, 1.0, 0.8),
        q_v0=1e-4,
        k_v=1e-3,
        q_w0=1e-4,
        k_w=1e-3,
        k_wv=0.0,
        odometry_window_s=1.0,
        unfitted_robots=(2,),
    )
    settings = ReplaySettings(dataset=short_dataset, observer=1, observed=3)
    assert PairResponse.of_team(fit, ds, settings).scales == ((1.1, 1.2), (0.9, 0.8))
    with pytest.raises(DataError, match=r"robot 2 of the pair has no odometry .* \[5\.00, 20"):
        PairResponse.of_team(fit, ds, dataclasses.replace(settings, observed=2))
