"""The console helpers on hand-made inputs: the team table in mm/mrad, the list of files,
line wrapping and docstrings as plain help text."""

from __future__ import annotations

from pathlib import Path

from relloc.cli.console import plain_text, team_summary_table, wrap_line, wrote_line

NAN = float("nan")


def test_team_table_shows_millimetres_and_milliradians_with_the_spread_over_runs():
    summary = {
        "pairs": {
            "a->b": {
                "position_rmse_m": 0.0123,
                "position_rmse_over_runs": {"std": 0.0021},
                "yaw_rmse_rad": 0.5,
                "yaw_rmse_over_runs": {"std": NAN},  # one run: no spread shown
                "anees": 1.05,
                "nees_run_average_in_band_percent": 93.2,
                "anis": 0.98,
                "convergence": {"median_time_s": 4.5},
            }
        },
        "team": {
            "position_rmse_m": NAN,  # no value: its spread is not shown either
            "position_rmse_over_runs": {"std": 0.001},
            "yaw_rmse_rad": None,
            "anees": 2.0,
            "anis": None,
        },
    }
    assert team_summary_table(summary).splitlines() == [
        "pair                pos mm  yaw mrad  ANEES  in band %  ANIS  conv s",
        "----------------  --------  --------  -----  ---------  ----  ------",
        "a->b              12.3±2.1       500   1.05       93.2  0.98     4.5",
        "team (all pairs)         —         —      2          —     —       —",
    ]


def test_files_of_one_folder_are_listed_by_name_after_it():
    files = [Path("out/a.png"), Path("out/summary.json")]
    assert wrote_line(files) == "wrote out/: a.png, summary.json"


def test_files_of_several_folders_are_listed_by_path():
    files = [Path("out/a.png"), Path("x/summary.json")]
    assert wrote_line(files) == "wrote out/a.png, x/summary.json"
    assert wrote_line([]) == "wrote nothing"


def test_a_long_path_is_never_split_and_later_lines_are_indented():
    text = "wrote " + "a/" * 20 + "file.png and-some-hyphen-words here"
    assert wrap_line(text, 30).splitlines() == [
        "wrote",
        "  " + "a/" * 20 + "file.png",
        "  and-some-hyphen-words here",
    ]


def test_a_docstring_loses_its_rest_markup():
    doc = "Uses :func:`~relloc.x.y` and ``code``. Example::\n\n    relloc run"
    assert plain_text(doc) == "Uses relloc.x.y and code. Example:\n\n    relloc run"
    assert plain_text(None) == ""
