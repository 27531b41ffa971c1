"""The MRCLAM loader keeps the most rows in time order (a longest non-decreasing subsequence of
the stamps) and skips only the others as "time goes backwards" (module docstring, "Time order").

A row out of place costs itself, not the rows after it: two swapped rows of run 6 cost 2 (the
rule before skipped every row between them), one far-future row costs 1.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from relloc.datasets.mrclam import (
    FileReport,
    MrclamOptions,
    _longest_ordered,
    _monotonic_mask,
    _RowSink,
    load_mrclam,
)
from relloc.errors import DataError

BACKWARDS = "time goes backwards"
HEADER = "# MRCLAM-layout test file\n# written by the test\n# format line\n# columns\n"
T0 = 1_000_000_000.0


# ----------------------------------------------------------------------------------------------
# Independent oracles (O(n²) dynamic programming)
# ----------------------------------------------------------------------------------------------


def _lnds_from(t: list[float]) -> list[int]:
    """``L[i]``: length of the longest non-decreasing subsequence of ``t`` starting at ``i``."""
    n = len(t)
    longest = [1] * n
    for i in range(n - 1, -1, -1):
        for j in range(i + 1, n):
            if t[j] >= t[i]:
                longest[i] = max(longest[i], 1 + longest[j])
    return longest


def _lnds_length(t: list[float]) -> int:
    """Length of a longest non-decreasing subsequence of ``t`` (DP over its last element)."""
    ending = [1] * len(t)
    for j in range(len(t)):
        for i in range(j):
            if t[i] <= t[j]:
                ending[j] = max(ending[j], ending[i] + 1)
    return max(ending, default=0)


def _lexicographically_first_lnds(t: list[float]) -> list[int]:
    """The indices of the longest non-decreasing subsequence that come first lexicographically:
    at each step the earliest row that keeps the order and can still complete a longest run."""
    longest = _lnds_from(t)
    need = max(longest, default=0)
    picked: list[int] = []
    for i, ti in enumerate(t):
        if need and longest[i] == need and (not picked or ti >= t[picked[-1]]):
            picked.append(i)
            need -= 1
    return picked


def _old_rule(t: list[float]) -> list[int]:
    """The rule before: keep a row unless it is earlier than the latest row kept before it."""
    kept: list[int] = []
    for i, ti in enumerate(t):
        if not kept or ti >= t[kept[-1]]:
            kept.append(i)
    return kept


# ----------------------------------------------------------------------------------------------
# By hand
# ----------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("stamps", "kept"),
    [
        ([], []),
        ([1.0], [0]),
        ([1.0, 2.0, 2.0, 3.0], [0, 1, 2, 3]),  # sorted, ties included: nothing skipped
        ([1.0, 2.0, 100.0, 3.0, 4.0, 5.0], [0, 1, 3, 4, 5]),  # far-future row: 1 skipped
        ([1.0, 2.0, 6.0, 4.0, 5.0, 3.0, 7.0], [0, 1, 3, 4, 6]),  # rows 3 and 6 swapped: 2
        ([1.0, 5.0, 3.0, 6.0], [0, 1, 3]),  # two longest runs: the earlier rows (as before)
        ([3.0, 2.0, 1.0], [0]),  # all backwards: the first row
        ([2.0, 2.0, 1.0, 1.0, 1.0], [2, 3, 4]),  # the longer run of ties wins
    ],
)
def test_the_longest_ordered_rows_are_kept(stamps: list[float], kept: list[int]) -> None:
    mask = _longest_ordered(np.array(stamps, dtype=float))
    assert np.flatnonzero(mask).tolist() == kept


def _write(folder: Path, name: str, rows: list[str]) -> None:
    (folder / name).write_text(HEADER + "\n".join(rows) + "\n")


def _small_folder(folder: Path) -> Path:
    """Robot 1 (barcode 5) and landmark 2 (barcode 63): 40 rows of each robot file, sorted."""
    folder.mkdir(parents=True)
    _write(folder, "Barcodes.dat", ["1 5", "2 63"])
    _write(folder, "Landmark_Groundtruth.dat", ["2 1.0 2.0 0.001 0.002"])
    _write(folder, "Robot1_Groundtruth.dat", [f"{T0 + 0.1 * i:.3f} 0.0 0.0 0.0" for i in range(40)])
    _write(folder, "Robot1_Odometry.dat", [f"{T0 + 0.1 * i:.3f} 0.1 0.0" for i in range(40)])
    # two readings per camera frame: shared stamps are in order
    _write(
        folder,
        "Robot1_Measurement.dat",
        [f"{T0 + 0.2 * (i // 2):.3f} 63 2.0 0.1" for i in range(40)],
    )
    return folder


@pytest.mark.parametrize(
    "file", ["Robot1_Groundtruth.dat", "Robot1_Odometry.dat", "Robot1_Measurement.dat"]
)
def test_a_sorted_file_skips_nothing(tmp_path: Path, file: str) -> None:
    ds = load_mrclam(_small_folder(tmp_path / "run"))
    report = ds.report.files[file]
    assert report.skipped == {} and report.rows_kept == report.rows_read == 40


@pytest.mark.parametrize(
    ("file", "row"),
    [
        ("Robot1_Groundtruth.dat", "{t} 0.0 0.0 0.0"),
        ("Robot1_Odometry.dat", "{t} 0.1 0.0"),
        ("Robot1_Measurement.dat", "{t} 63 2.0 0.1"),
    ],
)
@pytest.mark.parametrize("late_s", [500.0, 10 * 86_400.0])
def test_a_single_far_future_row_skips_only_itself(
    tmp_path: Path, file: str, row: str, late_s: float
) -> None:
    """Row 6 of 40 stamped ``late_s`` after the run's start: the old rule kept it and skipped
    the 34 rows after it; it is now the only row skipped (a skipped row sets no run length, so
    a day-plus clock jump in one row is not an error either)."""
    folder = _small_folder(tmp_path / "run")
    path = folder / file
    lines = path.read_text().split("\n")
    lines[4 + 5] = row.format(t=f"{T0 + late_s:.3f}")
    path.write_text("\n".join(lines))
    ds = load_mrclam(folder)
    report = ds.report.files[file]
    assert report.skipped == {BACKWARDS: 1}
    assert report.rows_kept == 39
    assert [e.line for e in report.examples[BACKWARDS]] == [10]
    assert f"line 10 ({BACKWARDS})" in ds.report.summary()
    with pytest.raises(DataError, match=f"{file}:10: {BACKWARDS}"):
        load_mrclam(folder, MrclamOptions(on_bad_row="raise"))


def test_duplicates_are_still_settled_among_the_rows_kept(tmp_path: Path) -> None:
    """A misplaced row next to a repeated stamp: the misplaced row is "backwards", the repeat is
    settled by the file's duplicate rule (odometry: the later command supersedes)."""
    folder = _small_folder(tmp_path / "run")
    rows = [f"{T0 + 0.1 * i:.3f} 0.1 0.0" for i in range(40)]
    rows[10] = f"{T0 + 0.9:.3f} 0.3 0.0"  # repeats row 9's stamp: supersedes it
    rows[20] = f"{T0 + 3.0:.3f} 0.1 0.0"  # ahead of its place
    _write(folder, "Robot1_Odometry.dat", rows)
    ds = load_mrclam(folder)
    report = ds.report.files["Robot1_Odometry.dat"]
    assert report.skipped == {BACKWARDS: 1, "duplicate time stamp (superseded by the next row)": 1}
    assert [e.line for e in report.examples[BACKWARDS]] == [25]
    odo = ds.robot(1).odometry
    assert len(odo.t) == 38 and np.all(np.diff(odo.t) > 0)
    assert odo.v[9] == pytest.approx(0.3)


# ----------------------------------------------------------------------------------------------
# The audit's case on the real run 6: lines 50 and 150 of a Robot2 file swapped
# ----------------------------------------------------------------------------------------------


def _robot2_of_run6(src: Path, dst: Path) -> Path:
    dst.mkdir(parents=True)
    for name in (
        "Barcodes.dat",
        "Landmark_Groundtruth.dat",
        "Robot2_Groundtruth.dat",
        "Robot2_Odometry.dat",
        "Robot2_Measurement.dat",
    ):
        shutil.copyfile(src / name, dst / name)
    return dst


@pytest.mark.parametrize("kind", ["Measurement", "Odometry", "Groundtruth"])
def test_two_swapped_lines_of_run6_skip_exactly_those_two(
    tmp_path: Path, kind: str, mrclam_run6: Path
) -> None:
    """Lines 50 and 150 of run 6's Robot2 files are data rows with distinct stamps, those of
    lines 51…149 lie strictly between them. Swapped, keeping the row now on line 50 would cost
    lines 51…149 (all earlier than it), keeping the one now on line 150 the same 99 rows (all
    later): the longest ordered set drops just the two, 2 skips (the old rule skipped 100)."""
    name = f"Robot2_{kind}.dat"
    clean = _robot2_of_run6(mrclam_run6, tmp_path / "clean")
    lines = (clean / name).read_bytes().split(b"\n")
    stamps = [float(line.split()[0]) for line in lines[49:150]]  # lines 50…150
    assert stamps[0] < min(stamps[1:-1]) and max(stamps[1:-1]) < stamps[-1]  # the premise

    swapped = _robot2_of_run6(mrclam_run6, tmp_path / "swapped")
    lines[49], lines[149] = lines[149], lines[49]
    (swapped / name).write_bytes(b"\n".join(lines))
    deleted = _robot2_of_run6(mrclam_run6, tmp_path / "deleted")
    (deleted / name).write_bytes(b"\n".join(lines[:49] + lines[50:149] + lines[150:]))

    before = load_mrclam(clean).report.files[name]
    ds = load_mrclam(swapped)
    report = ds.report.files[name]
    assert report.skipped == {**before.skipped, BACKWARDS: 2}
    assert report.rows_read == before.rows_read
    assert report.rows_kept == before.rows_kept - 2
    assert [e.line for e in report.examples[BACKWARDS]] == [50, 150]
    # what is kept is the file without the two rows, to the bit
    robot, expected = ds.robot(2), load_mrclam(deleted).robot(2)
    table = {"Measurement": "measurements", "Odometry": "odometry", "Groundtruth": "groundtruth"}[
        kind
    ]
    got, want = getattr(robot, table), getattr(expected, table)
    for column in ("t", "x", "y", "theta", "v", "omega", "subject", "barcode", "range", "bearing"):
        if hasattr(want, column):
            np.testing.assert_array_equal(getattr(got, column), getattr(want, column))
    if kind != "Measurement":  # strict loading stops at run 6's own odometry repeat first
        with pytest.raises(DataError, match=f"{name}:50: {BACKWARDS}"):
            load_mrclam(swapped, MrclamOptions(on_bad_row="raise"))


# ----------------------------------------------------------------------------------------------
# Properties
# ----------------------------------------------------------------------------------------------

# few distinct values, so that ties and long runs of misplaced rows are common
STAMPS = st.lists(st.integers(0, 12).map(float), max_size=40)


def _sink(n: int) -> _RowSink:
    lines = [f"{i}".encode() for i in range(1, n + 1)]
    return _RowSink(
        Path("Robot1_Measurement.dat"), lines, FileReport("Robot1_Measurement.dat"), MrclamOptions()
    )


@settings(max_examples=400, deadline=None)
@given(STAMPS)
def test_the_rows_kept_are_sorted_and_as_many_as_any_ordered_subsequence(
    stamps: list[float],
) -> None:
    t = np.array(stamps, dtype=float)
    sink = _sink(len(t))
    keep = _monotonic_mask(t, np.arange(1, len(t) + 1, dtype=np.int64), sink, duplicates="allow")
    kept = t[keep]
    assert np.all(np.diff(kept) >= 0)
    assert len(kept) == _lnds_length(stamps)
    assert sink.report.n_skipped == len(t) - len(kept)
    assert sink.report.skipped == ({BACKWARDS: len(t) - len(kept)} if len(kept) < len(t) else {})
    # among the longest, the lexicographically first (the earliest rows) …
    assert np.flatnonzero(keep).tolist() == _lexicographically_first_lnds(stamps)
    # … so wherever the old rule already kept a longest set, exactly that set
    old = _old_rule(stamps)
    if len(old) == len(kept):
        assert np.flatnonzero(keep).tolist() == old


@settings(max_examples=200, deadline=None)
@given(STAMPS, st.sampled_from(["keep_first", "keep_last"]))
def test_repeated_stamps_are_then_settled_among_the_ordered_rows(
    stamps: list[float], rule: str
) -> None:
    t = np.array(stamps, dtype=float)
    sink = _sink(len(t))
    keep = _monotonic_mask(t, np.arange(1, len(t) + 1, dtype=np.int64), sink, duplicates=rule)  # type: ignore[arg-type]
    kept = t[keep]
    assert np.all(np.diff(kept) > 0)
    ordered = _lexicographically_first_lnds(stamps)
    assert sink.report.skipped.get(BACKWARDS, 0) == len(t) - len(ordered)
    assert len(kept) == len(set(t[ordered].tolist()))
    assert sink.report.n_skipped == len(t) - len(kept)
