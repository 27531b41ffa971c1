"""A cell longer than the console line: console.py says "a cell is never cut", and a word is
broken only when it alone is longer than the line; its first piece then starts a line of its
own, not the header's line, where it would read as a wrong, shorter value (``value 12``)."""

from __future__ import annotations

from relloc.cli.console import compact_table


def test_a_value_longer_than_the_line_does_not_start_on_its_header_line():
    out = compact_table(["pair", "value"], [["a", 123456789]], width=10)
    lines = out.splitlines()
    assert "  value 12" not in lines, out
    # however the value is broken, its digits read in order from the start of a line
    assert "".join(line.strip() for line in lines if line.strip()[:1].isdigit()) == "123456789"
