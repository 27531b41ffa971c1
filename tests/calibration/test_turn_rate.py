"""The best linear filter of the commands, the velocities of the ground truth and the
turn-rate residual statistics, on seeded synthetic data with known answers."""

import numpy as np
import pytest

from relloc.calibration.odometry import (
    fit_command_fir,
    ground_truth_odometry,
    truth_velocity_dataset,
)
from relloc.calibration.turn_rate import residual_stats, turn_rate_residual
from relloc.calibration.window import CalibrationWindow
from relloc.errors import DataError


def test_fir_recovers_a_known_delay_and_gain(synthetic):
    """Commands that change every 0.02 s, followed after 0.1 s at 0.8 of their turn rate: the
    fitted filter's taps sum to 0.8 and centre on 0.1 s, the speed taps and the constant are
    near 0, and on a later window it leaves almost nothing of the turn rate."""
    rng = np.random.default_rng(12)
    robot = synthetic.commanded_robot(
        1, rng, duration=200.0, latency=0.1, scale_w=0.8, command_period=0.02
    )
    # the fit's grid starts at the window start: 1.01 s puts its times between the command
    # stamps (at multiples of 0.02 s), so that no lag hits a stamp up to rounding
    fir = fit_command_fir(robot, CalibrationWindow(1.01, 150.0, "synthetic"))
    assert fir.dc_gain == pytest.approx(0.8, abs=0.02)
    # (the robot's 0.01 s motion grid holds each delayed command from the first grid time at
    # or after it, up to rounding: the true delay is 0.1 s plus at most one motion step)
    assert fir.centroid_lag_s == pytest.approx(0.105, abs=0.01)
    assert abs(sum(fir.coef_v)) < 0.02 and abs(fir.constant) < 0.005
    t = np.arange(155.01, 195.0, 0.02)  # between the stamps, as in the fit
    e, ok = turn_rate_residual(robot, t, lambda tq: fir.predict(robot.odometry, tq))
    _, w_true = robot.odometry.at(t - 0.1)
    assert ok.all() and np.std(e) < 0.05 * np.std(0.8 * w_true)
    with pytest.raises(DataError, match="FIR"):
        fit_command_fir(robot, CalibrationWindow(0.0, 3.0, "synthetic"))


def test_ground_truth_odometry_is_the_true_motion(synthetic):
    """A noise-free unicycle: the re-recorded velocities are its true speed and turn rate,
    over the span of its commands."""
    rng = np.random.default_rng(4)
    robot = synthetic.commanded_robot(2, rng, duration=60.0, command_period=5.0)
    od = ground_truth_odometry(robot)
    assert od.t[0] == robot.odometry.t[0] and od.t[-1] == robot.odometry.t[-1]
    np.testing.assert_allclose(np.diff(od.t)[:-1], 0.02)
    t = np.arange(1.0, 54.0, 0.37)
    t = t[np.abs(t - np.round(t / 5.0) * 5.0) > 0.1]  # away from the command steps
    v_true, w_true = robot.odometry.at(t)
    v, w = od.at(t)
    np.testing.assert_allclose(v, v_true, atol=2e-3)
    np.testing.assert_allclose(w, w_true, atol=2e-3)
    ds = synthetic.dataset([robot])
    assert truth_velocity_dataset(ds).robot(2).groundtruth is robot.groundtruth


def test_block_random_walk_matches_the_integrated_heading():
    """An AR(1) turn-rate error (σ 0.05 rad/s, correlation time 0.5 s): the random walk
    σ_B √(B L) from one long record's 5 s block means matches the spread, over many records,
    of the heading error the error integrates to over L = 100 s; and a white error's block
    means shrink as √(dt/B)."""
    rng = np.random.default_rng(21)
    dt, tc, sigma, L = 0.02, 0.5, 0.05, 100.0
    a = np.exp(-dt / tc)

    def ar1(n: int, m: int) -> np.ndarray:
        x = np.zeros((m, n))
        x[:, 0] = sigma * rng.standard_normal(m)
        drive = sigma * np.sqrt(1 - a * a) * rng.standard_normal((m, n))
        for k in range(1, n):
            x[:, k] = a * x[:, k - 1] + drive[:, k]
        return x

    long = ar1(100_000, 1)[0]
    stats = residual_stats(long, np.ones(long.size, bool), block_s=5.0, dt=dt)
    assert stats.std == pytest.approx(sigma, rel=0.05) and stats.blocks == 400
    headings = ar1(round(L / dt), 400).sum(axis=1) * dt
    assert stats.yaw_random_walk(L) == pytest.approx(np.std(headings), rel=0.15)
    white = sigma * rng.standard_normal(100_000)
    ws = residual_stats(white, np.ones(white.size, bool), block_s=5.0, dt=dt)
    assert ws.block_std == pytest.approx(sigma * np.sqrt(dt / 5.0), rel=0.15)
    # a block holding an invalid time is left out
    valid = np.ones(white.size, bool)
    valid[10] = False
    assert residual_stats(white, valid, block_s=5.0, dt=dt).blocks == 399
