"""The MRCLAM loader on the real run 6 (skipped where absent) and on malformed folders."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from relloc.datasets.mrclam import MrclamOptions, load_mrclam
from relloc.errors import ConfigError, DataError

HEADER = "# MRCLAM-layout test file\n# written by the test\n# format line\n# columns\n"
T0 = 1_000_000_000.0


def _write(folder: Path, name: str, rows: list[str]) -> None:
    (folder / name).write_text(HEADER + "\n".join(rows) + "\n")


def _small_dataset(folder: Path, t0: float = T0) -> Path:
    """Two robots (subjects 1, 2; barcodes 5, 14), one landmark (subject 3, barcode 63) and a
    subject never seen (4, barcode 70); the first stamp is ``t0``."""
    folder.mkdir(parents=True, exist_ok=True)
    _write(folder, "Barcodes.dat", ["1 5", "2 14", "3 63", "4 70"])
    _write(folder, "Landmark_Groundtruth.dat", ["3 1.0 2.0 0.001 0.002"])
    for n in (1, 2):
        t = t0 + np.arange(0.0, 10.0, 0.1)
        # robot n turns through ±π so the circular interpolation is exercised
        theta = np.angle(np.exp(1j * (3.0 + 0.05 * n * np.arange(len(t)))))
        gt = [
            f"{ti:.3f} {0.1 * i:.4f} {n:.4f} {th:.4f}"
            for i, (ti, th) in enumerate(zip(t, theta, strict=True))
        ]
        _write(folder, f"Robot{n}_Groundtruth.dat", gt)
        odo = [f"{t0 + 1.0 + 0.2 * i:.3f} 0.1 {0.01 * n:.3f}" for i in range(40)]
        _write(folder, f"Robot{n}_Odometry.dat", odo)
        other = 14 if n == 1 else 5
        meas = [f"{t0 + 2.0 + 0.5 * i:.3f} {other} 1.5 0.1" for i in range(10)]
        meas.append(f"{t0 + 8.0:.3f} 63 2.5 -0.2")
        _write(folder, f"Robot{n}_Measurement.dat", meas)
    return folder


def _replace_line(path: Path, data_row: int, text: str) -> int:
    """Replace the data row ``data_row`` (0-based) and return its 1-based line number.

    Lines are cut at ``\\n`` only (as the loader counts them); ``text`` is written as UTF-8.
    """
    lines = path.read_bytes().split(b"\n")
    line_index = 4 + data_row
    lines[line_index] = text.encode("utf-8")
    path.write_bytes(b"\n".join(lines))
    return line_index + 1


def test_clean_folder_loads_on_one_clock(tmp_path: Path) -> None:
    ds = load_mrclam(_small_dataset(tmp_path / "ok"))
    assert ds.robot_ids == (1, 2)
    assert ds.t0_unix == pytest.approx(T0)
    assert ds.report.n_skipped == 0
    assert ds.barcodes == {5: 1, 14: 2, 63: 3, 70: 4}
    r1 = ds.robot(1)
    assert r1.barcode == 5
    assert r1.groundtruth.t[0] == pytest.approx(0.0)
    assert r1.odometry.t[0] == pytest.approx(1.0)
    assert list(np.unique(r1.measurements.subject)) == [2, 3]
    assert np.array_equal(ds.is_robot(r1.measurements.subject), r1.measurements.subject == 2)
    np.testing.assert_allclose(ds.landmarks.position(3), [1.0, 2.0])
    with pytest.raises(DataError, match="robot 7"):
        ds.robot(7)


def test_relative_stamps_are_the_written_differences_whatever_the_epoch(tmp_path: Path) -> None:
    """The same recording stamped on three dates (and on a clock from 0) loads with bitwise the
    same relative times: the differences of the millisecond stamps as written. Read as floats
    near 1.2e9 s the stamps carry errors up to 1.2e-7 s, which differ from date to date."""
    epochs = (T0, 1_248_444_175.103, 1_371_234_567.891, 0.0)
    loaded = [load_mrclam(_small_dataset(tmp_path / f"e{i}", t0)) for i, t0 in enumerate(epochs)]
    odometry = np.round(1.0 + 0.2 * np.arange(40), 3)
    for ds in loaded:
        np.testing.assert_array_equal(ds.robot(1).odometry.t, odometry)
        for n in (1, 2):
            for table in ("groundtruth", "odometry", "measurements"):
                t = getattr(ds.robot(n), table).t
                np.testing.assert_array_equal(t, getattr(loaded[0].robot(n), table).t)
    raw = np.loadtxt(tmp_path / "e2" / "Robot1_Odometry.dat") - epochs[2]
    assert np.max(np.abs(raw[:, 0] - odometry)) > 1e-9  # what plain float differences give


def test_groundtruth_interpolates_yaw_on_the_circle_and_flags_queries(tmp_path: Path) -> None:
    ds = load_mrclam(_small_dataset(tmp_path / "ok"))
    gt = ds.robot(2).groundtruth
    # find a sample pair straddling the ±π seam and query half-way between them
    jump = np.flatnonzero(np.abs(np.diff(gt.theta)) > np.pi)[0]
    tq = 0.5 * (gt.t[jump] + gt.t[jump + 1])
    q = gt.at([tq, -1.0, 100.0])
    assert abs(abs(q.theta[0]) - np.pi) < 0.06  # stays near ±π, not pulled through 0
    assert list(q.inside) == [True, False, False]
    assert list(q.valid) == [True, False, False]
    np.testing.assert_allclose(q.x[0], 0.5 * (gt.x[jump] + gt.x[jump + 1]))


def test_groundtruth_gap_is_reported(tmp_path: Path) -> None:
    folder = _small_dataset(tmp_path / "gap")
    path = folder / "Robot1_Groundtruth.dat"
    lines = path.read_text().splitlines()
    del lines[4 + 30 : 4 + 40]  # 1.0 s without ground truth
    path.write_text("\n".join(lines) + "\n")
    gt = load_mrclam(folder).robot(1).groundtruth
    assert gt.gaps.shape == (1, 2)
    assert gt.gaps[0, 1] - gt.gaps[0, 0] == pytest.approx(1.1, abs=1e-6)
    q = gt.at([3.5, 5.0])
    assert list(q.in_gap) == [True, False]
    assert not gt.at([3.5], gap_threshold=2.0).in_gap[0]


def test_odometry_holds_the_last_command(tmp_path: Path) -> None:
    odo = load_mrclam(_small_dataset(tmp_path / "ok")).robot(2).odometry
    v, w = odo.at([0.5, 1.0, 1.1, 100.0])
    np.testing.assert_allclose(v, [0.0, 0.1, 0.1, 0.1])
    np.testing.assert_allclose(w, [0.0, 0.02, 0.02, 0.02])


@pytest.mark.parametrize(
    ("file", "row", "text", "reason"),
    [
        ("Robot1_Groundtruth.dat", 5, "1000000000.5 1.0 2.0", "expected 4 columns"),
        ("Robot1_Groundtruth.dat", 5, "1000000000.5 nan 2.0 0.1", "non-finite value"),
        ("Robot1_Odometry.dat", 3, "1000000001.6 fast 0.1", "non-numeric value"),
        ("Robot1_Groundtruth.dat", 5, "1000000000.05 0.5 1.0 0.1", "time goes backwards"),
        (
            "Robot1_Groundtruth.dat",
            5,
            "1000000000.4 0.5 1.0 0.1",
            "duplicate time stamp (first kept)",
        ),
        ("Robot1_Measurement.dat", 2, "1000000003.0 99 1.0 0.1", "unknown barcode"),
        ("Robot1_Measurement.dat", 2, "1000000003.0 14.5 1.0 0.1", "non-integer barcode"),
        ("Robot1_Measurement.dat", 4, "1000000001.0 14 1.0 0.1", "time goes backwards"),
        ("Robot1_Odometry.dat", 3, "1000000001.1 0.1 0.01", "time goes backwards"),
        # ids: whole numbers in [1, 2^31 - 1] (1e19 used to wrap to a negative int64)
        ("Barcodes.dat", 3, "1e19 70", "subject outside [1, 2147483647]"),
        ("Barcodes.dat", 3, "4 -70", "barcode outside [1, 2147483647]"),
        (
            "Robot1_Measurement.dat",
            2,
            "1000000003.0 1e19 1.0 0.1",
            "barcode outside [1, 2147483647]",
        ),
        ("Landmark_Groundtruth.dat", 0, "0 1.0 2.0 0.001 0.002", "subject outside [1, 2147483647]"),
        # physical bounds (module docstring)
        ("Robot1_Measurement.dat", 2, "1000000003.0 14 0 0.1", "range outside (0, 100]"),
        ("Robot1_Measurement.dat", 2, "1000000003.0 14 -1.0 0.1", "range outside (0, 100]"),
        ("Robot1_Measurement.dat", 2, "1000000003.0 14 1e308 0.1", "range outside (0, 100]"),
        (
            "Robot1_Measurement.dat",
            2,
            "1000000003.0 14 1.0 7.0",
            "bearing outside [-6.28319, 6.28319]",
        ),
        ("Robot1_Groundtruth.dat", 5, "-1000000000.5 1.0 2.0 0.1", "time outside [0, 4294967296]"),
        ("Robot1_Groundtruth.dat", 5, "1e10 1.0 2.0 0.1", "time outside [0, 4294967296]"),
        ("Robot1_Groundtruth.dat", 5, "1000000000.5 1e308 2.0 0.1", "x outside [-100000, 100000]"),
        ("Robot1_Odometry.dat", 3, "1000000001.6 -1e308 0.1", "v outside [-100, 100]"),
        ("Robot1_Odometry.dat", 3, "1000000001.6 0.1 1e3", "omega outside [-100, 100]"),
        ("Landmark_Groundtruth.dat", 0, "3 1.0 2.0 -0.001 0.002", "x std-dev outside [0, 100000]"),
        ("Robot1_Groundtruth.dat", 5, "1000000000.5 1e999 2.0 0.1", "non-finite value"),
        # only ASCII numerals: other scripts' digits, full-width digits, underscores, bad bytes
        ("Robot1_Measurement.dat", 2, "1000000003.0 \u0661\u0664 1.0 0.1", "non-ASCII bytes"),
        ("Robot1_Measurement.dat", 2, "1000000003.0 \uff11\uff14 1.0 0.1", "non-ASCII bytes"),
        ("Robot1_Odometry.dat", 3, "1000000001.6 0.1 1_0", "non-numeric value"),
        ("Robot1_Odometry.dat", 3, "1000000001.6 0.1 0x1", "non-numeric value"),
        ("Robot1_Odometry.dat", 3, "1000000001.6 0.1\x0b0.01", "expected 3 columns"),
        ("Robot1_Odometry.dat", 3, "1000000001.6 0.1 0.01\x1c", "non-numeric value"),
    ],
)
def test_bad_rows_are_counted_or_raised(
    tmp_path: Path, file: str, row: int, text: str, reason: str
) -> None:
    folder = _small_dataset(tmp_path / "bad")
    line = _replace_line(folder / file, row, text)
    ds = load_mrclam(folder)
    report = ds.report.files[file]
    assert report.skipped == {reason: 1}
    assert report.rows_kept == report.rows_read - 1
    assert report.examples[reason][0].line == line
    assert f"line {line} ({reason})" in ds.report.summary()
    assert ds.report.to_dict()["n_skipped"] == 1
    with pytest.raises(DataError, match=f"{file}:{line}"):
        load_mrclam(folder, MrclamOptions(on_bad_row="raise"))


def test_duplicate_odometry_stamp_keeps_the_later_command(tmp_path: Path) -> None:
    folder = _small_dataset(tmp_path / "dup")
    _replace_line(folder / "Robot1_Odometry.dat", 1, "1000000001.0 0.3 0.5")
    odo = load_mrclam(folder).robot(1).odometry
    assert odo.t[0] == pytest.approx(1.0)
    assert odo.v[0] == pytest.approx(0.3) and odo.omega[0] == pytest.approx(0.5)


@pytest.mark.parametrize("missing", ["Barcodes.dat", "Robot2_Odometry.dat"])
def test_missing_file_is_named(tmp_path: Path, missing: str) -> None:
    folder = _small_dataset(tmp_path / "missing")
    (folder / missing).unlink()
    with pytest.raises(DataError, match=missing):
        load_mrclam(folder)


def test_unusable_folders_and_options(tmp_path: Path) -> None:
    with pytest.raises(DataError, match="not a folder"):
        load_mrclam(tmp_path / "nowhere")
    (tmp_path / "empty").mkdir()
    with pytest.raises(DataError, match="no RobotN"):
        load_mrclam(tmp_path / "empty")
    folder = _small_dataset(tmp_path / "nobarcode")
    _write(folder, "Barcodes.dat", ["1 5", "3 63"])
    with pytest.raises(DataError, match=r"robot 2 has no barcode$"):
        load_mrclam(folder)
    _write(folder, "Barcodes.dat", ["1 5", "2 1x4", "3 63"])  # its row unreadable: said where
    with pytest.raises(DataError, match=r"robot 2 has no barcode; rows skipped: line 6 \("):
        load_mrclam(folder)
    with pytest.raises(ConfigError, match="gap_threshold"):
        MrclamOptions(gap_threshold=0.0)
    with pytest.raises(ConfigError, match="on_bad_row"):
        MrclamOptions(on_bad_row="ignore")  # type: ignore[arg-type]
    ds = load_mrclam(_small_dataset(tmp_path / "one"), MrclamOptions(robots=(2,)))
    assert ds.robot_ids == (2,)


def _data_lines(path: Path) -> list[int]:
    """1-based numbers of the lines (cut at ``\\n`` only) that are data rows."""
    lines = path.read_bytes().split(b"\n")
    return [
        i
        for i, line in enumerate(lines, start=1)
        if line.strip(b" \t\r") and not line.strip(b" \t\r").startswith(b"#")
    ]


@pytest.mark.parametrize(
    "name",
    [
        "Robot1_Groundtruth.dat",
        "Robot1_Odometry.dat",
        "Robot2_Measurement.dat",
        "Barcodes.dat",
        "Landmark_Groundtruth.dat",
    ],
)
def test_a_directory_in_place_of_a_file_is_named(tmp_path: Path, name: str) -> None:
    folder = _small_dataset(tmp_path / "dir")
    (folder / name).unlink()
    (folder / name).mkdir()
    with pytest.raises(DataError, match=f"{name}: not a regular file"):
        load_mrclam(folder)


@pytest.mark.parametrize(
    ("content", "n_rows"),
    [(b"", 0), (HEADER.encode(), 0), (bytes(range(256)) * 8, 8 + 1)],
    ids=["empty", "comment-only", "binary"],
)
def test_odometry_without_a_usable_row_is_a_clear_error(
    tmp_path: Path, content: bytes, n_rows: int
) -> None:
    """The loader refuses it (it used to load, and the runtime conversion hit an IndexError)."""
    from relloc.runtime.dataset import mrclam_team_recording

    folder = _small_dataset(tmp_path / "odo")
    (folder / "Robot1_Odometry.dat").write_bytes(content)
    message = f"Robot1_Odometry.dat: 0 usable rows, need at least 1 \\({n_rows} of {n_rows} data"
    with pytest.raises(DataError, match=message):
        load_mrclam(folder)
    with pytest.raises(DataError, match=message):
        mrclam_team_recording(folder, np.random.default_rng(0))


def test_a_team_log_needs_two_robots(tmp_path: Path) -> None:
    from relloc.runtime.dataset import mrclam_team_recording

    folder = _small_dataset(tmp_path / "one")
    for kind in ("Groundtruth", "Odometry", "Measurement"):
        (folder / f"Robot2_{kind}.dat").unlink()
    with pytest.raises(DataError, match=r"at least 2 robots, the folder has \(1,\)"):
        mrclam_team_recording(folder, np.random.default_rng(0))


@pytest.mark.parametrize(
    ("file", "text"),
    [
        ("Robot1_Groundtruth.dat", "5.0 nan 1.0 0.1"),  # non-finite value
        ("Robot1_Groundtruth.dat", "5.0 1.0 0.1"),  # expected 4 columns
        ("Robot1_Odometry.dat", "5.0 fast 0.1"),  # non-numeric value
        ("Robot1_Measurement.dat", "5.0 99 1.0 0.1"),  # unknown barcode
        ("Robot2_Measurement.dat", "5.0 14.5 1.0 0.1"),  # non-integer barcode
    ],
)
def test_start_time_comes_only_from_rows_kept(tmp_path: Path, file: str, text: str) -> None:
    """A skipped first row at t = 5 s used to set the clock (duration 1e9 s)."""
    folder = _small_dataset(tmp_path / "first")
    _replace_line(folder / file, 0, text)
    ds = load_mrclam(folder)
    assert ds.report.files[file].n_skipped == 1
    assert ds.t0_unix == pytest.approx(T0)
    assert ds.duration == pytest.approx(9.9)


def test_a_landmark_listed_twice_is_an_error(tmp_path: Path) -> None:
    """Two positions for one surveyed landmark contradict each other: no row can be preferred."""
    folder = _small_dataset(tmp_path / "twice")
    _write(folder, "Landmark_Groundtruth.dat", ["3 1.0 2.0 0.001 0.002", "3 5.0 5.0 0.001 0.002"])
    for mode in ("skip", "raise"):
        with pytest.raises(
            DataError, match=r"Landmark_Groundtruth.dat:6: landmark subject 3 listed twice \(first"
        ):
            load_mrclam(folder, MrclamOptions(on_bad_row=mode))  # type: ignore[arg-type]


def test_a_clock_jump_of_more_than_a_day_is_an_error_naming_the_file(tmp_path: Path) -> None:
    """One ground-truth row 10⁸ s late once made mrclam-cl and wanasinghe2014 try to sample the
    whole span on a grid (18–37 GiB)."""
    folder = _small_dataset(tmp_path / "jump")
    path = folder / "Robot2_Groundtruth.dat"
    _replace_line(path, 99, f"{T0 + 1e8:.3f} 9.9 2.0 0.1")
    with pytest.raises(DataError, match=r"Robot2_Groundtruth.dat: a row stamped .* 1e\+08 s after"):
        load_mrclam(folder)
    _replace_line(path, 99, f"{T0 + 86_000:.3f} 9.9 2.0 0.1")  # under a day: a long run
    assert load_mrclam(folder).duration == pytest.approx(86_000)


def test_a_barcode_listed_twice_names_both_lines(tmp_path: Path) -> None:
    folder = _small_dataset(tmp_path / "twice")
    _write(folder, "Barcodes.dat", ["1 5", "2 14", "3 63", "4 14"])
    with pytest.raises(
        DataError, match=r"Barcodes.dat:8: barcode 14 listed twice \(first at line 6"
    ):
        load_mrclam(folder)


@pytest.mark.parametrize(
    "separator", ["\x0b", "\x0c", "\x1c", "\x1d", "\x1e", "\x85", "\u2028", "\r"]
)
def test_line_numbers_count_only_newlines(tmp_path: Path, separator: str) -> None:
    """Characters that Python's str.splitlines treats as line breaks do not shift line numbers."""
    folder = _small_dataset(tmp_path / "lines")
    path = folder / "Robot1_Odometry.dat"
    first = _replace_line(path, 1, f"1000000001.2 0.1{separator}0.01")
    later = _replace_line(path, 5, "1000000002.0 fast 0.01")
    report = load_mrclam(folder).report.files["Robot1_Odometry.dat"]
    assert report.rows_read == len(_data_lines(path)) == 40
    assert report.rows_kept + report.n_skipped == report.rows_read
    lines = sorted(ex.line for examples in report.examples.values() for ex in examples)
    assert lines == [first, later] == [6, 10]
    assert report.examples["non-numeric value"][0].line == later


def test_undecodable_bytes_are_a_skipped_row_with_its_true_line(tmp_path: Path) -> None:
    folder = _small_dataset(tmp_path / "bytes")
    path = folder / "Robot2_Groundtruth.dat"
    lines = path.read_bytes().split(b"\n")
    lines[4 + 3] = b"1000000000.3 \xff\xfe 2.0 0.1"
    lines[4 + 6] = b"1000000000.6 0.6 2.0 \xc3"
    path.write_bytes(b"\n".join(lines))
    report = load_mrclam(folder).report.files["Robot2_Groundtruth.dat"]
    assert report.skipped == {"non-ASCII bytes": 2}
    assert [(ex.line, ex.text) for ex in report.examples["non-ASCII bytes"]] == [
        (8, "1000000000.3 \\xff\\xfe 2.0 0.1"),
        (11, "1000000000.6 0.6 2.0 \\xc3"),
    ]
    with pytest.raises(DataError, match=r"Robot2_Groundtruth.dat:8: non-ASCII bytes"):
        load_mrclam(folder, MrclamOptions(on_bad_row="raise"))


def test_crlf_files_and_a_missing_final_newline_read_the_same(tmp_path: Path) -> None:
    plain = load_mrclam(_small_dataset(tmp_path / "lf"))
    folder = _small_dataset(tmp_path / "crlf")
    for path in folder.iterdir():
        path.write_bytes(path.read_bytes().rstrip(b"\n").replace(b"\n", b"\r\n"))
    crlf = load_mrclam(folder)
    assert crlf.report.n_skipped == 0
    for n in plain.robot_ids:
        np.testing.assert_array_equal(crlf.robot(n).groundtruth.t, plain.robot(n).groundtruth.t)
        np.testing.assert_array_equal(crlf.robot(n).odometry.omega, plain.robot(n).odometry.omega)
        np.testing.assert_array_equal(
            crlf.robot(n).measurements.bearing, plain.robot(n).measurements.bearing
        )


def test_robot_file_names_need_ascii_digits_without_leading_zeros(tmp_path: Path) -> None:
    folder = _small_dataset(tmp_path / "names")
    for kind in ("Groundtruth", "Odometry", "Measurement"):
        data = (folder / f"Robot2_{kind}.dat").read_bytes()
        for number in ("\u0663", "\uff13", "03"):  # Arabic-Indic 3, full-width 3, padded 3
            (folder / f"Robot{number}_{kind}.dat").write_bytes(data)
    assert load_mrclam(folder).robot_ids == (1, 2)


@pytest.mark.parametrize(
    ("options", "field"),
    [
        ({"robots": ("a",)}, "robots"),
        ({"robots": (True,)}, "robots"),
        ({"robots": 1}, "robots"),
        ({"max_examples": "3"}, "max_examples"),
        ({"gap_threshold": "0.5"}, "gap_threshold"),
        ({"gap_threshold": float("inf")}, "gap_threshold"),
    ],
)
def test_bad_options_are_config_errors(options: dict[str, object], field: str) -> None:
    with pytest.raises(ConfigError, match=field):
        MrclamOptions(**options)  # type: ignore[arg-type]


@pytest.fixture(scope="module")
def run6(mrclam_run6):  # type: ignore[no-untyped-def]
    return load_mrclam(mrclam_run6)


def test_real_run6_matches_its_documented_facts(run6) -> None:  # type: ignore[no-untyped-def]
    assert run6.robot_ids == (1, 2, 3, 4, 5)
    assert [run6.robot(n).barcode for n in run6.robot_ids] == [5, 14, 41, 32, 23]
    assert len(run6.landmarks.subject) == 15
    assert run6.robot(1).groundtruth.t[-1] == pytest.approx(771.9, abs=0.1)
    assert run6.duration == pytest.approx(900.0, abs=0.1)
    gaps = run6.robot(4).groundtruth.gaps
    assert np.any(np.isclose(gaps[:, 1] - gaps[:, 0], 2.03, atol=0.01))
    # the stray barcodes and the repeated odometry stamps are reported, nothing else is lost
    by_reason = run6.report.skipped_by_reason()
    assert set(by_reason) <= {
        "unknown barcode",
        "duplicate time stamp (superseded by the next row)",
    }
    assert by_reason["unknown barcode"] >= 1
    for n in run6.robot_ids:
        r = run6.robot(n)
        assert np.all(np.diff(r.groundtruth.t) > 0)
        assert np.all(np.diff(r.odometry.t) > 0)
        assert np.all(np.diff(r.measurements.t) >= 0)
        assert 6.0 < r.odometry.t[0] - r.groundtruth.t[0] < 17.0
