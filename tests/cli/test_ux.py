"""A researcher's first hour: a console summary that fits 80 columns and lists every file, every
figure of ``relloc run`` rendered, extras checked before computing (exit 5), the settle time an
option, subcommand usage on a misspelt flag, plain-text help, one data hint."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from relloc.cli import main
from relloc.cli.comparison import comparison_text, paper_tables
from relloc.cli.console import compact_table, plain_text, wrote_line
from relloc.pipeline.output import fmt

SRC = str(Path(__file__).resolve().parents[2] / "src")

# Runs the CLI with some top-level modules made unimportable (as on a core-only install): a
# finder placed first on sys.meta_path raises ModuleNotFoundError for them.
BLOCKED_CLI = """
import sys

class Block:
    def __init__(self, names):
        self.names = names

    def find_spec(self, name, path=None, target=None):
        if name.split(".")[0] in self.names:
            raise ModuleNotFoundError(f"No module named {name!r}", name=name)
        return None

sys.meta_path.insert(0, Block(set(sys.argv[1].split(","))))
from relloc.cli import main
sys.exit(main(sys.argv[2:]))
"""


def _blocked(blocked: str, *argv: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "PYTHONPATH": SRC, "COLUMNS": "80"}
    return subprocess.run(
        [sys.executable, "-c", BLOCKED_CLI, blocked, *argv],
        capture_output=True,
        text=True,
        env=env,
        cwd=cwd,
        timeout=300,
    )


QUICK = ["--runs", "2", "--seed", "3", "--duration", "12", "--executor", "serial"]


def test_run_console_fits_80_columns_lists_every_file_and_renders_every_figure(
    tmp_path, capsys, monkeypatch
):
    monkeypatch.setenv("COLUMNS", "80")
    monkeypatch.chdir(tmp_path)  # a short --out, as typed (a path is never split)
    out = Path("out")
    assert main(["run", "--out", str(out), "--settle", "2", *QUICK]) == 0
    text = capsys.readouterr().out
    lines = text.splitlines()
    assert max(len(line) for line in lines) <= 80
    summary = json.loads((out / "summary.json").read_text())
    assert summary["settle_s"] == 2.0
    assert "steady state from track age 2 s (--settle)" in " ".join(lines)
    # no cell cut: each pair's full label and its ANEES/ANIS as formatted sit on one row
    for label, s in summary["pairs"].items():
        row = next(line for line in lines if line.startswith(label))
        assert fmt(s["anees"], 3) in row and fmt(s["anis"], 3) in row
        spread = s["position_rmse_over_runs"]
        assert spread["runs"] == 2 and spread["interval95"][0] <= spread["interval95"][1]
        assert s["convergence"]["runs"] == 2
    # every file written is listed, every figure the report shows exists and is non-empty
    wrote = text[text.index("wrote ") :]
    figures = sorted(p.name for p in out.glob("*.png"))
    expected = {
        "errors_all.png",
        "nees_nis.png",
        "conditioning.png",
        "convergence.png",
        "trajectories.png",
    } | {f"error_bounds_{s['observer']}_{s['observed']}.png" for s in summary["pairs"].values()}
    assert set(figures) == expected
    report = (out / "report.md").read_text()
    for name in ["summary.json", "report.md", *figures]:
        assert name in wrote
        assert (out / name).stat().st_size > 1000 or name.endswith((".json", ".md"))
    for name in figures:
        assert f"({name})" in report
    assert "Spread over runs and convergence" in report


def test_compact_table_never_cuts_a_cell():
    headers = ["pair", "a", "b"]
    rows = [["a-very-long-observer-name->an-even-longer-observed-name", 1.23456, "x" * 30]]
    table = compact_table(headers, rows, width=40)
    assert max(len(line) for line in table.splitlines()) <= 40
    assert rows[0][0] in "".join(line.strip() for line in table.splitlines())  # wrapped, whole
    assert "a 1.23" in table and "b " + "x" * 30 in table
    wide = compact_table(headers, [["p", 1.0, 2.0]], width=80)
    assert wide.splitlines()[2].split() == ["p", "1", "2"]
    files = [Path("/some/dir") / f"figure_{i}.png" for i in range(12)]
    line = wrote_line(files, width=60)
    assert max(len(x) for x in line.splitlines()) <= 60
    assert all(f.name in line for f in files)


def test_no_plots_writes_summary_and_report_only(tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["run", "--out", str(out), "--no-plots", "--quiet", *QUICK]) == 0
    assert (out / "summary.json").is_file() and (out / "report.md").is_file()
    assert not list(out.glob("*.png"))
    assert "Figures were not drawn" in (out / "report.md").read_text()


#: Every module an extra provides (pyproject.toml): a core install has none of them.
ALL_EXTRAS = (
    "matplotlib,zenoh,msgpack,cryptography,rosbags,mcap,mcap_ros2,distributed,dask,filterpy,evo"
)


def test_core_install_run_writes_summary_and_report_without_figures(tmp_path):
    out = tmp_path / "out"
    done = _blocked(ALL_EXTRAS, "run", "--out", str(out), *QUICK, cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert "matplotlib is not installed" in done.stderr
    assert (out / "summary.json").is_file() and (out / "report.md").is_file()
    assert not list(out.glob("*.png"))
    assert "wrote" in done.stdout and "Traceback" not in done.stderr


@pytest.mark.parametrize(
    ("blocked", "argv", "extra"),
    [
        (ALL_EXTRAS, ["reproduce", "guler2023"], "plot"),
        ("matplotlib", ["reproduce", "sharma2013"], "plot"),
        ("matplotlib", ["reproduce", "wanasinghe-observability"], "plot"),
        (ALL_EXTRAS, ["team", "up", "default"], "runtime"),
        ("zenoh", ["node", "--robot", "observer"], "runtime"),
    ],
)
def test_a_missing_extra_exits_5_before_computing(tmp_path, blocked, argv, extra):
    out = tmp_path / "out"
    if argv[0] != "node":
        argv = [*argv, "--out", str(out)]
    done = _blocked(blocked, *argv, cwd=tmp_path)
    assert done.returncode == 5, done.stderr
    assert f"pip install 'relloc[{extra}]'" in done.stderr
    assert "Traceback" not in done.stderr
    assert not out.exists()  # nothing computed, nothing written


def test_a_misspelt_flag_prints_the_subcommands_usage(capsys):
    with pytest.raises(SystemExit) as stop:
        main(["run", "--filtr", "tekf"])
    assert stop.value.code == 2
    err = capsys.readouterr().err
    assert "usage: relloc run" in err and "unrecognized arguments: --filtr" in err
    with pytest.raises(SystemExit):
        main(["team", "up", "default", "--out", "o", "--dorp", "0.1"])
    assert "usage: relloc team up" in capsys.readouterr().err


def test_flag_names_in_errors(tmp_path, capsys):
    out = str(tmp_path / "o")
    for argv, message in (
        (["--keep-window", "-1"], "--keep-window: must be"),
        (["--settle", "-1"], "--settle: must be"),
        (["--yaw-bank", "-3"], "--yaw-bank: 0 (off) or an integer in [2, 64]"),
    ):
        assert main(["run", "--out", out, "--quiet", *argv]) == 2
        err = capsys.readouterr().err
        assert message in err
        assert "keep_window_s" not in err and "YawBankSettings" not in err


def test_observability_measurement_typo_is_a_config_error(capsys):
    assert main(["observability", "relative-pseudo-linear", "--measurements", "rnage"]) == 2
    assert "--measurements: unknown 'rnage'" in capsys.readouterr().err


def test_an_unwritable_json_path_names_the_flag(tmp_path, capsys):
    blocker = tmp_path / "file"
    blocker.write_text("")  # a file where the folder should be
    argv = ["observability", "relative-pseudo-linear", "--json", str(blocker / "out.json")]
    assert main(argv) == 2
    assert f"--json: {blocker} exists and is not a folder" in capsys.readouterr().err


def test_node_team_and_certs_help_are_plain_text(capsys):
    for argv in (["node", "--help"], ["team", "--help"], ["certs", "--help"]):
        with pytest.raises(SystemExit):
            main(argv)
        text = capsys.readouterr().out
        assert "``" not in text and ":mod:" not in text and ":func:" not in text
    with pytest.raises(SystemExit):
        main(["node", "--help"])
    assert "--duration 20 \\\n" in capsys.readouterr().out  # the continuation line kept
    with pytest.raises(SystemExit):
        main(["certs", "--help"])
    assert "ground1,ground2 \\\n        --duration 60" in capsys.readouterr().out
    assert plain_text("See :mod:`relloc.x` and ``y``::") == "See relloc.x and y:"


@pytest.mark.parametrize("experiment", ["mrclam-cl", "tiers-uwb"])
def test_data_not_found_names_the_option_and_the_variable(
    tmp_path, capsys, monkeypatch, experiment
):
    # --data-dir sets RELLOC_SHARED_DATA for the process; monkeypatch restores it afterwards
    # (tiers-uwb's message named only the variable)
    monkeypatch.setenv("RELLOC_SHARED_DATA", os.environ.get("RELLOC_SHARED_DATA", ""))
    missing = str(tmp_path / "nowhere")
    argv = ["reproduce", experiment, "--out", str(tmp_path / "o"), "--data-dir", missing]
    assert main([*argv, "--quiet"]) == 3
    err = capsys.readouterr().err
    assert missing in err and "--data-dir DIR" in err and "RELLOC_SHARED_DATA" in err


def test_reproduce_prints_the_ours_vs_paper_tables(tmp_path):
    report = tmp_path / "report.md"
    report.write_text(
        "# X\n\n## Headline\n\n| figure | ours | paper |\n|---|---|---|\n| rmse (m) | 0.1 | 0.2 |\n"
        "\n## Other\n\n| a | b |\n|---|---|\n| 1 | 2 |\n\n![cap](fig.png)\n"
    )
    (tmp_path / "fig.png").write_bytes(b"png")
    (tmp_path / "summary.json").write_text("{}")
    [table] = paper_tables(report.read_text())
    assert table.section == "Headline" and table.rows == [["rmse (m)", "0.1", "0.2"]]
    text = comparison_text("x", tmp_path)
    assert "Headline: ours vs paper" in text and "rmse (m)" in text and "0.2" in text
    assert "summary.json, report.md, fig.png" in text


def test_without_paper_numbers_each_part_of_the_report_shows_its_headline(tmp_path):
    """A report with one section per bag (tiers-uwb) and no paper column: the console shows
    each bag's first table (the same headers), not the first bag's only, and no other table."""
    case = "| case | pos RMSE (m) |\n|---|---|\n| team aligned | {} |\n"
    pairs = "| pair | pos RMSE (m) | odometry alone |\n|---|---|---|\n| a->b | 9.9 | 1 |\n"
    (tmp_path / "report.md").write_text(
        "# tiers-uwb\n\n## bag_one\n\n"
        + case.format("0.0929")
        + "\n"
        + pairs
        + "\n## bag_two\n\n"
        + case.format("0.0161")
        + "\n"
        + pairs
    )
    text = comparison_text("tiers-uwb", tmp_path)
    assert "bag_one: headline (no paper numbers to compare with)" in text
    assert "bag_two: headline (no paper numbers to compare with)" in text
    assert "0.0929" in text and "0.0161" in text and "a->b" not in text


def test_the_console_states_the_input_rows_each_part_skipped(tmp_path):
    """The report's lines on the loaders' skipped rows reach the console, each with its
    section where the report has several (one per bag)."""
    from relloc.pipeline.output import skipped_rows_line

    table = "| figure | ours | paper |\n|---|---|---|\n| rmse (m) | 0.1 | 0.2 |\n"
    one = skipped_rows_line(8004, {"folded: other direction": 8004}, "the bag")
    (tmp_path / "report.md").write_text(
        f"# X\n\n## bag_one\n\n{table}\n{skipped_rows_line(0, {}, 'the bag')}\n"
        f"\n## bag_two\n\n{one}\n"
    )
    text = " ".join(comparison_text("x", tmp_path, width=200).split())
    assert "bag_one: Input rows: every data row of the bag was used." in text
    assert (
        "bag_two: Input rows of the bag skipped (not used): 8004 (8004 folded: other direction)."
        in text
    )
    (tmp_path / "report.md").write_text(f"# X\n\n## run\n\n{table}\n{one}\n")
    assert "\nInput rows of the bag skipped" in comparison_text("x", tmp_path, width=200)


def test_the_extras_of_a_parsed_command():
    import argparse

    from relloc.cli.extras import needed_extras

    def ns(**kw):
        return argparse.Namespace(**kw)

    assert needed_extras(ns(command="run")) == ()
    assert needed_extras(ns(command="run", mcap="x.mcap")) == ("ros",)
    assert needed_extras(ns(command="reproduce", name="x", executor="dask://h:1")) == (
        "plot",
        "cluster",
    )
    assert needed_extras(ns(command="team", team_command="clock")) == ("runtime",)
    assert needed_extras(ns(command="bench", name="filters")) == ("bench",)
