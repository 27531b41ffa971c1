"""Degenerate and bad input to the calibration fits: each is refused with an error naming the
window, the robot or the argument, or stated in the fit — never a raw numpy exception, a NaN
fit or a placeholder passed on as a fit."""

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from relloc.calibration.camera import CameraFit, camera_residuals, fit_camera, lag_correlation
from relloc.calibration.odometry import fit_command_fir, fit_odometry_model, unfitted_note
from relloc.calibration.uwb import fit_uwb_noise
from relloc.calibration.window import CalibrationWindow, odometry_and_truth, spanning
from relloc.core.recording import FileSkips
from relloc.datasets.mrclam import GroundTruth, Odometry
from relloc.datasets.uwb import UwbRecording
from relloc.errors import ConfigError, DataError
from relloc.experiments.fit_file import load_fit, save_fit
from relloc.experiments.mrclam_cl import FittedModels

WINDOW = CalibrationWindow(0.0, 60.0, "calib")


def _moving(synthetic, subject=1, seed=1):
    return synthetic.commanded_robot(subject, np.random.default_rng(seed), duration=60.0)


def _with_truth(robot, keep):
    """``robot`` with only the ground-truth samples ``keep``."""
    gt = robot.groundtruth
    kept = {name: getattr(gt, name)[keep] for name in ("t", "x", "y", "theta")}
    return replace(robot, groundtruth=replace(gt, **kept))


# ----------------------------------------------------------------------------------------------
# Odometry
# ----------------------------------------------------------------------------------------------


def test_a_robot_without_samples_in_the_window_is_listed_as_unfitted(synthetic):
    """Robot 2's ground truth ends 2 s into the window: no sample, scales of 1 — stated."""
    ds = synthetic.dataset([_moving(synthetic), synthetic.still_robot(2, 0, 0, 0, 2.0)])
    fit = fit_odometry_model(ds, WINDOW, 1.0)
    assert (fit.scale_v[1], fit.scale_w[1], fit.unfitted_robots) == (1.0, 1.0, (2,))
    assert fit.to_dict()["unfitted_robots"] == (2,)
    alone = fit_odometry_model(synthetic.dataset([_moving(synthetic)]), WINDOW, 1.0)
    assert alone.unfitted_robots == ()
    # the reports of mrclam-cl and mrclam-association say it beside the fitted scales
    assert "robot 2 had no odometry" in unfitted_note(fit.unfitted_robots)
    assert unfitted_note(alone.unfitted_robots) == ""


def _fitted_models(odometry):
    camera = CameraFit(
        calibration_window=odometry.calibration_window,
        bearing_offset=(0.0,) * len(odometry.scale_v),
        sigma_bearing_raw=0.01,
        bearing_inflation=4.0,
        sigma_bearing=0.02,
        range_bias_coeffs=(0.05,),
        sigma_range_raw=0.05,
        range_inflation=4.0,
        sigma_range=0.1,
        range_interval_s=1.0,
        correlation={},
        n_residuals=100,
    )
    return FittedModels(odometry=odometry, camera=camera)


def test_the_fit_file_states_unfitted_robots_and_reads_files_without_the_key(synthetic, tmp_path):
    ds = synthetic.dataset([_moving(synthetic), synthetic.still_robot(2, 0, 0, 0, 2.0)])
    fit = _fitted_models(fit_odometry_model(ds, WINDOW, 1.0))
    path = tmp_path / "fit.json"
    save_fit(fit, path)
    raw = json.loads(path.read_text())
    assert raw["odometry"]["unfitted_robots"] == [2]
    assert load_fit(path) == fit
    # a team fitted robot by robot: no key, as in every file written before it existed
    all_fitted = replace(fit, odometry=replace(fit.odometry, unfitted_robots=()))
    save_fit(all_fitted, path)
    assert "unfitted_robots" not in json.loads(path.read_text())["odometry"]
    assert load_fit(path) == all_fitted
    for bad in ([2, 2], [0], [1, 2, 3]):
        raw["odometry"]["unfitted_robots"] = bad
        path.write_text(json.dumps(raw))
        with pytest.raises(DataError, match=r"fit\.json: odometry\.unfitted_robots: expected"):
            load_fit(path)


def test_a_window_shorter_than_three_integration_windows_says_so(synthetic):
    """A robot commanded from 0 s on a 20 s window with 7 s integration windows: from 1 s after
    its first command to the window's end is 19 s, not more than three windows (21 s). The
    error gives both lengths rather than claiming the odometry does not overlap the ground
    truth; on a 23 s window (22 s) the fit goes through."""
    ds = synthetic.dataset([_moving(synthetic)])
    assert ds.robot(1).odometry.t[0] == 0.0 and ds.robot(1).groundtruth.t[-1] > 25.0
    with pytest.raises(DataError) as e:
        fit_odometry_model(ds, CalibrationWindow(0.0, 20.0, "calib"), 7.0)
    assert str(e.value) == (
        "calibration window [0.00, 20.00] s of calib: to fit the odometry on, a robot needs "
        "more than three integration windows (21 s) from 1 s after its first command to 1 s "
        "before its last ground truth; the longest is robot 1's, 19 s"
    )
    assert fit_odometry_model(ds, CalibrationWindow(0.0, 23.0, "calib"), 7.0).scale_v[0] > 0


def test_rates_without_a_whole_integration_window_are_refused(synthetic):
    """Ground truth in 0.4 s bursts every 1.2 s: samples to fit the scales on, but no whole
    1 s window to fit the variance rates on (they were the floor, passed on as a fit)."""
    robot = _moving(synthetic)
    robot = _with_truth(robot, (robot.groundtruth.t % 1.2) < 0.4)
    with pytest.raises(DataError, match=r"of calib: 0 whole 1 s integration windows"):
        fit_odometry_model(synthetic.dataset([robot]), WINDOW, 1.0)


def test_a_robot_moving_against_its_commands_is_refused(synthetic):
    """Speed commands of the wrong sign fit a negative scale, which would reverse every later
    command (and which the fit file refuses to read back)."""
    robot = _moving(synthetic, 3)
    od = robot.odometry
    reversed_speed = replace(robot, odometry=replace(od, v=-od.v))
    with pytest.raises(DataError, match=r"robot 3 does not move with its commands: its speed"):
        fit_odometry_model(synthetic.dataset([reversed_speed]), WINDOW, 1.0)


def test_the_turn_rate_filter_of_a_robot_that_never_turns_is_refused(synthetic):
    """No turn-rate command: the filter's gain would be 0 and its mean delay 0/0."""
    t = np.arange(0.0, 60.0, 0.01)
    straight = synthetic.robot(
        4,
        GroundTruth(t=t, x=0.2 * t, y=0 * t, theta=0 * t, gap_threshold=0.5),
        Odometry(t=t, v=np.full_like(t, 0.2), omega=0 * t),
    )
    with pytest.raises(DataError, match=r"no commanded motion of robot 4 .* turn-rate filter"):
        fit_command_fir(straight, WINDOW)


def test_the_turn_rate_filter_refuses_a_lag_that_is_not_a_number(synthetic):
    with pytest.raises(ConfigError, match=r"fit_command_fir: lags_w_s\[1\]: must be a finite"):
        fit_command_fir(_moving(synthetic), WINDOW, lags_w_s=(0.0, float("nan")))


# ----------------------------------------------------------------------------------------------
# Camera
# ----------------------------------------------------------------------------------------------


def _camera(synthetic, bearing_error, range_error, noise=0.01):
    """One still robot at the origin detecting a landmark 2 m ahead every 0.5 s for 100 s."""
    rng = np.random.default_rng(6)
    t = np.arange(200) * 0.5
    meas = synthetic.measurements(
        t,
        np.full(t.size, 10),
        2.0 + range_error + noise * rng.standard_normal(t.size),
        bearing_error + noise * rng.standard_normal(t.size),
    )
    return synthetic.dataset([synthetic.still_robot(1, 0, 0, 0, 100.0, meas)], [(2.0, 0.0)])


@pytest.mark.parametrize(
    ("bearing_error", "range_error", "noise", "match"),
    [
        (0.2, 0.0, 0.01, r"0 of 200 bearing residuals within 0\.1 rad"),
        (0.0, 1.5, 0.01, r"0 of 200 range residuals within 1 m"),
        (0.0, 0.0, 0.0, "bearing residuals without spread"),
    ],
    ids=["every-bearing-off", "every-range-off", "noiseless"],
)
def test_a_camera_fit_without_inliers_or_spread_is_refused(
    synthetic, bearing_error, range_error, noise, match
):
    """A camera turned 0.2 rad (or reading 1.5 m long) has no inlier: a raw ValueError once;
    exact readings a σ of 0."""
    ds = _camera(synthetic, bearing_error, range_error, noise)
    with pytest.raises(DataError, match=rf"\[0\.00, 100\.00\] s of c: {match}"):
        fit_camera(ds, CalibrationWindow(0.0, 100.0, "c"), range_interval_s=1.0)


def test_lag_correlation_over_no_row_is_zero(synthetic):
    res = camera_residuals(_camera(synthetic, 0.0, 0.0), CalibrationWindow(0.0, 100.0, "c"))
    assert lag_correlation(res, res.range_error, np.zeros(res.t.size, dtype=bool), 1.0) == 0.0


# ----------------------------------------------------------------------------------------------
# UWB
# ----------------------------------------------------------------------------------------------


def _uwb(t, link, uwb_range):
    """A recording of the readings ``uwb_range`` at times ``t`` on links ``link`` (pairs)
    against a true range of 2 m, in time order (a recording's rule)."""
    order = np.argsort(np.asarray(t, dtype=float), kind="stable")
    t = np.asarray(t, dtype=float)[order]
    link = np.asarray(link, dtype=np.int64).reshape(-1, 2)[order]
    uwb_range = np.asarray(uwb_range, dtype=float)[order]
    skips = FileSkips(file="uwb.csv", rows_read=t.size, rows_kept=t.size)
    return UwbRecording(
        path=Path("uwb.csv"),
        t=t,
        node1=link[:, 0],
        node2=link[:, 1],
        uwb_range=uwb_range,
        mocap_range=np.full(t.size, 2.0),
        data_rows=t.size,
        skipped=skips,
    )


def test_a_uwb_fit_of_equal_ranges_is_refused():
    """Every reading 2.1 m: a spread of 0 was fitted, and every range taken as exact."""
    t = 0.1 * np.arange(50)
    rec = _uwb(t, [(1, 2)] * 50, np.full(50, 2.1))
    with pytest.raises(DataError, match=r"\[0\.00, 4\.90\] s of u: the 50 within-link .* spread"):
        fit_uwb_noise(rec, spanning(t, "u"))


def test_a_link_without_varying_consecutive_residuals_gives_no_lag_correlation():
    """Link 1–3 reads one range but for its last reading: its consecutive correlation is
    undefined and once made the fit's lag-1 correlation NaN; link 1–2's is kept."""
    t = 0.1 * np.arange(50)
    noisy = 2.0 + 0.02 * np.random.default_rng(7).standard_normal(50)
    flat = np.full(50, 2.1)
    flat[-1] = 2.3
    rec = _uwb(np.concatenate([t, t + 0.05]), [(1, 2)] * 50 + [(1, 3)] * 50, [*noisy, *flat])
    fit = fit_uwb_noise(rec, spanning(rec.t, "u"))
    r = noisy - np.median(noisy)
    assert fit.lag1_correlation == pytest.approx(np.corrcoef(r[:-1], r[1:])[0, 1])


# ----------------------------------------------------------------------------------------------
# Windows
# ----------------------------------------------------------------------------------------------


@pytest.mark.parametrize("start", ["0", None])
def test_a_window_end_that_is_not_a_number_is_refused(start):
    with pytest.raises(ConfigError, match="CalibrationWindow of 'r': start_s: expected a number"):
        CalibrationWindow(start, 1.0, "r")


def test_odometry_and_truth_that_do_not_overlap_are_refused_naming_the_robot(synthetic):
    gt = GroundTruth(np.array([10.0, 20.0]), np.zeros(2), np.zeros(2), np.zeros(2), 0.5)
    odo = Odometry(np.array([0.0, 5.0]), np.zeros(2), np.zeros(2))
    with pytest.raises(DataError, match=r"robot 7's odometry \[0\.00, 5\.00\] s and ground"):
        odometry_and_truth(synthetic.robot(7, gt, odo), "run6")
