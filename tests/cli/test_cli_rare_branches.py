"""Command-line branches no other test reaches: arguments refused with a message naming the
flag, and what a command prints (the bag's mapping skeleton, the console helpers, the
observability report's 50-digit rank)."""

from __future__ import annotations

from pathlib import Path

import pytest

from relloc.cli import main
from relloc.errors import DataError
from relloc.pipeline.output import fmt


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["bench", "nope"], "unknown benchmark 'nope'; available: filters"),
        (
            ["observability", "relative-nonlinear", "--at-state", "x=abc"],
            "--at-state: x must be a number, got 'abc'",
        ),
        (["run", "--map", "m.toml"], "--map: give the bag to run as SCENARIO"),
        (
            ["node", "--robot", "robot1", "--dataset", ".", "--estimator", "cooperative"],
            "--estimator cooperative: --fit FILE (written by relloc team up)",
        ),
        (
            ["node", "--realtime", "--robot", "1", "--scenario", "sharma2013"],
            "--realtime: this team source has no recording to replay",
        ),
        (
            ["node", "--robot", "ghost", "--scenario", "default"],
            "--robot: 'ghost' is not in the scenario ('observer',",
        ),
    ],
)
def test_a_bad_argument_is_refused_naming_it(tmp_path, monkeypatch, capsys, argv, message):
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err


def test_the_mapping_skeleton_says_when_range_topics_share_no_template():
    from relloc.cli.bag import mapping_skeleton
    from relloc.datasets.rosbag import TopicInfo

    def skeleton(*topics: str) -> str:
        infos = [TopicInfo(t, "sensor_msgs/msg/Range", 5, 0.0, 1.0) for t in topics]
        return mapping_skeleton(infos, name="b")

    shared = skeleton("/uwb/a1/to/b1", "/uwb/a2/to/b2")
    assert 'topics = "/uwb/{a}/to/{b}"' in shared and 'name = "a1"' in shared
    for topics in (
        ("/uwb/a1/b1",),  # one topic: nothing varies
        ("/uwb/a1/b1", "/uwb/a2/b2/x"),  # paths of different depths
        ("/u1/a1/b1", "/u2/a2/b2"),  # three segments vary
    ):
        text = skeleton(*topics)
        assert f"# {len(topics)} sensor_msgs/Range topics share no {{a}}/{{b}} template" in text
        assert "[uwb]" not in text


def test_console_helpers_print_columns_folders_and_missing_figures(monkeypatch):
    from relloc.cli import console

    monkeypatch.setenv("COLUMNS", "123")
    assert console.terminal_width() == 123
    assert console.wrote_line([]) == "wrote nothing"
    line = console.wrote_line([Path("a/x.json"), Path("b/y.md")], width=200)
    assert line == "wrote a/x.json, b/y.md"
    assert console._milli(None, None) == console._milli(float("nan"), None) == fmt(None)


def test_comparison_of_a_folder_without_a_report_names_the_report(tmp_path):
    from relloc.cli.comparison import comparison_text

    with pytest.raises(DataError, match=rf"{tmp_path / 'report.md'}: cannot read the report"):
        comparison_text("x", tmp_path)


def test_records_left_out_of_an_export_are_printed_by_reason(capsys):
    from relloc.cli.export_args import print_export

    print_export({"run": 0, "skipped": {"no truth": 3}})
    assert capsys.readouterr().out == "not exported: 3 records (no truth)\n"


def test_observability_prints_the_50_digit_rank_with_precise(capsys):
    assert main(["observability", "unicycle-landmarks", "--precise"]) == 0
    out = capsys.readouterr().out
    assert "rank       2 of 3 (NOT fully observable); 50-digit check: 2   [order" in out
