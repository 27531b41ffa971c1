"""simulate() on a team that stands still: every number of the recording can be derived by
hand."""

import numpy as np
import pytest

from relloc.errors import ConfigError
from relloc.sim.scenario import OdometryNoise, RobotSpec, Scenario, SensorSpec, VelocityMotion
from relloc.sim.simulate import simulate

SENSOR = SensorSpec(sigma_range=0.004, sigma_azimuth=0.01, sigma_elevation=0.05, rate_hz=10.0)


def _team(duration=2.0):
    a = RobotSpec(
        name="a",
        kind="ground",
        initial_pose=(2.0, 2.0, 0.0),
        motion=VelocityMotion(),
        sensor=SENSOR,
        observes=("b", "c"),
    )
    b = RobotSpec(
        name="b",
        kind="aerial",
        height=1.2,
        initial_pose=(5.0, 6.0, np.pi / 2),
        motion=VelocityMotion(),
        odometry=OdometryNoise(sigma_v=0.05, sigma_vz=0.02, sigma_w=0.03),
        sensor=SENSOR,
        observes=("a",),
    )
    c = RobotSpec(name="c", kind="ground", initial_pose=(2.0, 7.0, 0.0), motion=VelocityMotion())
    return Scenario(robots=(a, b, c), duration_s=duration, propagation_rate_hz=100.0)


def test_time_stamps_of_odometry_and_measurements():
    rec = simulate(_team(), np.random.default_rng(0))
    np.testing.assert_allclose(rec.odometry[0].t, np.arange(200) / 100.0)
    np.testing.assert_allclose(rec.truth[0].t, np.arange(201) / 100.0)
    m = rec.measurements
    # 10 Hz over 2 s: epochs 0.1 … 2.0 (the last included), three pairs each.
    np.testing.assert_allclose(np.unique(m.t), np.arange(1, 21) / 10.0)
    assert m.size == 60


def test_rows_are_sorted_by_time_then_observer_then_target():
    m = simulate(_team(), np.random.default_rng(0)).measurements
    pairs = list(zip(m.observer[:3].tolist(), m.target[:3].tolist(), strict=True))
    assert pairs == [(0, 1), (0, 2), (1, 0)]
    np.testing.assert_array_equal(m.t[:3], 0.1)


def test_readings_are_the_hand_geometry_plus_noise_of_the_stated_sigma():
    rec = simulate(_team(40.0), np.random.default_rng(3))
    m = rec.measurements
    np.testing.assert_allclose(m.sigma, np.tile([0.004, 0.01, 0.05], (m.size, 1)))
    # a at (2, 2, 0) yaw 0 sees b at (5, 6, 1.2): r = √(9 + 16 + 1.44), θ = atan2(4, 3),
    # α = atan2(1.2, 5). b (yaw 90°) sees a at world offset (−3, −4, −1.2), body (−4, 3, −1.2).
    # a sees c at (0, 5, 0): θ = 90°.
    expected = {
        (0, 1): [np.sqrt(26.44), np.arctan2(4.0, 3.0), np.arctan2(1.2, 5.0)],
        (1, 0): [np.sqrt(26.44), np.arctan2(3.0, -4.0), np.arctan2(-1.2, 5.0)],
        (0, 2): [5.0, np.pi / 2, 0.0],
    }
    for (i, j), z in expected.items():
        rows = m.value[(m.observer == i) & (m.target == j)]
        assert rows.shape[0] == 400
        err = rows - np.array(z)
        # 400 draws: the mean within 4 σ/√400, the sample σ within 15 % (> 4 SE of 3.5 %).
        np.testing.assert_allclose(err.mean(axis=0), 0.0, atol=4 * 0.05 / 20)
        np.testing.assert_allclose(err.std(axis=0), [0.004, 0.01, 0.05], rtol=0.15)


def test_odometry_noise_per_channel_of_ground_and_aerial_robots():
    rec = simulate(_team(40.0), np.random.default_rng(4))
    # Standing still: the odometry is the noise alone. 4000 steps: sample σ within 5 %.
    ground, aerial = rec.odometry[0], rec.odometry[1]
    np.testing.assert_array_equal(ground.velocity[:, 1:3], 0.0)
    np.testing.assert_allclose(ground.velocity[:, [0, 3]].std(axis=0), [0.05, 0.05], rtol=0.05)
    np.testing.assert_allclose(aerial.sigma, [0.05, 0.05, 0.02, 0.03])
    np.testing.assert_allclose(aerial.velocity.std(axis=0), [0.05, 0.05, 0.02, 0.03], rtol=0.05)
    np.testing.assert_array_equal(rec.truth[1].pose[-1], [5.0, 6.0, 1.2, np.pi / 2])


def test_leaving_the_arena_names_the_first_sample_outside():
    runaway = RobotSpec(
        name="runaway",
        kind="ground",
        initial_pose=(5.0, 10.0, 0.0),
        motion=VelocityMotion(mean=(2.0, 0.0, 0.0, 0.0)),
        sensor=SENSOR,
        observes=("c",),
    )
    c = RobotSpec(name="c", kind="ground", initial_pose=(2.0, 7.0, 0.0), motion=VelocityMotion())
    sc = Scenario(robots=(runaway, c), duration_s=10.0)
    # x = 5 + 2t passes the arena's x = 10 m edge at 2.5 s; the first sample beyond is 2.51 s.
    with pytest.raises(ConfigError, match=r"at t=2\.51 s \(x=10\.02, y=10\.00, z=0\.00\)"):
        simulate(sc, np.random.default_rng(0))


def test_step_count_rounds_and_a_sensor_may_run_at_the_propagation_rate():
    # 0.29 s × 100 Hz is 28.999999999999996 in floating point: 29 steps, not 28.
    assert _team(0.29).steps == 29
    fast = SensorSpec(rate_hz=100.0)
    a = RobotSpec(
        name="a",
        kind="ground",
        initial_pose=(2.0, 2.0, 0.0),
        motion=VelocityMotion(),
        sensor=fast,
        observes=("c",),
    )
    c = RobotSpec(name="c", kind="ground", initial_pose=(2.0, 7.0, 0.0), motion=VelocityMotion())
    rec = simulate(Scenario(robots=(a, c), duration_s=0.1), np.random.default_rng(0))
    np.testing.assert_allclose(rec.measurements.t, np.arange(1, 11) / 100.0)
