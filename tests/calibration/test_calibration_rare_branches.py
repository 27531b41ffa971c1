"""Calibration branches that only rarer data or bad settings reach: the JSON records of the
detection and field-of-view fits, a robot without commands, a decorrelation time that is never
reached, and refused settings (each naming where)."""

import json

import numpy as np
import pytest

from relloc.calibration.camera import fit_detection_probability, fit_field_of_view
from relloc.calibration.odometry import fit_command_fir, ground_truth_odometry
from relloc.calibration.turn_rate import residual_stats
from relloc.calibration.uwb import MAX_CORRELATION_LAG, decorrelation_time
from relloc.calibration.window import CalibrationWindow
from relloc.datasets.mrclam import Odometry
from relloc.errors import ConfigError


def test_detection_and_field_of_view_fits_are_json_records(synthetic):
    """Robot 1 sees robot 2 in every other of its 100 one-second frames, at bearing 0.2."""
    t = np.arange(0.0, 100.0, 2.0)
    seen = synthetic.measurements(t, np.full(t.size, 2), np.ones(t.size), np.full(t.size, 0.2))
    landmark = synthetic.measurements(t + 1.0, np.full(t.size, 10), np.ones(t.size), -0.1 + 0 * t)
    both = synthetic.measurements(
        np.concatenate([seen.t, landmark.t]),
        np.concatenate([seen.subject, landmark.subject]),
        np.ones(2 * t.size),
        np.concatenate([seen.bearing, landmark.bearing]),
    )
    ds = synthetic.dataset(
        [
            synthetic.still_robot(1, 0, 0, 0, 100.0, both),
            synthetic.still_robot(2, 1, 0, 0, 100.0),
        ],
        [(5.0, 5.0)],
    )
    window = CalibrationWindow(0.0, 100.0, "synthetic")
    p_d = fit_detection_probability(ds, window)
    record = json.loads(json.dumps(p_d.to_dict()))
    assert record["calibration_window"] == window.to_dict()
    assert (record["frames"], record["pairs"], record["detected_pairs"]) == (100, 100, 50)
    assert record["p_detect"] == pytest.approx(0.5)
    fov = json.loads(json.dumps(fit_field_of_view(ds, window).to_dict()))
    assert fov["calibration_window"] == window.to_dict()
    assert fov["half_width_rad"] == pytest.approx(0.2) and fov["n_bearings"] == 100


def test_ground_truth_odometry_of_a_robot_without_commands_is_empty(synthetic):
    robot = synthetic.still_robot(1, 0.0, 0.0, 0.0, 10.0)
    silent = synthetic.robot(1, robot.groundtruth, Odometry(np.zeros(0), np.zeros(0), np.zeros(0)))
    od = ground_truth_odometry(silent)
    assert od.t.size == od.v.size == od.omega.size == 0
    for dt in (0.0, -0.02, float("nan")):
        with pytest.raises(ConfigError, match="ground_truth_odometry: dt must be > 0"):
            ground_truth_odometry(robot, dt)


def test_fir_without_turn_rate_lags_is_refused(synthetic):
    rng = np.random.default_rng(3)
    robot = synthetic.commanded_robot(1, rng, duration=20.0)
    with pytest.raises(ConfigError, match="fit_command_fir: needs at least one turn-rate lag"):
        fit_command_fir(robot, CalibrationWindow(0.0, 20.0, "synthetic"), lags_w_s=())


def test_residual_blocks_shorter_than_the_grid_are_refused():
    e, ok = np.zeros(100), np.ones(100, dtype=bool)
    with pytest.raises(ConfigError, match=r"residual_stats: need block_s ≥ dt > 0"):
        residual_stats(e, ok, block_s=0.01, dt=0.02)
    with pytest.raises(ConfigError, match=r"residual_stats: need block_s ≥ dt > 0"):
        residual_stats(e, ok, block_s=1.0, dt=0.0)


def test_decorrelation_time_is_none_when_never_reached():
    """A ramp stays perfectly correlated with itself at every lag it has room for; readings
    farther apart than ``MAX_CORRELATION_LAG`` have no lag short enough to look at."""
    ramp = np.arange(6.0)
    assert decorrelation_time(np.arange(6.0), ramp) is None
    sparse = np.arange(8.0) * (MAX_CORRELATION_LAG + 1.0)
    noise = np.random.default_rng(0).standard_normal(8)
    assert decorrelation_time(sparse, noise) is None
    # the same readings one second apart decorrelate within a lag of a few seconds
    tau = decorrelation_time(np.arange(8.0), noise)
    assert tau is not None and 0.0 < tau < 7.0
