"""Property-based fuzzing of the MRCLAM loader (and of the runtime team log built on it).

Folders in the MRCLAM layout are generated from a small valid one by random mutations of its
files: rows replaced by random bytes or unicode text, tokens replaced by huge, NaN, negative or
non-ASCII numbers, columns dropped or added, rows duplicated or inserted, lines shuffled, line
endings changed, files emptied, cut down to their comments, deleted or replaced by directories.
Whatever the folder, the loader either raises a relloc error (``DataError`` / ``ConfigError``) or
returns a dataset in which every data row of every file is accounted for.

**Data rows** (what ``FileReport.rows_read`` must count): split the file's bytes at ``b"\\n"``;
strip spaces, tabs and carriage returns from both ends of each piece; the pieces left non-empty
that do not start with ``#`` are data rows (blank lines and ``#`` comments are not).
"""

from __future__ import annotations

import random
import re
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from relloc.datasets.mrclam import (
    MAX_RANGE_M,
    MAX_UNIX_TIME_S,
    MrclamDataset,
    MrclamOptions,
    load_mrclam,
)
from relloc.errors import ConfigError, DataError
from relloc.runtime.dataset import mrclam_team_recording

T0 = 1_000_000_000.0
HEADER = [b"# MRCLAM-layout fuzz file", b"# Time [s]  ...  (comment lines are not rows)"]
DIRECTORY = None  # marks a file replaced by a directory

# Tokens worth trying in any column: non-finite, huge, negative or zero values,
# ids that overflow an int64, other scripts' digits, Python-only float syntax, control characters.
NASTY_TOKENS = [
    "nan", "-inf", "Infinity", "1e308", "-1e308", "1e999", "1e19", "-1e19", "-1", "0", "-0",
    "1e-320", "4294967297", "2147483648", "3.5", "\u0661\u0664", "\uff11\uff14", "1_0", "0x1A",
    "+", ".", "e5", "", "#", "\x00", "\x0b", "\x0c", "\x1c", "\x85", "\u2028", "\u00a0", "\r", "é",
]  # fmt: skip


def data_rows(content: bytes) -> int:
    """Number of data rows in a file (module docstring)."""
    stripped = (line.strip(b" \t\r") for line in content.split(b"\n"))
    return sum(1 for s in stripped if s and not s.startswith(b"#"))


def _clean_files(seconds: float = 0.8) -> dict[str, list[bytes]]:
    """A valid folder: robots 1, 2, 3 (barcodes 5, 14, 41) and landmark 4 (barcode 63).

    Ground truth at 10 Hz, odometry at 5 Hz and measurements at 5 Hz for ``seconds``.
    """
    files = {
        "Barcodes.dat": [b"1 5", b"2 14", b"3 41", b"4 63"],
        "Landmark_Groundtruth.dat": [b"4 1.0 2.0 0.001 0.002"],
    }
    for n, other in ((1, 14), (2, 41), (3, 5)):
        t = T0 + 0.1 * np.arange(round(10 * seconds))
        files[f"Robot{n}_Groundtruth.dat"] = [
            f"{ti:.3f}\t{0.02 * i:.4f}\t{n:.1f}\t{np.angle(np.exp(0.05j * i)):.4f}".encode()
            for i, ti in enumerate(t)
        ]
        files[f"Robot{n}_Odometry.dat"] = [f"{ti + 0.05:.3f} 0.2 0.5".encode() for ti in t[::2]]
        files[f"Robot{n}_Measurement.dat"] = [
            f"{ti + 0.07:.3f}  {code}  {1.5 + 0.1 * n:.3f}  -0.1".encode()
            for ti, code in zip(t[::2], [other, 63] * len(t), strict=False)
        ]
    return {name: HEADER + rows for name, rows in files.items()}


# ----------------------------------------------------------------------------------------------
# Mutations
# ----------------------------------------------------------------------------------------------

junk_rows = st.one_of(
    st.binary(max_size=40),
    st.text(max_size=30).map(lambda s: s.encode("utf-8")),
    st.lists(st.sampled_from(NASTY_TOKENS), max_size=6).map(lambda t: " ".join(t).encode()),
)
tokens = st.one_of(
    st.sampled_from(NASTY_TOKENS),
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
    st.integers(min_value=-(2**70), max_value=2**70).map(str),
    st.text(alphabet="0123456789+-.eE", min_size=1, max_size=8),
).map(lambda s: s.encode("utf-8"))
ROW_KINDS = ["replace_row", "insert_row", "replace_token", "drop_column", "add_column", "repeat"]
LINE_KINDS = ["shuffle", "crlf", "unterminated"]  # the rows stay, their order or endings change
FILE_KINDS = ["empty", "comments_only", "directory", "delete"]  # the file loses every row


@dataclass(frozen=True)
class Mutation:
    """One change to file ``name``: ``kind`` at row ``where`` / column ``col`` with ``data``
    (indices wrap around the rows and columns there are; unused fields are ignored)."""

    kind: str
    name: str
    where: int
    col: int
    data: bytes


@st.composite
def mutations(draw: st.DrawFn, names: list[str], kinds: list[str]) -> Mutation:
    """A mutation of one of ``names``: tokens for token edits, junk rows for row edits."""
    kind = draw(st.sampled_from(kinds))
    data = draw(tokens if kind in ("replace_token", "add_column") else junk_rows)
    index = st.integers(min_value=0, max_value=10**6)
    return Mutation(kind, draw(st.sampled_from(names)), draw(index), draw(index), data)


def _mutate_rows(rows: list[bytes], m: Mutation) -> list[bytes]:
    """``rows`` after a row-level mutation (a copy)."""
    rows = list(rows)
    if m.kind == "insert_row":
        rows.insert(m.where % (len(rows) + 1), m.data)
        return rows
    if not rows:
        return rows
    i = m.where % len(rows)
    cols = rows[i].split()
    if m.kind == "replace_row":
        rows[i] = m.data
    elif m.kind == "repeat":
        rows[i:i] = [rows[i]] * (1 + m.col % 2)
    elif m.kind == "add_column":
        cols.insert(m.col % (len(cols) + 1), m.data)
        rows[i] = b" ".join(cols)
    elif cols and m.kind in ("replace_token", "drop_column"):
        if m.kind == "replace_token":
            cols[m.col % len(cols)] = m.data
        else:
            del cols[m.col % len(cols)]
        rows[i] = b" ".join(cols)
    return rows


def apply(files: dict[str, list[bytes]], todo: list[Mutation]) -> dict[str, bytes | None]:
    """The folder after ``todo``: name -> file bytes, or ``DIRECTORY``; deleted names absent."""
    lines = {name: list(rows) for name, rows in files.items()}
    gone: dict[str, bytes | None] = {}
    unterminated: set[str] = set()
    for m in todo:
        if m.name not in lines:  # deleted or replaced by a directory already
            continue
        if m.kind in ROW_KINDS:
            lines[m.name] = _mutate_rows(lines[m.name], m)
        elif m.kind == "shuffle":
            random.Random(m.where).shuffle(lines[m.name])
        elif m.kind == "crlf":
            lines[m.name] = [row + b"\r" for row in lines[m.name]]
        elif m.kind == "unterminated":
            unterminated.add(m.name)
        elif m.kind == "empty":
            lines[m.name] = []
        elif m.kind == "comments_only":
            lines[m.name] = list(HEADER)
        else:
            del lines[m.name]
            if m.kind == "directory":
                gone[m.name] = DIRECTORY
    end = {name: b"" if name in unterminated or not rows else b"\n" for name, rows in lines.items()}
    return gone | {name: b"\n".join(rows) + end[name] for name, rows in lines.items()}


@st.composite
def folders(
    draw: st.DrawFn, kinds: list[str], seconds: float = 0.8, max_mutations: int = 5
) -> dict[str, bytes | None]:
    """A folder after up to ``max_mutations`` mutations of ``kinds`` (see :func:`apply`)."""
    files = _clean_files(seconds)
    todo = st.lists(mutations(sorted(files), kinds), max_size=max_mutations)
    return apply(files, draw(todo))


def write(folder: dict[str, bytes | None], root: Path) -> Path:
    root.mkdir()
    for name, content in folder.items():
        if content is DIRECTORY:
            (root / name).mkdir()
        else:
            assert isinstance(content, bytes)
            (root / name).write_bytes(content)
    return root


# ----------------------------------------------------------------------------------------------
# Properties
# ----------------------------------------------------------------------------------------------


def _check_accounting(ds: MrclamDataset, folder: dict[str, bytes | None]) -> set[tuple[str, int]]:
    """Every data row kept or skipped, examples on their true lines; returns the skipped rows."""
    expected = {"Barcodes.dat", "Landmark_Groundtruth.dat"} | {
        f"Robot{n}_{kind}.dat"
        for n in ds.robot_ids
        for kind in ("Groundtruth", "Odometry", "Measurement")
    }
    assert set(ds.report.files) == expected
    skipped: set[tuple[str, int]] = set()
    for name, fr in ds.report.files.items():
        content = folder[name]
        assert isinstance(content, bytes)
        assert fr.rows_read == data_rows(content)
        assert fr.rows_kept + fr.n_skipped == fr.rows_read
        lines = content.split(b"\n")
        for reason, examples in fr.examples.items():
            assert len(examples) == fr.skipped[reason]  # max_examples is large: all are kept
            for ex in examples:
                raw = lines[ex.line - 1].strip(b" \t\r")
                assert raw and not raw.startswith(b"#")
                assert ex.text == raw.decode("ascii", errors="backslashreplace")
                skipped.add((name, ex.line))
    assert len(skipped) == ds.report.n_skipped  # no row is skipped twice
    return skipped


def _check_contents(ds: MrclamDataset) -> None:
    """Kept counts match the arrays; values are finite, in bounds and on one sorted clock."""
    files = ds.report.files
    assert len(ds.barcodes) == files["Barcodes.dat"].rows_kept
    assert len(ds.landmarks.subject) == files["Landmark_Groundtruth.dat"].rows_kept
    assert len(set(ds.landmarks.subject.tolist())) == len(ds.landmarks.subject)
    assert 0.0 <= ds.t0_unix <= MAX_UNIX_TIME_S
    starts = []
    for n in ds.robot_ids:
        r = ds.robot(n)
        gt, odo, meas = r.groundtruth, r.odometry, r.measurements
        assert len(gt.t) == files[f"Robot{n}_Groundtruth.dat"].rows_kept >= 2
        assert len(odo.t) == files[f"Robot{n}_Odometry.dat"].rows_kept >= 1
        assert len(meas) == files[f"Robot{n}_Measurement.dat"].rows_kept
        for arr in (gt.t, gt.x, gt.y, gt.theta, odo.t, odo.v, odo.omega, meas.t, meas.bearing):
            assert np.isfinite(arr).all()
        assert np.all(np.diff(gt.t) > 0) and np.all(np.diff(odo.t) > 0)
        assert np.all(np.diff(meas.t) >= 0)
        assert np.all((meas.range > 0) & (meas.range <= MAX_RANGE_M))
        assert set(meas.barcode.tolist()) <= set(ds.barcodes)
        assert np.array_equal(meas.subject, [ds.barcodes[b] for b in meas.barcode.tolist()])
        starts += [float(a[0]) for a in (gt.t, odo.t, meas.t) if len(a)]
    assert min(starts) == 0.0  # the clock starts at the earliest row kept
    assert 0.0 <= ds.duration <= MAX_UNIX_TIME_S


def test_the_unmutated_folders_load_without_a_skip() -> None:
    """The starting points of the fuzzing are valid (else mutations would prove little)."""
    with tempfile.TemporaryDirectory() as tmp:
        for seconds in (0.8, 20.0):
            root = write(apply(_clean_files(seconds), []), Path(tmp) / f"ds{seconds}")
            ds = load_mrclam(root, MrclamOptions(on_bad_row="raise"))
            assert ds.robot_ids == (1, 2, 3) and ds.report.n_skipped == 0
        log = mrclam_team_recording(root, np.random.default_rng(0), duration_s=12.0)
        assert log.span == (0.0, 12.0)


_STRICT_LINE = re.compile(r"/([^/]+\.dat):(\d+): ")


def _check_folder(folder: dict[str, bytes | None]) -> None:
    """Skip mode raises a relloc error or accounts for every row; strict mode agrees with it."""
    with tempfile.TemporaryDirectory() as tmp:
        root = write(folder, Path(tmp) / "ds")
        try:
            ds: MrclamDataset | None = load_mrclam(root, MrclamOptions(max_examples=10**6))
        except (DataError, ConfigError):
            ds = None
        skipped: set[tuple[str, int]] = set()
        if ds is not None:
            skipped = _check_accounting(ds, folder)
            _check_contents(ds)
        # strict mode fails exactly when something was skipped, at one of the skipped rows
        try:
            strict = load_mrclam(root, MrclamOptions(on_bad_row="raise"))
        except DataError as exc:
            if ds is not None:
                m = _STRICT_LINE.search(str(exc))
                assert m is not None, str(exc)
                assert (m.group(1), int(m.group(2))) in skipped
        else:
            assert ds is not None and not skipped
            assert strict.t0_unix == ds.t0_unix and strict.robot_ids == ds.robot_ids


@settings(derandomize=True, max_examples=80, deadline=None, database=None)
@given(folder=folders(ROW_KINDS * 2 + LINE_KINDS))
def test_mangled_rows_are_each_kept_or_counted_or_raise_a_relloc_error(
    folder: dict[str, bytes | None],
) -> None:
    _check_folder(folder)


@settings(derandomize=True, max_examples=30, deadline=None, database=None)
@given(folder=folders(ROW_KINDS + LINE_KINDS + FILE_KINDS * 2, max_mutations=3))
def test_mangled_files_raise_a_relloc_error_or_load_with_every_row_accounted_for(
    folder: dict[str, bytes | None],
) -> None:
    _check_folder(folder)


@settings(derandomize=True, max_examples=40, deadline=None, database=None)
@given(token=st.text(alphabet="0123456789+-.eE", min_size=1, max_size=10))
def test_fast_and_row_by_row_parsing_accept_and_read_the_same_numerals(token: str) -> None:
    """A clean file is parsed by numpy at once; one bad row sends it row by row. Both agree."""
    files = _clean_files()
    files["Landmark_Groundtruth.dat"] = [*HEADER, f"4 {token} 2.0 0.001 0.002".encode()]
    with tempfile.TemporaryDirectory() as tmp:
        fast = load_mrclam(write(apply(files, []), Path(tmp) / "fast"))
        files["Landmark_Groundtruth.dat"].append(b"not a row")
        slow = load_mrclam(write(apply(files, []), Path(tmp) / "slow"))
    slow_skips = dict(slow.report.files["Landmark_Groundtruth.dat"].skipped)
    assert slow_skips.pop("expected 5 columns") == 1
    assert fast.report.files["Landmark_Groundtruth.dat"].skipped == slow_skips
    np.testing.assert_array_equal(fast.landmarks.xy, slow.landmarks.xy)


@settings(derandomize=True, max_examples=25, deadline=None, database=None)
@given(folder=folders(ROW_KINDS + LINE_KINDS + FILE_KINDS, seconds=20.0, max_mutations=3))
def test_the_runtime_team_recording_raises_only_relloc_errors(
    folder: dict[str, bytes | None],
) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        root = write(folder, Path(tmp) / "ds")
        try:
            rec = mrclam_team_recording(root, np.random.default_rng(0), duration_s=12.0)
        except (DataError, ConfigError):
            return
    assert len(rec.robots) >= 2
    m = rec.measurements
    assert np.isfinite(m.value[:, :3]).all() and set(m.kind_names()) <= {"range_bearing_elevation"}
