"""Arguments that once crashed a command, hung it, or were accepted with no effect: each is now
refused before any work, with exit 2 and a message naming the flag or path."""

from __future__ import annotations

from pathlib import Path

import pytest

from relloc.cli import main


@pytest.fixture
def a_file(tmp_path: Path) -> Path:
    path = tmp_path / "a_file"
    path.write_text("")
    return path


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["observability", "os:system"], "'os:system': calling system() failed"),  # TypeError
        (["observability", "relative-nonlinear", "--seed", "-1"], "--seed: must be ≥ 0"),
        (
            ["observability", "relative-nonlinear", "--at-state", "x=nan"],
            "--at-state: x must be finite",
        ),
        (
            ["observability", "relative-nonlinear", "--at-state", "x=1,x=2"],
            "--at-state: x is given twice",
        ),
        (  # exit 4 after the whole analysis, with numpy's warnings, once
            ["observability", "relative-nonlinear", "--at-state", "x=0,y=0,z=0"],
            "--at-state/--at-inputs: no rank of 'relative-nonlinear' there",
        ),
        (["certs", "c", "--team", "demo", "--robots", "a,,b"], "--robots: an empty id"),
        (["observability", "unicycle-landmarks", "--landmarks", "1000000"], "--landmarks"),  # hung
        (
            ["observability", "relative-nonlinear", "--samples", "100000000000"],
            "--samples: must be in 1…1000, got 100000000000",
        ),
        (["observability", "relative-nonlinear", "--order", "-1"], "--order: must be ≥ 0, got -1"),
        # options a model does not read were ignored silently, and 0 landmarks became 1
        (
            ["observability", "airground", "--landmarks", "3"],
            "--landmarks: airground does not read it; read by unicycle-l",
        ),
        (
            ["observability", "relative-nonlinear", "--mode", "1"],
            "--mode: relative-nonlinear does not read it; read by airground",
        ),
        (
            ["observability", "unicycle-team", "--measurements", "range"],
            "--measurements: unicycle-team does not read it",
        ),
        (
            ["observability", "unicycle-landmarks", "--gps", "1"],
            "--gps: unicycle-landmarks does not read it; read by unicycle-team",
        ),
        (["observability", "os:getcwd", "--robots", "2"], "--robots: os:getcwd does not read it"),
        (["observability", "unicycle-landmarks", "--landmarks", "0"], "needs at least 1, got 0"),
        (["team", "up", "default", "--timeout", "nan"], "--timeout: must be a finite number"),
        (["team", "up", "default", "--realtime", "nan"], "--realtime: must be a finite number"),
        (["team", "up", "default", "--realtime", "-1"], "--realtime: must be a finite number"),
        # flags the target does not read were dropped silently
        (
            ["team", "up", "default", "--runs", "3"],
            "--runs: default does not read it; read by guler2023, desilva",
        ),
        (["certs", "c", "--team", "demo\n", "--robots", "a"], "--team: 'demo\\n' is not a valid"),
        (["team", "clock", "--roster", "a,a", "--duration", "1"], "a robot named twice in a,a"),
        (["team", "clock", "--roster", "a,,b", "--duration", "1"], "clock.roster: '' is not"),
        (
            ["team", "up", "default", "--case", "two_landmarks"],
            "--case: default does not read it; read by guler2023, sharma2013",
        ),
        (["team", "up", "default", "--fit", "f.json"], "--fit: default does not read it"),
        (["team", "up", "default", "--gate", "1"], "--gate: must be a finite number in (0, 1)"),
        (
            ["team", "up", "sharma2013", "--gate", "0.99"],
            "--gate: sharma2013 does not read it; read by --estimator track",
        ),
        (
            ["node", "--robot", "1", "--scenario", "sharma2013", "--gate", "0.99"],
            "--gate: sharma2013 does not read it; read by --estimator track",
        ),
        (
            ["node", "--robot", "1", "--scenario", "desilva2015", "--gate", "0.99"],
            "--gate: desilva2015 does not read it; read by --estimator track",
        ),
        (
            ["node", "--robot", "observer", "--scenario", "default", "--gate", "nan"],
            "--gate: must be a finite number in (0, 1)",
        ),
        (
            ["team", "up", "sharma2013", "--fit", "f.json"],
            "--fit: sharma2013 does not read it; read by --estimator cooperative",
        ),
        (
            ["team", "up", "sharma2013", "--filter", "tekf"],
            "--filter: sharma2013 does not read it; read by --estimator track",
        ),
        (["team", "up", "desilva2015", "--case", "x"], "--case: desilva2015 does not read it"),
        (["team", "up", "desilva2015", "--runs", "0"], "--runs: 0 must be ≥ 1"),
        (["team", "up", "sharma2013", "--runs", "-2"], "--runs: -2 must be ≥ 1"),
        (
            ["team", "up", "guler2023", "--estimator", "track"],
            "--estimator: guler2023 does not read it",
        ),
        (["team", "up", "default", "--estimator", "cooperative"], "is not a dataset folder"),
        (["airground", "world", "--team", "ta", "--duration", "1e12"], "robot-ticks"),  # 146 TiB
        (["airground", "world", "--team", "ta", "--kill", "Z_9@0.5"], "unknown robot 'Z_9'"),
        (
            ["airground", "world", "--team", "ta", "--restart", "R_1@0.5"],
            "is not down then (no earlier --kill)",
        ),
        (
            [
                "team",
                "clock",
                "--team",
                "tc",
                "--roster",
                "a,b",
                "--duration",
                "1",
                "--kill",
                "z@0.5",
            ],
            "unknown robot 'z'",
        ),
        (["node", "--scenario", "default", "--robot", "observer", "--paced", "nan"], "--paced:"),
        (["node", "--robot", "observer", "--run", "-1"], "--run: must be ≥ 0"),
        (["node", "--robot", "observer", "--tick", "nan"], "--tick: must be a finite number"),
        (["node", "--robot", "observer", "--partition", "x,y@1-2"], "unknown robot 'x'"),
        (
            ["node", "--robot", "observer", "--case", "nope"],
            "--case: default does not read it; read by sharma2013, --estimator cooperative",
        ),
        (
            ["node", "--robot", "observer", "--fit", "f.json"],
            "--fit: default does not read it; read by --estimator cooperative",
        ),
        # options a mode does not read were accepted and ignored: the bag's range-only filter
        # (the tracker's settings were recorded in its summary, unused) ...
        *(
            (["run", "bag", "--map", "m.toml", flag, value], f"{flag}: a bag (its UWB ranges")
            for flag, value in (
                ("--filter", "tekf"),
                ("--init", "known"),
                ("--yaw-bank", "4"),
                ("--keep-window", "1"),
                ("--gate", "0.5"),
                ("--seed", "7"),
            )
        ),
        # ... a reproduction's team (its own hub port, no export, guler2023's own tick) ...
        (
            ["team", "up", "sharma2013", "--port", "7000"],
            "--port: sharma2013 does not read it; read by --estimator track",
        ),
        (["team", "up", "desilva2015", "--mcap", "x.mcap"], "--mcap: desilva2015 does not read"),
        (["team", "up", "guler2023", "--tum", "t"], "--tum: guler2023 does not read it"),
        (
            ["team", "up", "guler2023", "--tick", "0.2"],
            "--tick: guler2023 does not read it; read by desilva2015, sharma2013",
        ),
        # ... a robot process' team source (a reproduction's estimators, a scenario's track
        # manager) and mode (the clock's ticks, or --realtime)
        (
            ["node", "--robot", "1", "--scenario", "sharma2013", "--filter", "tekf"],
            "--filter: sharma2013 does not read it; read by --estimator track",
        ),
        (
            ["node", "--robot", "L1", "--scenario", "desilva2015", "--init", "known"],
            "--init: desilva2015 does not read it; read by --estimator track",
        ),
        (
            ["node", "--robot", "L1", "--scenario", "desilva2015", "--case", "two_landmarks"],
            "--case: desilva2015 does not read it; read by sharma2013",
        ),
        (
            ["node", "--robot", "observer", "--run", "2"],
            "--run: default does not read it; read by desilva2015, sharma2013",
        ),
        (
            ["node", "--robot", "observer", "--estimator", "cooperative"],
            "--estimator: default does not read it; read with --dataset only",
        ),
        (
            ["node", "--robot", "observer", "--duration", "3"],
            "--duration: default does not read it; read by desilva2015, sharma2013, --estimator "
            "cooperative, --realtime",
        ),
        (
            ["node", "--robot", "observer", "--tick", "0.5"],
            "--tick: a node on the clock's ticks does not read it; read by --realtime",
        ),
        (
            ["node", "--robot", "observer", "--teammates", "network"],
            "--teammates: a node on the clock's ticks does not read it; read by --realtime",
        ),
        (
            ["node", "--realtime", "--robot", "robot1", "--dataset", "d", "--clock-timeout", "1"],
            "--clock-timeout: --realtime does not read it; read by a node on the clock's ticks",
        ),
        (
            ["node", "--realtime", "--robot", "robot1", "--dataset", "d", "--paced", "2"],
            "--paced: --realtime does not read it; read by a node on the clock's ticks",
        ),
    ],
)
def test_a_bad_argument_is_refused_before_any_work(tmp_path, monkeypatch, capsys, argv, message):
    monkeypatch.chdir(tmp_path)
    extra = ["--out", str(tmp_path / "o")] if argv[:2] == ["team", "up"] else []
    extra += ["--world-out", str(tmp_path / "w.npz")] if argv[0] == "airground" else []
    assert main([*argv, *extra]) == 2
    out, err = capsys.readouterr()
    assert message in err and "Traceback" not in err and "Warning" not in err
    assert "rank" not in out  # refused before any work
    assert not (tmp_path / "o").exists() and not (tmp_path / "w.npz").exists()


def test_an_output_path_under_a_file_is_refused_before_any_work(a_file, capsys):
    """The world's file was once written only after the whole run, and failed then."""
    assert main(["certs", str(a_file / "c"), "--team", "demo", "--robots", "a"]) == 2
    assert f"certs: cannot create {a_file / 'c'}" in capsys.readouterr().err
    world = ["airground", "world", "--team", "ta", "--duration", "1"]
    assert main([*world, "--world-out", str(a_file / "w.npz")]) == 2
    assert f"--world-out: {a_file} exists and is not a folder" in capsys.readouterr().err
    assert (
        main([*world, "--world-out", str(a_file.parent / "w.npz"), "--report", str(a_file / "r")])
        == 2
    )
    assert f"--report: {a_file} exists and is not a folder" in capsys.readouterr().err


def test_a_bag_folder_without_its_metadata_says_so(tmp_path, capsys):
    (tmp_path / "bag").mkdir()
    (tmp_path / "bag" / "x_0.db3").write_bytes(b"")
    assert main(["bag", "inspect", str(tmp_path / "bag")]) == 3
    assert "a rosbag2 folder needs its metadata.yaml, which is missing" in capsys.readouterr().err


def test_certs_keep_a_team_ca_unless_told_to_replace_it(tmp_path, capsys):
    """A second ``certs`` into the same folder once replaced the CA silently, so every
    certificate already copied to a robot stopped working."""
    argv = ["certs", str(tmp_path / "c"), "--team", "demo", "--robots", "a,b"]
    assert main(argv) == 0
    ca = (tmp_path / "c" / "ca.pem").read_bytes()
    assert main(argv) == 2
    assert "the folder holds a team's CA" in capsys.readouterr().err
    assert (tmp_path / "c" / "ca.pem").read_bytes() == ca
    assert main([*argv, "--replace"]) == 0
    assert (tmp_path / "c" / "ca.pem").read_bytes() != ca
