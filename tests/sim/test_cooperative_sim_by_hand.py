"""The planar cooperative simulator against hand geometry and stated noise: detection gates at
their edges, detection and GPS time stamps, per-channel noise σ and the prior draw."""

import numpy as np

from relloc.sim.cooperative import (
    CooperativeScenario,
    _controls,
    _detect,
    sharma2013_scenario,
    simulate,
)


def _poses(rec, robots, times):
    """Truth ``(x, y, z, ψ)`` of ``robots[k]`` at ``times[k]`` (robot index < 0: zeros)."""
    out = np.zeros((len(times), 4))
    for i in np.unique(robots[robots >= 0]):
        sel = robots == i
        out[sel] = rec.truth[i].at(times[sel])
    return out


def _scenario(**kw):
    return CooperativeScenario(
        start_poses=np.zeros((1, 3)),
        waypoints=(np.array([[10.0, 0.0]]),),
        landmarks_xy=np.zeros((0, 2)),
        **kw,
    )


def test_detection_gates_include_their_edges():
    s = _scenario(sensing_range=2.0, fov=np.pi / 2)
    pose = np.zeros((1, 3))
    # (2, 0) exactly at range; (1, ±1) exactly at ±45° = ±fov/2; (0, 1) at 90°; (2.01, 0) beyond
    # range; (0, 0) on the robot itself.
    pts = np.array([[2.0, 0.0], [1.0, 1.0], [1.0, -1.0], [0.0, 1.0], [2.01, 0.0], [0.0, 0.0]])
    _, tgt, _, brg = _detect(pose, pts, s, exclude_self=False)
    assert tgt.tolist() == [0, 1, 2]
    np.testing.assert_allclose(brg, [0.0, np.pi / 4, -np.pi / 4])


def test_bearing_is_measured_from_the_robot_heading():
    s = _scenario()
    pose = np.array([[1.0, 1.0, np.pi / 2]])
    _, _, dist, brg = _detect(pose, np.array([[4.0, 1.0]]), s, exclude_self=False)
    np.testing.assert_allclose([dist[0], brg[0]], [3.0, -np.pi / 2])


def test_detections_and_fixes_are_stamped_with_the_pose_they_saw():
    s = sharma2013_scenario(
        duration=60.0, sigma_bearing=1e-9, sigma_range=1e-9, gps_robots=(0,), gps_sigma=(1e-9,) * 3
    )
    rec = simulate(s, np.random.default_rng(0)).recording
    m = rec.measurements
    kinds = np.asarray(m.kind_names())
    rb = m.select(kinds == "range_bearing")
    assert rb.size > 100 and rb.t.min() == 0.1  # none at t = 0
    obs = _poses(rec, rb.observer, rb.t)
    tgt_xy = np.where(
        (rb.target >= 0)[:, None],
        _poses(rec, rb.target, rb.t)[:, :2],
        rec.landmarks[np.maximum(rb.landmark, 0), :2],
    )
    d = tgt_xy - obs[:, :2]
    np.testing.assert_allclose(rb.value[:, 0], np.hypot(d[:, 0], d[:, 1]), atol=1e-6)
    gps = m.select(kinds == "pose")
    np.testing.assert_allclose(gps.t, np.arange(1, 61) * 1.0)
    truth0 = rec.truth[0].at(gps.t)
    err = gps.value - truth0[:, [0, 1, 3]]
    err[:, 2] = np.angle(np.exp(1j * err[:, 2]))
    np.testing.assert_allclose(err, 0.0, atol=1e-6)


def test_odometry_range_and_gps_noise_of_the_stated_sigma():
    s = sharma2013_scenario(
        duration=100.0,
        sigma_v=0.3,
        sigma_w=0.05,
        sigma_range=0.5,
        gps_robots=(0, 1, 2, 3),
        gps_sigma=(0.5, 0.5, 0.05),
    )
    rec = simulate(s, np.random.default_rng(1)).recording
    v_err, w_err = [], []
    for od, tr in zip(rec.odometry[:4], rec.truth[:4], strict=True):
        v_err.append(od.velocity[:, 0] - 5.0)  # the true speed is the constant 5 m/s
        w_err.append(od.velocity[:, 3] - np.diff(tr.pose[:, 3]) / 0.1)  # ψ += ω dt exactly
    # 4000 draws: sample σ within 5 %.
    np.testing.assert_allclose([np.std(v_err), np.std(w_err)], [0.3, 0.05], rtol=0.05)
    m = rec.measurements
    kinds = np.asarray(m.kind_names())
    gps = m.select(kinds == "pose")
    truth = _poses(rec, gps.observer, gps.t)
    err = gps.value - truth[:, [0, 1, 3]]
    err[:, 2] = np.angle(np.exp(1j * err[:, 2]))
    # 400 fixes: sample σ within 15 % (> 4 SE of 3.5 %).
    np.testing.assert_allclose(err.std(axis=0), [0.5, 0.5, 0.05], rtol=0.15)
    rb = m.select(kinds == "range_bearing")
    robots = rb.target >= 0
    obs, tgt = _poses(rec, rb.observer, rb.t), _poses(rec, rb.target, rb.t)
    r_err = (rb.value[:, 0] - np.hypot(*(tgt[:, :2] - obs[:, :2]).T))[robots]
    assert r_err.size > 2000
    np.testing.assert_allclose(r_err.std(), 0.5, rtol=0.05)


def test_prior_mean_is_the_start_plus_noise_of_the_initial_sigma():
    starts = np.column_stack([np.arange(150.0), np.zeros(150), np.zeros(150)])
    s = CooperativeScenario(
        start_poses=starts,
        waypoints=tuple(np.array([[x, 50.0]]) for x in starts[:, 0]),
        landmarks_xy=np.zeros((0, 2)),
        duration=0.1,
    )
    sim = simulate(s, np.random.default_rng(2))
    err = sim.prior.mean.reshape(-1, 3) - s.start_poses
    # 150 robots: the position σ of 300 draws within 20 % (> 4 SE of 4.1 %), the heading σ
    # of 150 within 25 % (> 4 SE of 5.8 %).
    assert abs(err[:, :2].std() / 5.0 - 1.0) < 0.2
    assert abs(err[:, 2].std() / 0.2 - 1.0) < 0.25


def test_steering_is_proportional_to_the_heading_error_and_capped():
    s = _scenario(heading_gain=2.0, max_turn_rate=0.5, speed=3.0)
    pose = np.zeros((3, 3))
    # Targets at 90° right, 0.1 rad left (gain 2 → 0.2 rad/s), and straight behind-left.
    targets = np.array([[0.0, -10.0], [10.0 * np.cos(0.1), 10.0 * np.sin(0.1)], [-10.0, 1e-3]])
    np.testing.assert_allclose(
        _controls(pose, targets, s), [[3.0, -0.5], [3.0, 0.2], [3.0, 0.5]], atol=1e-12
    )
