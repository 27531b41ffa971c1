"""Loader for any folder in the layout of the UTIAS MRCLAM datasets.

Leung, Barfoot & Liu, "The UTIAS Multi-Robot Cooperative Localization and Mapping Dataset",
IJRR 30(8):969–974, 2011. A folder holds

- ``Barcodes.dat``: ``subject  barcode`` (robots are subjects 1..N, landmarks the rest);
- ``Landmark_Groundtruth.dat``: ``subject  x  y  σx  σy``;
- ``RobotN_Groundtruth.dat``: ``t  x  y  θ`` (Vicon, world frame);
- ``RobotN_Odometry.dat``: ``t  v  ω`` (commanded forward and angular velocity);
- ``RobotN_Measurement.dat``: ``t  barcode  range  bearing`` (camera; the second column is a
  *barcode*, mapped to a subject through ``Barcodes.dat``).

``#`` lines are comments; columns are whitespace-separated; times are Unix seconds.

How a file is read
------------------
A file is read as bytes and cut into lines at ``\\n`` only, so the line numbers in messages are
the ones an editor shows (``\\r``, ``\\x0b``, ``\\x1c``, ``\\x85`` or ``\\u2028`` never start a
line). A line that is empty once spaces, tabs and carriage returns are stripped from both ends is
*blank*; one that then starts with ``#`` is a *comment*; every other line is a **data row**, and
:attr:`FileReport.rows_read` counts exactly these. A data row is usable when it is ASCII, holds
the file's number of columns separated by spaces or tabs, each an ASCII decimal numeral
(``-1.5``, ``.5``, ``2e-3``; no ``_``, no digits of other scripts; ``nan`` and ``inf`` read as
non-finite) inside the column's bounds:

====================  =========================  =============================================
column                accepted values            why
====================  =========================  =============================================
time                  [0, 2³²] s                 Unix seconds, 1970 to 2106
subject, barcode      integers in [1, 2³¹ − 1]   positive ids that no integer type wraps
range                 (0, 100] m                 a camera range (MRCLAM's reach under 10 m)
θ, bearing            [−2π, 2π] rad              one turn either way: (−π, π] or [0, 2π)
x, y                  [−10⁵, 10⁵] m              a local metric frame (within 100 km)
σx, σy                [0, 10⁵] m                 standard deviations are not negative
v                     [−100, 100] m/s            far beyond any ground robot or drone
ω                     [−100, 100] rad/s          16 turns a second
====================  =========================  =============================================

What the loader guarantees
--------------------------
- **One clock.** Every time is relative to ``t0_unix``, the earliest time stamp of any robot
  row the loader *kept* (a skipped row never sets it); the absolute offset is kept in
  :attr:`MrclamDataset.t0_unix`. The relative times are rounded to the finest decimal step the
  absolute stamps resolve (1 µs at Unix times), so they are the differences of the stamps as
  written and the same whatever the recording's date (``_clock_decimals``).
- **Nothing lost silently.** Every data row of every file is kept or skipped, and for each file
  ``rows_read == rows_kept + n_skipped`` (:class:`FileReport`). A row that is not ASCII, has the
  wrong number of columns, a non-numeric, non-finite or out-of-bounds value, a non-integer id,
  an unknown barcode, a time going backwards, or (ground truth and odometry) a repeated time
  stamp is either skipped and *counted* in the :class:`LoadReport` (default; the first few
  examples per file and reason are kept with their line numbers) or, with
  ``MrclamOptions(on_bad_row="raise")``, raises :class:`~relloc.errors.DataError` naming the
  file and line.
  Measurement rows legitimately share time stamps (one camera frame sees several subjects);
  only a time going backwards is a fault there.
- **Time order: the most rows in order are kept.** Of a file's ``n`` usable rows with stamps
  ``t₁ … tₙ`` (in file order), the loader keeps a longest non-decreasing subsequence — rows
  ``i₁ < … < iₖ`` with ``t_{i₁} ≤ … ≤ t_{iₖ}`` and ``k`` as large as possible (patience sorting,
  ``O(n log n)``) — and skips the other ``n − k`` as "time goes backwards"; among equally long
  ones it keeps the one whose row numbers come first in lexicographic order (the earliest rows,
  so a file in which skipping each row earlier than the latest kept before it already leaves
  ``k`` rows keeps exactly those). A row out of place thus costs itself, not the rows after it:
  two swapped rows cost 2, one far-future stamp costs 1. Equal stamps are in order here; the
  duplicate rules below then apply to the rows kept.
- **Duplicate odometry stamps**: the later row is kept (it is the command in force from then on)
  and the earlier one is counted as superseded. Duplicate ground-truth stamps keep the first.
- **Always an error** (``DataError`` naming the file, and the line where there is one): a missing
  file or something other than a file in its place; fewer usable rows than a table needs (1 in
  ``Barcodes.dat`` and in each odometry file — every use of a robot starts from its commands —,
  2 in each ground-truth file); a subject or barcode listed twice in ``Barcodes.dat``; a robot
  without a barcode; a landmark listed twice in ``Landmark_Groundtruth.dat`` (a surveyed table
  giving one landmark two positions contradicts itself, and no rule can say which one is true,
  so the loader refuses the file rather than pick one); a subject that is both a robot loaded
  (``RobotN_*`` files) and a landmark in ``Landmark_Groundtruth.dat`` (one subject carries one
  barcode, so a camera reading of it could not say whether it saw the moving robot or the
  surveyed landmark; the layout numbers robots and landmarks apart); a row stamped more than a day
  (:data:`MAX_RUN_S`) after the run's first stamp (a clock jump, which would make every use
  that samples the run on a grid allocate without bound).
- **Ground truth at query times** (:meth:`GroundTruth.at`): x, y linearly interpolated, θ on the
  circle (unwrap, interpolate, wrap); each query is flagged when it lies outside the recorded span
  or inside a gap between consecutive samples longer than ``gap_threshold`` (the robot moved
  unobserved there, so interpolation is a guess).
- **Odometry at query times** (:meth:`Odometry.at`): zero-order hold of the last command (the
  robots keep moving through logging gaps; before the first command they stand still).
"""

from __future__ import annotations

import math
import numbers
import re
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from relloc.core import recording as rec
from relloc.core.angles import circular_interp
from relloc.core.limits import MAX_ABS_POSITION_M, MAX_SPEED_M_S, MAX_YAW_RATE_RAD_S
from relloc.datasets.columns import check_columns
from relloc.datasets.paths import DATA_HINT
from relloc.datasets.time_order import longest_non_decreasing
from relloc.errors import ConfigError, DataError

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
BoolArray = NDArray[np.bool_]

BARCODES_FILE = "Barcodes.dat"
LANDMARKS_FILE = "Landmark_Groundtruth.dat"
_ROBOT_FILE = re.compile(r"Robot([1-9][0-9]*)_(Groundtruth|Odometry|Measurement)\.dat", re.ASCII)
ROBOT_KINDS = ("Groundtruth", "Odometry", "Measurement")

# Bounds of the columns (module docstring); a value outside is a logging fault.
MAX_UNIX_TIME_S = 2.0**32
MAX_ID = 2**31 - 1
MAX_RANGE_M = 100.0
MAX_ABS_ANGLE_RAD = 2.0 * math.pi
MAX_RUN_S = 86_400.0
"""Longest span of one run's stamps (a day; MRCLAM's runs last 15–70 minutes)."""


# ----------------------------------------------------------------------------------------------
# Options and the load report
# ----------------------------------------------------------------------------------------------


@dataclass(frozen=True, kw_only=True)
class MrclamOptions:
    """How the loader treats imperfect data.

    Attributes:
        on_bad_row: ``"skip"`` counts and reports unusable rows; ``"raise"`` raises
            :class:`DataError` at the first one (file and line in the message).
        gap_threshold: ground-truth gaps longer than this (s) are flagged at query time.
        max_examples: examples kept per file and reason in the :class:`LoadReport`.
        robots: subjects to load (``None``: every ``RobotN_*`` triple found in the folder).
    """

    on_bad_row: Literal["skip", "raise"] = "skip"
    gap_threshold: float = 0.5
    max_examples: int = 3
    robots: tuple[int, ...] | None = None

    def __post_init__(self) -> None:
        if self.on_bad_row not in ("skip", "raise"):
            raise ConfigError(f"on_bad_row must be 'skip' or 'raise', got {self.on_bad_row!r}")
        if not (_is_number(self.gap_threshold) and 0 < self.gap_threshold < math.inf):
            raise ConfigError(f"gap_threshold must be a positive number, got {self.gap_threshold}")
        if not (_is_integer(self.max_examples) and self.max_examples >= 0):
            raise ConfigError(f"max_examples must be an integer ≥ 0, got {self.max_examples!r}")
        if self.robots is not None:
            if not (
                isinstance(self.robots, Sequence)
                and len(self.robots) > 0
                and all(_is_integer(r) and r >= 1 for r in self.robots)
            ):
                raise ConfigError(f"robots must be positive subject ids, got {self.robots!r}")


def _is_number(value: object) -> bool:
    """A real number that is not a bool."""
    return isinstance(value, numbers.Real) and not isinstance(value, bool)


def _is_integer(value: object) -> bool:
    """An integer (Python or numpy) that is not a bool."""
    return isinstance(value, numbers.Integral) and not isinstance(value, bool)


@dataclass(frozen=True)
class SkippedRow:
    """One example of a skipped row: 1-based line number, reason and the raw text.

    ``text`` is the line stripped of blanks, with any non-ASCII byte written as ``\\xNN``.
    """

    line: int
    reason: str
    text: str


@dataclass
class FileReport:
    """What happened to the data rows of one file: ``rows_read == rows_kept + n_skipped``.

    ``rows_read`` counts the file's data rows as the module docstring defines them (lines split
    at ``\\n`` that are neither blank nor ``#`` comments).
    """

    file: str
    rows_read: int = 0
    rows_kept: int = 0
    skipped: dict[str, int] = field(default_factory=dict)
    examples: dict[str, list[SkippedRow]] = field(default_factory=dict)

    @property
    def n_skipped(self) -> int:
        """Total number of rows skipped, all reasons."""
        return sum(self.skipped.values())


@dataclass
class LoadReport:
    """Per-file counts of rows read, kept and skipped (by reason, with examples)."""

    folder: str
    files: dict[str, FileReport] = field(default_factory=dict)

    @property
    def n_skipped(self) -> int:
        """Rows skipped over all files."""
        return sum(f.n_skipped for f in self.files.values())

    def skipped_by_reason(self) -> dict[str, int]:
        """Rows skipped over all files, by reason."""
        out: dict[str, int] = {}
        for f in self.files.values():
            for reason, n in f.skipped.items():
                out[reason] = out.get(reason, 0) + n
        return out

    def summary(self) -> str:
        """A human-readable account: one line per file that lost rows, with examples."""
        lines = [
            f"MRCLAM {self.folder}: {sum(f.rows_kept for f in self.files.values())} rows kept, "
            f"{self.n_skipped} skipped"
        ]
        for f in self.files.values():
            if not f.skipped:
                continue
            counts = ", ".join(f"{n} {reason}" for reason, n in sorted(f.skipped.items()))
            lines.append(f"  {f.file}: {f.rows_kept}/{f.rows_read} kept; skipped {counts}")
            for reason, examples in sorted(f.examples.items()):
                for ex in examples:
                    lines.append(f"    line {ex.line} ({reason}): {ex.text!r}")
        return "\n".join(lines)

    def to_dict(self) -> dict[str, object]:
        """JSON-ready form (for summary.json files)."""
        return {
            "folder": self.folder,
            "n_skipped": self.n_skipped,
            "skipped_by_reason": self.skipped_by_reason(),
            "files": {
                name: {
                    "rows_read": f.rows_read,
                    "rows_kept": f.rows_kept,
                    "skipped": dict(f.skipped),
                    "examples": {
                        r: [{"line": e.line, "text": e.text} for e in ex]
                        for r, ex in f.examples.items()
                    },
                }
                for name, f in self.files.items()
            },
        }


# ----------------------------------------------------------------------------------------------
# Table parsing (vectorised on the happy path, per row only where something is wrong)
# ----------------------------------------------------------------------------------------------

_BLANK = b" \t\r"  # stripped from both ends of a line
_SEPARATOR = re.compile(rb"[ \t]+")
_NUMERAL = re.compile(
    rb"[+-]?(?:(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?|(?i:nan|inf|infinity))"
)
# rows made only of these (joined by \n) may take the fast path
_FAST_PATH_BYTES = b"0123456789+-.eE \t\n"


def data_row(line: bytes) -> bytes | None:
    """``line`` stripped of blanks at both ends, or None for a blank or ``#`` comment line (a
    data row is everything else, module docstring)."""
    row = line.strip(_BLANK)
    return row if row and not row.startswith(b"#") else None


def finite_numeral(token: bytes) -> float | None:
    """The column ``token`` when it is a finite numeral as the loader reads one (ASCII decimal,
    no ``_``), else None."""
    if not _NUMERAL.fullmatch(token):
        return None
    x = float(token)
    return x if math.isfinite(x) else None


def leading_time(row: bytes) -> float | None:
    """The first column of the data row ``row`` when it is a finite numeral as the loader reads
    one (:func:`finite_numeral`), else None."""
    return finite_numeral(_SEPARATOR.split(row, maxsplit=1)[0])


@dataclass(frozen=True)
class _Column:
    """A column of a table: its name and the interval its values must lie in.

    The interval is ``[low, high]``, or ``(low, high]`` when ``open_low``; ``integer`` columns
    (ids) must also hold whole numbers.
    """

    name: str
    low: float
    high: float
    open_low: bool = False
    integer: bool = False

    @property
    def interval(self) -> str:
        """The interval as text, e.g. ``(0, 100]``."""
        return f"{'(' if self.open_low else '['}{_bound_text(self.low)}, {_bound_text(self.high)}]"

    def accepts(self, x: FloatArray) -> tuple[BoolArray, BoolArray]:
        """``(whole, inside)`` masks: whole numbers where required, values inside the interval."""
        whole = x == np.round(x) if self.integer else np.ones(x.shape, dtype=bool)
        above = x > self.low if self.open_low else x >= self.low
        return np.asarray(whole), np.asarray(above & (x <= self.high))


def _bound_text(x: float) -> str:
    """A bound as text: whole numbers exactly, others to 6 significant digits."""
    return str(int(x)) if float(x).is_integer() and abs(x) < 1e15 else f"{x:.6g}"


_TIME = _Column("time", 0.0, MAX_UNIX_TIME_S)
_SUBJECT = _Column("subject", 1, MAX_ID, integer=True)
_BARCODE = _Column("barcode", 1, MAX_ID, integer=True)
_X = _Column("x", -MAX_ABS_POSITION_M, MAX_ABS_POSITION_M)
_Y = _Column("y", -MAX_ABS_POSITION_M, MAX_ABS_POSITION_M)
_BARCODES_COLUMNS = (_SUBJECT, _BARCODE)
_LANDMARK_COLUMNS = (
    _SUBJECT,
    _X,
    _Y,
    _Column("x std-dev", 0.0, MAX_ABS_POSITION_M),
    _Column("y std-dev", 0.0, MAX_ABS_POSITION_M),
)
_GROUNDTRUTH_COLUMNS = (_TIME, _X, _Y, _Column("theta", -MAX_ABS_ANGLE_RAD, MAX_ABS_ANGLE_RAD))
_ODOMETRY_COLUMNS = (
    _TIME,
    _Column("v", -MAX_SPEED_M_S, MAX_SPEED_M_S),
    _Column("omega", -MAX_YAW_RATE_RAD_S, MAX_YAW_RATE_RAD_S),
)
_MEASUREMENT_COLUMNS = (
    _TIME,
    _BARCODE,
    _Column("range", 0.0, MAX_RANGE_M, open_low=True),
    _Column("bearing", -MAX_ABS_ANGLE_RAD, MAX_ABS_ANGLE_RAD),
)


class _RowSink:
    """Collects the skipped rows of one file, or raises at the first one in strict mode."""

    def __init__(
        self, path: Path, lines: list[bytes], report: FileReport, options: MrclamOptions
    ) -> None:
        self.path = path
        self.lines = lines
        self.report = report
        self.options = options

    def text(self, line: int) -> str:
        """Line ``line`` (1-based) without its blanks, non-ASCII bytes written as ``\\xNN``."""
        return self.lines[line - 1].strip(_BLANK).decode("ascii", errors="backslashreplace")

    def skip(self, line: int, reason: str) -> None:
        text = self.text(line)
        if self.options.on_bad_row == "raise":
            raise DataError(f"{self.path}:{line}: {reason}: {text!r}")
        self.report.skipped[reason] = self.report.skipped.get(reason, 0) + 1
        kept = self.report.examples.setdefault(reason, [])
        if len(kept) < self.options.max_examples:
            kept.append(SkippedRow(line, reason, text))

    def skip_many(self, lines: IntArray, reason: str) -> None:
        for ln in np.asarray(lines).tolist():
            self.skip(int(ln), reason)


def _read_lines(path: Path) -> list[bytes]:
    """The bytes of ``path`` cut at ``\\n`` (DataError if it is missing or not a readable file)."""
    try:
        if not path.is_file():
            what = "not a regular file" if path.exists() else "file missing"
            raise DataError(f"{path}: {what} (an MRCLAM folder needs this file)")
        data = path.read_bytes()
    except OSError as exc:
        raise DataError(f"{path}: cannot read: {exc}") from exc
    return data.split(b"\n")


def _parse_fast(rows: list[bytes], ncols: int) -> FloatArray | None:
    """numpy's C parser over all rows at once; ``None`` unless every row is ``ncols`` numerals.

    Only rows made of digits, ``+-.eE``, spaces and tabs are handed to numpy; on those its parser
    accepts and reads exactly what :func:`_parse_rows` does.
    """
    if not rows:
        return np.zeros((0, ncols))
    body = b"\n".join(rows)
    if body.translate(None, _FAST_PATH_BYTES):
        return None
    try:
        values = np.loadtxt(body.decode("ascii").split("\n"), dtype=float, ndmin=2, comments=None)
    except ValueError:
        return None
    return values if values.shape == (len(rows), ncols) else None


def _parse_rows(
    rows: list[bytes], numbers: list[int], ncols: int, sink: _RowSink
) -> tuple[FloatArray, IntArray]:
    """Slow path for a file with bad rows: parse each row, skip (count) the unusable ones."""
    parsed: list[list[float]] = []
    kept: list[int] = []
    for ln, row in zip(numbers, rows, strict=True):
        if not row.isascii():
            sink.skip(ln, "non-ASCII bytes")
            continue
        tokens = _SEPARATOR.split(row)
        if len(tokens) != ncols:
            sink.skip(ln, f"expected {ncols} columns")
            continue
        if not all(_NUMERAL.fullmatch(tok) for tok in tokens):
            sink.skip(ln, "non-numeric value")
            continue
        parsed.append([float(tok) for tok in tokens])
        kept.append(ln)
    return np.array(parsed, dtype=float).reshape(len(parsed), ncols), np.array(kept, np.int64)


def _check_columns(
    values: FloatArray, line_no: IntArray, columns: tuple[_Column, ...], sink: _RowSink
) -> tuple[FloatArray, IntArray]:
    """Keep the rows whose values are finite and inside every column's bounds (skip the rest).

    Checks run in column order and each row is skipped for the first check it fails.
    """
    finite = np.isfinite(values).all(axis=1)
    sink.skip_many(line_no[~finite], "non-finite value")
    values, line_no = values[finite], line_no[finite]
    for col, column in enumerate(columns):
        whole, inside = column.accepts(values[:, col])
        sink.skip_many(line_no[~whole], f"non-integer {column.name}")
        sink.skip_many(line_no[whole & ~inside], f"{column.name} outside {column.interval}")
        ok = whole & inside
        values, line_no = values[ok], line_no[ok]
    return values, line_no


def _read_table(
    path: Path,
    columns: tuple[_Column, ...],
    report: LoadReport,
    options: MrclamOptions,
    *,
    min_rows: int = 0,
) -> tuple[FloatArray, IntArray, _RowSink]:
    """The usable rows of a table: ``(values (n, ncols), 1-based line numbers, sink)``.

    Every data row is counted in the file's report (``rows_read``); unusable ones are skipped
    there. ``sink`` is returned so that the caller can skip more rows of the same file.
    """
    lines = _read_lines(path)
    file_report = FileReport(path.name)
    report.files[path.name] = file_report
    sink = _RowSink(path, lines, file_report, options)
    numbered = [(i, row) for i, line in enumerate(lines, start=1) if (row := data_row(line))]
    numbers = [i for i, _ in numbered]
    rows = [row for _, row in numbered]
    file_report.rows_read = len(rows)
    fast = _parse_fast(rows, len(columns))
    if fast is not None:
        values, line_no = fast, np.array(numbers, dtype=np.int64)
    else:
        values, line_no = _parse_rows(rows, numbers, len(columns), sink)
    values, line_no = _check_columns(values, line_no, columns, sink)
    if len(values) < min_rows:
        raise DataError(
            f"{path}: {len(values)} usable rows, need at least {min_rows} "
            f"({file_report.n_skipped} of {file_report.rows_read} data rows skipped)"
        )
    return values, line_no, sink


def _reject_repeats(path: Path, what: str, keys: FloatArray, line_no: IntArray) -> None:
    """DataError at the first key listed twice (a table names each subject or barcode once)."""
    first: dict[int, int] = {}
    for key, ln in zip(keys.astype(np.int64).tolist(), line_no.tolist(), strict=True):
        if key in first:
            raise DataError(f"{path}:{ln}: {what} {key} listed twice (first at line {first[key]})")
        first[key] = ln


def _monotonic_mask(
    t: FloatArray,
    line_no: IntArray,
    sink: _RowSink,
    *,
    duplicates: Literal["allow", "keep_first", "keep_last"],
) -> BoolArray:
    """Rows to keep so that time never goes backwards (and, unless allowed, never repeats).

    The rows of :func:`_longest_ordered` are kept and the others skipped ("time goes
    backwards"). Of the rows kept, equal times are all kept ("allow"), or all but the first /
    last of a run are skipped.
    """
    if len(t) == 0:
        return np.ones(0, dtype=bool)
    keep = _longest_ordered(t)
    if not keep.all():
        sink.skip_many(line_no[~keep], "time goes backwards")
    if duplicates == "allow":
        return np.asarray(keep)
    idx = np.flatnonzero(keep)
    tk = t[idx]
    if duplicates == "keep_first":
        repeat = np.concatenate(([False], tk[1:] == tk[:-1]))
        reason = "duplicate time stamp (first kept)"
    else:
        repeat = np.concatenate((tk[:-1] == tk[1:], [False]))
        reason = "duplicate time stamp (superseded by the next row)"
    if repeat.any():
        sink.skip_many(line_no[idx[repeat]], reason)
        keep[idx[repeat]] = False
    return np.asarray(keep)


def _longest_ordered(t: FloatArray) -> BoolArray:
    """Mask of a longest non-decreasing subsequence of ``t``: among the longest, the one whose
    indices come first in lexicographic order (module docstring, "Time order";
    :func:`relloc.datasets.time_order.longest_non_decreasing` with ``prefer="earlier"``). A
    sorted ``t`` keeps every row without the search."""
    keep = np.zeros(len(t), dtype=bool)
    if len(t) == 0 or bool(np.all(t[1:] >= t[:-1])):
        keep[:] = True
        return keep
    keep[longest_non_decreasing(t.tolist(), prefer="earlier")] = True
    return keep


# ----------------------------------------------------------------------------------------------
# Data containers
# ----------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class PoseQuery:
    """Ground truth at query times. ``valid = inside & ~in_gap``.

    Invalid queries still carry the interpolated (or end-clamped) value so that callers can
    choose; they must not use it as truth silently.
    """

    t: FloatArray
    x: FloatArray
    y: FloatArray
    theta: FloatArray
    inside: BoolArray
    in_gap: BoolArray

    @property
    def valid(self) -> BoolArray:
        """Queries inside the recorded span and not inside a long gap."""
        return np.asarray(self.inside & ~self.in_gap)

    @property
    def pose(self) -> FloatArray:
        """``(n, 3)`` array of (x, y, θ)."""
        return np.stack([self.x, self.y, self.theta], axis=-1)


@dataclass(frozen=True)
class GroundTruth:
    """Vicon pose track of one robot: strictly increasing times (s, dataset clock)."""

    t: FloatArray
    x: FloatArray
    y: FloatArray
    theta: FloatArray
    gap_threshold: float

    def __post_init__(self) -> None:
        columns = {"x": self.x, "y": self.y, "theta": self.theta}
        check_columns("mrclam GroundTruth", self.t, columns, strictly=True)
        if not (_is_number(self.gap_threshold) and 0 < self.gap_threshold < math.inf):
            raise DataError(
                "mrclam GroundTruth.gap_threshold: must be a positive number, got "
                f"{self.gap_threshold!r}"
            )

    @property
    def gaps(self) -> FloatArray:
        """``(k, 2)`` (start, end) of every gap longer than ``gap_threshold``."""
        dt = np.diff(self.t)
        i = np.flatnonzero(dt > self.gap_threshold)
        return np.stack([self.t[i], self.t[i + 1]], axis=-1) if len(i) else np.zeros((0, 2))

    def at(self, t_query: ArrayLike, *, gap_threshold: float | None = None) -> PoseQuery:
        """Pose at ``t_query`` (x, y linear; θ on the circle), with validity flags.

        A query is ``in_gap`` when the two samples around it are more than ``gap_threshold``
        (default: the dataset's) apart — a query at a sample is measured, never in a gap, at
        either end of one (as :meth:`relloc.core.recording.GroundTruth.valid_at` rules) — and
        not ``inside`` outside ``[t[0], t[-1]]``.
        """
        tq = np.atleast_1d(np.asarray(t_query, dtype=float))
        if not np.isfinite(tq).all():
            raise DataError("GroundTruth.at: query times must be finite")
        limit = self.gap_threshold if gap_threshold is None else float(gap_threshold)
        if len(self.t) == 0:
            nan = np.full(tq.shape, np.nan)
            no = np.zeros(tq.shape, dtype=bool)
            return PoseQuery(tq, nan, nan.copy(), nan.copy(), no, no.copy())
        inside = (tq >= self.t[0]) & (tq <= self.t[-1])
        hi = np.clip(np.searchsorted(self.t, tq, side="left"), 1, max(len(self.t) - 1, 1))
        lo = hi - 1
        if len(self.t) > 1:
            span = self.t[hi] - self.t[lo]
            at_sample = (tq == self.t[lo]) | (tq == self.t[hi])
            in_gap = inside & (span > limit) & ~at_sample
        else:
            in_gap = np.zeros(tq.shape, dtype=bool)
        x = np.interp(tq, self.t, self.x)
        y = np.interp(tq, self.t, self.y)
        theta = circular_interp(tq, self.t, self.theta)
        return PoseQuery(tq, x, y, np.asarray(theta), np.asarray(inside), np.asarray(in_gap))


@dataclass(frozen=True)
class Odometry:
    """Commanded body velocities of one robot: ``v`` (m/s forward), ``omega`` (rad/s)."""

    t: FloatArray
    v: FloatArray
    omega: FloatArray

    def __post_init__(self) -> None:
        check_columns("mrclam Odometry", self.t, {"v": self.v, "omega": self.omega})

    def at(self, t_query: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Zero-order hold of the last command at or before each query (0 before the first)."""
        tq = np.atleast_1d(np.asarray(t_query, dtype=float))
        i = np.searchsorted(self.t, tq, side="right") - 1
        started = i >= 0
        ic = np.clip(i, 0, max(len(self.t) - 1, 0))
        if len(self.t) == 0:
            return np.zeros(tq.shape), np.zeros(tq.shape)
        v = np.where(started, self.v[ic], 0.0)
        w = np.where(started, self.omega[ic], 0.0)
        return v, w


@dataclass(frozen=True)
class Measurements:
    """Camera observations of one robot: time, subject (mapped from barcode), range, bearing.

    Times are non-decreasing; several rows may share one time (one camera frame).
    """

    t: FloatArray
    subject: IntArray
    barcode: IntArray
    range: FloatArray
    bearing: FloatArray

    def __post_init__(self) -> None:
        columns = {
            "subject": self.subject,
            "barcode": self.barcode,
            "range": self.range,
            "bearing": self.bearing,
        }
        check_columns("mrclam Measurements", self.t, columns, integer=("subject", "barcode"))

    def __len__(self) -> int:
        return len(self.t)

    def of_subject(self, subject: int) -> Measurements:
        """Only the observations of ``subject``."""
        m = self.subject == subject
        return Measurements(
            self.t[m], self.subject[m], self.barcode[m], self.range[m], self.bearing[m]
        )


@dataclass(frozen=True)
class RobotData:
    """Everything recorded by and about one robot."""

    subject: int
    barcode: int
    groundtruth: GroundTruth
    odometry: Odometry
    measurements: Measurements


@dataclass(frozen=True)
class Landmarks:
    """Static landmarks: subject ids, world positions and their standard deviations."""

    subject: IntArray
    xy: FloatArray
    std: FloatArray

    def position(self, subject: int) -> FloatArray:
        """World (x, y) of landmark ``subject`` (DataError if unknown)."""
        idx = np.flatnonzero(self.subject == subject)
        if len(idx) == 0:
            raise DataError(f"landmark {subject} is not in {LANDMARKS_FILE}")
        return np.asarray(self.xy[idx[0]])


@dataclass(frozen=True)
class MrclamDataset:
    """A loaded MRCLAM folder on one clock (seconds since ``t0_unix``)."""

    path: Path
    t0_unix: float
    barcodes: Mapping[int, int]
    robots: Mapping[int, RobotData]
    landmarks: Landmarks
    report: LoadReport

    @property
    def robot_ids(self) -> tuple[int, ...]:
        """Subjects of the robots loaded, ascending."""
        return tuple(sorted(self.robots))

    @property
    def duration(self) -> float:
        """Latest time stamp of any robot file (s since ``t0_unix``)."""
        ends = []
        for r in self.robots.values():
            for arr in (r.groundtruth.t, r.odometry.t, r.measurements.t):
                if len(arr):
                    ends.append(float(arr[-1]))
        return max(ends) if ends else 0.0

    @property
    def truth_span(self) -> tuple[float, float]:
        """``(start, end)``: the span in which every robot has ground truth, from the latest
        first stamp to the earliest last stamp of the ``Robot*_Groundtruth.dat`` files (s since
        ``t0_unix``; a robot's Vicon record may end before the others' and before its own
        odometry: robot 1's at 771.9 s of run 6's 900 s). The loader gives every robot at least
        two ground-truth rows."""
        truth = [self.robots[s].groundtruth.t for s in self.robot_ids]
        return max(float(t[0]) for t in truth), min(float(t[-1]) for t in truth)

    @property
    def truth_end(self) -> float:
        """The latest ground-truth stamp of any robot (s since ``t0_unix``): where a replay
        can still be scored (rows of other files after it have no truth to score against)."""
        return max(float(r.groundtruth.t[-1]) for r in self.robots.values())

    def robot(self, subject: int) -> RobotData:
        """The data of robot ``subject`` (DataError naming the loaded ones if unknown)."""
        if subject not in self.robots:
            raise DataError(
                f"robot {subject} is not in {self.path} (robots: {list(self.robot_ids)})"
            )
        return self.robots[subject]

    def is_robot(self, subject: ArrayLike) -> BoolArray:
        """Mask of subjects that are robots of this dataset."""
        return np.isin(np.asarray(subject), np.asarray(self.robot_ids))


# ----------------------------------------------------------------------------------------------
# Loading
# ----------------------------------------------------------------------------------------------


def _load_barcodes(folder: Path, report: LoadReport, options: MrclamOptions) -> dict[int, int]:
    """``barcode -> subject``; a barcode or subject listed twice is an error."""
    path = folder / BARCODES_FILE
    values, line_no, sink = _read_table(path, _BARCODES_COLUMNS, report, options, min_rows=1)
    _reject_repeats(path, "subject", values[:, 0], line_no)
    _reject_repeats(path, "barcode", values[:, 1], line_no)
    ids = values.astype(np.int64).tolist()
    sink.report.rows_kept = len(ids)
    return {barcode: subject for subject, barcode in ids}


def _load_landmarks(
    folder: Path, report: LoadReport, options: MrclamOptions, robots: Sequence[int] = ()
) -> Landmarks:
    """The landmark table; a subject listed twice, or one of the ``robots`` loaded, is an error
    (module docstring)."""
    path = folder / LANDMARKS_FILE
    values, line_no, sink = _read_table(path, _LANDMARK_COLUMNS, report, options)
    _reject_repeats(path, "landmark subject", values[:, 0], line_no)
    robot_set = {int(r) for r in robots}
    for subject, ln in zip(values[:, 0].astype(np.int64).tolist(), line_no.tolist(), strict=True):
        if subject in robot_set:
            others = " and ".join(f"Robot{subject}_{kind}.dat" for kind in ROBOT_KINDS[1:])
            raise DataError(
                f"{folder / f'Robot{subject}_Groundtruth.dat'} (and {others}) make subject "
                f"{subject} a robot, but {path}:{ln} lists subject {subject} as a landmark; a "
                f"subject is one or the other (its barcode could not tell a camera which it saw)"
            )
    sink.report.rows_kept = len(values)
    return Landmarks(
        subject=values[:, 0].astype(np.int64), xy=values[:, 1:3].copy(), std=values[:, 3:5].copy()
    )


def _discover_robots(folder: Path, options: MrclamOptions) -> list[int]:
    """Subjects to load (found ``RobotN_*`` names or ``options.robots``), each with all 3 files."""
    if not folder.is_dir():
        raise DataError(
            f"{folder}: not a folder (expected an MRCLAM dataset folder: give one with "
            f"--dataset DIR, or {DATA_HINT})"
        )
    found: dict[int, set[str]] = {}
    try:
        names = [p.name for p in folder.iterdir()]
    except OSError as exc:
        raise DataError(f"{folder}: cannot list the folder: {exc}") from exc
    for name in names:
        m = _ROBOT_FILE.fullmatch(name)
        if m:
            found.setdefault(int(m.group(1)), set()).add(m.group(2))
    wanted = sorted(found) if options.robots is None else sorted({int(r) for r in options.robots})
    if not wanted:
        raise DataError(f"{folder}: no RobotN_Groundtruth/Odometry/Measurement.dat files")
    for n in wanted:
        missing = [k for k in ROBOT_KINDS if k not in found.get(n, set())]
        if missing:
            raise DataError(
                f"{folder / f'Robot{n}_{missing[0]}.dat'}: file missing "
                f"(robot {n} needs {', '.join(f'Robot{n}_{k}.dat' for k in ROBOT_KINDS)})"
            )
    return wanted


def load_mrclam(folder: Path | str, options: MrclamOptions | None = None) -> MrclamDataset:
    """Load an MRCLAM-layout folder (see the module docstring for what is guaranteed).

    Raises:
        DataError: a required file is missing or unusable, or (``on_bad_row="raise"``) a row is bad.
    """
    opts = options or MrclamOptions()
    folder = Path(folder)
    robot_ids = _discover_robots(folder, opts)
    report = LoadReport(str(folder))
    barcode_to_subject = _load_barcodes(folder, report, opts)
    landmarks = _load_landmarks(folder, report, opts, robot_ids)
    subject_to_barcode = {s: b for b, s in barcode_to_subject.items()}
    for n in robot_ids:
        if n not in subject_to_barcode:
            skipped = report.files[BARCODES_FILE].examples
            lines = sorted(
                f"line {e.line} ({reason})" for reason, ex in skipped.items() for e in ex
            )
            also = f"; rows skipped: {', '.join(lines)}" if lines else ""
            raise DataError(f"{folder / BARCODES_FILE}: robot {n} has no barcode{also}")

    on_unix_clock = {
        n: RobotData(
            subject=n,
            barcode=subject_to_barcode[n],
            groundtruth=_load_groundtruth(folder / f"Robot{n}_Groundtruth.dat", report, opts),
            odometry=_load_odometry(folder / f"Robot{n}_Odometry.dat", report, opts),
            measurements=_load_measurements(
                folder / f"Robot{n}_Measurement.dat", barcode_to_subject, report, opts
            ),
        )
        for n in robot_ids
    }
    # The common clock: the earliest time stamp of any row kept (every ground truth has one).
    t0 = min(_earliest_time(robot) for robot in on_unix_clock.values())
    _check_run_length(folder, on_unix_clock, t0)
    decimals = _clock_decimals(on_unix_clock.values())
    return MrclamDataset(
        path=folder,
        t0_unix=t0,
        barcodes=dict(barcode_to_subject),
        robots={n: _on_clock(robot, t0, decimals) for n, robot in on_unix_clock.items()},
        landmarks=landmarks,
        report=report,
    )


def _check_run_length(folder: Path, robots: Mapping[int, RobotData], t0: float) -> None:
    """DataError naming the file of a row stamped more than :data:`MAX_RUN_S` after the run's
    first stamp ``t0``: a clock jump (every later use samples the whole span on a grid)."""
    for n, robot in robots.items():
        for kind, t in zip(ROBOT_KINDS, _tables(robot), strict=True):
            if len(t) and float(t[-1]) - t0 > MAX_RUN_S:
                late = float(t[np.argmax(t - t0 > MAX_RUN_S)])
                raise DataError(
                    f"{folder / f'Robot{n}_{kind}.dat'}: a row stamped {late:.3f} lies "
                    f"{late - t0:.6g} s after the run's first stamp {t0:.3f}; a run lasts at "
                    f"most {MAX_RUN_S:g} s (a clock jump?)"
                )


def _earliest_time(robot: RobotData) -> float:
    """Earliest time stamp in any of the robot's (time-sorted, possibly empty) tables."""
    return min(float(t[0]) for t in _tables(robot) if len(t))


#: Finest decimal step the relative clock is rounded to (:func:`_clock_decimals`).
MAX_CLOCK_DECIMALS = 12


def _clock_decimals(robots: Iterable[RobotData]) -> int:
    """Decimals of the finest step ``10⁻ᵈ`` that the absolute stamps resolve: the smallest
    ``d`` with ``10⁻ᵈ ≥ ulp(|t|)`` at the largest stamp (at most :data:`MAX_CLOCK_DECIMALS`).

    A decimal stamp read into a float carries an error of up to half an ulp — 1.2e-7 s at Unix
    times near 1.2e9 s, where the ulp is 2.4e-7 s and ``d`` = 6. Rounded to ``10⁻ᵈ``, the
    difference of two stamps is the difference of the decimals written in the file (for a file
    written to ``d`` decimals or fewer, as MRCLAM's milliseconds are) and no longer depends on
    the clock's epoch; without it a sample written at the same millisecond as a grid point lands
    on either side of it by the float error alone, and fits that hold a command between stamps
    change with the date of the recording."""
    largest = max(
        (float(np.max(np.abs(t))) for r in robots for t in _tables(r) if len(t)), default=0.0
    )
    ulp = float(np.spacing(largest)) if largest > 0 else 0.0
    if ulp <= 10.0**-MAX_CLOCK_DECIMALS:
        return MAX_CLOCK_DECIMALS
    return int(-math.ceil(math.log10(ulp)))


def _tables(robot: RobotData) -> tuple[FloatArray, FloatArray, FloatArray]:
    """The time columns of the robot's three tables."""
    return robot.groundtruth.t, robot.odometry.t, robot.measurements.t


def _on_clock(robot: RobotData, t0: float, decimals: int) -> RobotData:
    """``robot`` with every time stamp made relative to ``t0``, rounded to ``decimals``
    (:func:`_clock_decimals`)."""

    def relative(t: FloatArray) -> FloatArray:
        return np.round(t - t0, decimals)

    return replace(
        robot,
        groundtruth=replace(robot.groundtruth, t=relative(robot.groundtruth.t)),
        odometry=replace(robot.odometry, t=relative(robot.odometry.t)),
        measurements=replace(robot.measurements, t=relative(robot.measurements.t)),
    )


def _load_groundtruth(path: Path, report: LoadReport, opts: MrclamOptions) -> GroundTruth:
    """Vicon track on the Unix clock: strictly increasing times (repeats keep the first row)."""
    values, line_no, sink = _read_table(path, _GROUNDTRUTH_COLUMNS, report, opts, min_rows=2)
    keep = _monotonic_mask(values[:, 0], line_no, sink, duplicates="keep_first")
    values = values[keep]
    if len(values) < 2:
        raise DataError(f"{path}: fewer than 2 usable ground-truth rows")
    sink.report.rows_kept = len(values)
    return GroundTruth(
        t=values[:, 0].copy(),
        x=values[:, 1].copy(),
        y=values[:, 2].copy(),
        theta=values[:, 3].copy(),
        gap_threshold=opts.gap_threshold,
    )


def _load_odometry(path: Path, report: LoadReport, opts: MrclamOptions) -> Odometry:
    """Commands on the Unix clock: strictly increasing times (repeats keep the last row)."""
    values, line_no, sink = _read_table(path, _ODOMETRY_COLUMNS, report, opts, min_rows=1)
    keep = _monotonic_mask(values[:, 0], line_no, sink, duplicates="keep_last")
    values = values[keep]
    sink.report.rows_kept = len(values)
    return Odometry(t=values[:, 0].copy(), v=values[:, 1].copy(), omega=values[:, 2].copy())


def _load_measurements(
    path: Path,
    barcode_to_subject: Mapping[int, int],
    report: LoadReport,
    opts: MrclamOptions,
) -> Measurements:
    """Camera rows on the Unix clock with known barcodes; times non-decreasing."""
    values, line_no, sink = _read_table(path, _MEASUREMENT_COLUMNS, report, opts)
    barcodes = values[:, 1].astype(np.int64)
    known_codes = np.fromiter(barcode_to_subject.keys(), dtype=np.int64)
    known = np.isin(barcodes, known_codes)
    if not known.all():
        sink.skip_many(line_no[~known], "unknown barcode")
        values, line_no, barcodes = values[known], line_no[known], barcodes[known]
    keep = _monotonic_mask(values[:, 0], line_no, sink, duplicates="allow")
    values, barcodes = values[keep], barcodes[keep]
    sink.report.rows_kept = len(values)
    return Measurements(
        t=values[:, 0].copy(),
        subject=_map_barcodes(barcodes, barcode_to_subject),
        barcode=barcodes,
        range=values[:, 2].copy(),
        bearing=values[:, 3].copy(),
    )


def _map_barcodes(barcodes: IntArray, barcode_to_subject: Mapping[int, int]) -> IntArray:
    """Vectorised ``barcode -> subject`` for barcodes known to be in the table."""
    codes = np.array(sorted(barcode_to_subject), dtype=np.int64)
    subjects = np.array([barcode_to_subject[int(c)] for c in codes], dtype=np.int64)
    if len(barcodes) == 0:
        return np.zeros(0, dtype=np.int64)
    return np.asarray(subjects[np.searchsorted(codes, barcodes)], dtype=np.int64)


# ----------------------------------------------------------------------------------------------
# Dataset → Recording
# ----------------------------------------------------------------------------------------------

#: Skip reasons of :func:`to_recording` (counted per measurement file in ``Recording.skips``).
UNMAPPED_SUBJECT = "subject is neither another robot nor a landmark"
REPEATED_READING = "repeated reading of one subject in one camera frame"


def to_recording(ds: MrclamDataset) -> rec.Recording:
    """The dataset as a :class:`relloc.core.recording.Recording` (the pipeline's input).

    Robots ``"1"`` … (their subject ids) on the ground; odometry ``(v, 0, 0, ω)`` as commanded
    (MRCLAM states no noise: ``sigma`` is 0, the estimator's odometry model supplies it);
    every camera reading a ``"range_bearing"`` row of another robot (``target``) or of a
    landmark (``landmark``, indexed in the order of ``Landmark_Groundtruth.dat``, positions
    ``(x, y, 0)``), rows of one time sorted in robot order, ``sigma`` not stated; the Vicon
    ground truth ``(x, y, 0, θ)`` with its gaps (``GroundTruth.gap_s``).

    Readings the table cannot hold are skipped and counted per measurement file
    (:data:`UNMAPPED_SUBJECT`: a robot seeing itself or a subject in no table;
    :data:`REPEATED_READING`: the same subject again at the same time stamp, the first kept);
    ``skips`` holds them with everything the loader skipped. ``meta`` holds the robots' and
    landmarks' subject ids and the clock offset ``t0_unix``.
    """
    robots = ds.robot_ids
    parts, conversion = [], {}
    for observer, rid in enumerate(robots):
        rows, skipped = _camera_rows(ds, rid, observer)
        parts.append(rows)
        conversion[f"Robot{rid}_Measurement.dat"] = skipped
    return rec.Recording(
        robots=tuple(str(rid) for rid in robots),
        platforms=("ground",) * len(robots),
        odometry=tuple(_unicycle_odometry(ds.robot(rid)) for rid in robots),
        measurements=rec.Measurements.concatenate(parts),
        truth=tuple(_pose_truth(ds.robot(rid)) for rid in robots),
        landmarks=np.column_stack([ds.landmarks.xy, np.zeros(len(ds.landmarks.subject))]),
        source=str(ds.path),
        meta={
            "robot_subjects": tuple(robots),
            "landmark_subjects": tuple(int(s) for s in ds.landmarks.subject),
            "t0_unix": ds.t0_unix,
        },
        skips=_skip_report(ds.report, conversion),
    )


def _camera_rows(
    ds: MrclamDataset, rid: int, observer: int
) -> tuple[rec.Measurements, dict[str, int]]:
    """Robot ``rid``'s camera readings as ``"range_bearing"`` rows, and what was skipped."""
    index = {r: i for i, r in enumerate(ds.robot_ids) if r != rid}
    lm_index = {int(s): k for k, s in enumerate(ds.landmarks.subject)}
    m = ds.robot(rid).measurements
    target = np.array([index.get(int(s), rec.NO_TARGET) for s in m.subject], dtype=np.int64)
    landmark = np.array([lm_index.get(int(s), rec.NO_TARGET) for s in m.subject], dtype=np.int64)
    mapped = (target != rec.NO_TARGET) | (landmark != rec.NO_TARGET)
    first = np.zeros(len(m), dtype=bool)
    key = np.stack([m.t, m.subject.astype(float)], axis=1)
    first[np.unique(key, axis=0, return_index=True)[1]] = True
    keep = mapped & first
    rows = rec.measurement_rows(
        "range_bearing",
        t=m.t[keep],
        observer=observer,
        target=target[keep],
        landmark=landmark[keep],
        value=np.column_stack([m.range[keep], m.bearing[keep]]),
    )
    skipped = {
        UNMAPPED_SUBJECT: int((~mapped).sum()),
        REPEATED_READING: int((mapped & ~first).sum()),
    }
    return rows, skipped


def _unicycle_odometry(robot: RobotData) -> rec.Odometry:
    """Commands ``(v, 0, 0, ω)``; no noise is stated (``sigma`` 0)."""
    od = robot.odometry
    zero = np.zeros(len(od.t))
    return rec.Odometry(
        t=od.t,
        velocity=np.column_stack([od.v, zero, zero, od.omega]),
        sigma=np.zeros(4),
        where=f"Robot{robot.subject}_Odometry.dat",
    )


def _pose_truth(robot: RobotData) -> rec.GroundTruth:
    """Vicon poses ``(x, y, 0, θ)``; samples further apart than the dataset's gap threshold
    enclose a gap (:attr:`relloc.core.recording.GroundTruth.gap_s`)."""
    g = robot.groundtruth
    return rec.GroundTruth(
        t=g.t,
        pose=np.column_stack([g.x, g.y, np.zeros(len(g.t)), g.theta]),
        where=f"Robot{robot.subject}_Groundtruth.dat",
        gap_s=g.gap_threshold,
    )


def _skip_report(report: LoadReport, conversion: Mapping[str, Mapping[str, int]]) -> rec.SkipReport:
    """The loader's report with the conversion's skips added to their files (counts only: the
    conversion works on loaded rows, whose line numbers are gone)."""
    files = []
    for name, f in report.files.items():
        extra = {r: n for r, n in conversion.get(name, {}).items() if n}
        files.append(
            rec.FileSkips(
                file=name,
                rows_read=f.rows_read,
                rows_kept=f.rows_kept - sum(extra.values()),
                skipped={**f.skipped, **extra},
                examples=tuple(
                    rec.SkippedRow(e.line, e.reason, e.text)
                    for ex in f.examples.values()
                    for e in ex
                ),
            )
        )
    return rec.SkipReport(files=tuple(files))
