"""Arguments that were accepted and failed only after the work (or never): a ``--json`` or
``--report`` path under a file, a bad ``--host`` that left a half-made CA behind, a misspelt
``--inputs`` name that exited 4 without naming the flag, a ``--case`` that sharma2013's team
checked only in its robot processes, and a partition of no robot in an air-ground robot. Each
is now refused with exit 2 and ``relloc: error:`` naming the flag, before any work."""

from __future__ import annotations

from pathlib import Path

import pytest

from relloc.cli import main


@pytest.fixture
def a_file(tmp_path: Path) -> Path:
    path = tmp_path / "a_file"
    path.write_text("")
    return path


def test_bench_json_under_a_file_is_refused_before_the_benchmark_runs(a_file, capsys):
    assert main(["bench", "filters", "--json", str(a_file / "x.json")]) == 2
    out, err = capsys.readouterr()
    assert out == ""  # the benchmark's table was printed first, the file refused after it
    assert err == f"relloc: error: --json: {a_file} exists and is not a folder\n"


def test_clock_report_under_a_file_is_refused_before_the_clock_starts(a_file, capsys):
    argv = ["team", "clock", "--team", "tc", "--roster", "a", "--duration", "1"]
    assert main([*argv, "--report", str(a_file / "r.json")]) == 2
    assert capsys.readouterr().err == (
        f"relloc: error: --report: {a_file} exists and is not a folder\n"
    )


def test_a_bad_host_leaves_no_ca_behind_and_the_rerun_works(tmp_path, capsys):
    folder = tmp_path / "c"
    argv = ["certs", str(folder), "--team", "demo", "--robots", "a"]
    assert main([*argv, "--host", "bad host"]) == 2
    err = capsys.readouterr().err
    assert err == "relloc: error: --host: 'bad host' is neither an IP address nor a DNS name\n"
    assert not (folder / "ca.pem").exists() and not (folder / "ca.key").exists()
    assert main([*argv, "--host", "robot.example"]) == 0  # was refused: "holds a team's CA"
    assert (folder / "ca.pem").is_file() and (folder / "a.pem").is_file()


def test_an_unknown_input_name_is_a_bad_argument(capsys):
    assert main(["observability", "relative-nonlinear", "--inputs", "v_q"]) == 2  # was 4
    out, err = capsys.readouterr()
    assert err.startswith(
        "relloc: error: --inputs: model 'relative-nonlinear': unknown input 'v_q'"
    )
    assert out == ""


def test_sharma_team_case_is_refused_before_its_processes_start(tmp_path, capsys):
    out = tmp_path / "o"
    assert main(["team", "up", "sharma2013", "--out", str(out), "--case", "nope"]) == 2  # was 1
    assert capsys.readouterr().err == (
        "relloc: error: --case: 'nope' is not one of "
        "['gps_robot1', 'no_landmark', 'one_landmark', 'two_landmarks']\n"
    )
    assert not out.exists()  # no run folder, no robot logs


def test_an_airground_robot_refuses_a_partition_of_no_robot_of_its_team(capsys):
    argv = ["airground", "robot", "--team", "ta", "--robot", "R_1", "--input-timeout", "0.5"]
    assert main([*argv, "--partition", "R_1,Z_7@1-2"]) == 2
    assert "relloc: error: faults: unknown robot 'Z_7'; the team is R_0, R_1, R_2" in (
        capsys.readouterr().err
    )


@pytest.mark.parametrize(
    ("argv", "flag"),
    [
        (["run", "--out", ""], "--out"),
        (["reproduce", "desilva2015", "--out", ""], "--out"),
        (["team", "up", "default", "--out", ""], "--out"),
        (["certs", "", "--team", "demo", "--robots", "a"], "folder"),
    ],
)
def test_an_empty_output_path_is_refused_not_the_current_folder(
    tmp_path, monkeypatch, capsys, argv, flag
):
    """An empty ``--out`` (or certificate folder) once wrote into the current folder."""
    monkeypatch.chdir(tmp_path)
    with pytest.raises(SystemExit) as exit_:
        main(argv)
    assert exit_.value.code == 2
    assert f"argument {flag}: an empty path" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []
