"""``relloc mrclam move``: an MRCLAM folder as if recorded in another world frame, at another
time and with other barcodes (:mod:`relloc.datasets.mrclam_move`)."""

from __future__ import annotations

import math
import tempfile
from decimal import Decimal
from pathlib import Path

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from relloc.cli import main
from relloc.cli.flags import barcode_map, number_pair
from relloc.datasets.mrclam import MrclamDataset, data_row, load_mrclam
from relloc.datasets.mrclam_move import move_mrclam
from relloc.errors import ConfigError, DataError

T0 = 1_000_000_000.0
HEADER = b"# MRCLAM-layout test file\n# Time [s] ...\n"
ROBOTS = {1: 5, 2: 14, 3: 41}  # subject -> barcode
LANDMARKS = {4: 63, 6: 81}
UNKNOWN_BARCODE = 50  # read by robot 2's camera, names no subject
#: Columns per file kind: "t" time, "xy" a position (two columns), "th" heading, "b" barcode,
#: "=" copied as it is.
COLUMNS = {
    "Barcodes": ("=", "b"),
    "Landmark": ("=", "xy", "xy", "=", "="),
    "Groundtruth": ("t", "xy", "xy", "th"),
    "Odometry": ("t", "=", "="),
    "Measurement": ("t", "b", "=", "="),
}


def _folder(root: Path) -> Path:
    """Three robots (subjects 1–3, barcodes 5, 14, 41) and two landmarks (4 and 6, barcodes 63
    and 81) on curved tracks: ground truth every 0.5 s, commands every 0.25 s over [0, 10) s,
    tab-separated as MRCLAM writes them; each robot sights the next one and a landmark every
    second, robot 2 also an unknown barcode; the earliest stamp is ``T0``."""
    root.mkdir(parents=True)
    codes = {**ROBOTS, **LANDMARKS}
    (root / "Barcodes.dat").write_bytes(
        HEADER + b"".join(f"  {s} \t  {b} \n".encode() for s, b in codes.items())
    )
    (root / "Landmark_Groundtruth.dat").write_bytes(
        HEADER + b"4 \t 1.25000000 \t -2.50000000 \t 0.00004570 \t 0.00027395\n"
        b"6 \t -3.10000000 \t 0.41000000 \t 0.00005198 \t 0.00026762\n"
    )
    for n in ROBOTS:
        other = ROBOTS[n % 3 + 1]
        gt = []
        for i in range(20):
            t = 0.5 * i
            x, y = n * math.cos(0.3 * t + n), 2.0 - n * math.sin(0.2 * t)
            th = math.remainder(0.4 * t + 2.0 * n, math.tau)
            gt.append(f"{T0 + t:.3f} \t {x:.8f} \t {y:.8f} \t {th:.8f}")
        odo = [f"{T0 + 0.25 * i:.3f} \t  0.086 \t -0.398" for i in range(40)]
        meas = []
        for i in range(10):
            meas.append(f"{T0 + i + 0.1:.3f} \t  {other} \t  1.500 \t  0.100")
            meas.append(f"{T0 + i + 0.1:.3f} \t  {63 if i % 2 else 81} \t  3.250 \t -0.700")
        if n == 2:
            meas.append(f"{T0 + 9.5:.3f} \t  {UNKNOWN_BARCODE} \t  2.000 \t  0.300")
        for kind, rows in (("Groundtruth", gt), ("Odometry", odo), ("Measurement", meas)):
            body = HEADER + b"\n".join(r.encode() for r in rows) + b"\n"
            (root / f"Robot{n}_{kind}.dat").write_bytes(body)
    return root


def _rows(path: Path) -> list[list[bytes]]:
    """The columns of every data row of ``path``."""
    rows = (data_row(line) for line in path.read_bytes().split(b"\n"))
    return [row.split() for row in rows if row is not None]


def _comments(path: Path) -> list[bytes]:
    return [ln for ln in path.read_bytes().split(b"\n") if ln.strip().startswith(b"#")]


def _kind(name: str) -> str:
    return name.split("_")[-1].removesuffix(".dat") if name.startswith("Robot") else name[:8]


def _inverse(rotation: float, shift: tuple[float, float]) -> tuple[float, tuple[float, float]]:
    """The move undoing ``p ↦ R(rotation) p + shift``: ``p ↦ R(−rotation) p − R(−rotation)
    shift``."""
    c, s = math.cos(rotation), math.sin(rotation)
    return -rotation, (-(c * shift[0] + s * shift[1]), -(-s * shift[0] + c * shift[1]))


def _relative_poses(ds: MrclamDataset) -> dict[tuple[int, int], np.ndarray]:
    """For every ordered pair of robots (i, j), at i's ground-truth times: j's position in i's
    body frame and j's heading relative to i's, the figures no world frame can change."""
    out = {}
    for i in ds.robot_ids:
        t = ds.robot(i).groundtruth.t
        a = ds.robot(i).groundtruth.at(t)
        for j in ds.robot_ids:
            if j == i:
                continue
            b = ds.robot(j).groundtruth.at(t)
            dx, dy = b.x - a.x, b.y - a.y
            c, s = np.cos(a.theta), np.sin(a.theta)
            dth = np.remainder(b.theta - a.theta + np.pi, 2 * np.pi) - np.pi
            out[i, j] = np.stack([c * dx + s * dy, -s * dx + c * dy, dth])
    return out


def _circular(a: float, b: float) -> float:
    return abs(math.remainder(a - b, math.tau))


@st.composite
def _barcode_maps(draw: st.DrawFn) -> dict[int, int]:
    """A one-to-one renumbering of some of the folder's barcodes: a permutation of them and a
    few fresh numbers, restricted to the folder's barcodes."""
    known = [*ROBOTS.values(), *LANDMARKS.values()]
    perm = draw(st.permutations([*known, 100, 101, 102, 2**31 - 1]))
    return {b: p for b, p in zip(known, perm, strict=False) if b != p}


# ----------------------------------------------------------------------------------------------
# The move, there and back
# ----------------------------------------------------------------------------------------------


@settings(derandomize=True, max_examples=40, deadline=None)
@given(
    rotation=st.floats(min_value=-10.0, max_value=10.0),
    shift=st.tuples(*[st.floats(min_value=-1000.0, max_value=1000.0)] * 2),
    clock=st.one_of(
        st.integers(min_value=-(10**9), max_value=10**9).map(lambda ms: ms / 1000),
        st.floats(min_value=-1e6, max_value=1e6),
    ),
    barcodes=_barcode_maps(),
)
def test_moving_there_and_back_gives_the_run_back_and_no_relative_figure_changes(
    rotation: float, shift: tuple[float, float], clock: float, barcodes: dict[int, int]
) -> None:
    """Moved by a random turn, shift, clock shift and renumbering and moved back by the inverse,
    every number comes back within the written precision (1e-8 m, 1e-8 rad; a stamp to the
    1e-12 s the clock keeps, and as written when the clock shift has at most the stamps' three
    decimals); comments and copied columns come back byte for byte. The moved run itself loads
    the same rows, on the same relative clock, with the same sightings, and every robot sees
    every other at the same place in its own frame."""
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        src = _folder(root / "run")
        there = move_mrclam(
            src,
            root / "there",
            rotation_rad=rotation,
            shift_m=shift,
            clock_s=clock,
            barcodes=barcodes,
        )
        back_rotation, back_shift = _inverse(rotation, shift)
        back = move_mrclam(
            there.destination,
            root / "back",
            rotation_rad=back_rotation,
            shift_m=back_shift,
            clock_s=-clock,
            barcodes={new: old for old, new in barcodes.items()},
        )
        ms_clock = Decimal(repr(clock)).as_tuple().exponent >= -3  # type: ignore[operator]
        for name, counts in back.files.items():
            assert (counts.unreadable, there.files[name].unreadable) == (0, 0), name
            assert _comments(back.destination / name) == _comments(src / name), name
            original, returned = _rows(src / name), _rows(back.destination / name)
            assert len(original) == len(returned) == counts.moved, name
            for row, row_back in zip(original, returned, strict=True):
                for kind, a, b in zip(COLUMNS[_kind(name)], row, row_back, strict=True):
                    if kind in ("=", "b"):
                        assert b == a, (name, row, row_back)
                    elif kind == "t":
                        assert abs(Decimal(b.decode()) - Decimal(a.decode())) <= Decimal("1e-12")
                        assert b == a or not ms_clock, (name, row, row_back)
                    elif kind == "xy":
                        assert abs(float(b) - float(a)) <= 1.000001e-8, (name, row, row_back)
                    else:
                        assert _circular(float(b), float(a)) <= 1.000001e-8, (name, row, row_back)

        here, moved = load_mrclam(src), load_mrclam(there.destination)
        assert moved.robot_ids == here.robot_ids
        assert moved.t0_unix == pytest.approx(here.t0_unix + clock, abs=1e-6)
        assert {b: s for b, s in moved.barcodes.items()} == {
            barcodes.get(b, b): s for b, s in here.barcodes.items()
        }
        for name, report in here.report.files.items():
            assert moved.report.files[name].rows_kept == report.rows_kept, name
        c, s = math.cos(rotation), math.sin(rotation)
        np.testing.assert_allclose(
            moved.landmarks.xy,
            here.landmarks.xy @ np.array([[c, s], [-s, c]]) + np.asarray(shift),
            atol=1e-8,
        )
        for n in here.robot_ids:
            a, b = here.robot(n), moved.robot(n)
            assert b.barcode == barcodes.get(a.barcode, a.barcode)
            for table in ("groundtruth", "odometry", "measurements"):
                np.testing.assert_allclose(getattr(b, table).t, getattr(a, table).t, atol=1e-9)
            np.testing.assert_array_equal(b.measurements.subject, a.measurements.subject)
            np.testing.assert_array_equal(b.measurements.range, a.measurements.range)
            np.testing.assert_array_equal(b.measurements.bearing, a.measurements.bearing)
            np.testing.assert_array_equal(b.odometry.v, a.odometry.v)
            np.testing.assert_array_equal(b.odometry.omega, a.odometry.omega)
            turned = np.remainder(a.groundtruth.theta + rotation + np.pi, 2 * np.pi) - np.pi
            gap = np.remainder(b.groundtruth.theta - turned + np.pi, 2 * np.pi) - np.pi
            assert np.abs(gap).max() <= 1.000001e-8 / 2 + 1e-12
        relative_here, relative_moved = _relative_poses(here), _relative_poses(moved)
        for pair, figures in relative_here.items():
            np.testing.assert_allclose(relative_moved[pair], figures, rtol=0, atol=1e-7)


def test_an_identity_move_rewrites_nothing_but_the_blanks_around_a_row(tmp_path: Path) -> None:
    """Moved by nothing, every data row comes out as it was (its separators too, only the
    blanks at its ends go) and every comment in its place: no digit is lost or added."""
    src = _folder(tmp_path / "run")
    report = move_mrclam(src, tmp_path / "same")
    for name in report.files:
        lines = [ln for ln in (src / name).read_bytes().split(b"\n") if ln.strip()]
        expected = [ln if ln.startswith(b"#") else data_row(ln) for ln in lines]
        assert (tmp_path / "same" / name).read_bytes() == b"\n".join(expected) + b"\n", name


def test_stamps_are_added_in_decimal_and_poses_keep_their_finer_digits(tmp_path: Path) -> None:
    src = _folder(tmp_path / "run")
    gt = src / "Robot1_Groundtruth.dat"
    gt.write_bytes(gt.read_bytes() + f"{T0 + 10:.6f} 0.1234567891 1e-3 0.5\n".encode())
    move_mrclam(src, tmp_path / "moved", clock_s=123456.789, shift_m=(1.0, 0.0))
    last = _rows(tmp_path / "moved" / "Robot1_Groundtruth.dat")[-1]
    # the stamp keeps its six decimals; x and y (a turn mixes them) the ten of x; θ the 8 of a pose
    assert last == [b"1000123466.789000", b"1.1234567891", b"0.0010000000", b"0.50000000"]
    first = _rows(tmp_path / "moved" / "Robot1_Groundtruth.dat")[0]
    assert first[0] == b"1000123456.789"  # T0 + 123456.789, no float rounding at 1e9


# ----------------------------------------------------------------------------------------------
# Rows that cannot be moved, and refusals
# ----------------------------------------------------------------------------------------------


def test_rows_that_cannot_be_moved_are_counted_and_left_out(tmp_path: Path) -> None:
    src = _folder(tmp_path / "run")
    meas = src / "Robot1_Measurement.dat"
    meas.write_bytes(
        meas.read_bytes()
        + b"nan 5 1 1\n1_000 5 1 1\n\xff\xfe 1 2\n5e9 5 1 1\n"  # no time the loader reads
        + b"1000000011 5.5 1 1\n1000000011 5 1\n"  # no barcode; three columns
        + b"1000000011 5 abc -9\n\n"  # moved: the loader judges the range, as in the source
    )
    report = move_mrclam(src, tmp_path / "moved", clock_s=1.0, barcodes={5: 11})
    counts = report.files["Robot1_Measurement.dat"]
    assert (counts.moved, counts.unreadable) == (21, 6)
    assert _rows(tmp_path / "moved" / "Robot1_Measurement.dat")[-1] == [
        b"1000000012",
        b"11",
        b"abc",
        b"-9",
    ]
    here, moved = load_mrclam(src), load_mrclam(tmp_path / "moved")
    for name, file_report in here.report.files.items():
        assert moved.report.files[name].rows_kept == file_report.rows_kept, name


def test_rows_of_every_file_kind_that_cannot_be_moved_are_counted(tmp_path: Path) -> None:
    """Not the file's number of columns, a position or heading beyond the loader's bounds:
    left out and counted in every file kind; a coordinate whose exponent is beyond
    :mod:`decimal`'s range (``0e-99999999999999999999``) is moved as the 0 the loader reads."""
    src = _folder(tmp_path / "run")

    def append(name: str, rows: bytes) -> None:
        (src / name).write_bytes((src / name).read_bytes() + rows)

    append("Barcodes.dat", b"7 \t 90 \t 1\n")  # three columns
    append("Landmark_Groundtruth.dat", b"8 abc 1.0 0.1 0.1\n9 1.0 2.0 0.1\n")
    append(
        "Robot1_Groundtruth.dat",
        f"{T0 + 10:.3f} 1.0 2.0\n{T0 + 10.5:.3f} 1.0 2.0 99\n{T0 + 11:.3f} 1e9 2.0 0.5\n".encode()
        + f"{T0 + 11.5:.3f} 0e-99999999999999999999 2.0 0.5\n".encode(),
    )
    append("Robot1_Odometry.dat", f"{T0 + 10.5:.3f} 0.1\n".encode())
    report = move_mrclam(src, tmp_path / "moved", rotation_rad=math.pi / 2, shift_m=(1.0, 0.0))
    counts = {name: (c.moved, c.unreadable) for name, c in report.files.items()}
    assert counts["Barcodes.dat"] == (5, 1)
    assert counts["Landmark_Groundtruth.dat"] == (2, 2)
    assert counts["Robot1_Groundtruth.dat"] == (21, 3)
    assert counts["Robot1_Odometry.dat"] == (40, 1)
    assert _rows(tmp_path / "moved" / "Robot1_Groundtruth.dat")[-1] == [
        b"1000000011.500",
        b"-1.00000000",
        b"0.00000000",
        b"2.07079633",
    ]
    here, moved = load_mrclam(src), load_mrclam(tmp_path / "moved")
    for name, file_report in here.report.files.items():
        assert moved.report.files[name].rows_kept == file_report.rows_kept, name


#: Columns of appended rows: times in and out of bounds, barcodes known, fresh (11, given to
#: robot 1 below) and unknown (50), and what the loader does not read.
ROW_TOKENS = ["1000000005", "1000000005.5", "5e9", "-1", "nan", "inf", "1e-400", "5", "5.0",
              "11", "50", "0", "1.5", "-7", "abc", "\xff", "1_0", "+.5e1"]  # fmt: skip


@settings(derandomize=True, max_examples=60, deadline=None)
@given(
    extra=st.lists(
        st.one_of(
            st.binary(max_size=24),
            st.lists(
                st.sampled_from(ROW_TOKENS),
                min_size=1,
                max_size=5,
            ).map(lambda tokens: " \t".join(tokens).encode("utf-8")),
        ),
        max_size=6,
    )
)
@example(extra=[b"1000000005 \t11 \t1.5 \t0"])  # refused: 11 would name robot 1
@example(extra=[b"1000000005 \t5 \t1.5 \t0", b"1000000005 \t50 \tabc \t0"])  # both moved
def test_any_rows_are_moved_counted_or_refused(extra: list[bytes]) -> None:
    """Whatever rows are appended to a measurement file, the move either writes a run whose
    counts cover every data row and which loads the same rows as its source, or raises a relloc
    error and writes nothing (a row reading barcode 11, which the map gives to robot 1)."""
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        src = _folder(root / "run")
        meas = src / "Robot1_Measurement.dat"
        meas.write_bytes(meas.read_bytes() + b"\n".join(extra))
        try:
            report = move_mrclam(src, root / "moved", rotation_rad=1.0, barcodes={5: 11})
        except (ConfigError, DataError):
            assert sorted(p.name for p in root.iterdir()) == ["run"]
            return
        for name, c in report.files.items():
            assert c.moved + c.unreadable == len(_rows(src / name)), name
            assert c.moved == len(_rows(root / "moved" / name)), name
        here, moved = load_mrclam(src), load_mrclam(root / "moved")
        for name, file_report in here.report.files.items():
            assert moved.report.files[name].rows_kept == file_report.rows_kept, name


@pytest.mark.parametrize(
    ("kwargs", "words"),
    [
        ({"rotation_rad": math.nan}, r"^rotation_rad: the turn must be a finite angle, got nan"),
        ({"shift_m": (1.0, math.inf)}, r"^shift_m: the shift must be two finite numbers"),
        ({"shift_m": (1.0,)}, r"^shift_m: "),
        ({"clock_s": -math.inf}, r"^clock_s: the clock shift must be a finite time, got -inf"),
        ({"barcodes": {5: 0}}, r"^barcodes: 5→0: barcodes are integers in \[1, 2147483647\]"),
        ({"barcodes": {True: 3}}, r"^barcodes: True→3"),
        ({"barcodes": {99: 3}}, r"^barcodes: 99 is not a barcode of .*Barcodes\.dat"),
        ({"barcodes": {5: 14}}, r"^barcodes: subjects 1 \(5→14\) and 2 \(keeps 14\) would both"),
        ({"barcodes": {5: 7, 14: 7}}, r"^barcodes: subjects 1 \(5→7\) and 2 \(14→7\) would both"),
        (
            {"barcodes": {5: UNKNOWN_BARCODE}},
            r"^barcodes: 5→50, but .*Robot2_Measurement\.dat:23 reads barcode 50, which names "
            r"no subject; its sightings would become sightings of subject 1",
        ),
        (
            {"clock_s": -2e9},
            r"^clock_s: shifted by -2000000000\.0 s, the stamp 1000000000\.000 at "
            r".*Robot1_Groundtruth\.dat:3 becomes -1000000000, outside the loader's",
        ),
        (
            {"rotation_rad": math.pi / 4, "shift_m": (99_999.0, 0.0)},
            r"^shift_m: turned by 0\.785\d+ rad and shifted by \(99999\.0, 0\.0\) m, the "
            r"position 1\.25000000 -2\.50000000 at .*Landmark_Groundtruth\.dat:3 becomes",
        ),
    ],
)
def test_bad_settings_are_config_errors_naming_the_parameter_and_write_nothing(
    tmp_path: Path, kwargs: dict[str, object], words: str
) -> None:
    src = _folder(tmp_path / "run")
    with pytest.raises(ConfigError, match=words):
        move_mrclam(src, tmp_path / "moved", **kwargs)  # type: ignore[arg-type]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run"]


def test_an_existing_destination_and_a_missing_source_are_refused(tmp_path: Path) -> None:
    src = _folder(tmp_path / "run")
    (tmp_path / "moved").mkdir()
    with pytest.raises(ConfigError, match=r"^mrclam move: .*moved exists; name a new folder"):
        move_mrclam(src, tmp_path / "moved", clock_s=1.0)
    with pytest.raises(DataError, match="nowhere"):
        move_mrclam(tmp_path / "nowhere", tmp_path / "other")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["moved", "run"]


# ----------------------------------------------------------------------------------------------
# The command
# ----------------------------------------------------------------------------------------------

MOVE_FLAGS = ["--rotate", "2", "--shift=3.7,-1.2", "--clock-shift", "123456.789"]


def test_the_cli_moves_a_folder_and_prints_every_file(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    src = _folder(tmp_path / "run")
    dst = tmp_path / "moved"
    assert main(["mrclam", "move", str(src), str(dst), *MOVE_FLAGS, "--barcodes", "5:11"]) == 0
    out = capsys.readouterr().out
    assert f"wrote {dst}: {src} turned by 2.0 rad, shifted by (3.7, -1.2) m" in out
    assert "clock +123456.789 s (t0 1000000000.000 → 1000123456.789 Unix s)" in out
    assert "barcodes 5→11" in out
    assert "Robot3_Measurement.dat" in out and "Landmark_Groundtruth.dat" in out
    moved = load_mrclam(dst)
    assert moved.t0_unix == pytest.approx(T0 + 123456.789) and moved.robot(1).barcode == 11
    x, y = 1.25, -2.5  # landmark 4
    c, s = math.cos(2.0), math.sin(2.0)
    np.testing.assert_allclose(moved.landmarks.xy[0], [c * x - s * y + 3.7, s * x + c * y - 1.2])


def test_the_cli_moves_a_cut_of_run6(
    mrclam_run6_cut, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A cut of run 6 moved by the CLI: each stamp is its own plus 123456.789 s, as written in
    decimal; every robot keeps its sightings (under its new barcode) and its place in the others'
    frames; moved back, the rows are the cut's within the written precision."""
    cut = mrclam_run6_cut(tmp_path / "cut", robots=(1, 2), keep_s=30.0)
    dst = tmp_path / "moved"
    argv = ["mrclam", "move", str(cut), str(dst), *MOVE_FLAGS, "--barcodes", "5:11,14:12"]
    assert main(argv) == 0
    assert "barcodes 5→11, 14→12" in capsys.readouterr().out
    for name in ("Robot1_Groundtruth.dat", "Robot2_Measurement.dat", "Robot2_Odometry.dat"):
        stamps = [Decimal(r[0].decode()) for r in _rows(cut / name)]
        moved = [Decimal(r[0].decode()) for r in _rows(dst / name)]
        assert moved == [t + Decimal("123456.789") for t in stamps], name
    here, there = load_mrclam(cut), load_mrclam(dst)
    assert (there.robot(1).barcode, there.robot(2).barcode) == (11, 12)
    for n in here.robot_ids:
        np.testing.assert_array_equal(
            there.robot(n).measurements.subject, here.robot(n).measurements.subject
        )
    relative_here, relative_there = _relative_poses(here), _relative_poses(there)
    for pair, figures in relative_here.items():
        np.testing.assert_allclose(relative_there[pair], figures, rtol=0, atol=1e-7)
    back_rotation, (bx, by) = _inverse(2.0, (3.7, -1.2))
    argv = ["mrclam", "move", str(dst), str(tmp_path / "back"), f"--rotate={back_rotation}"]
    argv += [f"--shift={bx!r},{by!r}", "--clock-shift=-123456.789", "--barcodes", "11:5,12:14"]
    assert main(argv) == 0
    for name in sorted(p.name for p in cut.iterdir()):
        kinds = COLUMNS[_kind(name)]
        for row, row_back in zip(_rows(cut / name), _rows(tmp_path / "back" / name), strict=True):
            for kind, a, b in zip(kinds, row, row_back, strict=True):
                if kind in ("xy", "th"):
                    assert _circular(float(a), float(b)) <= 1.000001e-8, (name, row, row_back)
                else:
                    assert a == b, (name, row, row_back)


@pytest.mark.parametrize(
    ("flags", "message"),
    [
        (["--rotate", "nan"], "--rotate: the turn must be a finite angle, got nan"),
        (["--shift", "1"], "--shift: '1' is not two numbers X,Y"),
        (["--shift", "1,2,3"], "--shift: '1,2,3' is not two numbers X,Y"),
        (["--shift=1,inf"], "--shift: the shift must be two finite numbers x, y, got (1.0, inf)"),
        (["--shift=1e5,0"], "--shift: turned by 0.0 rad and shifted by (100000.0, 0.0) m"),
        (["--clock-shift", "inf"], "--clock-shift: the clock shift must be a finite time"),
        (["--clock-shift=-2e9"], "--clock-shift: shifted by -2000000000.0 s, the stamp"),
        (["--barcodes", "5:11,5:12"], "--barcodes: barcode 5 is mapped twice in '5:11,5:12'"),
        (["--barcodes", "5-11"], "--barcodes: '5-11' in '5-11' is not OLD:NEW"),
        (["--barcodes", ""], "--barcodes: '' in '' is not OLD:NEW"),
        (["--barcodes", "5:0"], "--barcodes: 5→0: barcodes are integers in [1, 2147483647]"),
        (["--barcodes", "99:3"], "--barcodes: 99 is not a barcode of"),
        (["--barcodes", "5:14"], "--barcodes: subjects 1 (5→14) and 2 (keeps 14) would both"),
        (["--barcodes", "5:50"], "Robot2_Measurement.dat:23 reads barcode 50"),
    ],
)
def test_the_cli_refuses_a_bad_value_naming_its_flag_and_writes_nothing(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], flags: list[str], message: str
) -> None:
    src = _folder(tmp_path / "run")
    assert main(["mrclam", "move", str(src), str(tmp_path / "moved"), *flags]) == 2
    err = capsys.readouterr().err
    assert err.startswith("relloc: error: ") and message in err and "Traceback" not in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run"]


@pytest.mark.parametrize("flags", [["--rotate", "abc"], ["--clock-shift", "1,5"]])
def test_the_cli_refuses_a_value_that_is_not_a_number_with_its_usage(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], flags: list[str]
) -> None:
    src = _folder(tmp_path / "run")
    with pytest.raises(SystemExit) as exit_:
        main(["mrclam", "move", str(src), str(tmp_path / "moved"), *flags])
    assert exit_.value.code == 2
    assert f"argument {flags[0]}: invalid float value" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run"]


def test_the_cli_refuses_an_existing_destination(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    src = _folder(tmp_path / "run")
    assert main(["mrclam", "move", str(src), str(src)]) == 2
    assert "exists; name a new folder" in capsys.readouterr().err


# ----------------------------------------------------------------------------------------------
# The flags' parsers
# ----------------------------------------------------------------------------------------------

_MAP_TEXT = st.text(alphabet="0123456789:, \t-+x.\u0663\u00a0", max_size=30)


@settings(derandomize=True, max_examples=300, deadline=None)
@given(text=st.one_of(st.text(max_size=40), _MAP_TEXT))
def test_the_barcode_map_parser_parses_or_names_its_flag(text: str) -> None:
    """Any string is a map of whole numbers, each old barcode once, that reads back as itself,
    or a ConfigError naming the flag; never another exception."""
    try:
        mapping = barcode_map(text, "--barcodes")
    except ConfigError as exc:
        assert str(exc).startswith("--barcodes: ")
        return
    assert mapping is not None and mapping
    assert all(type(k) is int and type(v) is int for k, v in mapping.items())
    assert all(0 <= k < 10**10 and 0 <= v < 10**10 for k, v in mapping.items())
    assert barcode_map(",".join(f"{k}:{v}" for k, v in mapping.items()), "--barcodes") == mapping


@settings(derandomize=True, max_examples=200, deadline=None)
@given(
    mapping=st.dictionaries(
        st.integers(min_value=0, max_value=10**10 - 1),
        st.integers(min_value=0, max_value=10**10 - 1),
        min_size=1,
        max_size=6,
    ),
    blanks=st.sampled_from(["", " ", "\t", "  "]),
)
def test_every_map_written_out_parses_back(mapping: dict[int, int], blanks: str) -> None:
    text = ",".join(f"{blanks}{k}{blanks}:{blanks}{v}{blanks}" for k, v in mapping.items())
    assert barcode_map(text, "--barcodes") == mapping


@settings(derandomize=True, max_examples=200, deadline=None)
@given(text=st.text(max_size=30))
def test_the_shift_parser_parses_or_names_its_flag(text: str) -> None:
    try:
        pair = number_pair(text, "--shift")
    except ConfigError as exc:
        assert str(exc).startswith("--shift: ")
        return
    assert pair is not None and len(pair) == 2 and all(isinstance(v, float) for v in pair)


def test_mrclam_cl_gps_fixes_are_the_same_relative_to_the_robot_in_a_moved_run(
    tmp_path: Path,
) -> None:
    """mrclam-cl's GPS-like fixes of one seed, on a run and on the run moved to another frame
    and clock: the same times, and each fix moved with the world (``R p + shift``, ``θ + α``),
    so every figure of the GPS cases is frame-free (the noise was drawn in the world frame)."""
    from relloc.experiments.mrclam_cl import GPS_SIGMA, gps_fixes

    rotation, shift = 0.7, (-3.0, 2.5)
    src = _folder(tmp_path / "run")
    there = move_mrclam(
        src, tmp_path / "there", rotation_rad=rotation, shift_m=shift, clock_s=1000.0, barcodes={}
    )
    here, moved = load_mrclam(src), load_mrclam(there.destination)
    a = gps_fixes(here, 0.0, 9.5, np.random.default_rng(5))
    b = gps_fixes(moved, 0.0, 9.5, np.random.default_rng(5))
    assert a.size == b.size == 9
    np.testing.assert_allclose(b.t, a.t, atol=1e-9)
    c, s = math.cos(rotation), math.sin(rotation)
    turned = a.value[:, :2] @ np.array([[c, s], [-s, c]]) + np.asarray(shift)
    np.testing.assert_allclose(b.value[:, :2], turned, atol=1e-7)
    gap = np.remainder(b.value[:, 2] - a.value[:, 2] - rotation + np.pi, 2 * np.pi) - np.pi
    assert np.abs(gap).max() < 1e-7
    # the noise is still N(0, σ²) per axis: the fixes are off the truth by a few σ at most
    truth = here.robot(here.robot_ids[0]).groundtruth.at(a.t).pose
    assert np.all(np.abs(a.value[:, :2] - truth[:, :2]) < 5 * GPS_SIGMA[0])
