"""Hand-made cases of the camera and odometry fits that pin details the recovery tests leave
free: the row counts behind a bearing offset and bias, the bearings a bias was fitted over,
exact lag-pair counts and pair spacings, which detections count toward P_D, the ground
truth's central differences, the lagged command response, and the odometry fits' windows."""

import math

import numpy as np
import pytest

from relloc.calibration.camera import (
    CameraResiduals,
    camera_residuals,
    fit_camera,
    fit_detection_in_view,
    fit_detection_probability,
    lag_correlation,
    pair_spacing_s,
)
from relloc.calibration.odometry import (
    RATE_FLOOR,
    command_response,
    fit_command_fir,
    fit_largest_odometry_noise,
    fit_odometry_model,
    fit_odometry_noise,
    ground_truth_odometry,
    ground_truth_velocities,
    noise_lengths,
)
from relloc.calibration.window import CalibrationWindow
from relloc.datasets.mrclam import GroundTruth, Odometry
from relloc.errors import DataError

# ---------------------------------------------------------------------------------------------
# Camera
# ---------------------------------------------------------------------------------------------

#: Landmarks at bearings −0.4, 0, 0.4 rad and 1, 2 m from the origin.
LANDMARKS = [(d * math.cos(b), d * math.sin(b)) for b in (-0.4, 0.0, 0.4) for d in (1.0, 2.0)]


def _landmark_rows(n: int, errors: tuple[float, float]) -> tuple[np.ndarray, ...]:
    """``n`` detections, one a second, of the landmarks in turn by a robot at the origin facing
    +x, bearing errors alternating ``errors``, range errors alternating ±0.01 m."""
    k = np.arange(n)
    which = k % len(LANDMARKS)
    xy = np.asarray(LANDMARKS)[which]
    bearing = np.arctan2(xy[:, 1], xy[:, 0]) + np.where(k % 2 == 0, errors[0], errors[1])
    rng_m = np.hypot(xy[:, 0], xy[:, 1]) + np.where(k % 2 == 0, 0.01, -0.01)
    return k.astype(float), 10 + which, rng_m, bearing


def _two_camera_dataset(synthetic, n_first: int):
    """Robot 1 with ``n_first`` detections (bearing errors 0.02, 0.04: median 0.03), robot 2
    with 40 (errors ±0.01), both standing at the origin facing +x."""
    first = synthetic.measurements(*_landmark_rows(n_first, (0.02, 0.04)))
    second = synthetic.measurements(*_landmark_rows(40, (-0.01, 0.01)))
    robots = [
        synthetic.still_robot(1, 0.0, 0.0, 0.0, 60.0, first),
        synthetic.still_robot(2, 0.0, 0.0, 0.0, 60.0, second),
    ]
    return synthetic.dataset(robots, LANDMARKS)


WINDOW = CalibrationWindow(0.0, 60.0, "hand")


def test_a_bearing_offset_needs_more_than_ten_rows(synthetic):
    fit = fit_camera(_two_camera_dataset(synthetic, 10), WINDOW, range_interval_s=0.0)
    assert fit.bearing_offset[0] == 0.0
    fit = fit_camera(_two_camera_dataset(synthetic, 12), WINDOW, range_interval_s=0.0)
    assert fit.bearing_offset[0] == pytest.approx(0.03, abs=1e-12)


def test_a_bearing_bias_needs_more_than_thirty_rows_and_is_held_to_its_bearings(synthetic):
    # 30 rows: the offset alone, over every bearing
    fit = fit_camera(_two_camera_dataset(synthetic, 30), WINDOW, range_interval_s=0.0)
    assert fit.bearing_bias_coeffs[:3] == pytest.approx((0.03, 0.0, 0.0), abs=1e-12)
    assert fit.bearing_bias_limits[:2] == pytest.approx((-math.pi, math.pi))
    # 31 rows: a fitted bias, held to the measured bearings it was fitted on
    fit = fit_camera(_two_camera_dataset(synthetic, 31), WINDOW, range_interval_s=0.0)
    _, _, _, bearing = _landmark_rows(31, (0.02, 0.04))
    assert fit.bearing_bias_limits[:2] == pytest.approx((bearing.min(), bearing.max()))
    assert -0.4 < fit.bearing_bias_limits[0] < fit.bearing_bias_limits[1] < 0.5


def _residuals(t, key_subject, values) -> CameraResiduals:
    n = len(t)
    values = np.asarray(values, dtype=float)
    return CameraResiduals(
        observer=np.zeros(n, dtype=np.int64),
        subject=np.asarray(key_subject, dtype=np.int64),
        t=np.asarray(t, dtype=float),
        range=np.ones(n),
        bearing=np.zeros(n),
        range_error=values,
        bearing_error=values,
    )


def test_lag_correlation_with_exactly_ten_pairs_is_measured():
    # 11 readings one second apart: 10 pairs a second apart, (0…9) against (1…10): ρ = 1
    res = _residuals(np.arange(11.0), np.full(11, 10), np.arange(11.0))
    keep = np.ones(11, dtype=bool)
    assert lag_correlation(res, res.range_error, keep, 1.0) == pytest.approx(1.0)
    # 10 readings: 9 pairs, too few
    res = _residuals(np.arange(10.0), np.full(10, 10), np.arange(10.0))
    assert lag_correlation(res, res.range_error, keep[:10], 1.0) == 0.0


def test_pair_spacing_is_within_each_pair_not_across_pairs():
    # two landmarks each seen every 2 s at the same instants (and a third once): 2 s, though
    # consecutive detections of any pair are 0 s apart
    t = np.concatenate([np.arange(0.0, 20.0, 2.0)] * 2 + [[7.0]])
    subject = np.concatenate([np.full(10, 10), np.full(10, 11), [12]])
    order = np.argsort(t, kind="stable")
    res = _residuals(t[order], subject[order], np.zeros(21))
    assert pair_spacing_s(res) == pytest.approx(2.0)


def _detections_dataset(synthetic):
    """Robot 1 at the origin facing +x, frames at t = 0 … 9 each with a landmark; robot 2 at
    (1, 0) (straight ahead), its ground truth only for t < 3 s. Robot 1 detects robot 2 in
    frames 0 … 4 (twice in frame 0) and records a bogus detection of itself in frame 5."""
    t = np.concatenate([np.arange(10.0), np.arange(5.0), [0.0, 5.0]])
    subject = np.concatenate([np.full(10, 10), np.full(5, 2), [2, 1]])
    meas = synthetic.measurements(t, subject, np.ones(t.size), np.zeros(t.size))
    robots = [
        synthetic.still_robot(1, 0.0, 0.0, 0.0, 10.0, meas),
        synthetic.still_robot(2, 1.0, 0.0, 0.0, 3.0),
    ]
    return synthetic.dataset(robots, [(2.0, 0.0)])


def test_detection_probability_counts_each_frame_and_teammate_once(synthetic):
    fit = fit_detection_probability(_detections_dataset(synthetic), CalibrationWindow(0, 9.5, "d"))
    # 10 frames x 1 teammate; robot 2 seen in frames 0 … 4 (the duplicate and the
    # self-detection not counted)
    assert (fit.frames, fit.pairs, fit.detected_pairs) == (10, 10, 5)
    assert fit.p_detect == pytest.approx(0.5)


def test_detections_without_the_teammates_truth_are_left_out(synthetic):
    ds = _detections_dataset(synthetic)
    window = CalibrationWindow(0.0, 9.5, "d")
    # frames 3 and 4: robot 2 has no ground truth, so neither in view nor outside
    fit = fit_detection_in_view(ds, window, 0.5)
    assert (fit.pairs_in_view, fit.detected_in_view, fit.detected_outside) == (3, 3, 0)
    # and no residual: robot 2's rows are those of frames 0 (twice), 1 and 2
    res = camera_residuals(ds, window)
    assert np.sort(res.t[res.subject == 2]).tolist() == [0.0, 0.0, 1.0, 2.0]


# ---------------------------------------------------------------------------------------------
# Odometry
# ---------------------------------------------------------------------------------------------


def _circle(omega: float, v: float, duration: float, dt: float = 0.005) -> GroundTruth:
    t = np.arange(0.0, duration, dt)
    theta = omega * t
    x = v / omega * np.sin(theta)
    y = v / omega * (1.0 - np.cos(theta))
    return GroundTruth(t=t, x=x, y=y, theta=np.angle(np.exp(1j * theta)), gap_threshold=0.5)


def test_ground_truth_speed_is_the_chord_along_the_mid_heading():
    # on a circle at v = 1 m/s, ω = 2 rad/s the chord over t ± h has length
    # 2 (v/ω) sin(ωh) and points along the heading at t: speed v sin(ωh)/(ωh)
    gt = _circle(2.0, 1.0, 10.0)
    t = np.array([2.0, 5.0, 7.5])
    v, w, ok = ground_truth_velocities(gt, t, h=0.05)
    assert ok.all()
    np.testing.assert_allclose(v, math.sin(0.1) / 0.1, rtol=1e-9)
    np.testing.assert_allclose(w, 2.0, rtol=1e-9)


def test_ground_truth_odometry_holds_the_velocity_of_the_step_middle(synthetic):
    # θ = α t²/2 (α = 0.1 rad/s²): the central difference at s is α s, so the step
    # [t_k, t_k + 0.02) holds α (t_k + 0.01)
    t = np.arange(0.0, 10.0, 0.005)
    gt = GroundTruth(t=t, x=0 * t, y=0 * t, theta=0.05 * t**2, gap_threshold=0.5)
    cmd = Odometry(t=np.array([1.0, 9.0]), v=np.zeros(2), omega=np.zeros(2))
    od = ground_truth_odometry(synthetic.robot(1, gt, cmd))
    inner = (od.t > 1.0) & (od.t < 8.9)
    np.testing.assert_allclose(od.omega[inner], 0.1 * (od.t[inner] + 0.01), rtol=1e-6)
    # a robot with one command: one stamp
    one = Odometry(t=np.array([4.0]), v=np.zeros(1), omega=np.zeros(1))
    assert ground_truth_odometry(synthetic.robot(1, gt, one)).t.tolist() == [4.0]


def _step(t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    c = (np.asarray(t) >= 0.0).astype(float)
    return c, c


def _constant(t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    c = np.ones(np.shape(t))
    return c, 2.0 * c


def test_the_lagged_response_closes_the_gap_as_exp_of_minus_t_over_T():
    # a first-order lag: 1 − y shrinks by e^{−Δt/T} over any Δt after the step
    v, _ = command_response(_step, np.array([0.2, 0.4, 0.6]), 0.0, 0.2)
    assert (1.0 - v[1]) / (1.0 - v[0]) == pytest.approx(math.exp(-1.0), rel=1e-3)
    assert (1.0 - v[2]) / (1.0 - v[1]) == pytest.approx(math.exp(-1.0), rel=1e-3)
    # a constant command: at rest on it from the start, so exactly the command
    v, w = command_response(_constant, np.array([3.0, 5.0]), 0.1, 0.3)
    np.testing.assert_allclose(v, 1.0, rtol=1e-12)
    np.testing.assert_allclose(w, 2.0, rtol=1e-12)


def test_the_averaged_response_of_a_constant_command_is_the_command():
    v, w = command_response(_constant, np.array([10.0, 12.37]), 0.0, 0.0, average_s=0.05)
    np.testing.assert_allclose(v, 1.0, rtol=1e-12)
    np.testing.assert_allclose(w, 2.0, rtol=1e-12)


def test_the_fits_grid_starts_a_second_after_the_first_command(synthetic):
    # commands from 0 s, truth to 29.99 s: the grid is [1, 28.99) every 0.02 s, 1400 times
    robot = synthetic.commanded_robot(1, np.random.default_rng(2), duration=30.0)
    fir = fit_command_fir(robot, CalibrationWindow(0.0, 30.0, "g"))
    assert fir.samples == 1400


def test_three_whole_windows_fit_the_rates_and_a_shorter_robot_is_unfitted(synthetic):
    """Noise-free robots. Robot 1's grid [1, 7.49) holds three whole 2 s windows, as many as
    the rate coefficients: enough. Robot 2's grid [1, 5.99) is shorter than three windows:
    unfitted. Without noise the constant rates fit below the floor and are floored."""
    rng = np.random.default_rng(9)
    r1 = synthetic.commanded_robot(1, rng, duration=8.5)
    r2 = synthetic.commanded_robot(2, rng, duration=7.0)
    fit = fit_odometry_model(
        synthetic.dataset([r1, r2]), CalibrationWindow(0.0, 100.0, "w"), integration_s=2.0
    )
    assert fit.unfitted_robots == (2,)
    assert fit.q_v0 == RATE_FLOOR and fit.q_w0 == RATE_FLOOR


def test_rates_divide_by_the_windows_real_length(synthetic):
    """2 s and 2.005 s both cut 100 grid steps: the same windows, the same rates."""
    rng = np.random.default_rng(10)
    robot = synthetic.commanded_robot(1, rng, duration=12.0, sigma_v=0.3, sigma_w=0.6)
    ds = synthetic.dataset([robot])
    window = CalibrationWindow(0.0, 100.0, "w")
    a = fit_odometry_model(ds, window, integration_s=2.0)
    b = fit_odometry_model(ds, window, integration_s=2.005)
    rates = ("q_v0", "k_v", "q_w0", "k_w", "k_wv")
    assert max(getattr(a, r) for r in rates) > 10 * RATE_FLOOR
    assert [getattr(b, r) for r in rates] == pytest.approx([getattr(a, r) for r in rates])


def test_a_robot_that_stands_still_under_commands_is_refused(synthetic):
    t = np.arange(0.0, 30.0, 0.01)
    gt = GroundTruth(t=t, x=0 * t, y=0 * t, theta=0 * t, gap_threshold=0.5)
    cmd = Odometry(t=np.arange(0.0, 30.0, 1.0), v=np.full(30, 0.2), omega=np.full(30, 0.1))
    ds = synthetic.dataset([synthetic.robot(1, gt, cmd)])
    with pytest.raises(DataError, match="does not move with its commands"):
        fit_odometry_model(ds, CalibrationWindow(0.0, 30.0, "s"), integration_s=1.0)


def _turning_robot(synthetic, subject, v_odometry=None, keep=None):
    """0.2 m/s at 0.1 rad/s for 20 s; the odometry reports 0.12 rad/s (and ``v_odometry``)."""
    t = np.arange(0.0, 20.0, 0.01)
    theta = 0.3 + 0.1 * t
    x = 2.0 * (np.sin(theta) - np.sin(0.3))
    y = -2.0 * (np.cos(theta) - np.cos(0.3))
    k = np.ones(t.size, bool) if keep is None else keep
    gt = GroundTruth(
        t=t[k], x=x[k], y=y[k], theta=np.angle(np.exp(1j * theta[k])), gap_threshold=0.5
    )
    v = np.full_like(t, 0.2) if v_odometry is None else v_odometry
    return synthetic.robot(subject, gt, Odometry(t=t, v=v, omega=np.full_like(t, 0.12)))


def test_the_noise_bias_is_per_second_whatever_the_window(synthetic):
    fit = fit_odometry_noise(
        _turning_robot(synthetic, 1), CalibrationWindow(1.0, 19.0, "b"), window_s=2.0
    )
    assert fit.bias_w == pytest.approx(-0.02, abs=1e-4)


def test_the_noise_fit_divides_by_the_windows_real_length(synthetic):
    """1 s and 1.004 s both cut 100 grid steps at 100 Hz: the same windows, the same fit,
    and the length reported is the windows' 1 s."""
    robot = synthetic.commanded_robot(1, np.random.default_rng(3), duration=60.0, sigma_w=0.1)
    window = CalibrationWindow(1.0, 59.0, "r")
    a = fit_odometry_noise(robot, window, window_s=1.0)
    b = fit_odometry_noise(robot, window, window_s=1.004)
    assert b.n_windows == a.n_windows == 58
    for name in ("sigma_v", "sigma_lateral", "sigma_w", "bias_v", "bias_w"):
        assert getattr(b, name) == pytest.approx(getattr(a, name), rel=1e-12)
    assert b.window_s == pytest.approx(1.0, rel=1e-12)


def test_a_window_whose_end_has_no_truth_is_left_out(synthetic):
    # truth missing on [3.0, 3.8) and [8.0, 8.8): of the 18 one-second windows of [1, 19],
    # [2, 3) and [7, 8) end in a gap and [3, 4) and [8, 9) start in one: 14 are whole
    t = np.round(np.arange(0.0, 20.0, 0.01), 10)
    keep = ~(((t >= 3.0) & (t < 3.8)) | ((t >= 8.0) & (t < 8.8)))
    robot = _turning_robot(synthetic, 1, keep=keep)
    fit = fit_odometry_noise(robot, CalibrationWindow(1.0, 19.0, "g"), window_s=1.0)
    assert fit.n_windows == 14
    assert fit.sigma_w == pytest.approx(0.2, rel=0.02)


def test_noise_lengths_that_fit_exactly_twice_are_kept():
    assert noise_lengths((1.0, 5.0, 10.0), CalibrationWindow(0.0, 10.0, "n")) == [1.0, 5.0]


def test_the_largest_noise_is_judged_by_the_turn_rate(synthetic):
    """The speed error alternates ±0.05 m/s each second (white-equivalent 0.5 m/s over 1 s
    windows, 0 over 2 s): σ_v is largest at 1 s; the turn-rate error is a constant
    0.02 rad/s, whose σ_ω grows with the window: the 5 s fit is kept."""
    t = np.arange(0.0, 20.0, 0.01)
    v = 0.2 + np.where(np.floor(t + 1e-9) % 2 == 0, 0.05, -0.05)
    robot = _turning_robot(synthetic, 1, v_odometry=v)
    fit = fit_largest_odometry_noise(robot, CalibrationWindow(1.0, 19.0, "l"))
    assert fit.window_s == 5.0
    assert fit.sigma_w == pytest.approx(0.02 * math.sqrt(5.0 / 0.01), rel=0.02)


def test_the_turn_rate_noise_rate_grows_with_the_turn_of_either_sign(synthetic):
    """A robot turning left and right in turn (|ω| uniform in 0.1 … 0.8 rad/s) with white
    turn-rate noise of rate k |ω| (k = 4e-4 rad²/s per rad/s): the fitted rate is k |ω| at
    a slow and a fast turn, whichever the sign (200 windows of 1 s: about ±10 %)."""
    k, dt, duration = 4e-4, 0.01, 200.0
    rng = np.random.default_rng(1)
    t_cmd = np.arange(0.0, duration, 2.0)
    sign = np.where(np.arange(t_cmd.size) % 2 == 0, 1.0, -1.0)
    odo = Odometry(
        t=t_cmd, v=np.full(t_cmd.size, 0.2), omega=sign * rng.uniform(0.1, 0.8, t_cmd.size)
    )
    t = np.arange(0.0, duration, dt)
    v, w_cmd = odo.at(t)
    w = w_cmd + np.sqrt(k * np.abs(w_cmd) / dt) * rng.standard_normal(t.size)
    theta = np.concatenate([[0.0], np.cumsum(w * dt)])[:-1]
    mid = theta + 0.5 * w * dt
    x = np.concatenate([[0.0], np.cumsum(v * dt * np.cos(mid))])[:-1]
    y = np.concatenate([[0.0], np.cumsum(v * dt * np.sin(mid))])[:-1]
    gt = GroundTruth(t=t, x=x, y=y, theta=np.angle(np.exp(1j * theta)), gap_threshold=0.5)
    ds = synthetic.dataset([synthetic.robot(1, gt, odo)])
    fit = fit_odometry_model(ds, CalibrationWindow(0.0, duration, "turns"), integration_s=1.0)
    for turn in (0.2, 0.7):
        rate = fit.q_w0 + fit.k_w * turn + fit.k_wv * 0.2
        assert rate == pytest.approx(k * turn, rel=0.3)
