"""The edges of the command-line range checks, each refused with exit 2 and the flag named:
zero where a value must be > 0, infinity where it must be finite, one parameter too few, a file
where a dataset folder is expected; and what is accepted at those edges (a desilva2015-kidnapped
team is a desilva2015 team, a node on wall time reads ``--duration``)."""

from __future__ import annotations

from types import SimpleNamespace

import pytest

from relloc.cli import main


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["node", "--robot", "observer", "--tick", "0"], "--tick: must be a finite number > 0"),
        (
            ["observability", "relative-nonlinear", "--at-state", "x=inf"],
            "--at-state: x must be finite, got 'inf'",
        ),
        (
            ["observability", "relative-nonlinear", "--samples", "0"],
            "--samples: must be in 1…1000, got 0",
        ),
        (
            ["observability", "unicycle-landmarks", "--landmarks", "11"],
            "--landmarks: must be in 0…10, got 11",
        ),
        (
            ["observability", "unicycle-landmarks", "--at-state", "x=1,lx_0=2"],
            "--at-state: 'unicycle-landmarks' has free parameters; give them too: ly_0",
        ),
        # a desilva2015-kidnapped team reads --runs as desilva2015's does
        (["team", "up", "desilva2015-kidnapped", "--runs", "0"], "--runs: 0 must be ≥ 1"),
        (
            ["team", "up", "a_file", "--estimator", "cooperative"],
            "--estimator cooperative: a_file is not a dataset folder",
        ),
        # on wall time every source reads --duration: the missing folder is what is refused
        (
            ["node", "--realtime", "--robot", "r", "--dataset", "missing", "--duration", "3"],
            "team source: 'missing' is neither 'default', a ",
        ),
    ],
)
def test_an_edge_value_is_refused_naming_its_flag(tmp_path, monkeypatch, capsys, argv, message):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "a_file").write_text("")
    extra = ["--out", str(tmp_path / "o")] if argv[:2] == ["team", "up"] else []
    assert main([*argv, *extra]) == 2
    out, err = capsys.readouterr()
    assert f"relloc: error: {message}" in err and "Traceback" not in err
    assert out == "" and not (tmp_path / "o").exists()


def test_a_model_with_free_parameters_is_ranked_at_the_given_ones(capsys):
    argv = ["observability", "unicycle-landmarks", "--at-state", "x=1,y=0,lx_0=3,ly_0=0"]
    assert main(argv) == 0
    assert "rank at the given state and constant inputs: " in capsys.readouterr().out


def test_the_file_table_of_mrclam_tools_is_aligned_by_hand(capsys):
    from relloc.cli.mrclam import _print_files

    row = SimpleNamespace(kept=3, outside=10, unreadable=0)
    _print_files({"a.dat": row}, ("kept", "outside", "unreadable"))
    assert capsys.readouterr().out == (
        "file      kept  outside  unreadable\na.dat        3       10           0\n"
    )
