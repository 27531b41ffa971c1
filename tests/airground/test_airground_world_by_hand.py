"""The air-ground world's sensors and drone flight from hand-placed states: camera footprint,
altitude band, detection probability, sighting geometry, Gauss–Markov steps, noise channels,
time stamps, priors and start."""

import math

import numpy as np

from relloc.models.uwb_noise import UwbNoiseModel
from relloc.sim.airground import (
    AirGroundScenario,
    AirGroundWorld,
    CameraSettings,
    DroneSettings,
    _Drones,
    _in_footprint,
)

SC = AirGroundScenario(offsets=((1.0, 0.0),), duration=2.0)
# Leader at (1, 0) heading 0.3, follower at (0.5, 0.4) heading −0.2.
POSES = np.array([[1.0, 0.0, 0.3], [0.5, 0.4, -0.2]])


def _drones(x=0.75, y=0.2, z=1.75, yaw=0.1, m=1):
    return _Drones(
        position=np.tile([x, y, z], (m, 1)),
        velocity=np.zeros((m, 2)),
        altitude_deviation=np.zeros(m),
        yaw_error=np.full(m, yaw),
    )


def test_footprint_half_widths_and_gate():
    cam = CameraSettings()
    hx, hy = cam.half_extent(1.75)
    # 1.75 tan(31°) − 0.1 and 1.75 tan(24.5°) − 0.1
    assert abs(hx - 0.9515067) < 1e-6 and abs(hy - 0.6975206) < 1e-6
    drone = np.array([0.0, 0.0, 1.75])
    assert _in_footprint(cam, drone, np.array([0.95, 0.69]))
    assert not _in_footprint(cam, drone, np.array([0.0, 0.8]))  # inside along x, not along y
    assert not _in_footprint(cam, drone, np.array([0.96, 0.0]))


def test_sighting_geometry_with_the_heading_hold_error():
    cam = CameraSettings(p_detect=1.0, bearing_sigma=1e-9, heading_sigma=1e-9)
    sc = AirGroundScenario(offsets=((1.0, 0.0),), duration=2.0, camera=cam)
    rows, fixes = _drones().camera_frame(sc, 0.5, POSES, np.random.default_rng(0))
    # r = p_0 − p_1 = (0.5, −0.4); bearing atan2(−0.4, 0.5) + yaw error 0.1; headings + 0.1.
    np.testing.assert_allclose(rows.value, [[math.atan2(-0.4, 0.5) + 0.1, -0.1, 0.4]], atol=1e-7)
    np.testing.assert_array_equal(rows.t, [0.5])
    assert rows.observer.tolist() == [2] and rows.target.tolist() == [1]
    assert fixes[0].subject == 0


def test_a_pair_seen_by_two_drones_is_reported_once():
    cam = CameraSettings(p_detect=1.0)
    sc = AirGroundScenario(offsets=((1.0, 0.0),), duration=2.0, camera=cam, n_drones=2)
    rows, fixes = _drones(m=2).camera_frame(sc, 0.5, POSES, np.random.default_rng(0))
    assert rows.size == 1 and rows.observer.tolist() == [2]
    assert [f.subject for f in fixes] == [0, 0]


def test_no_reading_outside_the_altitude_band():
    cam = CameraSettings(p_detect=1.0)
    sc = AirGroundScenario(offsets=((1.0, 0.0),), duration=2.0, camera=cam)
    for z in (1.39, 1.86):
        rows, fixes = _drones(z=z).camera_frame(sc, 0.5, POSES, np.random.default_rng(0))
        assert rows.size == 0 and fixes == [None]
    rows, _ = _drones(z=1.85).camera_frame(sc, 0.5, POSES, np.random.default_rng(0))
    assert rows.size == 1


def test_detection_probability_and_marker_fix_noise():
    cam = CameraSettings(p_detect=0.8)
    sc = AirGroundScenario(
        offsets=((1.0, 0.0),), duration=2.0, camera=cam, drone=DroneSettings(midpoint_sigma=0.05)
    )
    rng, drones = np.random.default_rng(1), _drones()
    n, leader_fix, pos = 3000, 0, []
    for _ in range(n):
        _, fixes = drones.camera_frame(sc, 0.5, POSES, rng)
        if fixes[0] is not None and fixes[0].subject == 0:
            leader_fix += 1
            pos.append(fixes[0].position - POSES[0, :2])
    # Binomial(3000, 0.8): σ = 21.9, bound 4 σ. Fix position σ 0.05 per axis, within 5 %.
    assert abs(leader_fix - 2400) < 88
    np.testing.assert_allclose(np.std(pos, axis=0), [0.05, 0.05], rtol=0.05)


def test_gauss_markov_one_tick_steps():
    sc = AirGroundScenario(offsets=((1.0, 0.0),), duration=2.0)  # dt 0.05, τ_alt 3, τ_yaw 5
    drones, rng = _drones(yaw=0.0), np.random.default_rng(2)
    alt, yaw = [], []
    for _ in range(4000):
        drones.altitude_deviation[:] = 0.0
        drones.yaw_error[:] = 0.0
        drones.fly(sc, np.zeros((1, 2)), rng)
        alt.append(drones.position[0, 2] - 1.75)
        yaw.append(drones.yaw_error[0])
    # From 0, one step has σ √(1 − e^(−2dt/τ)): 0.04·0.18106 and 0.01·0.14072 (within 5 %).
    np.testing.assert_allclose([np.std(alt), np.std(yaw)], [0.0072424, 0.0014072], rtol=0.05)
    # Without noise a deviation decays by e^(−dt/τ) a tick.
    quiet = AirGroundScenario(
        offsets=((1.0, 0.0),), duration=2.0, drone=DroneSettings(altitude_sigma=0.0, yaw_sigma=0.0)
    )
    drones = _drones(yaw=0.2)
    drones.altitude_deviation[:] = 0.1
    drones.fly(quiet, np.array([[0.2, -0.4]]), rng)
    np.testing.assert_allclose(
        drones.position[0], [0.76, 0.18, 1.75 + 0.1 * math.exp(-0.05 / 3.0)], atol=1e-12
    )
    np.testing.assert_allclose(drones.yaw_error, [0.2 * math.exp(-0.05 / 5.0)], atol=1e-12)


def test_velocity_noise_channels_time_stamps_priors_and_start():
    sc = AirGroundScenario(offsets=((1.0, 0.0),), duration=2.0, velocity_noise=(0.3, 0.0))
    world = AirGroundWorld.start(sc, np.random.default_rng(3))
    # The drone hovers above the midpoint of leader (0, 0) and follower (−1, 0).
    np.testing.assert_allclose(world.drone_position(0), [-0.5, 0.0, 1.75])
    np.testing.assert_allclose(world.priors["R_1"].cov, np.diag([0.04, 0.04, 0.0225, 0.0225]))
    before = world.poses.copy()
    world.step(np.zeros((2, 2)), np.zeros((1, 2)))
    # σ_ω = 0: headings exactly kept; σ_v = 0.3: both UGVs moved.
    np.testing.assert_array_equal(world.poses[:, 2], before[:, 2])
    assert np.all(np.hypot(*(world.poses[:, :2] - before[:, :2]).T) > 0)
    # Readings of tick 0 → 1 are stamped at its end, t = dt.
    np.testing.assert_array_equal(np.unique(world.batch.t), [0.05])
    rec = world.recording()
    np.testing.assert_array_equal(rec.odometry[0].sigma, [0.3, 0.0, 0.0, 0.0])


def test_uwb_ranges_stay_positive():
    uwb = UwbNoiseModel(bias=0.0, spread=2.0, outlier_rate=0.0, outlier_excess_mean=0.0)
    sc = AirGroundScenario(offsets=((0.3, 0.0),), duration=2.0, uwb=uwb, uwb_every=1)
    world = AirGroundWorld.start(sc, np.random.default_rng(4))
    values = []
    for _ in range(40):
        world.step(np.zeros((2, 2)), np.zeros((1, 2)))
        ranges = world.batch.select(np.asarray(world.batch.kind_names()) == "range")
        values.append(ranges.value[:, 0])
    v = np.concatenate(values)
    assert v.size == 40 and np.all(v >= 1e-3) and np.any(v == 1e-3)
