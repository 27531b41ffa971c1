"""What ``relloc reproduce NAME`` prints: the ours-vs-paper tables of the report it wrote.

Every reproduction writes ``report.md`` with its headline comparisons as markdown tables that
have a ``paper`` column (:func:`relloc.pipeline.output.markdown_table`); those tables are the
ones each experiment chose to set beside the paper (a report without one shows its headline
instead: its first table and the later ones of the same headers, one per part of a report that
repeats a layout, such as ``tiers-uwb``'s bags). :func:`paper_tables` reads them back and
:func:`comparison_text` lays them out for the terminal (:func:`relloc.cli.console.compact_table`),
followed by the report's lines on the input rows the loaders skipped and the list of files
written (``summary.json``, ``report.md`` and every figure the report shows).
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

from relloc.cli.console import compact_table, wrap_line, wrote_line
from relloc.errors import DataError
from relloc.pipeline.output import SKIPPED_ROWS_START

_FIGURE = re.compile(r"!\[[^\]]*\]\(([^)\s]+)\)")


@dataclass(frozen=True)
class Table:
    """One markdown table of a report: the section it is in, its headers and its cells."""

    section: str
    headers: list[str]
    rows: list[list[str]]


def _cells(line: str) -> list[str]:
    return [c.strip() for c in line.strip().strip("|").split("|")]


def tables(markdown: str) -> list[Table]:
    """Every markdown table of a report, with the heading of the section it is in."""
    out: list[Table] = []
    section = ""
    lines = markdown.splitlines()
    i = 0
    while i < len(lines):
        line = lines[i]
        if line.startswith("#"):
            section = line.lstrip("#").strip()
        is_table = (
            line.startswith("|")
            and i + 1 < len(lines)
            and re.fullmatch(r"\|(\s*:?-+:?\s*\|)+", lines[i + 1].strip()) is not None
        )
        if is_table:
            headers = _cells(line)
            rows = []
            i += 2
            while i < len(lines) and lines[i].startswith("|"):
                rows.append(_cells(lines[i]))
                i += 1
            out.append(Table(section, headers, rows))
            continue
        i += 1
    return out


def paper_tables(markdown: str) -> list[Table]:
    """The tables with a column about the paper (a header that mentions ``paper``)."""
    return [t for t in tables(markdown) if any("paper" in h.lower() for h in t.headers)]


def headline_tables(markdown: str) -> list[Table]:
    """A report's first table and every later one of the same headers: the headline of each of
    its parts where a report repeats one layout per part (``tiers-uwb``: one per bag)."""
    every = tables(markdown)
    return [t for t in every if t.headers == every[0].headers] if every else []


def skipped_rows_lines(markdown: str) -> list[tuple[str, str]]:
    """``(section, line)`` of every report line on the input rows the loaders skipped
    (:func:`relloc.pipeline.output.skipped_rows_line`), with the heading it is under."""
    found, section = [], ""
    for line in markdown.splitlines():
        if line.startswith("#"):
            section = line.lstrip("#").strip()
        elif line.startswith(SKIPPED_ROWS_START):
            found.append((section, line))
    return found


def figures(markdown: str) -> list[str]:
    """The figure files a report shows, in order, without repeats."""
    return list(dict.fromkeys(_FIGURE.findall(markdown)))


def comparison_text(name: str, out_dir: Path, *, width: int = 80) -> str:
    """The ours-vs-paper tables of ``out_dir/report.md`` and the list of files written."""
    report = out_dir / "report.md"
    try:
        markdown = report.read_text()
    except OSError as exc:
        raise DataError(f"{report}: cannot read the report ({exc.strerror or exc})") from None
    parts = []
    found, what = paper_tables(markdown), "ours vs paper"
    if not found:  # the paper gives no numbers to set beside: show the report's headline
        found, what = headline_tables(markdown), "headline (no paper numbers to compare with)"
    for t in found:
        rows = [r + [""] * (len(t.headers) - len(r)) for r in t.rows]
        parts.append(wrap_line(f"{name} — {t.section}: {what}", width))
        parts.append(compact_table(t.headers, [r[: len(t.headers)] for r in rows], width=width))
        parts.append("")
    skips = skipped_rows_lines(markdown)
    for section, line in skips:
        parts.append(wrap_line(f"{section}: {line}" if len(skips) > 1 else line, width))
    files = [out_dir / "summary.json", report] + [out_dir / f for f in figures(markdown)]
    parts.append(wrote_line([f for f in files if f.exists()], width))
    return "\n".join(parts)
