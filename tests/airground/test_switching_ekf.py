"""Switching EKF (seed 003 Eq. 4, Algorithm 1) through the estimator contract: mode rule and the
held broadcast set, sw = 3 drift and recovery, the triangle block, gating, counts, bad input."""

import math
from dataclasses import replace

import numpy as np
import pytest

from relloc.core.contract import Estimator, HeldOdometry
from relloc.core.gaussian import Gaussian
from relloc.core.recording import Measurements, empty_measurements, measurement_rows
from relloc.errors import ConfigError, DataError
from relloc.estimators.switching_ekf import SwitchingEkf, SwitchingEkfSettings, select_mode
from relloc.models.airground import Mode
from relloc.models.unicycle import unicycle_step

DT = 0.05
#: A camera frame every tick: a sighting holds its pair in S for one tick.
SETTINGS = SwitchingEkfSettings(
    sigma_v=0.02,
    sigma_w=0.04,
    range_sigma=0.05,
    bearing_sigma=0.02,
    heading_sigma=0.02,
    sighting_hold=DT,
)
#: Leader, one follower and a drone (robot indices 0, 1, 2).
PAIR_TEAM = ("R_0", "R_1", "D_1")


def test_select_mode_follows_the_broadcast_set():
    assert select_mode(2, (1, 2)) is Mode.PAIR_SEEN
    assert select_mode(3, (1, 2)) is Mode.OTHER_PAIR_SEEN
    assert select_mode(3, ()) is Mode.NONE_SEEN


def _truth_x(leader, follower):
    return np.array([*(leader[:2] - follower[:2]), follower[2], leader[2]])


def _odometry(u_follower, u_leader, n_robots=3):
    v = np.zeros((n_robots, 4))
    v[0, [0, 3]] = u_leader
    v[1, [0, 3]] = u_follower
    return HeldOdometry(velocity=v, stamp=np.zeros(n_robots))


def _sighting(t, target, x, rng, observer=2, sigma=0.02):
    value = [
        math.atan2(x[1], x[0]) + rng.normal(0, sigma),
        x[2] + rng.normal(0, sigma),
        x[3] + rng.normal(0, sigma),
    ]
    return measurement_rows(
        "pair_sighting", t=np.array([t]), observer=observer, target=target, value=[value]
    )


def _filter(x0, settings=SETTINGS, robots=PAIR_TEAM, owner="R_1", sides=None):
    prior = Gaussian(x0 + np.array([0.1, -0.1, 0.05, -0.05]), np.diag([0.04, 0.04, 0.01, 0.01]))
    return SwitchingEkf(
        robots=robots,
        owner=owner,
        leader="R_0",
        prior=prior,
        settings=settings,
        sides=sides or {},
    )


def _run_pair(detect, n_steps, seed, settings=SETTINGS, outlier_at=None, u=None):
    """One leader–follower pair; ``detect(k)`` says if the drone sees the pair at tick k."""
    rng = np.random.default_rng(seed)
    leader, follower = np.array([0.0, 0.0, 0.0]), np.array([-0.6, -0.6, 0.2])
    f = _filter(_truth_x(leader, follower), settings)
    errors, modes, pos_var = [], [], []
    u = np.array([0.12, -0.15, 0.1, 0.1]) if u is None else u
    for k in range(n_steps):
        t = (k + 1) * DT
        act = u + rng.normal(0, [0.01, 0.02, 0.01, 0.02])
        follower = unicycle_step(follower, act[:2], DT)
        leader = unicycle_step(leader, act[2:], DT)
        x = _truth_x(leader, follower)
        d = float(np.hypot(*x[:2]) + rng.normal(0, 0.05))
        if outlier_at is not None and k == outlier_at:
            d += 3.0
        parts = [measurement_rows("range", t=np.array([t]), observer=1, target=0, value=[d])]
        if detect(k):
            parts.append(_sighting(t, 1, x, rng))
        f.advance(t, _odometry(u[:2], u[2:]))
        f.measure(Measurements.concatenate(parts))
        modes.append(f.mode())
        errors.append(np.hypot(*(f.belief.mean[:2] - x[:2])))
        pos_var.append(np.trace(f.belief.cov[:2, :2]))
    return np.array(errors), modes, np.array(pos_var), f


def test_is_an_estimator_with_a_belief_of_the_leader_in_the_follower_frame():
    f = _filter(np.array([0.6, 0.6, 0.2, 0.0]))
    assert isinstance(f, Estimator)
    assert (f.owner, f.name) == ("R_1", "switching_ekf")
    (b,) = f.beliefs()
    assert (b.subject, b.frame, b.age, b.info["sw"]) == ("R_0", "airground_follower", 0.0, 3.0)


def test_modes_follow_detections_and_counts_add_up():
    _, modes, _, f = _run_pair(lambda k: 100 <= k < 200, 300, 0)
    assert all(m is Mode.NONE_SEEN for m in modes[:100])
    assert all(m is Mode.PAIR_SEEN for m in modes[100:200])
    assert all(m is Mode.NONE_SEEN for m in modes[200:])
    counts = f.take_counts()
    assert counts.get("camera_applied", 0) + counts.get("camera_rejected", 0) == 100
    assert counts.get("range_applied", 0) + counts.get("range_rejected", 0) == 300
    updates = f.take_updates()
    assert len(updates) == 400 and {u.dof for u in updates} == {1, 3}
    assert all(u.subject == "R_0" and np.isfinite(u.cond_s) for u in updates)
    assert f.take_counts() == {} and f.take_updates() == []  # handed over once


def test_broadcast_set_is_held_for_one_camera_frame():
    # Camera frames every 2 ticks (hold 0.1 s); the pair is seen at the first frame only.
    rng = np.random.default_rng(3)
    x = np.array([0.6, 0.6, 0.2, 0.0])
    f = _filter(x, replace(SETTINGS, sighting_hold=2 * DT))
    still = _odometry([0.0, 0.0], [0.0, 0.0])
    seen = []
    for k in range(1, 6):
        t = k * DT
        f.advance(t, still)
        if k == 1:
            f.measure(_sighting(t, 1, x, rng))
        seen.append(f.beliefs()[0].info["sw"])
    # held over the tick after the frame, dropped at the next frame (t = 0.15 s)
    assert seen == [1.0, 1.0, 3.0, 3.0, 3.0]


def test_range_only_error_grows_then_recovers_at_next_detection():
    # Parallel motion (r constant): range alone cannot fix the bearing. Detected for 4 s,
    # range-only (sw = 3) for 40 s, then detected again.
    detect = lambda k: k < 80 or k >= 880  # noqa: E731
    parallel = np.array([0.1, 0.0, 0.1, 0.0])
    before, late, after = [], [], []
    for seed in range(4):
        err, _, pos_var, _ = _run_pair(detect, 960, seed, u=parallel)
        before.append(err[60:80].mean())
        late.append(err[860:880].mean())
        after.append(err[940:960].mean())
        # the filter knows: its position variance grows without bearings, drops at detection
        assert pos_var[879] > 5 * pos_var[79]
        assert pos_var[959] < 0.2 * pos_var[879]
    assert np.mean(late) > 3 * np.mean(before)
    assert np.mean(after) < 0.3 * np.mean(late)
    assert max(after) < 0.05


def test_gross_range_outlier_is_gated_and_counted():
    err, _, _, f = _run_pair(lambda k: True, 200, 1, outlier_at=150)
    assert f.take_counts()["range_rejected"] >= 1
    assert err[150:].max() < 0.1


def test_other_pair_gives_the_triangle_block_and_a_refusal_falls_back_to_range():
    # Leader at the origin, R_1 at (-0.6, -0.3), R_2 at (-0.6, 0.3): the drone sees {R_0, R_2}.
    robots = ("R_0", "R_1", "R_2", "D_1")
    p = {0: np.array([0.0, 0.0]), 1: np.array([-0.6, -0.3]), 2: np.array([-0.6, 0.3])}
    x1 = np.array([*(p[0] - p[1]), 0.0, 0.0])
    x2 = np.array([*(p[0] - p[2]), 0.0, 0.0])
    f = _filter(x1, robots=robots, sides={"R_2": 1})  # R_1 is left of the ray R_0→R_2
    rng = np.random.default_rng(5)

    def ranges(t, scale=1.0):
        pairs = [(0, 1), (0, 2), (1, 2)]
        d = [float(np.hypot(*(p[a] - p[b]))) for a, b in pairs]
        d[2] *= scale
        obs, tgt = zip(*pairs, strict=True)
        return measurement_rows("range", t=np.full(3, t), observer=obs, target=tgt, value=d)

    still = HeldOdometry.still(4)
    f.advance(DT, still)
    f.measure(Measurements.concatenate([ranges(DT), _sighting(DT, 2, x2, rng, observer=3)]))
    assert f.mode() is Mode.OTHER_PAIR_SEEN
    counts = f.take_counts()
    assert counts["triangle_applied"] == 1 and counts["leader_heading_applied"] == 1
    # an impossible triangle (d_12 far too long) is refused, counted, and only d is used
    f.advance(2 * DT, still)
    f.measure(Measurements.concatenate([ranges(2 * DT, 3.0), _sighting(2 * DT, 2, x2, rng, 3)]))
    counts = f.take_counts()
    assert counts["triangle_refusals"] == 1 and counts["range_applied"] == 1
    assert f.diagnostics.refusal_examples[0].startswith("t=0.10s: R_2: ")


def test_rows_it_cannot_use_are_counted_not_fused():
    f = _filter(np.array([0.6, 0.6, 0.2, 0.0]))
    f.advance(DT, HeldOdometry.still(3))
    f.measure(measurement_rows("bearing", t=np.array([DT]), observer=2, target=1, value=[0.3]))
    f.measure(measurement_rows("range", t=np.array([DT]), observer=2, value=[1.0]))
    assert f.take_counts() == {"rows_ignored": 2}
    assert f.take_updates() == []
    f.measure(empty_measurements())
    assert f.take_counts() == {}


def test_bad_input_is_a_clear_error():
    f = _filter(np.array([1.0, 0, 0, 0]))
    bad = HeldOdometry(velocity=np.full((3, 4), np.nan), stamp=np.zeros(3))
    with pytest.raises(DataError, match=r"R_1 at t=0\.050s: bad input"):
        f.advance(DT, bad)
    with pytest.raises(DataError, match="odometry of 2 robots"):
        f.advance(DT, HeldOdometry.still(2))
    f.advance(DT, HeldOdometry.still(3))
    with pytest.raises(DataError, match="time went back"):
        f.advance(0.0, HeldOdometry.still(3))
    with pytest.raises(ConfigError, match="unknown robot 'R_9'"):
        _filter(np.zeros(4), owner="R_9")
    with pytest.raises(ConfigError, match="sides"):
        _filter(np.zeros(4), sides={"R_0": 2})
    with pytest.raises(ConfigError, match="sighting_hold"):
        SwitchingEkfSettings(sighting_hold=0.0)
