"""``relloc run``: default scenario smoke test, a user's TOML, bad TOML → exit code 2."""

import json
import os
import textwrap

import pytest

from relloc.cli import main

SMALL = """
name = "pair"
duration_s = 8.0

[[robots]]
name = "leader"
kind = "ground"
initial_pose = [5.0, 2.0, 1.5707963267948966]
[robots.motion]
type = "velocity"
mean = [0.1, 0.0, 0.0, 0.0]
amplitude = [0.0, 0.0, 0.0, 0.1]
[robots.sensor]
fov_deg = 120.0
max_range = 12.0

[[robots]]
name = "drone"
kind = "aerial"
height = 2.0
[robots.motion]
type = "waypoints"
points = [[3.0, 8.0], [7.0, 8.0], [5.0, 11.0]]
speed = 0.5
"""


def test_run_default_scenario_writes_summary_report_and_figures(tmp_path, capsys):
    out = tmp_path / "out"
    argv = ["run", "--out", str(out), "--runs", "2", "--seed", "3", "--duration", "12"]
    argv += ["--executor", "serial"]
    assert main(argv) == 0
    printed = capsys.readouterr()
    assert "earlier run" not in printed.err and "observer->aerial1" in printed.out
    summary = json.loads((out / "summary.json").read_text())
    assert summary["seed"] == 3 and summary["runs"] == 2 and summary["filter"] == "plkf"
    assert set(summary["pairs"]) == {
        "observer->aerial1",
        "observer->aerial2",
        "observer->ground1",
        "observer->ground2",
    }
    for s in summary["pairs"].values():
        assert 0.0 < s["position_rmse_m"] < 0.2 and 0.0 < s["yaw_rmse_rad"] < 0.2
        assert s["anees"] > 0.0 and 0.0 <= s["nees_percent_beyond"] <= 100.0
        share = s["nees_beyond_interval"]
        assert share["percent"] == s["nees_percent_beyond"]
        # two independent runs: each run one cluster
        assert share["clustering"] == "runs" and share["clusters"] == share["runs"] == 2
    report = (out / "report.md").read_text()
    share = summary["team"]["nees_beyond_interval"]
    lo, hi = share["interval"]
    assert f"| {lo:.1f}–{hi:.1f} {share['verdict']} |" in report
    # the run-averaged NEES's verdict beside its share in band (two runs: a verdict per pair)
    assert "| avg NEES in band % | its verdict |" in report
    for s in summary["pairs"].values():
        assert s["nees_run_average_verdict"] in {"consistent", "conservative", "over-confident"}
        short = " (blocks short)" if s["nees_run_average_blocks_short"] else ""
        assert isinstance(s["nees_run_average_blocks_short"], bool)
        assert f"| {s['nees_run_average_verdict']}{short} |" in report
    pngs = sorted(p.name for p in out.glob("*.png"))
    assert {"errors_all.png", "nees_nis.png", "conditioning.png", "trajectories.png"} <= set(pngs)
    for name in pngs:
        assert f"({name})" in report
    # run again into the same folder: every file of the first run is replaced, and a file no
    # run of this kind writes is named as an earlier run's
    (out / "old.png").write_bytes(b"")
    os.utime(out / "old.png", (0, 0))
    assert main(argv) == 0
    err = capsys.readouterr().err
    assert f"relloc: note: 1 file under {out} from an earlier run, not this one: old.png" in err


def test_run_user_scenario_with_tekf_and_a_gate(tmp_path):
    path = tmp_path / "my.toml"
    path.write_text(textwrap.dedent(SMALL))
    out = tmp_path / "out"
    code = main(
        [
            "run",
            str(path),
            "--out",
            str(out),
            "--runs",
            "1",
            "--filter",
            "tekf",
            "--gate",
            "0.999",
            "--yaw-bank",
            "0",
            "--executor",
            "serial",
            "--quiet",
        ]
    )
    assert code == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["scenario"] == "pair" and summary["filter"] == "tekf"
    assert summary["yaw_bank_components"] == 0  # --yaw-bank 0: a single filter per track
    assert summary["gate_probability"] == 0.999
    assert "- **gate_probability**: 0.999" in (out / "report.md").read_text()
    assert list(summary["pairs"]) == ["leader->drone"]


def test_bad_toml_exits_2_naming_the_field(tmp_path, capsys):
    path = tmp_path / "bad.toml"
    path.write_text(textwrap.dedent(SMALL.replace("fov_deg = 120.0", "fov_deg = 400.0")))
    code = main(["run", str(path), "--out", str(tmp_path / "o"), "--runs", "1", "--quiet"])
    assert code == 2
    assert "robots[0].sensor.fov_deg: must be in (0, 360]" in capsys.readouterr().err
    assert not (tmp_path / "o" / "summary.json").exists()


def test_a_motion_leaving_the_arena_names_the_file_before_any_run(tmp_path, capsys):
    path = tmp_path / "runaway.toml"
    path.write_text(SMALL.replace("mean = [0.1, 0.0, 0.0, 0.0]", "mean = [5.0, 0.0, 0.0, 0.0]"))
    code = main(["run", str(path), "--out", str(tmp_path / "o"), "--executor", "serial"])
    assert code == 2
    err = capsys.readouterr().err
    assert f"{path}: robots[0].motion: robot 'leader' leaves the arena" in err


def test_an_empty_export_path_is_refused_not_the_current_folder(tmp_path, capsys):
    for flag in ("--tum", "--mcap"):
        with pytest.raises(SystemExit) as exit_:
            main(["run", "--out", str(tmp_path / "o"), "--quiet", flag, ""])
        assert exit_.value.code == 2
        assert f"argument {flag}: an empty path" in capsys.readouterr().err


def test_bad_options_exit_2_naming_the_option(tmp_path, capsys):
    out = str(tmp_path / "o")
    for argv, message in (
        (["--runs", "0"], "--runs: must be an integer in 1…1000000"),
        (["--runs", "99999999999"], "--runs: must be an integer in 1…1000000"),  # hung seeding
        (["--executor", "dask://"], "--executor: 'dask://' is not dask://HOST:PORT"),
        (["--executor", "dask://localhost:abc"], "is not dask://HOST:PORT (a port 1…65535)"),
        (["--duration", "-1"], "--duration: duration_s: must be in (0, ∞)"),
        (["--yaw-bank", "1"], "--yaw-bank: 0 (off) or"),
        (["--gate", "1.5"], "--gate: must be a finite number in (0, 1), got 1.5"),
        (["--gate", "1"], "--gate: must be a finite number in (0, 1), got 1.0"),
    ):
        assert main(["run", "--out", out, "--quiet", *argv]) == 2
        assert message in capsys.readouterr().err


def test_run_too_short_to_measure_exits_2_with_a_clear_message(tmp_path, capsys):
    out = tmp_path / "o"
    argv = ["run", "--out", str(out), "--runs", "2", "--executor", "serial", "--quiet"]
    assert main([*argv, "--duration", "0.05"]) == 2
    err = capsys.readouterr().err
    assert "no results: no observing robot measured another robot in any run" in err
    assert "Traceback" not in err and not (out / "summary.json").exists()


def test_run_shorter_than_the_settle_time_says_so(tmp_path, capsys):
    out = tmp_path / "o"
    argv = ["run", "--out", str(out), "--runs", "1", "--executor", "serial", "--quiet"]
    assert main([*argv, "--duration", "1"]) == 0
    assert "no steady-state results: no track reached the settle time (5 s)" in (
        capsys.readouterr().err
    )
    assert json.loads((out / "summary.json").read_text())["team"]["samples"] == 0


def test_broken_scenario_files_exit_2_naming_file_and_field(tmp_path, capsys):
    cases = {
        "latin1.toml": (SMALL.replace('"drone"', '"dr\xf6ne"').encode("latin-1"), "not UTF-8"),
        "deep.toml": (("x = " + "[" * 5000 + "]" * 5000 + "\n").encode(), "nested too deeply"),
        "slash.toml": (SMALL.replace('"drone"', '"a/b"').encode(), "robots[1].name: must match"),
        "long.toml": (
            SMALL.replace("duration_s = 8.0", "duration_s = 1e308").encode(),
            "(MAX_SIMULATED_STEPS)",
        ),
        "view.toml": (
            SMALL.replace("max_range = 12.0", "max_range = 60.0\nmin_range = 50.0").encode(),
            "initial guesses are drawn between the largest min_range (50 m)",
        ),
    }
    for name, (content, message) in cases.items():
        path = tmp_path / name
        path.write_bytes(content)
        code = main(["run", str(path), "--out", str(tmp_path / "o"), "--runs", "1", "--quiet"])
        err = capsys.readouterr().err
        assert code == 2, (name, err)
        assert str(path) in err or name == "view.toml", err
        assert message in err, (name, err)


def test_out_below_a_file_exits_2(tmp_path, capsys):
    blocker = tmp_path / "file"
    blocker.write_text("")
    argv = ["run", "--out", str(blocker / "sub"), "--runs", "1", "--executor", "serial"]
    assert main([*argv, "--quiet", "--duration", "1"]) == 2
    assert f"--out: cannot create {blocker / 'sub'}" in capsys.readouterr().err
