"""A subject that is both a robot (``RobotN_*`` files) and a landmark (``Landmark_Groundtruth.dat``)
is refused when the folder is loaded, naming the files, the line and the subject.

One subject carries one barcode (``Barcodes.dat``), so a camera reading of it could not say
whether the robot or the landmark was seen; before, the folder loaded and the conversion to a
recording failed later with "row 40 names both a robot and a landmark", naming no file.
"""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import pytest

from relloc.datasets.mrclam import MrclamOptions, load_mrclam
from relloc.errors import DataError

HEADER = "# MRCLAM-layout test file\n# written by the test\n# format line\n# columns\n"
T0 = 1_000_000_000.0


def _write(folder: Path, name: str, rows: list[str]) -> None:
    (folder / name).write_text(HEADER + "\n".join(rows) + "\n")


def _folder(folder: Path, robots: tuple[int, ...]) -> Path:
    """Barcodes for subjects 1, 2, 3 (5, 14, 63); subject 3 is the landmark (line 5)."""
    folder.mkdir(parents=True)
    _write(folder, "Barcodes.dat", ["1 5", "2 14", "3 63"])
    _write(folder, "Landmark_Groundtruth.dat", ["3 1.0 2.0 0.001 0.002"])
    for n in robots:
        _write(
            folder, f"Robot{n}_Groundtruth.dat", [f"{T0 + 0.1 * i:.3f} 0 0 0" for i in range(20)]
        )
        _write(folder, f"Robot{n}_Odometry.dat", [f"{T0 + 0.1 * i:.3f} 0.1 0" for i in range(20)])
        _write(folder, f"Robot{n}_Measurement.dat", [f"{T0 + 0.5:.3f} 63 2.0 0.1"])
    return folder


def test_a_robot_that_is_also_a_landmark_is_refused_at_load_time(tmp_path: Path) -> None:
    folder = _folder(tmp_path / "run", robots=(1, 3))
    message = (
        f"{folder / 'Robot3_Groundtruth.dat'} (and Robot3_Odometry.dat and Robot3_Measurement.dat) "
        f"make subject 3 a robot, but {folder / 'Landmark_Groundtruth.dat'}:5 lists subject 3 as "
        "a landmark"
    )
    with pytest.raises(DataError, match=re.escape(message)):
        load_mrclam(folder)
    with pytest.raises(DataError, match=re.escape(message)):
        load_mrclam(folder, MrclamOptions(on_bad_row="raise"))


def test_the_robots_not_loaded_do_not_clash(tmp_path: Path) -> None:
    """Only the robots loaded are robots of the dataset: leaving robot 3 out loads the rest."""
    folder = _folder(tmp_path / "run", robots=(1, 3))
    ds = load_mrclam(folder, MrclamOptions(robots=(1,)))
    assert ds.robot_ids == (1,)
    assert ds.landmarks.subject.tolist() == [3]


def test_a_run6_robot_renamed_to_a_landmark_subject_is_refused(
    tmp_path: Path, mrclam_run6: Path
) -> None:
    """The audit's folder: run 6 with Robot5_* renamed Robot9_*; subject 9 is a landmark (line 8
    of Landmark_Groundtruth.dat, barcode 70)."""
    src = mrclam_run6
    dst = tmp_path / "x"
    dst.mkdir()
    for name in ("Barcodes.dat", "Landmark_Groundtruth.dat"):
        shutil.copyfile(src / name, dst / name)
    for kind in ("Groundtruth", "Odometry", "Measurement"):
        shutil.copyfile(src / f"Robot5_{kind}.dat", dst / f"Robot9_{kind}.dat")
    landmark_line = (dst / "Landmark_Groundtruth.dat").read_text().split("\n")[7]
    assert landmark_line.split()[0] == "9"  # the premise: line 8 is landmark 9
    with pytest.raises(DataError) as caught:
        load_mrclam(dst)
    text = str(caught.value)
    assert str(dst / "Robot9_Groundtruth.dat") in text
    assert f"{dst / 'Landmark_Groundtruth.dat'}:8 lists subject 9 as a landmark" in text
    assert "subject 9 a robot" in text
