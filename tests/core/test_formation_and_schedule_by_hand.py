"""Formation control and drone scheduling of the air-ground team, checked against hand-derived
facts: the leader-frame feed-forward that holds a turning formation exactly (follower velocity
by finite differences of the formation's geometry), convergence of the feedback, reversing,
heading gain and wrapping, saturation, the follower spacing check, and the sliding / partition
schedules written out by hand."""

from __future__ import annotations

import math

import numpy as np
import pytest

from relloc.control import DroneSchedule, FormationSettings, desired_relative, formation_command
from relloc.control.formation import formation_offsets
from relloc.errors import ConfigError
from relloc.models.unicycle import unicycle_step

WIDE = FormationSettings(gain=0.6, heading_gain=2.0, v_max=2.0, w_max=3.0)


def test_desired_offset_turns_with_the_leader() -> None:
    np.testing.assert_allclose(
        desired_relative(np.array([1.0, 0.0]), math.pi / 2, "leader"), [0, 1], atol=1e-15
    )
    np.testing.assert_allclose(desired_relative(np.array([1.0, 2.0]), 0.7, "global"), [1, 2])


def test_feed_forward_holds_a_turning_formation() -> None:
    # leader on a circle: θ_0(t) = θ + ω t, ṗ_0 = v (cos θ_0, sin θ_0). A follower holding
    # r = p_0 − p_i = R(θ_0) c moves with p_i(t) = p_0(t) − R(θ_0(t)) c; at its place and facing
    # along that velocity, the command must be exactly (|ṗ_i|, 0)
    v0, w0, th, c = 0.2, 0.5, 0.3, np.array([-0.5, 0.3])

    def follower(t: float) -> np.ndarray:
        a = th + w0 * t
        p0 = (v0 / w0) * np.array([math.sin(a), -math.cos(a)])
        rot = np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])
        return p0 - rot @ c

    h = 1e-5
    vel = (follower(h) - follower(-h)) / (2 * h)
    rot0 = np.array([[math.cos(th), -math.sin(th)], [math.sin(th), math.cos(th)]])
    estimate = np.array([*(rot0 @ c), math.atan2(vel[1], vel[0]), th])
    v, omega = formation_command(estimate, c, "leader", (v0, w0), WIDE)
    assert v == pytest.approx(float(np.hypot(*vel)), rel=1e-8)
    assert omega == pytest.approx(0.0, abs=1e-8)


def test_feedback_brings_a_displaced_follower_back() -> None:
    offset = np.array([0.5, 0.5])
    leader = np.array([0.0, 0.0, 0.0])
    pose = np.array([-0.8, -0.3, 0.4])  # r = p_0 − p_i = (0.8, 0.3): 0.36 m off
    start = float(np.hypot(*(leader[:2] - pose[:2] - offset)))
    for _ in range(3000):
        r = leader[:2] - pose[:2]
        u = formation_command(np.array([*r, pose[2], 0.0]), offset, "global", (0.0, 0.0), WIDE)
        pose = unicycle_step(pose, np.array(u), 0.01)
    end = float(np.hypot(*(leader[:2] - pose[:2] - offset)))
    assert start > 0.3
    assert end < 0.02


def test_reversing_heading_gain_wrapping_and_saturation() -> None:
    off = np.array([0.5, 0.0])
    still = (0.0, 0.0)
    s = FormationSettings()  # gain 0.6, heading gain 2, v_max 0.35, w_max 1.5
    # r − r_des = (0.1, 0): wanted velocity (0.06, 0)
    v, w = formation_command(np.array([0.6, 0.0, math.pi, 0.0]), off, "global", still, s)
    assert v == pytest.approx(-0.06)  # facing away: back up
    assert w == pytest.approx(-1.5)  # 2·(−π) saturated
    v, w = formation_command(np.array([0.6, 0.0, 0.3, 0.0]), off, "global", still, s)
    assert v == pytest.approx(0.06 * math.cos(0.3))
    assert w == pytest.approx(-0.6)  # heading gain 2 on Δ = −0.3
    v, w = formation_command(np.array([0.6, 0.0, 2 * math.pi - 0.3, 0.0]), off, "global", still, s)
    assert w == pytest.approx(0.6)  # Δ wrapped to +0.3
    v, w = formation_command(np.array([10.5, 0.0, 0.0, 0.0]), off, "global", still, s)
    assert (v, w) == (pytest.approx(0.35), pytest.approx(0.0))
    v, _ = formation_command(np.array([-9.5, 0.0, 0.0, 0.0]), off, "global", still, s)
    assert v == pytest.approx(-0.35)


def test_followers_closer_than_the_separation_are_refused() -> None:
    with pytest.raises(ConfigError, match="sits on follower 1"):
        formation_offsets([(1.0, 0.0), (1.05, 0.0)], "offsets")
    assert formation_offsets([(1.0, 0.0), (1.2, 0.0)], "offsets") == ((1.0, 0.0), (1.2, 0.0))


def test_sliding_schedule_by_hand() -> None:
    s = DroneSchedule(n_followers=5, n_drones=2, dwell_steps=1)
    assert [s.targets(k) for k in range(6)] == [(1, 2), (2, 3), (3, 4), (4, 5), (1, 2), (2, 3)]
    shifted = DroneSchedule(n_followers=5, n_drones=2, dwell_steps=3, offset=1)
    assert [shifted.targets(k) for k in (0, 2, 3, 9)] == [(2, 3), (2, 3), (3, 4), (1, 2)]


def test_partition_schedule_by_hand() -> None:
    s = DroneSchedule(n_followers=5, n_drones=2, dwell_steps=1, policy="partition")
    assert s.groups() == ((1, 2, 3), (4, 5))
    assert [s.targets(k) for k in range(4)] == [(1, 4), (2, 5), (3, 4), (1, 5)]
