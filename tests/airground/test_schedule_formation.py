"""Drone midpoint schedule (Section 3.2, any N and M) and formation control from estimates."""

import math

import numpy as np
import pytest

from relloc.control import DroneSchedule, FormationSettings, desired_relative, formation_command
from relloc.errors import ConfigError
from relloc.models.unicycle import unicycle_step


def _sequence(s, windows):
    return [s.targets(b * s.dwell_steps) for b in range(windows)]


def test_one_drone_sequence_of_the_paper():
    # Fig. 4: (m4, m1, m2, m3, m4, ...) with one drone.
    s = DroneSchedule(n_followers=4, n_drones=1, dwell_steps=160, offset=3)
    assert [t[0] for t in _sequence(s, 6)] == [4, 1, 2, 3, 4, 1]
    assert s.targets(159) == (4,) and s.targets(160) == (1,)


def test_sliding_window_returns_to_first_midpoints():
    # m_{b+1..b+M} until b + M = N, then back to m_1..m_M.
    s = DroneSchedule(n_followers=5, n_drones=2, dwell_steps=3)
    assert _sequence(s, 5) == [(1, 2), (2, 3), (3, 4), (4, 5), (1, 2)]


def test_partition_matches_two_drone_simulation():
    s = DroneSchedule(n_followers=4, n_drones=2, dwell_steps=2, policy="partition")
    assert s.groups() == ((1, 2), (3, 4))
    assert _sequence(s, 3) == [(1, 3), (2, 4), (1, 3)]
    uneven = DroneSchedule(n_followers=5, n_drones=3, dwell_steps=1, policy="partition")
    assert uneven.groups() == ((1, 2), (3, 4), (5,))


@pytest.mark.parametrize("policy", ["sliding", "partition"])
@pytest.mark.parametrize(("n", "m"), [(1, 1), (3, 1), (4, 3), (2, 5), (7, 2)])
def test_every_midpoint_is_visited_for_any_n_and_m(policy, n, m):
    s = DroneSchedule(n_followers=n, n_drones=m, dwell_steps=1, policy=policy)
    seen = {f for k in range(3 * n) for f in s.targets(k)}
    assert seen == set(range(1, n + 1))
    assert all(len(s.targets(k)) == m for k in range(5))


def test_bad_schedule_config_names_the_field():
    with pytest.raises(ConfigError, match="dwell_steps"):
        DroneSchedule(n_followers=3, n_drones=1, dwell_steps=0)
    with pytest.raises(ConfigError, match="policy"):
        DroneSchedule(n_followers=3, n_drones=1, dwell_steps=1, policy="random")  # type: ignore[arg-type]


@pytest.mark.parametrize("frame", ["global", "leader"])
def test_formation_converges_with_perfect_estimates(frame):
    leader, follower = np.array([0.0, 0.0, 0.3]), np.array([-1.2, 0.4, -0.5])
    offset = np.array([0.5, 0.5])
    settings = FormationSettings()
    dt = 0.05
    for k in range(1600):
        u0 = (0.1, 0.2 * math.sin(2 * math.pi * k * dt / 40.0))
        x = np.array([*(leader[:2] - follower[:2]), follower[2], leader[2]])
        v, w = formation_command(x, offset, frame, u0, settings)
        leader = unicycle_step(leader, np.array(u0), dt)
        follower = unicycle_step(follower, np.array([v, w]), dt)
    r = leader[:2] - follower[:2]
    np.testing.assert_allclose(r, desired_relative(offset, leader[2], frame), atol=0.03)
