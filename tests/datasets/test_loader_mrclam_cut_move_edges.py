"""``relloc mrclam cut`` and ``relloc mrclam move`` on a tiny hand-written run: the ends of the
span, the settings refused, the rows counted as unreadable and the text of what is written."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from relloc.datasets.mrclam import load_mrclam
from relloc.datasets.mrclam_cut import FileCut, cut_mrclam
from relloc.datasets.mrclam_move import FileMove, move_mrclam
from relloc.errors import ConfigError, DataError

T0 = 1_000_000_000


def _run(root: Path, *, extra: dict[str, str] | None = None) -> Path:
    """Robots 1 and 2 (barcodes 5, 6), landmark 3 (barcode 7); ground truth and odometry at
    T0 + 0 … 4 s, one camera row each at T0 + 0.5 s."""
    root.mkdir(parents=True)
    files = {
        "Barcodes.dat": "1 5\n2 6\n3 7\n",
        "Landmark_Groundtruth.dat": "3 0.0 1.0 0.001 0.002\n",
    }
    for n in (1, 2):
        files[f"Robot{n}_Groundtruth.dat"] = "".join(
            f"{T0 + s}.0 {s}.0 {n}.0 0.0\n" for s in range(5)
        )
        files[f"Robot{n}_Odometry.dat"] = "".join(f"{T0 + s}.0 0.1 0.0\n" for s in range(5))
        files[f"Robot{n}_Measurement.dat"] = f"{T0}.5 7 1.5 0.1\n"
    for name, text in (extra or {}).items():
        files[name] = files[name] + text
    for name, text in files.items():
        (root / name).write_text(text)
    return root


# ----------------------------------------------------------------------------------------------
# cut
# ----------------------------------------------------------------------------------------------


def test_a_cut_keeps_rows_from_its_start_up_to_but_not_at_its_end(tmp_path):
    report = cut_mrclam(_run(tmp_path / "src"), tmp_path / "dst", start_s=1.0, end_s=3.0)
    assert report.files["Robot1_Groundtruth.dat"] == FileCut(kept=2, outside=3, unreadable=0)
    assert (tmp_path / "dst/Robot1_Odometry.dat").read_bytes() == (
        b"1000000001.0 0.1 0.0\n1000000002.0 0.1 0.0\n"
    )


def test_a_cut_lists_its_robots_in_order_and_refuses_an_empty_choice(tmp_path):
    src = _run(tmp_path / "src")
    assert cut_mrclam(src, tmp_path / "a", robots=[2, 1]).robots == (1, 2)
    with pytest.raises(ConfigError, match=r"mrclam cut: no robot chosen \(robots: \[1, 2\]\)"):
        cut_mrclam(src, tmp_path / "b", robots=[])
    assert not (tmp_path / "b").exists()


def test_a_start_at_the_runs_last_stamp_is_refused(tmp_path):
    with pytest.raises(ConfigError, match=r"start 4 s is at or past the end of .*4\.000 s after"):
        cut_mrclam(_run(tmp_path / "src"), tmp_path / "dst", start_s=4.0)


def test_a_left_over_staging_folder_does_not_stop_a_cut(tmp_path):
    src = _run(tmp_path / "src")
    (tmp_path / ".dst.partial").mkdir()
    (tmp_path / ".dst.partial/junk.txt").write_text("from a killed run")
    cut_mrclam(src, tmp_path / "dst", start_s=1.0)
    assert not (tmp_path / "dst/junk.txt").exists()
    assert load_mrclam(tmp_path / "dst").robot_ids == (1, 2)


def test_a_cut_that_is_not_a_run_names_the_file_as_it_would_have_been_written(tmp_path):
    dst = tmp_path / "dst"
    with pytest.raises(DataError) as info:
        cut_mrclam(_run(tmp_path / "src"), dst, start_s=3.5)
    assert f"{dst / 'Robot1_Groundtruth.dat'}: 1 usable rows, need at least 2" in str(info.value)
    assert ".dst.partial" not in str(info.value)


# ----------------------------------------------------------------------------------------------
# move
# ----------------------------------------------------------------------------------------------


def test_a_half_turn_writes_a_rounded_minus_zero_as_zero(tmp_path):
    """(0, 1) turned by π is (−1.2e-16, −1): written to 8 decimals, 0 and −1."""
    move_mrclam(_run(tmp_path / "src"), tmp_path / "dst", rotation_rad=math.pi)
    assert (tmp_path / "dst/Landmark_Groundtruth.dat").read_text() == (
        "3 0.00000000 -1.00000000 0.001 0.002\n"
    )


def test_a_position_moved_exactly_onto_the_bound_is_accepted(tmp_path):
    """Robot 1's last ground-truth row (4, 1) shifted by 99 996 m lands on x = 10⁵ m."""
    move_mrclam(_run(tmp_path / "src"), tmp_path / "dst", shift_m=(99_996.0, 0.0))
    rows = (tmp_path / "dst/Robot1_Groundtruth.dat").read_text().splitlines()
    assert rows[-1] == "1000000004.0 100000.00000000 1.00000000 0.00000000"


def test_positions_keep_at_most_12_decimals(tmp_path):
    src = _run(tmp_path / "src")
    (src / "Landmark_Groundtruth.dat").write_text("3 0.12345678901234 1.0 0.001 0.002\n")
    move_mrclam(src, tmp_path / "dst")
    assert (tmp_path / "dst/Landmark_Groundtruth.dat").read_text() == (
        "3 0.123456789012 1.000000000000 0.001 0.002\n"
    )


def test_rows_the_loader_skips_are_unreadable_to_the_move_not_refused(tmp_path):
    """A barcode row of three columns, a camera row reading barcode 6.5, an odometry row
    stamped past 2³² s and a landmark 2·10⁵ m away: the loader skips each, the move counts
    each as unreadable (and would refuse none of them after the shift)."""
    src = _run(
        tmp_path / "src",
        extra={
            "Barcodes.dat": "4 9 9\n",
            "Robot1_Measurement.dat": f"{T0}.6 6.5 1.5 0.1\n",
            "Robot1_Odometry.dat": "5000000000.0 0.1 0.0\n",
            "Landmark_Groundtruth.dat": "4 200000.0 0.0 0.0 0.0\n",
        },
    )
    report = move_mrclam(src, tmp_path / "dst", shift_m=(1.0, 0.0), clock_s=1.0)
    for name in (
        "Barcodes.dat",
        "Robot1_Measurement.dat",
        "Robot1_Odometry.dat",
        "Landmark_Groundtruth.dat",
    ):
        assert report.files[name].unreadable == 1, name
    assert report.files["Robot1_Odometry.dat"] == FileMove(moved=5, unreadable=1)


def test_a_stamp_shifted_out_of_bounds_names_its_file_and_line(tmp_path):
    src = _run(tmp_path / "src")
    gt = src / "Robot1_Groundtruth.dat"
    gt.write_text("# t x y theta\n" + gt.read_text())
    with pytest.raises(ConfigError) as info:
        move_mrclam(src, tmp_path / "dst", clock_s=-1_000_000_000.5)
    assert f"the stamp 1000000000.0 at {gt}:2 becomes -0.5" in str(info.value)


def test_a_barcode_map_onto_a_kept_barcode_says_which_subject_keeps_it(tmp_path):
    with pytest.raises(ConfigError) as info:
        move_mrclam(_run(tmp_path / "src"), tmp_path / "dst", barcodes={5: 7})
    assert str(info.value) == (
        "barcodes: subjects 1 (5→7) and 3 (keeps 7) would both carry barcode 7; "
        "a barcode names one subject"
    )


def test_a_barcode_map_onto_0_is_refused_as_not_an_id(tmp_path):
    with pytest.raises(ConfigError, match=r"^barcodes: 5→0: barcodes are integers in \[1, 2147"):
        move_mrclam(_run(tmp_path / "src"), tmp_path / "dst", barcodes={5: 0})


def test_only_camera_rows_refuse_a_new_barcode_that_names_no_subject(tmp_path):
    """``Barcodes.dat`` holds a row the loader skips (subject 0) with barcode 11; mapping
    5 → 11 moves it as it is (only a *measured* barcode 11 would turn into sightings of
    subject 1)."""
    src = _run(tmp_path / "src", extra={"Barcodes.dat": "0 11\n"})
    report = move_mrclam(src, tmp_path / "dst", barcodes={5: 11})
    assert report.files["Barcodes.dat"] == FileMove(moved=4, unreadable=0)
    assert (tmp_path / "dst/Barcodes.dat").read_text() == "1 11\n2 6\n3 7\n0 11\n"
    assert load_mrclam(tmp_path / "dst").barcodes == {11: 1, 6: 2, 7: 3}


def test_a_turned_heading_is_wrapped_into_minus_pi_to_pi(tmp_path):
    """3 rad turned by 1 rad is 4 rad, written as 4 − 2π = −2.28318531."""
    src = _run(tmp_path / "src")
    gt = src / "Robot1_Groundtruth.dat"
    gt.write_text(gt.read_text().replace(" 0.0\n", " 3.0\n"))
    move_mrclam(src, tmp_path / "dst", rotation_rad=1.0)
    rows = (tmp_path / "dst/Robot1_Groundtruth.dat").read_text().splitlines()
    assert [row.split()[3] for row in rows] == ["-2.28318531"] * 5
