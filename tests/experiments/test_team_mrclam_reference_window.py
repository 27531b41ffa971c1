"""``relloc team up MRCLAM_DIR --estimator cooperative``'s in-process reference: the case's team
EIF recorded at every output time from the first common ground-truth time up to the run's end,
that end included (``--duration`` picks it on the 0.5 s grid)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from mrclam_synthetic import write_mrclam_folder

from relloc.calibration.camera import CameraFit
from relloc.calibration.odometry import OdometryModelFit
from relloc.calibration.window import CalibrationWindow
from relloc.datasets.mrclam import load_mrclam
from relloc.estimators.cooperative import CooperativeEstimator
from relloc.experiments.mrclam_cl import FittedModels
from relloc.experiments.mrclam_team import in_process, prepared_team, window_end


def _fit(folder: str) -> FittedModels:
    """Round hand-made models of five robots (not fitted)."""
    window = CalibrationWindow(0.0, 2.0, folder)
    return FittedModels(
        odometry=OdometryModelFit(
            calibration_window=window,
            latency_s=0.0,
            time_constant_s=0.0,
            scale_v=(1.0,) * 5,
            scale_w=(1.0,) * 5,
            q_v0=1e-4,
            k_v=0.01,
            q_w0=1e-4,
            k_w=0.01,
            k_wv=0.0,
            odometry_window_s=1.0,
        ),
        camera=CameraFit(
            calibration_window=window,
            bearing_offset=(0.0,) * 5,
            sigma_bearing_raw=0.01,
            bearing_inflation=1.0,
            sigma_bearing=0.01,
            range_bias_coeffs=(0.0,) * 5,
            sigma_range_raw=0.05,
            range_inflation=1.0,
            sigma_range=0.05,
            range_interval_s=1.0,
            correlation={},
            n_residuals=10,
        ),
    )


def test_the_reference_is_recorded_on_the_grid_up_to_the_end_it_is_given(tmp_path: Path) -> None:
    folder = write_mrclam_folder(tmp_path / "Synthetic", 4.0)
    ds = load_mrclam(folder)
    # seed 381907: used nowhere else in the tests (robot 1's fixes; nothing statistical)
    prepared, settings = prepared_team(ds, _fit(str(folder)), 381907, "range_bearing/none")
    assert prepared.t_start == 0.0
    end = window_end(prepared, 1.5)
    assert end == 1.5
    t, mean, _ = in_process(prepared, settings, end).stacked(
        CooperativeEstimator.owner, prepared.recording.robots
    )
    np.testing.assert_allclose(t, [0.0, 0.5, 1.0, 1.5])
    assert mean.shape == (4, 5, 3) and np.isfinite(mean).all()
    assert window_end(prepared, 1.2) == pytest.approx(1.0)  # the grid time at or before
