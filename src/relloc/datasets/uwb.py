"""Loader for inter-robot UWB range recordings in the TIERS csv layout.

The TIERS recording (Yu et al., arXiv:2304.06264; shared as ``../shared/data/uwb/tiers``) has the
header ``timestamp,node1,node2,uwb_range,mocap_range,tb_node1_yaw,tb_node2_yaw,error`` with one
row per (time, node pair); ``error = uwb_range − mocap_range``. Several rows share a timestamp
(one row per pair), so timestamps must be non-decreasing, not strictly increasing.

Lines and rows
--------------
The file is read as bytes and split on ``b"\\n"``; when the file ends with ``b"\\n"`` the empty
piece after it is not a line. Lines are numbered from 1. Line 1 is the header (a leading UTF-8
byte-order mark is dropped; it must name the columns of :data:`REQUIRED_COLUMNS`, once each, in any
order; other columns are allowed). Every later line that is not blank (only ASCII whitespace) is a
*data row*; blank lines carry nothing and are counted in :attr:`UwbRecording.blank_lines`. Each
line is decoded on its own (strict UTF-8, one trailing ``\\r`` dropped) and split into fields on its
own (``csv`` rules within the line, so a stray quote never joins it to the next line). Every data
row is either *read* (it is in the arrays) or *skipped* (counted by reason in
:attr:`UwbRecording.skipped`, the first few kept with their line number)::

    n_rows + skipped.n_skipped == data_rows
    1 + data_rows + blank_lines == number of lines

Which rows are skipped
----------------------
Checked on each row alone: not valid UTF-8; not one csv line; a column count other than the
header's; a ``timestamp``, range or ``error`` value that is not a finite number; a node id that is
not an integer in ``0 … MAX_NODE_ID`` (ids are parsed exactly, never rounded or wrapped); a node
paired with itself; a range not in ``(0, MAX_RANGE]``; an ``error`` column that disagrees with
``uwb_range − mocap_range`` by more than :data:`ERROR_COLUMN_TOL`. Columns the loader does not
read (the yaws, any extra column) are not checked.

Checked on the timestamps of the rows that pass, in file order:

1. *Implausible*: a time more than :data:`MAX_TIME_GAP` seconds from the median time of its
   ``2 · TIME_WINDOW`` nearest rows in the file (``TIME_WINDOW`` before and after; the window is
   shifted at the ends of the file, and is every other row in a shorter file; of an even count
   the lower middle value is the median). A ranging network reports many times a second, so such
   a time is a typo (a first row stamped 0, a digit too many). The median is unmoved by up to
   ``TIME_WINDOW − 1`` bad times among the neighbours, so a few bad times never make a good row
   look bad.
2. *Out of order*: of the rows left, those kept are a longest non-decreasing subsequence of the
   timestamps (the fewest rows whose removal puts time in order, tolerance 0). A time that is off
   by less than ``MAX_TIME_GAP`` but out of order costs one row, never the rows after it. When the
   fewest rows are not unique (a swapped pair ``10, 20, 15, 30``: either 20 or 15 can go) the
   earlier one is skipped.

Repeated rows are not faults: a copy in order is kept, a copy out of order is skipped by rule 2.

A file that is missing, a directory, unreadable, empty, has an unusable header, or has no usable
row raises :class:`~relloc.errors.DataError` naming the file (and line 1 for a bad header).
"""

from __future__ import annotations

import csv
import math
from collections import Counter
from dataclasses import dataclass
from decimal import Decimal, InvalidOperation
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from relloc.core.recording import FileSkips, SkippedRow
from relloc.datasets.columns import check_columns
from relloc.datasets.paths import DATA_HINT
from relloc.datasets.time_order import longest_non_decreasing
from relloc.errors import DataError

REQUIRED_COLUMNS = ("timestamp", "node1", "node2", "uwb_range", "mocap_range")
#: Read when present: checked against ``uwb_range − mocap_range`` (the yaws are not read).
CHECKED_COLUMNS = ("error",)
#: Tolerance (m) on ``error − (uwb_range − mocap_range)`` before a row is called inconsistent.
ERROR_COLUMN_TOL = 1e-6
#: Largest node id: ids are stored as int64, so larger ones are out of range (not wrapped).
MAX_NODE_ID = int(np.iinfo(np.int64).max)
#: Longest plausible range (m); UWB radios reach a few hundred metres at most.
MAX_RANGE = 1000.0
#: A time farther than this (s) from the median time of its neighbours is implausible.
MAX_TIME_GAP = 60.0
#: Rows on each side of a row whose median time it is compared with.
TIME_WINDOW = 3
#: How many skipped rows are kept verbatim (with line number and reason).
MAX_SKIP_EXAMPLES = 5

_BOM = b"\xef\xbb\xbf"


@dataclass(frozen=True, kw_only=True)
class UwbRecording:
    """A validated UWB recording; arrays share one row index, in file order.

    ``n_rows + skipped.n_skipped == data_rows`` (see the module docstring for what a data row is).
    """

    path: Path
    t: NDArray[np.float64]
    node1: NDArray[np.int64]
    node2: NDArray[np.int64]
    uwb_range: NDArray[np.float64]
    mocap_range: NDArray[np.float64]
    data_rows: int
    blank_lines: int = 0
    skipped: FileSkips

    def __post_init__(self) -> None:
        """The loader's rules on the rows it keeps, checked on the container itself so that a
        recording built otherwise (a bag's radios, by hand) obeys them too: one length for
        every column, finite times and ranges, integer node ids of two different nodes, times
        non-decreasing. DataError naming the file and the column otherwise."""
        columns = {
            "node1": self.node1,
            "node2": self.node2,
            "uwb_range": self.uwb_range,
            "mocap_range": self.mocap_range,
        }
        where = f"{self.path}: UwbRecording"
        check_columns(where, self.t, columns, integer=("node1", "node2"))
        if np.any(np.asarray(self.node1) == np.asarray(self.node2)):
            raise DataError(f"{where}: a row pairs a node with itself")

    @property
    def error(self) -> NDArray[np.float64]:
        """Range error ``uwb_range − mocap_range`` (m)."""
        return self.uwb_range - self.mocap_range

    @property
    def n_rows(self) -> int:
        """Number of usable rows."""
        return int(self.t.size)

    def describe(self) -> str:
        """One line: the file, rows read of the data rows, and what was skipped."""
        return (
            f"{self.path}: {self.n_rows} of {self.data_rows} rows read; {self.skipped.describe()}"
        )

    def links(self) -> list[tuple[int, int]]:
        """The distinct unordered node pairs, sorted."""
        pairs = {
            (min(a, b), max(a, b))
            for a, b in zip(self.node1.tolist(), self.node2.tolist(), strict=True)
        }
        return sorted(pairs)

    def link_mask(self, link: tuple[int, int]) -> NDArray[np.bool_]:
        """Rows of one unordered node pair."""
        a, b = link
        return ((self.node1 == a) & (self.node2 == b)) | ((self.node1 == b) & (self.node2 == a))


# ----------------------------------------------------------------------------------------------
# One line, one row
# ----------------------------------------------------------------------------------------------


class _BadRow(Exception):
    """A line that cannot be used: ``reason`` is the category counted, ``detail`` the specifics."""

    def __init__(self, reason: str, detail: str) -> None:
        super().__init__(detail)
        self.reason = reason
        self.detail = detail


@dataclass(frozen=True)
class _Row:
    """One data row that passed the per-row checks, with its line number."""

    line: int
    t: float
    node1: int
    node2: int
    uwb: float
    mocap: float


def _decode(raw: bytes) -> str:
    """One line as text: strict UTF-8, one trailing ``\\r`` (CRLF files) dropped."""
    raw = raw.removesuffix(b"\r")
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        bad = raw[exc.start : exc.start + 1]
        raise _BadRow("invalid UTF-8", f"byte {exc.start + 1} ({bad!r}) is not UTF-8") from None


def _fields(text: str) -> list[str]:
    """The fields of one line by csv rules; a quote left open is an error, not a line join."""
    try:
        return next(csv.reader([text], strict=True), [])
    except csv.Error as exc:
        raise _BadRow("not one csv line", str(exc)) from None


def _parse_float(text: str, column: str) -> float:
    """A finite float, or :class:`_BadRow`."""
    try:
        value = float(text)
    except ValueError:
        raise _BadRow("not a number", f"{column}={text!r} is not a number") from None
    if not math.isfinite(value):
        raise _BadRow("not finite", f"{column}={text!r} is not finite")
    return value


def _parse_node(text: str, column: str) -> int:
    """An integer id in ``0 … MAX_NODE_ID``, parsed exactly (``3``, ``3.0``, ``3e0``)."""
    try:
        value = Decimal(text)
    except InvalidOperation:
        raise _BadRow("bad node id", f"{column}={text!r} is not a number") from None
    if not value.is_finite() or value < 0 or value > MAX_NODE_ID:
        raise _BadRow("bad node id", f"{column}={text!r} is not in 0 … {MAX_NODE_ID}")
    if value != value.to_integral_value():
        raise _BadRow("bad node id", f"{column}={text!r} is not an integer")
    return int(value)


def _parse_range(text: str, column: str) -> float:
    """A range in ``(0, MAX_RANGE]`` metres."""
    value = _parse_float(text, column)
    if not 0.0 < value <= MAX_RANGE:
        raise _BadRow("range out of bounds", f"{column}={value} is not in (0, {MAX_RANGE:g}] m")
    return value


def _parse_row(fields: list[str], line: int, header: _Header) -> _Row:
    """Validate one data row's fields (every check that needs this row alone)."""
    col = header.col
    if len(fields) != header.n_columns:
        raise _BadRow("wrong column count", f"{len(fields)} columns, header has {header.n_columns}")
    t = _parse_float(fields[col["timestamp"]], "timestamp")
    n1 = _parse_node(fields[col["node1"]], "node1")
    n2 = _parse_node(fields[col["node2"]], "node2")
    if n1 == n2:
        raise _BadRow("node paired with itself", f"node1 = node2 = {n1}")
    uwb = _parse_range(fields[col["uwb_range"]], "uwb_range")
    mocap = _parse_range(fields[col["mocap_range"]], "mocap_range")
    if "error" in col:
        err = _parse_float(fields[col["error"]], "error")
        if abs(err - (uwb - mocap)) > ERROR_COLUMN_TOL:
            raise _BadRow(
                "error column disagrees",
                f"error column {err} disagrees with uwb − mocap = {uwb - mocap}",
            )
    return _Row(line, t, n1, n2, uwb, mocap)


# ----------------------------------------------------------------------------------------------
# The file: bytes, lines, header
# ----------------------------------------------------------------------------------------------


def _read_lines(path: Path) -> list[bytes]:
    """The file's lines as bytes (see the module docstring), or :class:`DataError`."""
    try:
        data = path.read_bytes()
    except FileNotFoundError:
        raise DataError(f"{path}: UWB csv not found; {DATA_HINT}") from None
    except IsADirectoryError:
        raise DataError(f"{path}: is a directory, expected a UWB csv file; {DATA_HINT}") from None
    except (OSError, ValueError) as exc:
        raise DataError(f"{path}: cannot read UWB csv: {exc}") from exc
    lines = data.removeprefix(_BOM).split(b"\n")
    if lines[-1] == b"":
        lines.pop()
    if not lines:
        raise DataError(f"{path}: empty file (expected a header line {','.join(REQUIRED_COLUMNS)})")
    return lines


@dataclass(frozen=True)
class _Header:
    """Line 1: the index of each column the loader reads, and the number of columns."""

    col: dict[str, int]
    n_columns: int


def _parse_header(path: Path, raw: bytes) -> _Header:
    """Parse line 1; :class:`DataError` when a required column is missing or repeated."""
    try:
        names = [name.strip() for name in _fields(_decode(raw))]
    except _BadRow as bad:
        raise DataError(f"{path}: line 1: unreadable header: {bad.detail}") from None
    missing = [c for c in REQUIRED_COLUMNS if c not in names]
    if missing:
        raise DataError(f"{path}: line 1: missing column(s) {missing}; header is {names}")
    read = (*REQUIRED_COLUMNS, *CHECKED_COLUMNS)
    twice = sorted({c for c in read if names.count(c) > 1})
    if twice:
        raise DataError(f"{path}: line 1: column(s) {twice} appear more than once")
    return _Header({name: k for k, name in enumerate(names) if name in read}, len(names))


# ----------------------------------------------------------------------------------------------
# Timestamps across rows
# ----------------------------------------------------------------------------------------------


def _implausible(t: NDArray[np.float64]) -> NDArray[np.bool_]:
    """Per row: more than :data:`MAX_TIME_GAP` from the median time of its nearest rows (rule 1).

    Row ``i`` is compared with rows ``i − w … i + w`` (``w = TIME_WINDOW``) without itself, the
    window shifted to ``0 … 2w`` or ``n − 1 − 2w … n − 1`` at the ends of the file; the median of
    the ``2w`` others is the lower middle one.
    """
    n = t.size
    if n < 2:
        return np.zeros(n, dtype=bool)
    width = min(2 * TIME_WINDOW + 1, n)
    rows = np.arange(n)
    start = np.clip(rows - TIME_WINDOW, 0, n - width)
    window = start[:, None] + np.arange(width)[None, :]
    others = window[window != rows[:, None]].reshape(n, width - 1)
    middle = (width - 2) // 2
    median = np.partition(t[others], middle, axis=1)[:, middle]
    with np.errstate(over="ignore"):  # |t − median| beyond float range is inf: implausible
        return np.abs(t - median) > MAX_TIME_GAP


class _SkipLog:
    """Skipped rows of one file: every (line, reason, detail), reported by line order."""

    def __init__(self) -> None:
        self._rows: list[tuple[int, str, str]] = []

    def add(self, line: int, reason: str, detail: str) -> None:
        self._rows.append((line, reason, detail))

    def report(self, path: Path, rows_read: int, rows_kept: int) -> FileSkips:
        first = sorted(self._rows)[:MAX_SKIP_EXAMPLES]
        return FileSkips(
            file=str(path),
            rows_read=rows_read,
            rows_kept=rows_kept,
            skipped=dict(Counter(reason for _, reason, _ in self._rows)),
            examples=tuple(SkippedRow(line, reason, detail) for line, reason, detail in first),
        )


def _in_time_order(rows: list[_Row], skips: _SkipLog) -> list[_Row]:
    """Drop rows with implausible times, then out-of-order ones (rules 1 and 2, module doc)."""
    bad_time = _implausible(np.array([r.t for r in rows], dtype=float))
    plausible: list[_Row] = []
    for row, bad in zip(rows, bad_time.tolist(), strict=True):
        if bad:
            skips.add(
                row.line,
                "implausible timestamp",
                f"timestamp {row.t} is more than {MAX_TIME_GAP:g} s from its neighbours' median",
            )
        else:
            plausible.append(row)
    keep = set(longest_non_decreasing([r.t for r in plausible]))
    kept: list[_Row] = []
    for i, row in enumerate(plausible):
        if i in keep:
            kept.append(row)
        elif kept and row.t < kept[-1].t:
            skips.add(
                row.line,
                "timestamp out of order",
                f"timestamp {row.t} goes back in time (line {kept[-1].line} has {kept[-1].t})",
            )
        else:
            skips.add(
                row.line,
                "timestamp out of order",
                f"timestamp {row.t} is later than the rows after it",
            )
    return kept


# ----------------------------------------------------------------------------------------------
# Entry point
# ----------------------------------------------------------------------------------------------


def load_uwb_csv(path: Path | str) -> UwbRecording:
    """Read and validate a TIERS-layout UWB csv (rules and row accounting: module docstring)."""
    path = Path(path)
    lines = _read_lines(path)
    header = _parse_header(path, lines[0])
    skips = _SkipLog()
    rows: list[_Row] = []
    data_rows = blank_lines = 0
    for line, raw in enumerate(lines[1:], start=2):
        if not raw.strip():
            blank_lines += 1
            continue
        data_rows += 1
        try:
            rows.append(_parse_row(_fields(_decode(raw)), line, header))
        except _BadRow as bad:
            skips.add(line, bad.reason, bad.detail)
    kept = _in_time_order(rows, skips)
    report = skips.report(path, data_rows, len(kept))
    if not kept:
        raise DataError(
            f"{path}: no usable row ({data_rows} data rows, "
            + (report.describe() if report.n_skipped else "none after the header")
            + ")"
        )
    return UwbRecording(
        path=path,
        t=np.array([r.t for r in kept], dtype=float),
        node1=np.array([r.node1 for r in kept], dtype=np.int64),
        node2=np.array([r.node2 for r in kept], dtype=np.int64),
        uwb_range=np.array([r.uwb for r in kept], dtype=float),
        mocap_range=np.array([r.mocap for r in kept], dtype=float),
        data_rows=data_rows,
        blank_lines=blank_lines,
        skipped=report,
    )
