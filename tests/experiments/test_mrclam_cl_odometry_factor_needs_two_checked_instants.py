"""mrclam-cl's odometry noise factor is checked over the second half of the calibration window
from the first output time where every robot has ground truth; a half holding one such time,
not two, leaves the factor unfitted (1) and says why."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

from relloc.calibration.window import CalibrationWindow
from relloc.datasets.mrclam import load_mrclam
from relloc.experiments.mrclam_cl import fit_odometry_inflation


def _write_mrclam_folder(folder: Path, duration: float) -> Path:
    where = Path(__file__).parents[1] / "cooperative" / "conftest.py"
    spec = importlib.util.spec_from_file_location("cooperative_conftest", where)
    assert spec is not None and spec.loader is not None
    cooperative = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(cooperative)
    return Path(cooperative.write_mrclam_folder(folder, duration=duration))


@pytest.fixture(scope="module")
def one_checked_instant(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """12 s of five simulated robots, robot 5's ground truth ending at 6.05 s: of the output
    times (every 0.5 s) in [6, 12] s only 6 s has every robot's truth."""
    out = _write_mrclam_folder(tmp_path_factory.mktemp("mrclam") / "Synthetic", 12.0)
    gt = out / "Robot5_Groundtruth.dat"
    lines = gt.read_text().splitlines(keepends=True)
    head = [s for s in lines if s.startswith("#")]
    data = [s for s in lines if not s.startswith("#")]
    t0 = float(data[0].split()[0])
    gt.write_text("".join(head + [s for s in data if float(s.split()[0]) - t0 < 6.05]))
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
