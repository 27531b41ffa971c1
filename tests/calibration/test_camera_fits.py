"""Camera fits recover a known bearing offset, range bias, noise, correlation, P_D and field
of view from seeded synthetic detections, and refuse windows without enough data."""

import numpy as np
import pytest

from relloc.calibration.camera import (
    camera_residuals,
    corrected_readings,
    fit_camera,
    fit_detection_in_view,
    fit_detection_probability,
    fit_field_of_view,
    lag_correlation,
    landmark_wait_s,
)
from relloc.calibration.window import CalibrationWindow
from relloc.core.recording import Measurements, measurement_rows
from relloc.errors import ConfigError, DataError
from relloc.models.planar_measurement import range_bias_features

BIAS = np.array([0.05, -0.02, 0.1, 0.01, -0.03])  # b(η, ρ) = c · (1, η, η², ρ, ρη²)
OFFSETS = (0.02, -0.01)
SIGMA_R, SIGMA_B, TAU_B = 0.03, 0.01, 1.0
PERIOD = 0.25
DURATION = 200.0


def _detections(rng, pose, targets, offset, bearing_bias=None):
    """Every target every PERIOD s: biased white ranges, offset Gauss–Markov bearings (plus
    ``bearing_bias(η)`` when given)."""
    t_one = np.arange(0.0, DURATION - 1.0, PERIOD)
    a = np.exp(-PERIOD / TAU_B)
    rows = []
    for subject, xy in targets:
        dx, dy = xy[0] - pose[0], xy[1] - pose[1]
        rho, eta = np.hypot(dx, dy), np.arctan2(dy, dx) - pose[2]
        e = np.empty(t_one.size)
        e[0] = SIGMA_B * rng.standard_normal()
        for k in range(1, t_one.size):
            e[k] = a * e[k - 1] + SIGMA_B * np.sqrt(1 - a * a) * rng.standard_normal()
        bias = range_bias_features(np.array(eta), np.array(rho)) @ BIAS
        r = rho + bias + SIGMA_R * rng.standard_normal(t_one.size)
        eta_bias = 0.0 if bearing_bias is None else bearing_bias(eta)
        rows.append((t_one, np.full(t_one.size, subject), r, eta + offset + eta_bias + e))
    return [np.concatenate(c) for c in zip(*rows, strict=True)]


def _camera_dataset(synthetic, rng, bearing_bias=None):
    landmarks = [(np.cos(b) * d, np.sin(b) * d) for b in (-0.5, -0.2, 0.1, 0.4) for d in (1, 2, 4)]
    poses = ((0.0, 0.0, 0.0), (0.5, 0.5, 0.1))
    robots = []
    for i, (pose, offset) in enumerate(zip(poses, OFFSETS, strict=True)):
        targets = [(10 + k, xy) for k, xy in enumerate(landmarks)]
        other = poses[1 - i]
        if i == 0:
            targets.append((2, other[:2]))  # robot 1 also sees robot 2
        meas = synthetic.measurements(*_detections(rng, pose, targets, offset, bearing_bias))
        robots.append(synthetic.still_robot(i + 1, *pose, DURATION, meas))
    return synthetic.dataset(robots, landmarks)


def test_camera_fit_recovers_offsets_bias_noise_and_correlation(synthetic):
    ds = _camera_dataset(synthetic, np.random.default_rng(5))
    window = CalibrationWindow(0.0, DURATION, "synthetic")
    fit = fit_camera(ds, window, range_interval_s=1.0)
    assert fit.calibration_window == window
    assert fit.bearing_offset == pytest.approx(OFFSETS, abs=2e-3)
    assert fit.sigma_bearing_raw == pytest.approx(SIGMA_B, rel=0.1)
    assert fit.sigma_range_raw == pytest.approx(SIGMA_R, rel=0.1)
    # the fitted bias matches the true one where the camera saw the targets
    res = camera_residuals(ds, window)
    X = range_bias_features(res.bearing, res.range)
    assert np.max(np.abs(X @ (np.asarray(fit.range_bias_coeffs) - BIAS))) < 5e-3
    # Gauss–Markov bearings: ρ(lag) = exp(−lag/τ); white ranges: ρ ≈ 0
    for lag in (0.5, 1.0, 2.0):
        assert fit.correlation["bearing"][f"{lag:g}s"] == pytest.approx(
            np.exp(-lag / TAU_B), abs=0.05
        )
        assert abs(fit.correlation["range"][f"{lag:g}s"]) < 0.05
    assert fit.correlation["pair_spacing_s"]["median"] == pytest.approx(PERIOD)
    # correlated bearings need a large inflation, white ranges almost none
    assert fit.bearing_inflation > 5.0 and fit.range_inflation < 1.5
    assert fit.sigma_bearing == pytest.approx(
        fit.sigma_bearing_raw * np.sqrt(fit.bearing_inflation)
    )
    assert fit.to_dict()["calibration_window"] == window.to_dict()


def test_camera_fit_recovers_a_bearing_bias_across_the_image(synthetic):
    # seed 11: not used while developing the bearing-bias fit
    def curve(eta):
        return 0.02 * eta + 0.03 * eta**2  # small enough to stay inside the inlier cut

    ds = _camera_dataset(synthetic, np.random.default_rng(11), bearing_bias=curve)
    window = CalibrationWindow(0.0, DURATION, "synthetic")
    fit = fit_camera(ds, window, range_interval_s=1.0)
    res = camera_residuals(ds, window)
    truth = np.asarray(OFFSETS)[res.observer] + curve(res.bearing)
    miss = fit.bearing_bias(res.observer, res.bearing) - truth
    # well inside σ_η (the bearings' Gauss–Markov part leaves each target a common error)
    assert np.sqrt(np.mean(miss**2)) < 0.2 * SIGMA_B and np.max(np.abs(miss)) < 0.6 * SIGMA_B
    # what the bias leaves is the white part of the bearing noise
    assert fit.sigma_bearing_raw == pytest.approx(SIGMA_B, rel=0.1)
    # beyond the bearings it was fitted on, the bias is held at its edge value
    lo, hi = fit.bearing_bias_limits[0], fit.bearing_bias_limits[1]
    edge = fit.bearing_bias(np.zeros(2, dtype=np.int64), np.array([lo, hi]))
    far = fit.bearing_bias(np.zeros(2, dtype=np.int64), np.array([lo - 1.0, hi + 1.0]))
    assert far == pytest.approx(edge)


def test_corrected_readings_remove_the_fitted_biases(synthetic):
    """The camera rows, corrected with the fit, read the truth up to the white noise; rows of
    other kinds are left alone, and without ``ranges`` so are the ranges."""
    ds = _camera_dataset(synthetic, np.random.default_rng(13))
    window = CalibrationWindow(0.0, DURATION, "synthetic")
    fit = fit_camera(ds, window, range_interval_s=1.0)
    res = camera_residuals(ds, window)
    order = np.argsort(res.t, kind="stable")
    camera = measurement_rows(
        "range_bearing",
        t=res.t[order],
        observer=res.observer[order],
        target=np.where(res.subject[order] == 2, 1, -1),
        landmark=np.where(res.subject[order] >= 10, res.subject[order] - 10, -1),
        value=np.column_stack([res.range, res.bearing])[order],
    )
    heights = measurement_rows("height", t=np.arange(5.0), observer=0, target=1, value=np.ones(5))
    m = Measurements.concatenate([camera, heights])
    out = corrected_readings(m, fit, ranges=True)
    rows = m.kind == camera.kind[0]
    range_error = out.value[rows, 0] - (res.range - res.range_error)[order]
    bearing_error = out.value[rows, 1] - (res.bearing - res.bearing_error)[order]
    # the raw ranges are biased by BIAS (up to 0.2 m), the corrected ones only noisy
    assert np.sqrt(np.mean(res.range_error**2)) > 3 * SIGMA_R
    assert np.sqrt(np.mean(range_error**2)) == pytest.approx(SIGMA_R, rel=0.15)
    # the per-robot offsets are gone from the bearings
    assert abs(np.median(bearing_error[m.observer[rows] == 0])) < 2e-3
    assert abs(np.median(bearing_error[m.observer[rows] == 1])) < 2e-3
    np.testing.assert_array_equal(out.value[~rows], m.value[~rows])
    plain = corrected_readings(m, fit)
    np.testing.assert_array_equal(plain.value[rows, 0], m.value[rows, 0])
    np.testing.assert_array_equal(plain.value[rows, 1], out.value[rows, 1])


def test_lag_correlation_of_a_lone_pair_is_zero_without_enough_pairs(synthetic):
    ds = _camera_dataset(synthetic, np.random.default_rng(2))
    res = camera_residuals(ds, CalibrationWindow(0.0, 1.0, "synthetic"))
    keep = np.ones(res.t.size, dtype=bool)
    assert lag_correlation(res, res.bearing_error, keep, 5.0) == 0.0


def test_camera_fit_refuses_a_window_with_too_few_detections(synthetic):
    ds = _camera_dataset(synthetic, np.random.default_rng(1))
    with pytest.raises(DataError, match=r"\[500.00, 600.00\] s of synthetic: fewer than 20"):
        fit_camera(ds, CalibrationWindow(500.0, 600.0, "synthetic"), range_interval_s=1.0)
    with pytest.raises(ConfigError, match="range_interval_s"):
        fit_camera(ds, CalibrationWindow(0.0, 10.0, "synthetic"), range_interval_s=-1.0)


def _frames_dataset(synthetic):
    """Robot 1: 100 frames (t = 0 … 99) each showing a landmark, robot 2 in frames 0 … 29;
    robot 2: 100 frames (t = 0.5 … 99.5), robot 1 in the even ones, a landmark in the odd."""
    t1, t2 = np.arange(100.0), np.arange(100.0) + 0.5
    rows1 = (
        np.concatenate([t1, t1[:30]]),
        np.concatenate([np.full(100, 10), np.full(30, 2)]),
        np.ones(130),
        np.concatenate([np.full(100, 0.3), np.full(30, -0.55)]),
    )
    rows2 = (
        np.concatenate([t2[::2], t2[1::2]]),
        np.concatenate([np.full(50, 1), np.full(50, 10)]),
        np.ones(100),
        np.concatenate([np.full(50, 0.2), np.full(50, 0.1)]),
    )
    r1 = synthetic.still_robot(1, 0, 0, 0, 100.0, synthetic.measurements(*rows1))
    r2 = synthetic.still_robot(2, 1, 0, 0, 100.0, synthetic.measurements(*rows2))
    return synthetic.dataset([r1, r2], [(5.0, 5.0)])


def test_detection_probability_is_the_share_of_frames_showing_a_teammate(synthetic):
    ds = _frames_dataset(synthetic)
    fit = fit_detection_probability(ds, CalibrationWindow(0.0, 100.0, "synthetic"))
    assert (fit.frames, fit.pairs, fit.detected_pairs) == (200, 200, 80)
    assert fit.p_detect == pytest.approx(0.4)
    # only the window counts: the first 30 s hold 30 + 30 frames, 30 + 15 detections
    early = fit_detection_probability(ds, CalibrationWindow(0.0, 29.9, "synthetic"))
    assert early.p_detect == pytest.approx(45 / 60)
    # a window without frames is refused, naming it (no made-up P_D), and P_D is clipped
    with pytest.raises(DataError, match=r"\[200.00, 300.00\] s of s: no \(camera frame, other"):
        fit_detection_probability(ds, CalibrationWindow(200.0, 300.0, "s"))
    assert fit_detection_probability(ds, CalibrationWindow(0.0, 0.4, "s")).p_detect == 0.95


def test_detection_in_view_counts_only_teammates_the_truth_puts_in_view(synthetic):
    ds = _frames_dataset(synthetic)
    window = CalibrationWindow(0.0, 100.0, "synthetic")
    # robot 2 lies straight ahead of robot 1 (in view, seen in 30 of 100 frames); robot 1 lies
    # behind robot 2 (out of a ±0.5 rad view, yet "seen" in 50 frames: counted as outside)
    fit = fit_detection_in_view(ds, window, 0.5)
    assert (fit.pairs_in_view, fit.detected_in_view, fit.detected_outside) == (100, 30, 50)
    assert fit.p_detect == pytest.approx(0.3) and fit.half_width_rad == 0.5
    # a view all around is the share over all frames
    everywhere = fit_detection_in_view(ds, window, np.pi)
    assert everywhere.p_detect == pytest.approx(fit_detection_probability(ds, window).p_detect)
    assert fit.to_dict()["calibration_window"] == window.to_dict()
    with pytest.raises(ConfigError, match="half_width_rad"):
        fit_detection_in_view(ds, window, 0.0)


def test_detection_in_view_refuses_a_window_without_a_teammate_in_view(synthetic):
    """Robot 1 sees only a landmark, with robot 2 behind it; robot 2 records no frame at all.
    Over all frames robot 2 is never seen (P_D clipped to its floor); in view there is no
    (frame, robot) pair, and neither fit makes up a P_D where the window holds no frame."""
    t = np.arange(100.0)
    landmark = synthetic.measurements(t, np.full(100, 10), np.ones(100), np.zeros(100))
    ds = synthetic.dataset(
        [
            synthetic.still_robot(1, 0, 0, 0, 100.0, landmark),
            synthetic.still_robot(2, -1, 0, 0, 100.0),
        ],
        [(1.0, 0.0)],
    )
    window = CalibrationWindow(0.0, 99.0, "synthetic")
    everywhere = fit_detection_probability(ds, window)
    assert (everywhere.pairs, everywhere.detected_pairs, everywhere.p_detect) == (100, 0, 0.05)
    with pytest.raises(DataError, match=r"99.00\] s of synthetic: no camera frame with another"):
        fit_detection_in_view(ds, window, 0.5)
    with pytest.raises(DataError, match=r"\[200.00, 300.00\] s of s: no camera frame"):
        fit_detection_in_view(ds, CalibrationWindow(200.0, 300.0, "s"), 0.5)


def test_field_of_view_is_the_widest_bearing_in_the_window(synthetic):
    ds = _frames_dataset(synthetic)
    whole = fit_field_of_view(ds, CalibrationWindow(0.0, 100.0, "s"))
    assert whole.half_width_rad == pytest.approx(0.55) and whole.n_bearings == 230
    later = fit_field_of_view(ds, CalibrationWindow(40.0, 100.0, "s"))
    assert later.half_width_rad == pytest.approx(0.3)
    with pytest.raises(DataError, match="no usable camera bearings"):
        fit_field_of_view(ds, CalibrationWindow(200.0, 300.0, "s"))


def test_landmark_wait_is_the_mean_residual_gap(synthetic):
    rows = (np.array([2.0, 4.0]), np.array([10, 10]), np.ones(2), np.zeros(2))
    r1 = synthetic.still_robot(1, 0, 0, 0, 10.0, synthetic.measurements(*rows))
    ds = synthetic.dataset([r1], [(1.0, 0.0)])
    # gaps 2, 2, 6 s in [0, 10]: Σg²/(2Σg) = 44/20
    assert landmark_wait_s(ds, CalibrationWindow(0.0, 10.0, "s")) == pytest.approx(2.2)
