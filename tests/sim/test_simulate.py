"""simulate(): determinism per seed, exact kinematics, odometry noise, FOV and range gating."""

import dataclasses

import numpy as np
import pytest

from relloc.core.recording import relative_pose
from relloc.errors import ConfigError
from relloc.sim.scenario import (
    RobotSpec,
    Scenario,
    SensorSpec,
    VelocityMotion,
    WaypointMotion,
    default_scenario,
)
from relloc.sim.sensors import range_azimuth_elevation, visible
from relloc.sim.simulate import simulate
from relloc.sim.trajectories import integrate_body_velocities


def _short_default(duration=10.0):
    return dataclasses.replace(default_scenario(), duration_s=duration)


def test_same_seed_same_recording_different_seed_different_recording():
    sc = _short_default()
    a = simulate(sc, np.random.default_rng(5))
    b = simulate(sc, np.random.default_rng(5))
    c = simulate(sc, np.random.default_rng(6))
    np.testing.assert_array_equal(a.measurements.value, b.measurements.value)
    np.testing.assert_array_equal(a.odometry[2].velocity, b.odometry[2].velocity)
    assert not np.array_equal(a.odometry[2].velocity, c.odometry[2].velocity)
    np.testing.assert_array_equal(a.truth[1].pose, c.truth[1].pose)  # truth is not random


def test_exact_integration_matches_a_circle():
    # v = 1 m/s, ω = 0.5 rad/s: a circle of radius 2 centred at (0, 2).
    dt, n = 0.1, 200
    poses = integrate_body_velocities(np.zeros(4), np.tile([1.0, 0.0, 0.0, 0.5], (n, 1)), dt)
    radius = np.hypot(poses[:, 0], poses[:, 1] - 2.0)
    np.testing.assert_allclose(radius, 2.0, atol=1e-12)
    np.testing.assert_allclose(poses[-1, 3], 0.5 * dt * n)


def test_odometry_is_commands_plus_noise_of_the_stated_sigma():
    sc = _short_default(30.0)
    rec = simulate(sc, np.random.default_rng(0))
    # The ground observer's truth: its body velocity from consecutive exact poses.
    truth = rec.truth[0].pose
    dt = 1.0 / sc.propagation_rate_hz
    od = rec.odometry[0]
    yaw_rate = np.diff(truth[:, 3]) / dt
    residual = od.velocity[:, 3] - yaw_rate
    sigma_w = od.sigma[3]
    n = residual.size
    # Sample variance / σ² ~ χ²(n)/n: 99.9 % band ±3.3·sqrt(2/n).
    assert abs(residual.var() / sigma_w**2 - 1.0) < 3.3 * np.sqrt(2.0 / n)
    np.testing.assert_array_equal(od.velocity[:, 1:3], 0.0)  # a ground robot has no v_y, v_z


def test_measurements_are_gated_by_fov_and_range_and_noise_is_right():
    sc = _short_default(60.0)
    rec = simulate(sc, np.random.default_rng(1))
    sensor = sc.robots[0].sensor
    m = rec.measurements
    assert np.all(m.observer == 0)
    assert set(m.kind_names()) == {"range_bearing_elevation"}
    np.testing.assert_array_equal(m.origin, m.target)  # simulated: every reading is of its target
    truth_rel = relative_pose(
        rec.truth[0].at(m.t),
        np.vstack([rec.truth[j].at(t)[0] for j, t in zip(m.target, m.t, strict=True)]),
    )
    z_true = range_azimuth_elevation(truth_rel)
    assert visible(z_true, sensor).all()
    err = (m.value - z_true) / m.sigma
    err[:, 1] = np.angle(np.exp(1j * (m.value[:, 1] - z_true[:, 1]))) / m.sigma[:, 1]
    nees = np.sum(err**2, axis=1)
    # Mean of χ²(3) over M rows: 99.9 % band ±3.3·sqrt(6/M).
    assert abs(nees.mean() - 3.0) < 3.3 * np.sqrt(6.0 / m.size)
    # Robots leave and re-enter the 120° view: fewer rows than epochs for some target.
    epochs = int(sc.duration_s * sensor.rate_hz)
    counts = np.bincount(m.target, minlength=5)[1:]
    assert counts.max() <= epochs and counts.min() < epochs


def test_range_limit_and_360_fov():
    pose_a = np.zeros((3, 4))
    pose_b = np.array([[1.0, 0.0, 0.0, 0.0], [-3.0, 0.0, 0.0, 0.0], [0.0, 20.0, 0.0, 0.0]])
    z = range_azimuth_elevation(relative_pose(pose_a, pose_b))
    np.testing.assert_array_equal(
        visible(z, SensorSpec(fov_deg=90.0, max_range=10.0)), [True, False, False]
    )
    np.testing.assert_array_equal(
        visible(z, SensorSpec(fov_deg=360.0, max_range=10.0)), [True, True, False]
    )


def test_leaving_the_arena_is_a_config_error_naming_the_robot():
    runaway = RobotSpec(
        name="runaway",
        kind="ground",
        initial_pose=(5.0, 10.0, 0.0),
        motion=VelocityMotion(mean=(2.0, 0.0, 0.0, 0.0)),
        sensor=SensorSpec(),
    )
    other = RobotSpec(
        name="c",
        kind="aerial",
        height=1.0,
        motion=WaypointMotion(points=((4.0, 4.0), (6.0, 4.0), (5.0, 6.0))),
    )
    sc = Scenario(robots=(runaway, other), duration_s=10.0)
    with pytest.raises(ConfigError, match=r"robots\[0\].motion: robot 'runaway' leaves the arena"):
        simulate(sc, np.random.default_rng(0))


def test_default_trajectories_stay_in_the_arena_for_the_full_run():
    rec = simulate(default_scenario(), np.random.default_rng(2))
    assert rec.measurements.size > 0.9 * 4 * 600


def test_measurements_stay_inside_the_simulated_span():
    """640.5 Hz × 1 s rounds to 640 steps, so the grid ends at 0.99922 s, before the 10 Hz
    sensor's epoch at 1 s; that epoch is not simulated (it used to make the log query truth
    outside its span)."""
    sc = dataclasses.replace(_short_default(1.0), propagation_rate_hz=640.5)
    rec = simulate(sc, np.random.default_rng(0))
    assert rec.truth is not None and rec.truth[0].t[-1] < 1.0
    np.testing.assert_allclose(np.unique(rec.measurements.t), np.arange(1, 10) / 10.0)
