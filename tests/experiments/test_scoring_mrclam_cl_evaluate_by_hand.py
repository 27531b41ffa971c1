"""``relloc.experiments.mrclam_cl.evaluate`` on hand-made estimates of three robots standing at
the origin: the per-robot figures, their mean, the scored window and the NEES."""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest

from relloc.datasets.mrclam import GroundTruth

OUT_T = np.array([0.0, 5.0, 10.0, 15.0, 20.0])


def _dataset() -> SimpleNamespace:
    t = np.arange(0.0, 20.01, 0.1)
    z = np.zeros(t.size)
    truth = GroundTruth(t=t, x=z, y=z, theta=z, gap_threshold=0.5)
    return SimpleNamespace(
        robot_ids=(1, 2, 3), robot=lambda r: SimpleNamespace(groundtruth=truth), path="hand"
    )


def _result() -> dict[str, np.ndarray]:
    """Robot 1 at (3, 4) m off (5 m) except (0, 1) m at 20 s; robot 2 in place with its heading
    2π + 0.2 rad (0.2 rad off once wrapped) except 2π + 0.6 rad at 20 s; robot 3 exact;
    covariances 0.01·I, robot 2's 0.04·I."""
    mean = np.zeros((OUT_T.size, 3, 3))
    mean[:, 0, :2] = [3.0, 4.0]
    mean[-1, 0, :2] = [0.0, 1.0]
    mean[:, 1, 2] = 2 * np.pi + np.array([0.2, 0.2, 0.2, 0.2, 0.6])
    cov = np.tile(np.eye(3) * 0.01, (OUT_T.size, 3, 1, 1))
    cov[:, 1] = np.eye(3) * 0.04
    return {"mean": mean, "cov": cov}


def test_per_robot_figures_and_their_mean() -> None:
    from relloc.experiments.mrclam_cl import evaluate

    out = evaluate(_result(), _dataset(), OUT_T, 0.0)
    pos = np.sqrt((4 * 25 + 1) / 5)
    assert out["pos_rmse_m"] == pytest.approx({"1": pos, "2": 0.0, "3": 0.0, "mean": pos / 3})
    heading = np.sqrt((4 * 0.04 + 0.36) / 5)
    assert out["heading_rmse_rad"] == pytest.approx(
        {"1": 0.0, "2": heading, "3": 0.0, "mean": heading / 3}
    )
    assert out["final_pos_err_m"] == pytest.approx({"1": 1.0, "2": 0.0, "3": 0.0, "mean": 1 / 3})
    # NEES: robot 1 25/0.01 four times and 1/0.01 once, robot 2 0.04/0.04 four times and
    # 0.36/0.04 once, robot 3 0
    assert out["anees"] == pytest.approx((4 * 2500 + 100 + 4 * 1.0 + 9.0) / 15 / 3)
    assert out["records_without_truth"] == {} and out["robots_without_truth"] == []


def test_the_scored_window_includes_both_ends() -> None:
    """[5, 15] s: the records at 5, 10 and 15 s, robot 1 5 m off at each."""
    from relloc.experiments.mrclam_cl import evaluate

    out = evaluate(_result(), _dataset(), OUT_T, 5.0, 15.0)
    assert out["pos_rmse_m"]["1"] == pytest.approx(5.0)
    assert out["final_pos_err_m"]["1"] == pytest.approx(5.0)
    assert out["anees"] == pytest.approx((3 * 2500 + 3 * 1.0) / 9 / 3)
    only_end = evaluate(_result(), _dataset(), OUT_T, 20.0, 20.0)
    assert only_end["final_pos_err_m"]["1"] == pytest.approx(1.0)


def _landmark_gap_inputs(first_landmark: float) -> tuple[Any, Any, Any]:
    """One robot standing at the origin; it detects a landmark at ``first_landmark`` and at
    9.5 s (its unknown bearing at 5.9 s is not a landmark); its records at 0, 0.5, 2, 6 and
    10 s have heading errors 0.1, 0.1, 0.2, 0.4 and 0.1 rad (0.23 rad² in all)."""
    from relloc.core.recording import Measurements, measurement_rows

    out_t = np.array([0.0, 0.5, 2.0, 6.0, 10.0])
    rows = Measurements.concatenate(
        [
            measurement_rows(
                "bearing", t=[first_landmark, 9.5], observer=0, landmark=0, value=[[0.0]] * 2
            ),
            measurement_rows("bearing", t=[5.9], observer=0, value=[[0.0]]),
        ]
    )
    prepared = SimpleNamespace(recording=SimpleNamespace(measurements=rows), out_t=out_t)
    t = np.arange(0.0, 20.01, 0.1)
    z = np.zeros(t.size)
    truth = GroundTruth(t=t, x=z, y=z, theta=z, gap_threshold=0.5)
    ds = SimpleNamespace(robot_ids=(1,), robot=lambda r: SimpleNamespace(groundtruth=truth))
    mean = np.zeros((5, 1, 3))
    mean[:, 0, 2] = [0.1, 0.1, 0.2, 0.4, 0.1]
    return {"mean": mean}, ds, prepared


def test_heading_error_binned_by_the_time_since_the_last_landmark() -> None:
    """Landmarks at 0 s and 9.5 s: the records are 0, 0.5, 2, 6 and 0.5 s after one."""
    from relloc.experiments.mrclam_cl import heading_error_by_landmark_gap

    out = heading_error_by_landmark_gap(*_landmark_gap_inputs(0.0))
    assert list(out) == ["0-1s", "1-5s", "5-infs"]
    assert out["0-1s"] == pytest.approx(
        {"time_share": 0.6, "heading_rmse_rad": 0.1, "squared_error_share": 0.03 / 0.23}
    )
    assert out["1-5s"] == pytest.approx(
        {"time_share": 0.2, "heading_rmse_rad": 0.2, "squared_error_share": 0.04 / 0.23}
    )
    assert out["5-infs"] == pytest.approx(
        {"time_share": 0.2, "heading_rmse_rad": 0.4, "squared_error_share": 0.16 / 0.23}
    )
