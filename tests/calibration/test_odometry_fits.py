"""Odometry fits recover known latency, scales and noise from seeded synthetic robots, and
refuse windows without enough data."""

import numpy as np
import pytest

from relloc.calibration.odometry import (
    MAX_LATENCY_S,
    MAX_TIME_CONSTANT_S,
    OdometryModelFit,
    calibrated_commands,
    calibrated_team,
    fit_largest_odometry_noise,
    fit_odometry_model,
    fit_odometry_noise,
)
from relloc.calibration.window import CalibrationWindow
from relloc.core.recording import Odometry as BodyOdometry
from relloc.datasets.mrclam import GroundTruth, Odometry
from relloc.errors import ConfigError, DataError


def test_odometry_noise_fit_recovers_a_known_error(synthetic):
    t = np.arange(0.0, 20.0, 0.01)
    theta = 0.3 + 0.1 * t  # turning at 0.1 rad/s while moving at 0.2 m/s
    x = 0.2 / 0.1 * (np.sin(theta) - np.sin(0.3))
    y = -0.2 / 0.1 * (np.cos(theta) - np.cos(0.3))
    gt = GroundTruth(t=t, x=x, y=y, theta=np.angle(np.exp(1j * theta)), gap_threshold=0.5)
    # odometry over-reports speed by 0.05 m/s and turn rate by 0.02 rad/s
    odo = Odometry(t=t, v=np.full_like(t, 0.25), omega=np.full_like(t, 0.12))
    robot = synthetic.robot(1, gt, odo)
    window = CalibrationWindow(1.0, 19.0, "synthetic robot 1")
    fit = fit_odometry_noise(robot, window, window_s=1.0)
    assert fit.n_windows == 18
    assert fit.calibration_window == window
    assert fit.to_dict()["calibration_window"] == window.to_dict()
    assert fit.bias_v == pytest.approx(-0.05, abs=1e-3)
    assert fit.bias_w == pytest.approx(-0.02, abs=1e-4)
    # a constant error e accumulates e·W per window: σ_eq = |e| sqrt(W / dt)
    assert fit.sigma_v == pytest.approx(0.5, rel=0.02)
    assert fit.sigma_w == pytest.approx(0.2, rel=0.02)
    assert fit.sigma_lateral < 0.02
    with pytest.raises(DataError, match=r"calibration window \[1.00, 2.50\].*fewer than two"):
        fit_odometry_noise(robot, CalibrationWindow(1.0, 2.5, "synthetic"), window_s=1.0)


def test_largest_noise_takes_the_time_scale_a_persistent_error_grows_to(synthetic):
    """A constant turn-rate error of 0.02 rad/s is white-equivalent to 0.02·√(W/dt), growing
    with the window length W: of the lengths that fit twice into 18 s (1, 2, 5 s; not 10, 20,
    40 s) the largest σ_ω is the 5 s one."""
    t = np.arange(0.0, 20.0, 0.01)
    theta = 0.3 + 0.1 * t
    x = 0.2 / 0.1 * (np.sin(theta) - np.sin(0.3))
    y = -0.2 / 0.1 * (np.cos(theta) - np.cos(0.3))
    gt = GroundTruth(t=t, x=x, y=y, theta=np.angle(np.exp(1j * theta)), gap_threshold=0.5)
    odo = Odometry(t=t, v=np.full_like(t, 0.2), omega=np.full_like(t, 0.12))
    robot = synthetic.robot(1, gt, odo)
    fit = fit_largest_odometry_noise(robot, CalibrationWindow(1.0, 19.0, "synthetic robot 1"))
    assert fit.window_s == 5.0 and fit.n_windows == 3
    assert fit.sigma_w == pytest.approx(0.02 * np.sqrt(5.0 / 0.01), rel=0.02)
    only_1s = fit_largest_odometry_noise(robot, CalibrationWindow(1.0, 19.0, "s"), (1.0, 40.0))
    assert only_1s.window_s == 1.0 and only_1s.sigma_w == pytest.approx(0.2, rel=0.02)
    with pytest.raises(DataError, match=r"\[1.00, 2.50\].*no noise window of \(2.0, 5.0\) s"):
        fit_largest_odometry_noise(robot, CalibrationWindow(1.0, 2.5, "synthetic"), (2.0, 5.0))


def test_largest_noise_leaves_out_lengths_whose_windows_hit_truth_gaps(synthetic):
    """Vicon gaps at 3.0–3.8 s and 8.0–8.8 s: of the 5 s windows of [1, 19] s only one is
    whole, so 5 s has no fit and the 2 s fit (the largest σ_ω left, a constant 0.02 rad/s
    turn-rate error) is kept; with only 5 s allowed the fit's own error is raised."""
    t = np.arange(0.0, 20.0, 0.01)
    keep = ~(((t >= 3.0) & (t < 3.8)) | ((t >= 8.0) & (t < 8.8)))
    theta = 0.3 + 0.1 * t
    x = 0.2 / 0.1 * (np.sin(theta) - np.sin(0.3))
    y = -0.2 / 0.1 * (np.cos(theta) - np.cos(0.3))
    gt = GroundTruth(
        t=t[keep],
        x=x[keep],
        y=y[keep],
        theta=np.angle(np.exp(1j * theta[keep])),
        gap_threshold=0.5,
    )
    odo = Odometry(t=t, v=np.full_like(t, 0.2), omega=np.full_like(t, 0.12))
    robot = synthetic.robot(2, gt, odo)
    window = CalibrationWindow(1.0, 19.0, "synthetic robot 2")
    fit = fit_largest_odometry_noise(robot, window)
    assert fit.window_s == 2.0
    assert fit.sigma_w == pytest.approx(0.02 * np.sqrt(2.0 / 0.01), rel=0.02)
    with pytest.raises(DataError, match="robot 2: ground truth has gaps in every window"):
        fit_largest_odometry_noise(robot, window, (5.0,))


def test_odometry_noise_fit_recovers_white_input_noise(synthetic):
    rng = np.random.default_rng(3)
    robot = synthetic.commanded_robot(1, rng, duration=200.0, sigma_v=0.05, sigma_w=0.1)
    fit = fit_odometry_noise(robot, CalibrationWindow(1.0, 199.0, "synthetic"), rate_hz=100.0)
    # per-step white noise of σ at the fit's own rate is σ_eq = σ (198 windows: ±5 %)
    assert fit.sigma_v == pytest.approx(0.05, rel=0.15)
    assert fit.sigma_w == pytest.approx(0.1, rel=0.15)
    assert abs(fit.bias_v) < 0.01 and abs(fit.bias_w) < 0.02


def test_odometry_noise_fit_refuses_windows_without_ground_truth(synthetic):
    t = np.concatenate([np.arange(0.0, 1.0, 0.01), np.arange(9.0, 10.0, 0.01)])
    gt = GroundTruth(t=t, x=0 * t, y=0 * t, theta=0 * t, gap_threshold=0.5)
    odo = Odometry(t=t, v=0 * t, omega=0 * t)
    robot = synthetic.robot(4, gt, odo)
    with pytest.raises(DataError, match="robot 4: ground truth has gaps in every window"):
        fit_odometry_noise(robot, CalibrationWindow(1.0, 9.0, "synthetic"))
    with pytest.raises(ConfigError, match="rate_hz"):
        fit_odometry_noise(robot, CalibrationWindow(1.0, 9.0, "synthetic"), rate_hz=0.0)


@pytest.mark.parametrize(
    ("parameter", "value", "match"),
    [
        ("latency_s", np.nan, r"latency_s must lie in \[0, 0.5\] s .*got nan"),
        ("latency_s", -5.0, "latency_s must lie in"),
        ("latency_s", 1e9, "latency_s must lie in"),
        ("time_constant_s", -1.0, r"time_constant_s must lie in \[0, 0.6\] s"),
        ("time_constant_s", np.inf, "time_constant_s must lie in"),
        ("scale_v", np.nan, r"scale_v: must be a finite number in \(0, inf\), got nan"),
        ("scale_v", 0.0, r"scale_v: must be a finite number in \(0, inf\)"),
        ("scale_w", -1.0, r"scale_w: must be a finite number in \(0, inf\)"),
        ("scale_w", np.inf, r"scale_w: must be a finite number in \(0, inf\)"),
        ("rate_hz", np.inf, r"rate_hz: must be a finite number in \(0, inf\)"),
        ("window_s", np.inf, r"window_s: must be a finite number in \(0, inf\), got inf"),
        ("window_s", np.nan, r"window_s: must be a finite number in \(0, inf\)"),
        ("window_s", 0.001, r"window_s must lie between one step \(1/rate_hz = 0.01 s\)"),
        ("rate_hz", 1e9, r"rate_hz 1e\+09 over \[1.00, 19.00\] s of synthetic is more than"),
        ("window_s", 30.0, r"window_s must .*window \[1.00, 19.00\] s of synthetic, got 30 s"),
    ],
)
def test_odometry_noise_fit_names_a_bad_parameter(synthetic, parameter, value, match):
    """Each parameter is refused by name: none gives a silently wrong σ (a NaN latency used to
    give σ_v ≈ 1 m/s instead of 0.01, a NaN scale a NaN σ) or a raw exception."""
    robot = synthetic.commanded_robot(1, np.random.default_rng(2), duration=20.0)
    window = CalibrationWindow(1.0, 19.0, "synthetic")
    with pytest.raises(ConfigError, match=f"fit_odometry_noise: {match}"):
        fit_odometry_noise(robot, window, **{parameter: value})
    # the largest latency and time constant the model fit can find are taken
    edge = fit_odometry_noise(
        robot, window, latency_s=MAX_LATENCY_S, time_constant_s=MAX_TIME_CONSTANT_S
    )
    assert np.isfinite(edge.sigma_v) and edge.n_windows == 18


def test_odometry_model_refuses_a_robot_without_commanded_motion(synthetic):
    """A robot whose commands are all zero has no scale to fit (a scale of 0 would erase every
    later command of it): the fit names the robot, whether the whole team stands still or one
    robot among moving ones; a robot that drives without turning has no turn-rate scale."""
    window = CalibrationWindow(1.0, 29.0, "calib")
    still = synthetic.dataset(
        [synthetic.still_robot(1, 0, 0, 0, 30.0), synthetic.still_robot(2, 1, 1, 0, 30.0)]
    )
    with pytest.raises(DataError, match=r"of calib: no commanded motion of robot 1 in the"):
        fit_odometry_model(still, window, 2.0)
    moving = synthetic.commanded_robot(1, np.random.default_rng(4), duration=30.0)
    one_still = synthetic.dataset([moving, synthetic.still_robot(2, 1, 1, 0, 30.0)])
    with pytest.raises(DataError, match="motion of robot 2 in the window to fit its speed scale"):
        fit_odometry_model(one_still, window, 2.0)
    t = np.arange(0.0, 30.0, 0.01)
    straight = synthetic.robot(
        3,
        GroundTruth(t=t, x=0.2 * t, y=0 * t, theta=0 * t, gap_threshold=0.5),
        Odometry(t=t, v=np.full_like(t, 0.2), omega=0 * t),
    )
    with pytest.raises(DataError, match="robot 3 in the window to fit its turn-rate scale"):
        fit_odometry_model(synthetic.dataset([moving, straight]), window, 2.0)


#: Variance rates (m²/s, rad²/s) of the white input noise of :func:`_white_noise_team`.
Q_V, Q_W = 1e-4, 4e-4


def _white_noise_team(synthetic, seed, subjects, **motion):
    """Commanded robots whose motion carries white input noise of the rates ``Q_V``, ``Q_W``
    on a 100 Hz grid (``motion``: duration, command period, latency, scales)."""
    rng = np.random.default_rng(seed)
    dt = 0.01
    return [
        synthetic.commanded_robot(
            subject, rng, sigma_v=np.sqrt(Q_V / dt), sigma_w=np.sqrt(Q_W / dt), dt=dt, **motion
        )
        for subject in subjects
    ]


def _assert_rates_at_the_typical_command(fit):
    """The fitted rate at |v| ≈ 0.25 m/s, |ω| ≈ 0.25 rad/s is the true one."""
    rate_v = fit.q_v0 + fit.k_v * 0.25
    rate_w = fit.q_w0 + fit.k_w * 0.25 + fit.k_wv * 0.25
    assert rate_v == pytest.approx(Q_V, rel=0.3)
    assert rate_w == pytest.approx(Q_W, rel=0.3)


def test_odometry_model_recovers_latency_scales_and_noise_rate(synthetic):
    motion = {"duration": 200.0, "latency": 0.2, "scale_v": 0.9, "scale_w": 1.1}
    robots = _white_noise_team(synthetic, 7, (1, 2), command_period=4.0, **motion)
    ds = synthetic.dataset(robots)
    window = CalibrationWindow(0.0, 200.0, "synthetic")
    fit = fit_odometry_model(ds, window, integration_s=1.0)
    assert fit.calibration_window == window and fit.odometry_window_s == 1.0
    assert fit.latency_s == pytest.approx(0.2, abs=0.011)
    assert fit.time_constant_s == 0.0  # a pure delay: no lag invented
    # (central differences of the ground truth round the command steps off: ~1 % low)
    assert fit.scale_v == pytest.approx((0.9, 0.9), rel=0.02)
    assert fit.scale_w == pytest.approx((1.1, 1.1), rel=0.02)
    _assert_rates_at_the_typical_command(fit)
    assert set(fit.to_dict()) >= {"latency_s", "scale_v", "q_v0", "calibration_window"}


def test_rates_over_long_windows_of_a_turning_robot_are_the_true_rates(synthetic):
    """Windows of 8 s of a robot turning at up to 0.5 rad/s: it turns up to 4 rad in one, so the
    chord between a window's ends falls well short of its path and the wrapped end-to-end
    heading difference is off by 2π; the path length and total turn along the ground truth are
    exact, and the fitted rates are the white input noise's."""
    robots = _white_noise_team(synthetic, 3, (1, 2, 3), duration=600.0, command_period=8.0)
    fit = fit_odometry_model(
        synthetic.dataset(robots), CalibrationWindow(0.0, 600.0, "synthetic"), integration_s=8.0
    )
    _assert_rates_at_the_typical_command(fit)


def test_odometry_model_recovers_a_first_order_lag(synthetic):
    """A robot that follows its delayed commands through a 0.2 s lag: the fit finds the delay,
    the lag and the scales of the steady motion (a pure delay would shrink the scales)."""
    rng = np.random.default_rng(5)
    robots = [
        synthetic.commanded_robot(
            subject,
            rng,
            duration=200.0,
            latency=0.1,
            time_constant=0.2,
            scale_v=0.95,
            scale_w=0.9,
            command_period=2.0,
        )
        for subject in (1, 2)
    ]
    fit = fit_odometry_model(
        synthetic.dataset(robots), CalibrationWindow(0.0, 200.0, "synthetic"), integration_s=1.0
    )
    assert fit.latency_s == pytest.approx(0.1, abs=0.011)
    assert fit.time_constant_s == 0.2
    assert fit.scale_v == pytest.approx((0.95, 0.95), rel=0.01)
    assert fit.scale_w == pytest.approx((0.9, 0.9), rel=0.01)


def test_calibrated_commands_follow_the_fitted_response():
    """Re-stamped by τ, lagged by T (steps approach the command as 1 − e^{−t/T}), scaled."""
    od = BodyOdometry(
        t=np.array([0.0, 10.0]),
        velocity=np.array([[0, 0, 0, 0], [1.0, 0, 0, 2.0]]),
        sigma=np.zeros(4),
    )
    cal = calibrated_commands(od, latency_s=0.1, scale_v=0.5, scale_w=0.25, time_constant_s=0.2)
    held = cal.held_at(np.array([10.05, 10.1 + 0.2, 10.1 + 1.0, 30.0]))
    np.testing.assert_allclose(held[0], 0.0)  # before the delayed step
    np.testing.assert_allclose(
        held[1, [0, 3]], [0.5, 0.5] * np.array([1 - np.exp(-1.0)] * 2), atol=0.05
    )
    np.testing.assert_allclose(held[2:, [0, 3]], [[0.5, 0.5], [0.5, 0.5]], atol=0.01)
    plain = calibrated_commands(od, latency_s=0.1, scale_v=0.5, scale_w=0.25)
    np.testing.assert_array_equal(plain.t, od.t + 0.1)
    np.testing.assert_array_equal(plain.velocity[1], [0.5, 0, 0, 0.5])


def test_calibrated_team_gives_each_robot_its_own_scales():
    """The team's latency and lag for every robot, robot i's scales for robot i."""
    od = BodyOdometry(
        t=np.array([0.0, 10.0]),
        velocity=np.array([[0, 0, 0, 0], [1.0, 0, 0, 2.0]]),
        sigma=np.zeros(4),
    )
    fit = OdometryModelFit(
        calibration_window=CalibrationWindow(0.0, 10.0, "synthetic"),
        latency_s=0.1,
        time_constant_s=0.2,
        scale_v=(0.5, 0.8),
        scale_w=(0.25, 1.2),
        q_v0=1e-4,
        k_v=0.0,
        q_w0=1e-4,
        k_w=0.0,
        k_wv=0.0,
        odometry_window_s=1.0,
    )
    team = calibrated_team((od, od), fit)
    late = np.array([30.0])
    np.testing.assert_allclose(team[0].held_at(late)[0, [0, 3]], [0.5, 0.5], atol=1e-3)
    np.testing.assert_allclose(team[1].held_at(late)[0, [0, 3]], [0.8, 2.4], atol=1e-3)
    one = calibrated_commands(od, 0.1, 0.8, 1.2, 0.2)
    np.testing.assert_array_equal(team[1].t, one.t)
    np.testing.assert_array_equal(team[1].velocity, one.velocity)
    with pytest.raises(ConfigError, match="3 robots' odometry, 2 fitted scales"):
        calibrated_team((od, od, od), fit)


def test_odometry_model_refuses_a_window_without_ground_truth(synthetic):
    rng = np.random.default_rng(1)
    ds = synthetic.dataset([synthetic.commanded_robot(1, rng, duration=20.0)])
    with pytest.raises(DataError, match=r"\[50.00, 80.00\] s of synthetic: .* robot 1's, 0 s$"):
        fit_odometry_model(ds, CalibrationWindow(50.0, 80.0, "synthetic"), integration_s=1.0)
    with pytest.raises(ConfigError, match="integration_s"):
        fit_odometry_model(ds, CalibrationWindow(0.0, 20.0, "synthetic"), integration_s=0.0)
