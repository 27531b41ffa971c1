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

What the loader guarantees
--------------------------
- **One clock.** Every time is relative to ``t0_unix``, the earliest time stamp of any robot
  file; the absolute offset is kept in :attr:`MrclamDataset.t0_unix`.
- **Nothing lost silently.** A row with the wrong number of columns, a non-numeric or non-finite
  value, a non-integer id, an unknown barcode, a time going backwards, or (ground truth and
  odometry) a repeated time stamp is either skipped and *counted* in the :class:`LoadReport`
  (default; the first few examples per file and reason are kept with their line numbers) or,
  with ``MrclamOptions(on_bad_row="raise")``, raises :class:`~relloc.errors.DataError` naming
  the file and line. Missing files and unusable tables always raise ``DataError``.
  Measurement rows legitimately share time stamps (one camera frame sees several subjects);
  only a time going backwards is a fault there.
- **Duplicate odometry stamps**: the later row is kept (it is the command in force from then on)
  and the earlier one is counted as superseded. Duplicate ground-truth stamps keep the first.
- **Ground truth at query times** (:meth:`GroundTruth.at`): x, y linearly interpolated, θ on the
  circle (unwrap, interpolate, wrap); each query is flagged when it lies outside the recorded span
  or inside a gap between consecutive samples longer than ``gap_threshold`` (the robot moved
  unobserved there, so interpolation is a guess).
- **Odometry at query times** (:meth:`Odometry.at`): zero-order hold of the last command (the
  robots keep moving through logging gaps; before the first command they stand still).
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from relloc.core import recording as rec
from relloc.core.angles import circular_interp
from relloc.errors import ConfigError, DataError

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
BoolArray = NDArray[np.bool_]

BARCODES_FILE = "Barcodes.dat"
LANDMARKS_FILE = "Landmark_Groundtruth.dat"
_ROBOT_FILE = re.compile(r"^Robot(\d+)_(Groundtruth|Odometry|Measurement)\.dat$")
_ROBOT_KINDS = ("Groundtruth", "Odometry", "Measurement")


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
        if not (np.isfinite(self.gap_threshold) and self.gap_threshold > 0):
            raise ConfigError(f"gap_threshold must be a positive number, got {self.gap_threshold}")
        if self.max_examples < 0:
            raise ConfigError(f"max_examples must be ≥ 0, got {self.max_examples}")
        if self.robots is not None:
            if len(self.robots) == 0 or any(int(r) < 1 for r in self.robots):
                raise ConfigError(f"robots must be positive subject ids, got {self.robots}")


@dataclass(frozen=True)
class SkippedRow:
    """One example of a skipped row: 1-based line number, reason and the raw text."""

    line: int
    reason: str
    text: str


@dataclass
class FileReport:
    """What happened to the rows of one file."""

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


class _RowSink:
    """Collects skipped rows of one file, or raises at the first one in strict mode."""

    def __init__(self, path: Path, report: FileReport, options: MrclamOptions) -> None:
        self.path = path
        self.report = report
        self.options = options

    def skip(self, line: int, reason: str, text: str) -> None:
        if self.options.on_bad_row == "raise":
            raise DataError(f"{self.path}:{line}: {reason}: {text!r}")
        self.report.skipped[reason] = self.report.skipped.get(reason, 0) + 1
        kept = self.report.examples.setdefault(reason, [])
        if len(kept) < self.options.max_examples:
            kept.append(SkippedRow(line, reason, text))

    def skip_many(self, lines: IntArray, reason: str, texts: list[str]) -> None:
        for ln in np.asarray(lines).tolist():
            self.skip(int(ln), reason, texts[int(ln) - 1].strip())


# ----------------------------------------------------------------------------------------------
# Table parsing (vectorised on the happy path, per row only where something is wrong)
# ----------------------------------------------------------------------------------------------


def _is_data(line: str) -> bool:
    """A line that is neither blank nor a ``#`` comment."""
    stripped = line.lstrip()
    return bool(stripped) and not stripped.startswith("#")


def _parse_fast(
    raw: list[str], numbers: list[int], ncols: int
) -> tuple[FloatArray | None, list[int]]:
    """numpy's C parser over all data lines; ``None`` when any line is not ``ncols`` numbers."""
    if not numbers:
        return np.zeros((0, ncols)), []
    try:
        values = np.loadtxt([raw[i - 1] for i in numbers], dtype=float, ndmin=2, comments=None)
    except ValueError:
        return None, []
    if values.shape != (len(numbers), ncols):
        return None, []
    return values, numbers


def _parse_row_by_row(
    raw: list[str], numbers: list[int], ncols: int, sink: _RowSink
) -> tuple[FloatArray, list[int]]:
    """Slow path for a file with bad rows: parse each row, skip (count) the unusable ones."""
    rows: list[list[float]] = []
    kept: list[int] = []
    for ln in numbers:
        text = raw[ln - 1].strip()
        toks = text.split()
        if len(toks) != ncols:
            sink.skip(ln, f"expected {ncols} columns", text)
            continue
        try:
            rows.append([float(t) for t in toks])
        except ValueError:
            sink.skip(ln, "non-numeric value", text)
            continue
        kept.append(ln)
    return np.array(rows, dtype=float).reshape(len(rows), ncols), kept


def _read_table(
    path: Path, ncols: int, sink: _RowSink, *, min_rows: int = 0
) -> tuple[FloatArray, IntArray, list[str]]:
    """Parse a whitespace table into ``(values (n, ncols), 1-based line numbers, raw lines)``.

    Rows with the wrong column count, a non-numeric or a non-finite value are skipped (counted).
    """
    if not path.is_file():
        raise DataError(f"{path}: file missing (an MRCLAM folder needs it)")
    try:
        text = path.read_text(encoding="utf-8", errors="replace")
    except OSError as exc:
        raise DataError(f"{path}: cannot read: {exc}") from exc
    raw = text.splitlines()
    numbers = [i for i, line in enumerate(raw, start=1) if _is_data(line)]
    sink.report.rows_read = len(numbers)
    values, keep_numbers = _parse_fast(raw, numbers, ncols)
    if values is None:
        values, keep_numbers = _parse_row_by_row(raw, numbers, ncols, sink)
    line_no = np.asarray(keep_numbers, dtype=np.int64)
    finite = np.isfinite(values).all(axis=1)
    if not finite.all():
        sink.skip_many(line_no[~finite], "non-finite value", raw)
        values, line_no = values[finite], line_no[finite]
    if len(values) < min_rows:
        raise DataError(
            f"{path}: {len(values)} usable rows, need at least {min_rows} "
            f"({sink.report.n_skipped} skipped)"
        )
    return values, line_no, raw


def _integer_column(
    values: FloatArray, col: int, line_no: IntArray, raw: list[str], sink: _RowSink, what: str
) -> BoolArray:
    """Mask of rows whose column ``col`` holds an integer (others are skipped, counted)."""
    ok = values[:, col] == np.round(values[:, col])
    if not ok.all():
        sink.skip_many(line_no[~ok], f"non-integer {what}", raw)
    return np.asarray(ok)


def _monotonic_mask(
    t: FloatArray,
    line_no: IntArray,
    raw: list[str],
    sink: _RowSink,
    *,
    duplicates: Literal["allow", "keep_first", "keep_last"],
) -> BoolArray:
    """Rows to keep so that time never goes backwards (and, unless allowed, never repeats).

    A row whose time is earlier than the latest time kept so far is skipped ("time goes
    backwards"). Equal times are kept ("allow"), or all but the first / last of a run are skipped.
    """
    if len(t) == 0:
        return np.ones(0, dtype=bool)
    running_max = np.maximum.accumulate(t)
    prev_max = np.concatenate(([-np.inf], running_max[:-1]))
    keep = t >= prev_max
    if not keep.all():
        sink.skip_many(line_no[~keep], "time goes backwards", raw)
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
        sink.skip_many(line_no[idx[repeat]], reason, raw)
        keep[idx[repeat]] = False
    return np.asarray(keep)


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

    @property
    def gaps(self) -> FloatArray:
        """``(k, 2)`` (start, end) of every gap longer than ``gap_threshold``."""
        dt = np.diff(self.t)
        i = np.flatnonzero(dt > self.gap_threshold)
        return np.stack([self.t[i], self.t[i + 1]], axis=-1) if len(i) else np.zeros((0, 2))

    def at(self, t_query: ArrayLike, *, gap_threshold: float | None = None) -> PoseQuery:
        """Pose at ``t_query`` (x, y linear; θ on the circle), with validity flags.

        A query is ``in_gap`` when the two samples around it are more than ``gap_threshold``
        (default: the dataset's) apart, and not ``inside`` outside ``[t[0], t[-1]]``.
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
        span = self.t[hi] - self.t[lo] if len(self.t) > 1 else np.zeros(tq.shape)
        in_gap = inside & (span > limit)
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


def _sink(path: Path, report: LoadReport, options: MrclamOptions) -> _RowSink:
    file_report = FileReport(path.name)
    report.files[path.name] = file_report
    return _RowSink(path, file_report, options)


def _load_barcodes(folder: Path, report: LoadReport, options: MrclamOptions) -> dict[int, int]:
    """``barcode -> subject``; a barcode or subject listed twice is an error."""
    path = folder / BARCODES_FILE
    sink = _sink(path, report, options)
    values, line_no, raw = _read_table(path, 2, sink, min_rows=1)
    ok = _integer_column(values, 0, line_no, raw, sink, "subject") & _integer_column(
        values, 1, line_no, raw, sink, "barcode"
    )
    table: dict[int, int] = {}
    subjects: set[int] = set()
    for (subject, barcode), ln in zip(values[ok].astype(np.int64), line_no[ok], strict=True):
        if int(barcode) in table or int(subject) in subjects:
            raise DataError(f"{path}:{ln}: subject {subject} or barcode {barcode} listed twice")
        table[int(barcode)] = int(subject)
        subjects.add(int(subject))
    sink.report.rows_kept = len(table)
    return table


def _load_landmarks(folder: Path, report: LoadReport, options: MrclamOptions) -> Landmarks:
    path = folder / LANDMARKS_FILE
    sink = _sink(path, report, options)
    values, line_no, raw = _read_table(path, 5, sink)
    ok = _integer_column(values, 0, line_no, raw, sink, "subject")
    values = values[ok]
    sink.report.rows_kept = len(values)
    return Landmarks(
        subject=values[:, 0].astype(np.int64), xy=values[:, 1:3].copy(), std=values[:, 3:5].copy()
    )


def _discover_robots(folder: Path, options: MrclamOptions) -> list[int]:
    if not folder.is_dir():
        raise DataError(f"{folder}: not a folder (expected an MRCLAM dataset folder)")
    found: dict[int, set[str]] = {}
    for p in folder.iterdir():
        m = _ROBOT_FILE.match(p.name)
        if m:
            found.setdefault(int(m.group(1)), set()).add(m.group(2))
    wanted = sorted(found) if options.robots is None else sorted(set(options.robots))
    if not wanted:
        raise DataError(f"{folder}: no RobotN_Groundtruth/Odometry/Measurement.dat files")
    for n in wanted:
        missing = [k for k in _ROBOT_KINDS if k not in found.get(n, set())]
        if missing:
            raise DataError(
                f"{folder / f'Robot{n}_{missing[0]}.dat'}: file missing "
                f"(robot {n} needs {', '.join(f'Robot{n}_{k}.dat' for k in _ROBOT_KINDS)})"
            )
    return wanted


def _first_time(path: Path) -> float | None:
    """Earliest finite time stamp in column 0 of a file (cheap scan of its first data rows)."""
    with path.open(encoding="utf-8", errors="replace") as fh:
        for line in fh:
            toks = line.split()
            if not toks or toks[0].startswith("#"):
                continue
            try:
                value = float(toks[0])
            except ValueError:
                continue
            if np.isfinite(value):
                return value
    return None


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
    landmarks = _load_landmarks(folder, report, opts)
    subject_to_barcode = {s: b for b, s in barcode_to_subject.items()}
    for n in robot_ids:
        if n not in subject_to_barcode:
            raise DataError(f"{folder / BARCODES_FILE}: robot {n} has no barcode")

    # The common clock: earliest time stamp of any robot file (the files are time-sorted, so
    # this is the first row; if an early row is bad the next one is taken).
    paths = {(n, k): folder / f"Robot{n}_{k}.dat" for n in robot_ids for k in _ROBOT_KINDS}
    firsts = [t for t in (_first_time(p) for p in paths.values()) if t is not None]
    if not firsts:
        raise DataError(f"{folder}: no time stamp in any robot file")
    t0 = float(min(firsts))

    robots: dict[int, RobotData] = {}
    for n in robot_ids:
        robots[n] = RobotData(
            subject=n,
            barcode=subject_to_barcode[n],
            groundtruth=_load_groundtruth(paths[(n, "Groundtruth")], t0, report, opts),
            odometry=_load_odometry(paths[(n, "Odometry")], t0, report, opts),
            measurements=_load_measurements(
                paths[(n, "Measurement")], t0, barcode_to_subject, report, opts
            ),
        )
    return MrclamDataset(
        path=folder,
        t0_unix=t0,
        barcodes=dict(barcode_to_subject),
        robots=robots,
        landmarks=landmarks,
        report=report,
    )


def _load_groundtruth(
    path: Path, t0: float, report: LoadReport, opts: MrclamOptions
) -> GroundTruth:
    sink = _sink(path, report, opts)
    values, line_no, raw = _read_table(path, 4, sink, min_rows=2)
    keep = _monotonic_mask(values[:, 0], line_no, raw, sink, duplicates="keep_first")
    values = values[keep]
    if len(values) < 2:
        raise DataError(f"{path}: fewer than 2 usable ground-truth rows")
    sink.report.rows_kept = len(values)
    return GroundTruth(
        t=values[:, 0] - t0,
        x=values[:, 1].copy(),
        y=values[:, 2].copy(),
        theta=values[:, 3].copy(),
        gap_threshold=opts.gap_threshold,
    )


def _load_odometry(path: Path, t0: float, report: LoadReport, opts: MrclamOptions) -> Odometry:
    sink = _sink(path, report, opts)
    values, line_no, raw = _read_table(path, 3, sink)
    keep = _monotonic_mask(values[:, 0], line_no, raw, sink, duplicates="keep_last")
    values = values[keep]
    sink.report.rows_kept = len(values)
    return Odometry(t=values[:, 0] - t0, v=values[:, 1].copy(), omega=values[:, 2].copy())


def _load_measurements(
    path: Path,
    t0: float,
    barcode_to_subject: Mapping[int, int],
    report: LoadReport,
    opts: MrclamOptions,
) -> Measurements:
    sink = _sink(path, report, opts)
    values, line_no, raw = _read_table(path, 4, sink)
    ok = _integer_column(values, 1, line_no, raw, sink, "barcode")
    values, line_no = values[ok], line_no[ok]
    barcodes = values[:, 1].astype(np.int64)
    known_codes = np.fromiter(barcode_to_subject.keys(), dtype=np.int64)
    known = np.isin(barcodes, known_codes)
    if not known.all():
        sink.skip_many(line_no[~known], "unknown barcode", raw)
        values, line_no, barcodes = values[known], line_no[known], barcodes[known]
    keep = _monotonic_mask(values[:, 0], line_no, raw, sink, duplicates="allow")
    values, barcodes = values[keep], barcodes[keep]
    sink.report.rows_kept = len(values)
    return Measurements(
        t=values[:, 0] - t0,
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
# Odometry error model fitted against ground truth
# ----------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class OdometryNoiseFit:
    """Equivalent white-noise standard deviations of one robot's odometry channels.

    ``sigma_v`` (forward speed), ``sigma_lateral`` (sideways speed a unicycle reports as 0) in
    m/s and ``sigma_w`` (yaw rate) in rad/s, for noise drawn independently at every step of a
    ``rate_hz`` propagation; ``bias_v``, ``bias_w`` are the mean errors (true − reported).
    """

    sigma_v: float
    sigma_lateral: float
    sigma_w: float
    bias_v: float
    bias_w: float
    rate_hz: float
    window_s: float
    n_windows: int


def fit_odometry_noise(
    robot: RobotData,
    *,
    t_start: float,
    t_end: float,
    rate_hz: float = 100.0,
    window_s: float = 1.0,
) -> OdometryNoiseFit:
    """Fit the white-noise level that explains the odometry's drift over ``window_s`` seconds.

    On a ``rate_hz`` grid the reported commands (zero-order hold) are integrated over windows of
    length ``W = window_s`` and compared with the ground-truth motion over the same window
    (body-frame increments ``cos θ Δx + sin θ Δy``, ``−sin θ Δx + cos θ Δy`` and ``Δθ``).
    White noise of standard deviation σ held over each step ``dt`` accumulates a displacement
    variance ``σ² dt W``, so the equivalent σ is ``sqrt(mean(D²) / (dt W))`` with ``D`` the
    windowed error (bias included, which makes the fit conservative). The real errors are
    correlated over seconds (command lag, scale errors), so a σ fitted for one window length
    is only right at that time scale. Windows touching a ground-truth gap are left out.
    """
    if not (rate_hz > 0 and window_s > 0 and t_end > t_start):
        raise ConfigError(
            f"fit_odometry_noise: need rate_hz > 0, window_s > 0, t_end > t_start; got "
            f"{rate_hz}, {window_s}, [{t_start}, {t_end}]"
        )
    dt = 1.0 / rate_hz
    steps = max(round(window_s * rate_hz), 1)
    n_windows = int((t_end - t_start) // (steps * dt))
    if n_windows < 2:
        raise DataError(
            f"robot {robot.subject}: [{t_start:g}, {t_end:g}] s holds fewer than two "
            f"{window_s:g} s windows for the odometry fit"
        )
    t = t_start + dt * np.arange(n_windows * steps + 1)
    q = robot.groundtruth.at(t)
    v_cmd, w_cmd = robot.odometry.at(t[:-1])
    c, s = np.cos(q.theta[:-1]), np.sin(q.theta[:-1])
    dx, dy = np.diff(q.x), np.diff(q.y)
    dth = np.diff(np.unwrap(q.theta))
    err = np.stack(
        [c * dx + s * dy - v_cmd * dt, -s * dx + c * dy, dth - w_cmd * dt], axis=-1
    ).reshape(n_windows, steps, 3)
    ok = q.valid[:-1].reshape(n_windows, steps).all(axis=1) & q.valid[steps::steps]
    if ok.sum() < 2:
        raise DataError(f"robot {robot.subject}: ground truth has gaps in every fit window")
    D = err[ok].sum(axis=1)
    sigma = np.sqrt(np.mean(D * D, axis=0) / (dt * window_s))
    bias = D.mean(axis=0) / window_s
    return OdometryNoiseFit(
        sigma_v=float(sigma[0]),
        sigma_lateral=float(sigma[1]),
        sigma_w=float(sigma[2]),
        bias_v=float(bias[0]),
        bias_w=float(bias[2]),
        rate_hz=float(rate_hz),
        window_s=float(window_s),
        n_windows=int(ok.sum()),
    )


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
    ground truth ``(x, y, 0, θ)`` (gaps are not marked: :meth:`GroundTruth.at` flags them).

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
    """Vicon poses ``(x, y, 0, θ)``."""
    g = robot.groundtruth
    return rec.GroundTruth(
        t=g.t,
        pose=np.column_stack([g.x, g.y, np.zeros(len(g.t)), g.theta]),
        where=f"Robot{robot.subject}_Groundtruth.dat",
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
