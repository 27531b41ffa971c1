"""The console's narrow-terminal layout wraps at spaces: a word (a hyphenated one too) is
broken only when it alone is longer than the line."""

from __future__ import annotations

from relloc.cli.console import compact_table

CONDITIONS = "robot 1 moving or robot 2 moving or robot 3 moving or robot 4 moving"
VERDICT = "the filter is over-confident over the whole run, unobservable when still"


def _words(text: str) -> set[str]:
    return {w.strip(",") for w in text.split()}


def test_fallback_rows_wrap_long_values_at_spaces():
    headers = ["case", "rank", "conditions (ours)", "verdict"]
    rows = [["theorem2_connected_no_landmarks", "12/15", CONDITIONS, VERDICT]]
    for width in (34, 40, 52, 80):
        table = compact_table(headers, rows, width=width)
        lines = table.splitlines()
        assert max(len(line) for line in lines) <= width
        words = set().union(*(_words(line) for line in lines))
        # every word of every cell is printed whole on one line: none is cut
        assert _words(" ".join([*headers[1:], *rows[0]])) <= words, (width, table)
        assert not any(line.startswith("   ") for line in lines[1:])  # no stray space
    # a short header-value pair still stays on one line
    assert "rank 12/15" in compact_table(headers, rows, width=40)


def test_only_a_word_longer_than_the_line_is_broken():
    word = "x" * 50
    table = compact_table(["a", "b"], [["label", f"short {word} tail"]], width=30)
    lines = table.splitlines()
    assert max(len(line) for line in lines) <= 30
    assert word in "".join(line.strip() for line in lines)
    assert "b short" in table and any(line.strip() == "tail" or "tail" in line for line in lines)
