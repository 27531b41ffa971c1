"""``relloc mrclam cut``: a time span and some robots of an MRCLAM folder as a run of its own."""

from __future__ import annotations

import math
import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from relloc.cli import main
from relloc.datasets.mrclam import load_mrclam
from relloc.datasets.mrclam_cut import cut_mrclam
from relloc.errors import ConfigError, DataError

T0 = 1_000_000_000.0
HEADER = b"# MRCLAM-layout test file\n# Time [s] ...\n"


def _folder(root: Path) -> Path:
    """Three robots (subjects 1–3, barcodes 5, 14, 41) and one landmark (4, barcode 63): ground
    truth every 0.5 s and commands every 0.25 s over [0, 10) s, a sighting of the next robot
    every second; the earliest stamp is ``T0``."""
    root.mkdir(parents=True)
    (root / "Barcodes.dat").write_bytes(HEADER + b"1 5\n2 14\n3 41\n4 63\n")
    (root / "Landmark_Groundtruth.dat").write_bytes(HEADER + b"4 1.0 2.0 0.001 0.002\n")
    for n, other in ((1, 14), (2, 41), (3, 5)):
        gt = [f"{T0 + 0.5 * i:.3f} {0.05 * i:.3f} {n}.0 0.1" for i in range(20)]
        odo = [f"{T0 + 0.25 * i:.3f} 0.1 0.0" for i in range(40)]
        meas = [f"{T0 + 1.0 * i + 0.1:.3f} {other} 1.5 0.1" for i in range(10)]
        for kind, rows in (("Groundtruth", gt), ("Odometry", odo), ("Measurement", meas)):
            (root / f"Robot{n}_{kind}.dat").write_bytes(HEADER + "\n".join(rows).encode() + b"\n")
    return root


def _data_rows(path: Path) -> list[bytes]:
    lines = (ln.strip(b" \t\r") for ln in path.read_bytes().split(b"\n"))
    return [ln for ln in lines if ln and not ln.startswith(b"#")]


def test_a_cut_keeps_the_rows_of_its_span_and_robots_byte_for_byte(tmp_path: Path) -> None:
    src = _folder(tmp_path / "run")
    report = cut_mrclam(src, tmp_path / "part", start_s=2.0, end_s=6.0, robots=[3, 1])
    part = report.destination
    assert report.robots == (1, 3) and report.t0_unix == T0
    assert sorted(p.name for p in part.iterdir()) == [
        "Barcodes.dat",
        "Landmark_Groundtruth.dat",
        *(f"Robot{n}_{k}.dat" for n in (1, 3) for k in ("Groundtruth", "Measurement", "Odometry")),
    ]
    assert (part / "Barcodes.dat").read_bytes() == (src / "Barcodes.dat").read_bytes()
    for name, counts in report.files.items():
        rows = _data_rows(src / name)
        times = [float(r.split()[0]) - T0 for r in rows]
        expected = [r for r, t in zip(rows, times, strict=True) if 2.0 <= t < 6.0]
        assert _data_rows(part / name) == expected, name
        assert (part / name).read_bytes().startswith(HEADER), name  # comments kept
        assert (counts.kept, counts.outside, counts.unreadable) == (
            len(expected),
            len(rows) - len(expected),
            0,
        )
    cut = load_mrclam(part)
    assert cut.robot_ids == (1, 3)
    assert cut.t0_unix == pytest.approx(T0 + 2.0)  # the 2.0 s ground-truth row
    # robot 3 still sights robot 1, whose files are kept; robot 1's sightings are of robot 2,
    # whose barcode stays in Barcodes.dat although its files are gone
    assert set(cut.robot(3).measurements.subject) == {1}
    assert set(cut.robot(1).measurements.subject) == {2}


def test_rows_without_a_readable_time_are_counted_not_kept(tmp_path: Path) -> None:
    src = _folder(tmp_path / "run")
    odo = src / "Robot2_Odometry.dat"
    odo.write_bytes(odo.read_bytes() + b"nan 0.1 0.0\n1_000 0.1 0.0\n\xff\xfe 1 2\nabc 1 2\n\n")
    report = cut_mrclam(src, tmp_path / "part", end_s=5.0)
    counts = report.files["Robot2_Odometry.dat"]
    assert (counts.kept, counts.outside, counts.unreadable) == (20, 20, 4)
    assert counts.kept + counts.outside + counts.unreadable == len(_data_rows(odo))


@pytest.mark.parametrize(
    ("kwargs", "words"),
    [
        ({"start_s": -1.0}, "start -1.0 s must be a finite time ≥ 0"),
        ({"start_s": math.nan}, "start nan s"),
        ({"start_s": 3.0, "end_s": 3.0}, "end 3.0 s must come after start 3.0 s"),
        ({"robots": [1, 7]}, "robots [7] are not in"),
        ({"robots": []}, "no robot chosen"),
    ],
)
def test_bad_settings_are_config_errors_and_write_nothing(
    tmp_path: Path, kwargs: dict[str, object], words: str
) -> None:
    src = _folder(tmp_path / "run")
    with pytest.raises(ConfigError, match=r"^mrclam cut: ") as err:
        cut_mrclam(src, tmp_path / "part", **kwargs)  # type: ignore[arg-type]
    assert words in str(err.value)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run"]


def test_an_existing_destination_is_refused(tmp_path: Path) -> None:
    src = _folder(tmp_path / "run")
    (tmp_path / "part").mkdir()
    with pytest.raises(ConfigError, match="part exists; name a new folder"):
        cut_mrclam(src, tmp_path / "part")


def test_a_destination_under_a_file_is_a_data_error_naming_it(tmp_path: Path) -> None:
    src = _folder(tmp_path / "run")
    (tmp_path / "afile").write_text("")
    with pytest.raises(DataError, match="afile/part: cannot create the folder"):
        cut_mrclam(src, tmp_path / "afile" / "part")


def test_a_part_that_is_not_a_usable_run_names_the_file_and_leaves_nothing(tmp_path: Path) -> None:
    src = _folder(tmp_path / "run")
    # [9.6, 20) s holds no ground-truth row (they end at 9.5 s): no robot can be scored
    with pytest.raises(DataError, match=r"\[9\.6, 20\) s .* not a usable run: .*Groundtruth") as e:
        cut_mrclam(src, tmp_path / "part", start_s=9.6, end_s=20.0)
    # named as the file it would have written, not the staging folder's
    assert f"{tmp_path / 'part' / 'Robot1_Groundtruth.dat'}: 0 usable rows" in str(e.value)
    assert ".partial" not in str(e.value)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run"]


def test_a_missing_source_is_a_data_error(tmp_path: Path) -> None:
    with pytest.raises(DataError):
        cut_mrclam(tmp_path / "nowhere", tmp_path / "part")


@settings(max_examples=60, deadline=None)
@given(
    extra=st.lists(st.binary(max_size=24), max_size=6),
    start=st.floats(min_value=0.0, max_value=12.0),
    length=st.floats(min_value=1e-3, max_value=12.0),
)
def test_any_rows_are_kept_counted_or_refused(extra: list[bytes], start: float, length: float):
    """Whatever bytes are appended to a robot file, the cut either writes a loadable run whose
    counts cover every data row of every file, or raises a relloc error and writes nothing."""
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        src = _folder(root / "run")
        meas = src / "Robot1_Measurement.dat"
        meas.write_bytes(meas.read_bytes() + b"\n".join(extra))
        try:
            report = cut_mrclam(src, root / "part", start_s=start, end_s=start + length)
        except (ConfigError, DataError):
            assert sorted(p.name for p in root.iterdir()) == ["run"]
            return
        for name, c in report.files.items():
            assert c.kept + c.outside + c.unreadable == len(_data_rows(src / name)), name
            assert c.kept == len(_data_rows(root / "part" / name)), name
        load_mrclam(root / "part")


def test_the_cli_prints_every_file_and_maps_errors_to_exit_codes(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    src = _folder(tmp_path / "run")
    part = tmp_path / "part"
    assert main(["mrclam", "cut", str(src), str(part), "--start", "4", "--robots", "2,3"]) == 0
    out = capsys.readouterr().out
    assert f"wrote {part}: [4, inf) s" in out and "robots [2, 3]" in out
    assert "Robot2_Odometry.dat" in out and "Robot1_Odometry.dat" not in out
    assert main(["mrclam", "cut", str(src), str(tmp_path / "b"), "--robots", "1,x"]) == 2
    assert "--robots: '1,x' is not a comma-separated list" in capsys.readouterr().err
    assert main(["mrclam", "cut", str(src), str(tmp_path / "c"), "--start", "30"]) == 2
    err = capsys.readouterr().err
    assert "start 30 s is at or past the end of" in err
    assert "whose last row is stamped 9.750 s after its first" in err  # commands to 9.75 s


def test_run6_from_450_s_is_the_same_recording_on_its_own_clock(
    tmp_path: Path, mrclam_run6: Path
) -> None:
    src = mrclam_run6
    whole = load_mrclam(src)
    part = load_mrclam(cut_mrclam(src, tmp_path / "late", start_s=450.0).destination)
    shift = part.t0_unix - whole.t0_unix
    assert 450.0 <= shift < 450.1
    for n in whole.robot_ids:
        a, b = whole.robot(n).groundtruth, part.robot(n).groundtruth
        late = a.t >= 450.0
        np.testing.assert_allclose(b.t + shift, a.t[late], atol=1e-6)
        for column in ("x", "y", "theta"):
            np.testing.assert_array_equal(getattr(b, column), getattr(a, column)[late])
