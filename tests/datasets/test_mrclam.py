"""The MRCLAM loader on the real run 6 (skipped where absent) and on malformed folders."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from relloc.datasets.mrclam import MrclamOptions, load_mrclam
from relloc.datasets.paths import default_mrclam_dataset
from relloc.errors import ConfigError, DataError

HEADER = "# MRCLAM-layout test file\n# written by the test\n# format line\n# columns\n"
T0 = 1_000_000_000.0


def _write(folder: Path, name: str, rows: list[str]) -> None:
    (folder / name).write_text(HEADER + "\n".join(rows) + "\n")


def _small_dataset(folder: Path) -> Path:
    """Two robots (subjects 1, 2; barcodes 5, 14) and one landmark (subject 3, barcode 63)."""
    folder.mkdir(parents=True, exist_ok=True)
    _write(folder, "Barcodes.dat", ["1 5", "2 14", "3 63"])
    _write(folder, "Landmark_Groundtruth.dat", ["3 1.0 2.0 0.001 0.002"])
    for n in (1, 2):
        t = T0 + np.arange(0.0, 10.0, 0.1)
        # robot n turns through ±π so the circular interpolation is exercised
        theta = np.angle(np.exp(1j * (3.0 + 0.05 * n * np.arange(len(t)))))
        gt = [
            f"{ti:.3f} {0.1 * i:.4f} {n:.4f} {th:.4f}"
            for i, (ti, th) in enumerate(zip(t, theta, strict=True))
        ]
        _write(folder, f"Robot{n}_Groundtruth.dat", gt)
        odo = [f"{T0 + 1.0 + 0.2 * i:.3f} 0.1 {0.01 * n:.3f}" for i in range(40)]
        _write(folder, f"Robot{n}_Odometry.dat", odo)
        other = 14 if n == 1 else 5
        meas = [f"{T0 + 2.0 + 0.5 * i:.3f} {other} 1.5 0.1" for i in range(10)]
        meas.append(f"{T0 + 8.0:.3f} 63 2.5 -0.2")
        _write(folder, f"Robot{n}_Measurement.dat", meas)
    return folder


def _replace_line(path: Path, data_row: int, text: str) -> int:
    """Replace the data row ``data_row`` (0-based) and return its 1-based line number."""
    lines = path.read_text().splitlines()
    line_index = 4 + data_row
    lines[line_index] = text
    path.write_text("\n".join(lines) + "\n")
    return line_index + 1


def test_clean_folder_loads_on_one_clock(tmp_path: Path) -> None:
    ds = load_mrclam(_small_dataset(tmp_path / "ok"))
    assert ds.robot_ids == (1, 2)
    assert ds.t0_unix == pytest.approx(T0)
    assert ds.report.n_skipped == 0
    assert ds.barcodes == {5: 1, 14: 2, 63: 3}
    r1 = ds.robot(1)
    assert r1.barcode == 5
    assert r1.groundtruth.t[0] == pytest.approx(0.0)
    assert r1.odometry.t[0] == pytest.approx(1.0)
    assert list(np.unique(r1.measurements.subject)) == [2, 3]
    assert np.array_equal(ds.is_robot(r1.measurements.subject), r1.measurements.subject == 2)
    np.testing.assert_allclose(ds.landmarks.position(3), [1.0, 2.0])
    with pytest.raises(DataError, match="robot 7"):
        ds.robot(7)


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
    with pytest.raises(DataError, match="robot 2 has no barcode"):
        load_mrclam(folder)
    with pytest.raises(ConfigError, match="gap_threshold"):
        MrclamOptions(gap_threshold=0.0)
    with pytest.raises(ConfigError, match="on_bad_row"):
        MrclamOptions(on_bad_row="ignore")  # type: ignore[arg-type]
    ds = load_mrclam(_small_dataset(tmp_path / "one"), MrclamOptions(robots=(2,)))
    assert ds.robot_ids == (2,)


@pytest.fixture(scope="module")
def run6():  # type: ignore[no-untyped-def]
    folder = default_mrclam_dataset()
    if not (folder / "Barcodes.dat").is_file():
        pytest.skip(f"MRCLAM run 6 not found at {folder} (shared data absent)")
    return load_mrclam(folder)


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
