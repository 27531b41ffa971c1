"""compact_table at the edges of its width: a table exactly as wide as the line stays a table."""

from __future__ import annotations

from relloc.cli.console import compact_table


def test_a_table_exactly_as_wide_as_the_line_is_laid_out_side_by_side():
    # widths 10 and 1 with a 2-space gap: 13 columns
    out = compact_table(["a", "b"], [["x" * 10, 1]], width=13)
    assert out == "a           b\n----------  -\nxxxxxxxxxx  1"


def test_one_column_too_wide_falls_back_to_label_blocks():
    out = compact_table(["a", "b"], [["x" * 10, 1]], width=12)
    assert out == "xxxxxxxxxx\n  b 1"


def test_a_pair_that_fits_with_its_comma_stays_on_one_line():
    # "hh " + 14 v's + "," is 18 columns: exactly the 20-column line after the 2-space indent
    out = compact_table(["pair", "hh", "k"], [["L", "v" * 14, 1]], width=20)
    assert out == "L\n  hh " + "v" * 14 + ",\n  k 1"


def test_a_pair_one_column_too_long_for_its_comma_wraps_at_its_space_and_no_cell_is_cut():
    # "hh " + 15 v's + "," would be 19 columns after the indent: header and value part at the
    # space, and the value is never broken
    out = compact_table(["pair", "hh", "k"], [["L", "v" * 15, 1]], width=20)
    assert out == "L\n  hh\n  " + "v" * 15 + ",\n  k 1"
    assert all(len(line) <= 20 for line in out.splitlines())


def test_a_row_with_an_empty_label_keeps_an_empty_label_line():
    out = compact_table(["pair", "value"], [["", 12345678], ["b", 1]], width=10)
    assert out.splitlines() == ["", "  value", "  12345678", "b", "  value 1"]


def test_an_empty_last_cell_leaves_no_trailing_spaces():
    out = compact_table(["label", "note"], [["x", ""], ["yy", "ok"]])
    assert out == "label  note\n-----  ----\nx\nyy       ok"


def test_a_hyphenated_label_wraps_at_its_space_not_at_its_hyphen():
    out = compact_table(["pair", "n"], [["ab cd-efgh", 1]], width=8)
    assert out == "ab\ncd-efgh\n  n 1"
