"""Console output that reads in a narrow terminal: compact result tables and the list of files.

:func:`compact_table` lays rows out in plain text within a given width (80 columns by
default): each column as wide as its widest cell, numbers right-aligned. Rows that do not fit
even so are printed as ``label: header value, …`` blocks instead — a cell is never cut. The
full tables are in ``report.md``; the console shows the key figures only.
"""

from __future__ import annotations

import math
import re
import shutil
import textwrap
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from relloc.pipeline.output import fmt

GAP = "  "
NBSP = "\u00a0"


def terminal_width(default: int = 80) -> int:
    """``$COLUMNS`` if set, else the terminal's width, else ``default``
    (:func:`shutil.get_terminal_size` reads them in that order)."""
    return shutil.get_terminal_size((default, 24)).columns


def compact_table(
    headers: Sequence[str], rows: Sequence[Sequence[Any]], *, width: int = 80, digits: int = 3
) -> str:
    """A plain-text table no wider than ``width``; the first column is the row label.

    Falls back to one ``label`` line plus wrapped ``header value`` pairs per row when the
    columns cannot fit side by side.
    """
    cells = [[fmt(c, digits) for c in row] for row in rows]
    widths = [max(len(h), *(len(r[i]) for r in cells)) for i, h in enumerate(headers)]
    if sum(widths) + len(GAP) * (len(widths) - 1) <= width:
        lines = [_join(headers, widths), _join(["-" * w for w in widths], widths)]
        lines += [_join(r, widths) for r in cells]
        return "\n".join(lines)
    lines = []
    indent = "  "
    for r in cells:
        lines += _wrap_words(r[0], width) or [""]  # a label wider than the line wraps
        # a header and its value stay on one line (joined with no-break spaces) when they fit
        # on one; a longer pair wraps at its spaces like any text
        pairs = ", ".join(
            _bind(f"{h} {v}", width - len(indent)) for h, v in zip(headers[1:], r[1:], strict=True)
        )
        wrapped = _wrap_words(pairs, width, indent)
        lines += [w.replace(NBSP, " ") for w in wrapped]
    return "\n".join(lines)


def _bind(text: str, width: int) -> str:
    """``text`` with no-break spaces when it fits in ``width`` columns (a 1-column allowance
    for the ``,`` that follows it), else as it is."""
    return text.replace(" ", NBSP) if len(text) < width else text


def _wrap_words(text: str, width: int, indent: str = "") -> list[str]:
    """``text`` wrapped at spaces only, every line after ``indent``: a word (hyphenated ones
    too) is broken only when it alone is longer than the line, and then starts a line of its
    own (textwrap would put its first piece after the word before it, where ``value 123…``
    reads as a shorter value)."""
    room = max(width - len(indent), 1)
    pieces = [w[i : i + room] for w in text.split(" ") if w for i in range(0, len(w), room)]
    return textwrap.wrap(
        " ".join(pieces),
        width,
        initial_indent=indent,
        subsequent_indent=indent,
        break_long_words=False,
        break_on_hyphens=False,
    )


def _join(cells: Sequence[str], widths: Sequence[int]) -> str:
    out = [cells[0].ljust(widths[0])]
    out += [c.rjust(w) for c, w in zip(cells[1:], widths[1:], strict=True)]
    return GAP.join(out).rstrip()


def wrap_line(text: str, width: int = 80, indent: str = "  ") -> str:
    """One logical line wrapped at ``width`` (long words such as paths are never split)."""
    return "\n".join(
        textwrap.wrap(
            text,
            width,
            subsequent_indent=indent,
            break_long_words=False,
            break_on_hyphens=False,
        )
    )


def wrote_line(files: Sequence[Path], width: int = 80) -> str:
    """``wrote DIR/: a, b, c`` — every file written, relative to their common folder."""
    if not files:
        return "wrote nothing"
    folders = {Path(f).parent for f in files}
    if len(folders) == 1:
        folder = folders.pop()
        names = ", ".join(Path(f).name for f in files)
        return wrap_line(f"wrote {folder}/: {names}", width)
    return wrap_line("wrote " + ", ".join(str(f) for f in files), width)


def team_summary_table(summary: Mapping[str, Any], *, width: int = 80) -> str:
    """The key per-pair figures of a team run (``relloc run``, ``relloc team up``).

    Columns: the pair; steady-state position RMSE in mm and yaw RMSE in mrad (mean over runs ±
    std when there are several runs, else the pooled value); ANEES and ANIS (ideal 1); the share
    of recording times at which the run-averaged NEES is inside its 95 % band; the median time
    to converge from the unknown start. ``summary.json`` keeps SI units (m, rad).
    """
    headers = ["pair", "pos mm", "yaw mrad", "ANEES", "in band %", "ANIS", "conv s"]
    rows = []
    items = [*summary["pairs"].items(), ("team (all pairs)", summary["team"])]
    for label, s in items:
        conv = s.get("convergence", {})
        rows.append(
            [
                label,
                _milli(s["position_rmse_m"], s.get("position_rmse_over_runs")),
                _milli(s["yaw_rmse_rad"], s.get("yaw_rmse_over_runs")),
                s["anees"],
                s.get("nees_run_average_in_band_percent"),
                s["anis"],
                conv.get("median_time_s"),
            ]
        )
    return compact_table(headers, rows, width=width)


def _milli(value: Any, spread: Mapping[str, Any] | None) -> str:
    """``value`` (×1000) with ``±std`` (×1000) when the spread covers at least two runs."""
    if value is None or not isinstance(value, (int, float)) or value != value:
        return fmt(None)
    text = fmt(1000.0 * value, 3)
    std = spread.get("std") if spread else None
    if isinstance(std, float) and math.isfinite(std):
        text += f"±{fmt(1000.0 * std, 2)}"
    return text


_ROLE = re.compile(r":(?:mod|func|class|meth|data|attr|obj|exc):`~?([^`]+)`")


def plain_text(doc: str | None) -> str:
    """A reST docstring as plain help text: roles and ````literals```` lose their markup and a
    literal-block ``::`` becomes ``:`` (for ``argparse`` with ``RawDescriptionHelpFormatter``)."""
    text = _ROLE.sub(r"\1", doc or "")
    text = text.replace("``", "")
    text = re.sub(r"(\S)::$", r"\1:", text, flags=re.MULTILINE)
    return text.strip()
