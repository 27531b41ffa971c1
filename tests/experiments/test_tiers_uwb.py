"""``relloc reproduce tiers-uwb`` and ``relloc run BAG --map`` on stretches of the real TIERS
bags, cut with rosbags into new bags (the checks a bag of the same layout gets)."""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import numpy as np
import pytest

from relloc.datasets.paths import shared_data_dir

TIERS = shared_data_dir() / "tiers"
pytestmark = pytest.mark.skipif(
    not TIERS.is_dir(), reason=f"TIERS bags not found at {TIERS} (outside the workspace)"
)


def cut(src: Path, dst: Path, start_s: float, end_s: float) -> Path:
    """The messages of ``src`` received in ``[start_s, end_s]`` from its start, as a new bag
    (topics of types the standard typestore lacks are left out)."""
    from rosbags.highlevel import AnyReader
    from rosbags.rosbag2 import Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    with AnyReader([src], default_typestore=store) as reader, Writer(dst, version=8) as writer:
        t0 = reader.start_time
        cons = {}
        for c in reader.connections:
            if c.msgtype in store.types:
                cons[c.id] = writer.add_connection(c.topic, c.msgtype, typestore=store)
        lo, hi = t0 + int(start_s * 1e9), t0 + int(end_s * 1e9)
        for c, t, raw in reader.messages(start=lo, stop=hi):
            if c.id in cons:
                writer.write(cons[c.id], t, raw)
    return dst


def test_calibrated_on_one_stretch_scored_on_another(tmp_path, states_skipped_rows):
    from relloc.cli import main

    src = TIERS / "relative_case4_test1"
    calibration = cut(src, tmp_path / "first", 0.0, 8.0)
    other = cut(src, tmp_path / "second", 20.0, 26.0)
    out = tmp_path / "out"
    # a mapping that states a σ, which the fitted one replaces (said in the report)
    from importlib import resources

    shipped = resources.files("relloc.datasets").joinpath("mappings", "tiers_relative.toml")
    text = shipped.read_text(encoding="utf-8")
    (tmp_path / "map.toml").write_text(text.replace("[uwb]\n", "[uwb]\nsigma = 0.25\n", 1))
    code = main(
        [
            "reproduce",
            "tiers-uwb",
            "--out",
            str(out),
            "--bag",
            str(other),
            "--map",
            str(tmp_path / "map.toml"),
            "--calibrate-on",
            str(calibration),
            "--quiet",
        ]
    )
    assert code == 0
    summary = json.loads((out / "summary.json").read_text())
    b = summary["bags"]["second"]
    assert b["calibration"]["source"] == "bag"
    assert b["calibration"]["bag"] == str(calibration)
    assert b["scored_window_s"][0] == pytest.approx(0.0, abs=0.1)
    held = b["calibration"]["heldout"]
    assert held["calibrated"]["rmse_m"] < held["raw"]["rmse_m"]
    for case in ("aligned", "anchored"):
        team = b["team"][case]
        assert team["pos_rmse_m"] < team["baselines"]["uncalibrated"]["pos_rmse_m"]
        assert {"nees_pct_beyond", "converged_after_s"} <= set(team)
        share = team["nees_beyond_interval"]
        assert share["percent"] == team["nees_pct_beyond"] and share["samples"] > 0
        assert share["interval"][0] <= share["percent"] <= share["interval"][1]
    assert b["team"]["anchored"]["mode"] == "leave-one-out"  # every robot stands
    assert b["pairs"] == {}  # no odometry in this layout
    report = (out / "report.md").read_text()
    assert "| team aligned" in report and "its 95 % interval" in report
    aside = sum(b["loader"]["uwb_readings_not_in_recording"].values())
    bag = f"the bag (less its {aside} UWB readings not in the recording)" if aside else "the bag"
    assert states_skipped_rows(report, b["loader"]["skips"]["rows_skipped"], bag)
    assert b["calibration"]["mapping_sigma_replaced_m"] == 0.25
    assert "(it replaces the mapping's stated 0.25 m)" in report


def test_pairs_with_odometry_get_an_observability_verdict(tmp_path):
    from relloc.datasets.bag_mapping import load_mapping
    from relloc.datasets.rosbag import load_bag
    from relloc.experiments.tiers_uwb_pairs import moving_pairs, observability

    bag = load_bag(
        cut(TIERS / "cooperative_shortbag", tmp_path / "c", 0.0, 6.0),
        load_mapping("tiers_cooperative"),
    )
    rec = bag.recording
    pairs = [(rec.robots[i], rec.robots[j]) for i, j in moving_pairs(rec)]
    assert ("turtlebot1", "turtlebot3") in pairs
    i, j = rec.index("turtlebot1"), rec.index("turtlebot5")
    verdict = observability(rec, i, j, 1.0, 5.0)
    # turtlebot5 stands (zero twist): range-only needs both robots to move (seed 000 model)
    assert verdict["max_rank"] < 4 and verdict["verdict"].startswith("unobservable")
    assert "v_l ≠ 0 and v_c ≠ 0" in verdict["generic_conditions"]


def test_relloc_run_on_a_bag(tmp_path, capsys, states_skipped_rows):
    from relloc.cli import main

    bag = cut(TIERS / "cooperative_shortbag", tmp_path / "c", 0.0, 6.0)
    out = tmp_path / "run"
    tum = tmp_path / "tum"
    argv = ["run", str(bag), "--map", "tiers_cooperative", "--out", str(out),
            "--mcap", str(tmp_path / "bag.mcap"), "--tum", str(tum)]  # fmt: skip
    assert main(argv) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert "turtlebot1->turtlebot3" in summary["pairs"]
    # the bag's estimates exported: the TUM files give back the export's RMSE of the pair
    assert (tmp_path / "bag.mcap").stat().st_size > 0
    est = np.loadtxt(tum / "turtlebot1" / "turtlebot3.tum")
    truth = np.loadtxt(tum / "turtlebot1" / "turtlebot3.truth.tum")
    rmse = np.sqrt(np.mean(np.sum((est[:, 1:4] - truth[:, 1:4]) ** 2, axis=1)))
    exported = summary["export"]["series"]["turtlebot1->turtlebot3"]["position_rmse_m"]
    assert rmse == pytest.approx(exported, rel=1e-9)
    # /cali/turtle05 has unset header stamps: placed by their receive time, and said so
    assert set(summary["loader"]["stamps_from_receive"]) == {"/cali/turtle05/odom"}
    printed = capsys.readouterr().out
    assert "turtlebot1->turtlebot3" in printed
    # the rows the bag's loader skipped: in summary.json, report.md and on the console
    # (less the UWB readings to or between static radios, which the report counts on their own)
    skipped = summary["loader"]["skips"]["rows_skipped"]
    aside = sum(summary["loader"]["uwb_readings_not_in_recording"].values())
    assert aside > 0  # this bag has readings to and between static radios
    bag = f"the bag (less its {aside} UWB readings not in the recording)"
    assert states_skipped_rows((out / "report.md").read_text(), skipped, bag)
    assert states_skipped_rows(" ".join(printed.split()), skipped, bag)
    # every file written is listed, the figures too (only summary.json and report.md were)
    figures = sorted(p.name for p in out.glob("*.png"))
    assert figures and all(name in printed for name in figures)
    # --no-plots is honoured; flags a single replay cannot use are refused, not ignored
    plain = tmp_path / "plain"
    assert main([*argv[:5], str(plain), "--no-plots", "--quiet"]) == 0
    assert sorted(p.name for p in plain.iterdir()) == ["report.md", "summary.json"]
    plain_summary = json.loads((plain / "summary.json").read_text())
    assert plain_summary["antenna_offset_not_modelled_m"] == 0
    # the range-only filter is stated; no track manager runs on a bag's ranges, so none of
    # their settings is stated and a flag that sets one is refused
    assert plain_summary["filter"] == "range_pair"
    assert not {"seed", "init", "keep_window_s", "gate_probability"} & set(plain_summary)
    assert main([*argv[:5], str(tmp_path / "gated"), "--gate", "0.99"]) == 2
    assert "offsets" not in capsys.readouterr().err
    # an antenna offset this range filter does not model is said, not dropped silently
    from importlib import resources

    text = resources.files("relloc.datasets").joinpath("mappings", "tiers_cooperative.toml")
    text = text.read_text(encoding="utf-8")
    moved = text.replace(
        'robot = "turtlebot1"\n', 'robot = "turtlebot1"\noffset = [0.3, 0.4, 0.0]\n'
    )
    assert moved != text
    (tmp_path / "moved.toml").write_text(moved)
    offset = [*argv[:3], str(tmp_path / "moved.toml"), "--out", str(tmp_path / "o")]
    assert main([*offset, "--no-plots", "--quiet"]) == 0
    assert "antenna offsets (up to 0.5 m) are not modelled" in capsys.readouterr().err
    assert "up to 0.5 m from its robot's origin" in (tmp_path / "o" / "report.md").read_text()
    # (in this 6 s cut turtlebot4's odometry has fewer than two samples: its pairs are named)
    without = summary["range_pairs_without_odometry"]
    assert without and all("turtlebot4" in pair for pair in without)
    # a robot without odometry: its range-linked pairs are not tracked, and said so
    blind = text.replace('odometry = "/cali/turtle03/odom"\n', "")
    assert blind != text
    (tmp_path / "blind.toml").write_text(blind)
    argv_blind = [*argv[:3], str(tmp_path / "blind.toml"), "--out", str(tmp_path / "b")]
    assert main([*argv_blind, "--no-plots", "--quiet"]) == 0
    skipped = json.loads((tmp_path / "b" / "summary.json").read_text())
    unused = skipped["range_pairs_without_odometry"]
    assert "turtlebot1-turtlebot3" in unused and all(n > 0 for n in unused.values())
    assert all("turtlebot3" in pair or "turtlebot4" in pair for pair in unused)
    assert not any("turtlebot3" in label for label in skipped["pairs"])
    assert "turtlebot1-turtlebot3 not tracked" in capsys.readouterr().err
    assert "Not tracked: robots linked by UWB ranges" in (tmp_path / "b" / "report.md").read_text()
    for flag, value in (("--runs", "3"), ("--duration", "5"), ("--executor", "serial")):
        assert main([*argv[:5], str(tmp_path / "no"), flag, value, "--quiet"]) == 2
        assert f"{flag}:" in capsys.readouterr().err
    # a settle time the 6 s cut never reaches: no steady-state sample, and the console says so
    assert main([*argv[:5], str(tmp_path / "s"), "--settle", "100", "--no-plots", "--quiet"]) == 0
    assert (
        "relloc: note: no steady-state results: no track reached the settle time (100 s) in "
        "the bag, so accuracy and consistency are NaN; lower --settle"
    ) in capsys.readouterr().err


def test_bag_inspect_on_a_real_bag(capsys):
    from relloc.cli import main

    assert main(["bag", "inspect", str(TIERS / "cooperative_shortbag")]) == 0
    out = capsys.readouterr().out
    assert "/uwb/tof/n_1/n_2/distance" in out and 'topics = "/uwb/tof/{a}/{b}/distance"' in out


def test_calibrating_on_the_scored_bag_is_refused(tmp_path):
    from relloc.cli import main

    bag = str(TIERS / "relative_case4_test1")
    argv = ["reproduce", "tiers-uwb", "--out", str(tmp_path), "--bag", bag, "--map",
            "tiers_relative", "--calibrate-on", bag, "--quiet"]  # fmt: skip
    assert main(argv) == 2
    assert main(["reproduce", "tiers-uwb", "--out", str(tmp_path), "--bag", bag]) == 2  # no --map
    # the same recording named by its storage file was once taken for another bag
    (db3,) = (TIERS / "relative_case4_test1").glob("*.db3")
    assert main([*argv[:-2], str(db3), "--quiet"]) == 2


def test_a_bag_of_the_layout_with_moving_robots(tmp_path):
    """The acceptance shape: another bag of the relative layout, robots moving, calibrated on
    the real relative_case4_test1; two robots stand, so they are the anchors and the free
    robots' mirror image in their line is the ambiguity ranges leave."""
    sys.path.insert(0, str(Path(__file__).parent))
    from tiers_synthetic import synth

    from relloc.cli import main

    bag = synth(tmp_path / "moving", duration=12.0)
    out = tmp_path / "out"
    real = str(TIERS / "relative_case4_test1")
    argv = ["reproduce", "tiers-uwb", "--out", str(out), "--bag", str(bag), "--map",
            "tiers_relative", "--calibrate-on", real, "--quiet"]  # fmt: skip
    assert main(argv) == 0
    b = json.loads((out / "summary.json").read_text())["bags"]["moving"]
    anchored = b["team"]["anchored"]
    assert anchored["anchors"] == ["turtlebot5", "turtlebot7"] and anchored["mirror_ambiguous"]
    assert anchored["mode"] == "anchors"
    for case in ("aligned", "anchored"):
        team = b["team"][case]
        assert team["pos_rmse_m"] < team["baselines"]["uncalibrated"]["pos_rmse_m"]
        assert team["pos_rmse_m"] < 0.5


def test_pairs_of_a_bag_with_odometry_are_tracked_and_judged(tmp_path, capsys):
    """The pair part (range + both odometries from an unknown start, ``pair_case``) on 15 s of
    the cooperative bag, which until now ran in no test: every moving pair is tracked over the
    scored stretch and scored beside its baselines; the observability tool calls every pair with
    the standing turtlebot5 unobservable (range-only needs both to move) and finds full rank
    along the stretch for turtlebot1 and turtlebot3, which both drive."""
    from relloc.cli import main

    bag = cut(TIERS / "cooperative_shortbag", tmp_path / "c", 0.0, 15.0)
    out = tmp_path / "out"
    argv = ["reproduce", "tiers-uwb", "--out", str(out), "--bag", str(bag), "--map",
            "tiers_cooperative"]  # fmt: skip
    assert main(argv) == 0
    # tiers-uwb draws nothing at random: the console says so instead of "seed None"
    assert "tiers-uwb: no seed (nothing drawn at random), runs 1" in capsys.readouterr().out
    pairs = json.loads((out / "summary.json").read_text())["bags"]["c"]["pairs"]
    assert "turtlebot1->turtlebot3" in pairs and len(pairs) >= 4
    for name, pair in pairs.items():
        assert pair["records"] > 50, name
        scores = [pair["pos_rmse_m"], *(b["pos_rmse_m"] for b in pair["baselines"].values())]
        assert all(math.isfinite(s) and s >= 0.0 for s in scores), name
        if "turtlebot5" in name:
            assert pair["observability"]["max_rank"] < 4, name
            assert pair["observability"]["verdict"].startswith("unobservable"), name
    assert pairs["turtlebot1->turtlebot3"]["observability"]["max_rank"] == 4
    # the report says what the pair table's baselines and convergence column mean
    report = (out / "report.md").read_text()
    assert "*odometry alone* starts at the true relative pose" in report
    assert "within 0.3 m and 0.5 rad to the end of the stretch (— : never)" in report
