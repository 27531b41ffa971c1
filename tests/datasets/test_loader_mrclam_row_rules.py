"""The MRCLAM loader's documented row rules at their edges, on tiny hand-written folders.

One robot (subject 1, barcode 5) and one landmark (subject 2, barcode 7) unless a test says
otherwise; stamps near ``T0`` Unix seconds, so the loaded clock is ``stamp − T0``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from relloc.datasets.mrclam import (
    GroundTruth,
    MrclamOptions,
    Odometry,
    load_mrclam,
    to_recording,
)
from relloc.errors import ConfigError, DataError

T0 = 1_000_000_000.0


def _folder(
    root: Path,
    *,
    barcodes: str = "1 5\n2 7\n",
    landmarks: str = "2 1.0 2.0 0.0 0.0\n",
    gt: str = "1000000000.0 0 0 0\n1000000001.0 1 0 0\n",
    odo: str = "1000000000.0 0.1 0.0\n",
    meas: str = "1000000000.5 7 1.5 0.1\n",
) -> Path:
    root.mkdir(parents=True, exist_ok=True)
    (root / "Barcodes.dat").write_text(barcodes)
    (root / "Landmark_Groundtruth.dat").write_text(landmarks)
    (root / "Robot1_Groundtruth.dat").write_text(gt)
    (root / "Robot1_Odometry.dat").write_text(odo)
    (root / "Robot1_Measurement.dat").write_text(meas)
    return root


def test_the_hand_written_folder_loads_as_written(tmp_path):
    ds = load_mrclam(_folder(tmp_path / "run"))
    assert ds.t0_unix == T0
    r = ds.robot(1)
    assert r.groundtruth.t.tolist() == [0.0, 1.0]
    assert r.odometry.t.tolist() == [0.0] and r.odometry.v.tolist() == [0.1]
    assert r.measurements.t.tolist() == [0.5] and r.measurements.subject.tolist() == [2]
    assert ds.report.n_skipped == 0


@pytest.mark.parametrize("max_examples", [0, 1, 3])
def test_at_most_max_examples_skipped_rows_are_kept_per_file_and_reason(tmp_path, max_examples):
    """Five measurement rows with an unknown barcode: all five counted, the first
    ``max_examples`` kept as examples with their line numbers."""
    meas = "".join(f"1000000000.{k} 99 1.5 0.1\n" for k in range(1, 6))
    ds = load_mrclam(_folder(tmp_path / "run", meas=meas), MrclamOptions(max_examples=max_examples))
    report = ds.report.files["Robot1_Measurement.dat"]
    assert report.skipped == {"unknown barcode": 5}
    assert [e.line for e in report.examples.get("unknown barcode", [])] == [1, 2, 3][:max_examples]


# ----------------------------------------------------------------------------------------------
# Ground truth and odometry at query times
# ----------------------------------------------------------------------------------------------


def _truth(t: list[float], threshold: float = 0.5):
    a = np.array(t)
    return GroundTruth(t=a, x=a.copy(), y=0 * a, theta=0 * a, gap_threshold=threshold)


def test_a_gap_is_a_step_longer_than_the_threshold_not_one_equal_to_it():
    g = _truth([0.0, 0.5, 1.5, 2.0])
    assert g.gaps.tolist() == [[0.5, 1.5]]


def test_queries_between_samples_exactly_threshold_apart_are_valid():
    q = _truth([0.0, 0.5, 1.5, 2.0]).at([0.0, 0.25, 0.5, 1.0, 1.75, 2.0])
    assert q.inside.tolist() == [True, True, True, True, True, True]
    # 0.25 and 1.75 lie in steps of exactly 0.5 s; 1.0 lies in the 1 s gap; 0.0 and 0.5 are
    # samples whose next step is 0.5 s.
    assert q.in_gap[[0, 1, 2, 3, 4]].tolist() == [False, False, False, True, False]
    assert q.x.tolist() == [0.0, 0.25, 0.5, 1.0, 1.75, 2.0]


def test_queries_outside_the_recorded_span_are_not_inside():
    q = _truth([1.0, 1.5, 2.0]).at([0.999, 1.0, 2.0, 2.001])
    assert q.inside.tolist() == [False, True, True, False]


def test_odometry_holds_the_command_stamped_at_the_query_time():
    od = Odometry(t=np.array([1.0, 2.0]), v=np.array([0.1, 0.2]), omega=np.array([0.01, 0.02]))
    v, w = od.at([0.5, 1.0, 1.5, 2.0, 9.0])
    assert v.tolist() == [0.0, 0.1, 0.1, 0.2, 0.2]
    assert w.tolist() == [0.0, 0.01, 0.01, 0.02, 0.02]


# ----------------------------------------------------------------------------------------------
# The run's clock
# ----------------------------------------------------------------------------------------------


def test_a_row_exactly_a_day_after_the_first_stamp_is_accepted(tmp_path):
    odo = "1000000000.0 0.1 0.0\n1000086400.0 0.2 0.0\n"
    ds = load_mrclam(_folder(tmp_path / "run", odo=odo))
    assert ds.robot(1).odometry.t.tolist() == [0.0, 86400.0]


def test_a_clock_jump_names_the_file_and_the_first_row_past_a_day(tmp_path):
    odo = "1000000000.0 0.1 0.0\n1000086401.0 0.2 0.0\n1000086402.0 0.2 0.0\n"
    run = _folder(tmp_path / "run", odo=odo)
    with pytest.raises(DataError) as info:
        load_mrclam(run)
    message = str(info.value)
    assert message.startswith(f"{run / 'Robot1_Odometry.dat'}: a row stamped 1000086401.000 ")
    assert "lies 86401 s after the run's first stamp 1000000000.000" in message


def test_relative_times_are_the_differences_of_the_stamps_as_written(tmp_path):
    """1000000000.004 − 1000000000 is 0.004 s; the float difference is 0.0039999485 (the
    stamp read into a float is off by 5.1e-8, under half its 1.2e-7 ulp)."""
    gt = "1000000000.0 0 0 0\n1000000000.004 1 0 0\n1000000001.007 1 0 0\n"
    ds = load_mrclam(_folder(tmp_path / "run", gt=gt))
    assert ds.robot(1).groundtruth.t.tolist() == [0.0, 0.004, 1.007]


# ----------------------------------------------------------------------------------------------
# Measurements and the recording
# ----------------------------------------------------------------------------------------------


def test_a_row_after_an_unknown_barcode_is_skipped_with_its_own_line(tmp_path):
    meas = "1000000000.5 7 1.5 0.1\n1000000000.6 99 1.5 0.1\n1000000000.4 7 1.5 0.1\n"
    ds = load_mrclam(_folder(tmp_path / "run", meas=meas))
    report = ds.report.files["Robot1_Measurement.dat"]
    assert report.skipped == {"unknown barcode": 1, "time goes backwards": 1}
    assert [e.line for e in report.examples["unknown barcode"]] == [2]
    assert [e.line for e in report.examples["time goes backwards"]] == [3]
    assert ds.robot(1).measurements.t.tolist() == [0.5]


def test_the_recording_keeps_the_first_of_repeated_readings_and_drops_self_sightings(tmp_path):
    """Barcode 5 is robot 1 itself: unmapped. Two readings of landmark 2 at one stamp: the
    first is kept. The file's report: 4 read, the loader kept 4, the conversion 2."""
    meas = (
        "1000000000.5 7 1.5 0.1\n"
        "1000000000.5 7 2.5 0.2\n"
        "1000000000.5 5 1.0 0.0\n"
        "1000000000.7 7 1.6 0.1\n"
    )
    ds = load_mrclam(_folder(tmp_path / "run", meas=meas))
    rec = to_recording(ds)
    m = rec.measurements
    assert m.t.tolist() == [0.5, 0.7]
    assert m.value[:, 0].tolist() == [1.5, 1.6]
    (camera,) = [f for f in rec.skips.files if f.file == "Robot1_Measurement.dat"]
    assert (camera.rows_read, camera.rows_kept) == (4, 2)
    assert dict(camera.skipped) == {
        "subject is neither another robot nor a landmark": 1,
        "repeated reading of one subject in one camera frame": 1,
    }


def _two_robots(root: Path) -> Path:
    """Robot 1's truth spans 0–10 s, robot 2's 2–6 s."""
    _folder(
        root,
        barcodes="1 5\n2 6\n3 7\n",
        landmarks="3 1.0 2.0 0.0 0.0\n",
        gt="1000000000.0 0 0 0\n1000000010.0 1 0 0\n",
    )
    (root / "Robot2_Groundtruth.dat").write_text("1000000002.0 0 1 0\n1000000006.0 1 1 0\n")
    (root / "Robot2_Odometry.dat").write_text("1000000001.0 0.1 0.0\n")
    (root / "Robot2_Measurement.dat").write_text("1000000003.0 5 2.0 0.0\n")
    return root


def test_truth_span_is_where_every_robot_has_truth_and_truth_end_the_latest(tmp_path):
    ds = load_mrclam(_two_robots(tmp_path / "run"))
    assert ds.truth_span == (2.0, 6.0)
    assert ds.truth_end == 10.0


def test_ground_truth_left_with_one_row_after_repeats_is_refused(tmp_path):
    """Two usable rows with one stamp: the repeat is skipped (first kept), one row is left, and
    ground truth needs two."""
    run = _folder(tmp_path / "run", gt="1000000000.0 0 0 0\n1000000000.0 1 0 0\n")
    with pytest.raises(DataError, match=r"Robot1_Groundtruth\.dat: fewer than 2 usable ground"):
        load_mrclam(run)


# ----------------------------------------------------------------------------------------------
# Which robots, and what a missing piece is called
# ----------------------------------------------------------------------------------------------


def test_the_robots_option_loads_only_the_robots_named(tmp_path):
    ds = load_mrclam(_two_robots(tmp_path / "run"), MrclamOptions(robots=(2,)))
    assert ds.robot_ids == (2,)
    assert set(ds.report.files) == {
        "Barcodes.dat",
        "Landmark_Groundtruth.dat",
        "Robot2_Groundtruth.dat",
        "Robot2_Odometry.dat",
        "Robot2_Measurement.dat",
    }


def test_a_robot_id_below_1_is_not_a_subject():
    with pytest.raises(ConfigError, match=r"robots must be positive subject ids, got \(0,\)"):
        MrclamOptions(robots=(0,))


def test_a_missing_robot_file_is_named(tmp_path):
    run = _folder(tmp_path / "run")
    (run / "Robot1_Measurement.dat").unlink()
    with pytest.raises(DataError) as info:
        load_mrclam(run)
    assert str(info.value).startswith(f"{run / 'Robot1_Measurement.dat'}: file missing (robot 1")


def test_a_robot_without_a_barcode_names_the_skipped_barcode_rows(tmp_path):
    run = _folder(tmp_path / "run", barcodes="# subject barcode\n1 5x\n2 7\n")
    with pytest.raises(DataError) as info:
        load_mrclam(run)
    assert str(info.value) == (
        f"{run / 'Barcodes.dat'}: robot 1 has no barcode; rows skipped: line 2 (non-numeric value)"
    )
