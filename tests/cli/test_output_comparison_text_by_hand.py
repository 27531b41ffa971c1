"""What ``relloc reproduce`` prints from a hand-written report.md: the tables beside the paper
(or the headline), the skipped-rows lines and the files written."""

from __future__ import annotations

from relloc.cli.comparison import comparison_text, figures, tables

PAPER_REPORT = """# Title
## Part A
| metric | ours | Paper value |
|:---|---:|:---:|
| rmse | 1.5 | 1.4 |
|n|3|
## Part B
| x | y |
|---|---|
| 1 | 2 |
Input rows of the dataset skipped (not used): 2 (2 bad).
![fig](a.png)
![fig again](a.png)
![missing](b.png)
"""

BAGS_REPORT = """## Bag 1
| x | y |
|---|---|
| 1 | 2 |
Input rows of bag 1 skipped (not used): 1 (1 bad).
## Other
| a |
|---|
| 7 |
## Bag 2
| x | y |
|---|---|
| 3 | 4 |
Input rows of bag 2 skipped (not used): 5 (5 bad).
"""


def test_the_table_beside_the_paper_is_shown_with_short_rows_padded(tmp_path):  # type: ignore[no-untyped-def]
    (tmp_path / "report.md").write_text(PAPER_REPORT)
    (tmp_path / "summary.json").write_text("{}")
    (tmp_path / "a.png").write_bytes(b"png")
    text = comparison_text("demo", tmp_path, width=400)
    assert text.splitlines() == [
        "demo — Part A: ours vs paper",
        "metric  ours  Paper value",
        "------  ----  -----------",
        "rmse     1.5          1.4",
        "n          3",
        "",
        "Input rows of the dataset skipped (not used): 2 (2 bad).",
        f"wrote {tmp_path}/: summary.json, report.md, a.png",
    ]


def test_without_paper_numbers_every_table_of_the_first_layout_is_shown(tmp_path):  # type: ignore[no-untyped-def]
    (tmp_path / "report.md").write_text(BAGS_REPORT)
    text = comparison_text("demo", tmp_path, width=400)
    assert text.splitlines() == [
        "demo — Bag 1: headline (no paper numbers to compare with)",
        "x  y",
        "-  -",
        "1  2",
        "",
        "demo — Bag 2: headline (no paper numbers to compare with)",
        "x  y",
        "-  -",
        "3  4",
        "",
        "Bag 1: Input rows of bag 1 skipped (not used): 1 (1 bad).",
        "Bag 2: Input rows of bag 2 skipped (not used): 5 (5 bad).",
        f"wrote {tmp_path}/: report.md",
    ]


def test_tables_keep_their_section_and_aligned_separators():
    found = tables(PAPER_REPORT)
    assert [(t.section, t.headers, t.rows) for t in found] == [
        ("Part A", ["metric", "ours", "Paper value"], [["rmse", "1.5", "1.4"], ["n", "3"]]),
        ("Part B", ["x", "y"], [["1", "2"]]),
    ]


def test_figures_are_listed_once_in_order():
    assert figures(PAPER_REPORT) == ["a.png", "b.png"]


def test_the_console_states_a_count_of_runs_or_each_blocks_count() -> None:
    from relloc.cli.reproduce import _runs_text

    assert _runs_text(30) == "30"
    assert _runs_text({"one_drone": 3, "two_drones": 11}) == "one_drone 3, two_drones 11"


def test_a_bag_with_readings_kept_out_of_the_recording_does_not_claim_them() -> None:
    from relloc.pipeline.output import bag_rows_source, skipped_rows_line

    assert bag_rows_source({}) == "the bag"
    source = bag_rows_source({"to a static radio of unknown position": 2262, "between two": 878})
    assert skipped_rows_line(0, {}, source) == (
        "Input rows: every data row of the bag (less its 3140 UWB readings not in the "
        "recording) was used."
    )
