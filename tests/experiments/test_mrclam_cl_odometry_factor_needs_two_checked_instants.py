"""mrclam-cl's odometry noise factor is checked over the second half of the calibration window
from the first output time where every robot has ground truth; a half holding one such time,
not two, leaves the factor unfitted (1) and says why."""

from __future__ import annotations

from pathlib import Path

import pytest
from mrclam_synthetic import truth_ending_before, write_mrclam_folder

from relloc.calibration.window import CalibrationWindow
from relloc.datasets.mrclam import load_mrclam
from relloc.experiments.mrclam_cl import fit_odometry_inflation


@pytest.fixture(scope="module")
def one_checked_instant(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """12 s of five simulated robots, robot 5's ground truth ending at 6.05 s: of the output
    times (every 0.5 s) in [6, 12] s only 6 s has every robot's truth."""
    out = write_mrclam_folder(tmp_path_factory.mktemp("mrclam") / "Synthetic", 12.0)
    truth_ending_before(out, 5, 6.05)
    return out


def test_one_instant_with_every_robot_s_truth_is_too_few_to_check_a_factor_on(
    one_checked_instant: Path,
) -> None:
    ds = load_mrclam(one_checked_instant)
    assert ds.truth_span[0] == 0.0
    checked = [ds.robot(5).groundtruth.at(t).valid for t in (6.0, 6.5)]
    assert checked == [True, False]
    got = fit_odometry_inflation(ds, CalibrationWindow(0.0, 12.0, "the test window"))
    assert got.k == 1.0 and not got.met and got.tried == ()
    assert got.not_fitted == (
        "[6.00, 12.00] s of the test window: no two output times where every robot has ground truth"
    )
