"""True motion of the simulator against hand-derived kinematics: lateral and vertical body
velocity, midpoint-sampled commands, closed and open way-point paths."""

import numpy as np

from relloc.sim.scenario import RobotSpec, VelocityMotion, WaypointMotion
from relloc.sim.trajectories import SplinePath, integrate_body_velocities, robot_motion


def test_sideways_and_climbing_body_velocity_while_turning():
    # Body velocity (1, 1) m/s, climb 0.2 m/s, ω = 0.5 rad/s for 1 s from the origin, yaw 0:
    # p(t) = (1/ω) [[sin ωt, cos ωt − 1], [1 − cos ωt, sin ωt]] (1, 1)ᵀ, z = 0.2 t.
    poses = integrate_body_velocities(np.zeros(4), np.tile([1.0, 1.0, 0.2, 0.5], (10, 1)), 0.1)
    np.testing.assert_allclose(
        poses[-1], [0.7140162009891515, 1.2036859534276605, 0.2, 0.5], atol=1e-12
    )


def test_sideways_motion_with_a_turned_start():
    # Yaw π/2: the body y axis points along world −x. 1 m/s sideways for 1 s.
    pose0 = np.array([3.0, 4.0, 1.0, np.pi / 2])
    poses = integrate_body_velocities(pose0, np.tile([0.0, 1.0, 0.0, 0.0], (10, 1)), 0.1)
    np.testing.assert_allclose(poses[-1], [2.0, 4.0, 1.0, np.pi / 2], atol=1e-12)


def test_velocity_commands_are_taken_at_the_step_midpoints():
    spec = RobotSpec(
        name="a",
        kind="aerial",
        height=1.5,
        initial_pose=(1.0, 2.0, 0.3),
        motion=VelocityMotion(
            mean=(0.5, 0.0, 0.0, 0.0),
            amplitude=(0.0, 0.0, 0.0, 0.4),
            period_s=(10.0, 10.0, 10.0, 2.0),
            phase_rad=(0.0, 0.0, 0.0, 0.3),
        ),
    )
    t = np.arange(11) * 0.1
    poses, commands = robot_motion(spec, t)
    np.testing.assert_array_equal(poses[0], [1.0, 2.0, 1.5, 0.3])
    # ω_k = 0.4 sin(2π (k + ½) 0.1 / 2 + 0.3): k = 0 → 0.4 sin(0.05π + 0.3), k = 5 → 0.55π + 0.3.
    np.testing.assert_allclose(commands[[0, 5], 3], [0.17653176605577886, 0.35893806648672383])
    np.testing.assert_allclose(commands[:, 0], 0.5)


def test_spline_through_points_of_a_circle_is_close_to_the_circle():
    ang = np.arange(8) * np.pi / 4
    path = SplinePath(tuple((5 + 2 * np.cos(a), 10 + 2 * np.sin(a)) for a in ang), closed=True)
    # A periodic cubic through 8 points of a radius-2 circle: length ≈ 4π, curvature ≈ 1/2
    # (within 10 %: it bulges at the knots), counter-clockwise tangent at (7, 10) is +y.
    assert abs(path.length - 4 * np.pi) < 0.01 * 4 * np.pi
    s = np.linspace(0.0, path.length, 50)
    heading, curvature = path.heading_and_curvature(s)
    np.testing.assert_allclose(curvature, 0.5, rtol=0.1)
    assert abs(heading[0] - np.pi / 2) < 1e-6
    np.testing.assert_allclose(path.position(s + path.length), path.position(s), atol=1e-9)


def test_closed_path_robot_laps_and_keeps_going():
    ang = np.arange(8) * np.pi / 4
    motion = WaypointMotion(
        points=tuple((5 + 2 * np.cos(a), 10 + 2 * np.sin(a)) for a in ang),
        closed=True,
        speed=0.5,
    )
    spec = RobotSpec(name="g", kind="ground", motion=motion)
    lap = SplinePath(motion.points, closed=True).length / 0.5
    t = np.arange(round(1.5 * lap * 100) + 1) / 100.0
    poses, _ = robot_motion(spec, t)
    k = round(lap * 100)
    # After one lap (to within one 5 mm step) it is back at the start, turned by 2π.
    assert np.hypot(*(poses[k, :2] - poses[0, :2])) < 0.01
    assert abs(poses[k, 3] - poses[0, 3] - 2 * np.pi) < 0.02
    # Half a lap later it is on the far side of the circle, (3, 10).
    np.testing.assert_allclose(poses[-1, :2], [3.0, 10.0], atol=0.05)


def test_open_path_stops_within_half_a_step_of_its_end():
    motion = WaypointMotion(points=((1.0, 5.0), (1.5, 5.0), (2.0, 5.0)), speed=0.3, closed=False)
    spec = RobotSpec(name="g", kind="ground", motion=motion)
    t = np.arange(501) / 100.0
    poses, commands = robot_motion(spec, t)
    # 1 m at 3 mm a step: step k moves while its midpoint (k + ½)·3 mm < 1 m, so 333 steps.
    assert int(np.count_nonzero(commands[:, 0])) == 333
    np.testing.assert_allclose(poses[-1], [1.0 + 333 * 0.003, 5.0, 0.0, 0.0], atol=1e-9)


def test_fixed_heading_aerial_robot_flies_the_path_sideways_and_bobs():
    ang = np.arange(8) * np.pi / 4
    motion = WaypointMotion(
        points=tuple((5 + 2 * np.cos(a), 10 + 2 * np.sin(a)) for a in ang),
        speed=0.5,
        heading="fixed",
        yaw_rad=np.pi / 2,
        z_amplitude=0.3,
        z_period_s=4.0,
    )
    spec = RobotSpec(name="d", kind="aerial", height=1.0, motion=motion)
    lap = SplinePath(motion.points, closed=True).length / 0.5
    t = np.arange(round(1.5 * lap * 100) + 1) / 100.0
    poses, _ = robot_motion(spec, t)
    np.testing.assert_allclose(poses[:, 3], np.pi / 2)
    np.testing.assert_allclose(poses[0, :2], [7.0, 10.0])
    # Counter-clockwise: at (5, 12) a quarter lap in; back at the start after a lap, on the far
    # side (3, 10) half a lap later.
    np.testing.assert_allclose(poses[round(lap * 25), :2], [5.0, 12.0], atol=0.05)
    k = round(lap * 100)
    assert np.hypot(*(poses[k, :2] - poses[0, :2])) < 0.01
    np.testing.assert_allclose(poses[-1, :2], [3.0, 10.0], atol=0.05)
    # z = 1 + 0.3 sin(2π t / 4) exactly at the grid: 1.0, 1.3, 1.0, 0.7 at t = 0, 1, 2, 3 s.
    np.testing.assert_allclose(poses[[0, 100, 200, 300], 2], [1.0, 1.3, 1.0, 0.7], atol=1e-12)
