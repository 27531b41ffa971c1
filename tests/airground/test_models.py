"""Follower relative model (Eq. 3), measurement Jacobians (Eq. 4), drone kinematics."""

import numpy as np
import pytest

from relloc.models.airground import (
    Mode,
    drone_step,
    mode_measurement,
    relative_jacobians,
    relative_step,
)
from relloc.models.unicycle import unicycle_step


def test_relative_step_matches_two_unicycles():
    rng = np.random.default_rng(0)
    leader, follower = np.array([0.3, -0.2, 0.4]), np.array([-0.5, 0.1, -1.0])
    x = np.array([*(leader[:2] - follower[:2]), follower[2], leader[2]])
    for _ in range(50):
        u = rng.uniform([-0.3, -1, -0.3, -1], [0.3, 1, 0.3, 1])
        leader = unicycle_step(leader, u[2:], 0.05)
        follower = unicycle_step(follower, u[:2], 0.05)
        x = relative_step(x, u, 0.05)
    np.testing.assert_allclose(x[:2], leader[:2] - follower[:2], atol=1e-12)
    np.testing.assert_allclose(x[2:], [follower[2], leader[2]], atol=1e-12)


def test_jacobians_match_finite_differences():
    x, u, dt, eps = np.array([0.4, -0.7, 0.3, 1.2]), np.array([0.2, 0.5, 0.15, -0.3]), 0.1, 1e-7
    F, G = relative_jacobians(x, u, dt)
    for k in range(4):
        dx = np.zeros(4)
        dx[k] = eps
        np.testing.assert_allclose(
            (relative_step(x + dx, u, dt) - relative_step(x, u, dt)) / eps, F[:, k], atol=1e-6
        )
        np.testing.assert_allclose(
            (relative_step(x, u + dx, dt) - relative_step(x, u, dt)) / eps, G[:, k], atol=1e-6
        )


@pytest.mark.parametrize("mode", list(Mode))
def test_measurement_jacobians(mode):
    x, eps = np.array([0.6, -0.4, 0.3, 1.0]), 1e-7
    z, H, angles = mode_measurement(x, mode)
    assert len(z) == {Mode.PAIR_SEEN: 4, Mode.OTHER_PAIR_SEEN: 3, Mode.NONE_SEEN: 1}[mode]
    assert len(angles) == len(z) and not angles[0]
    for k in range(4):
        dx = np.zeros(4)
        dx[k] = eps
        np.testing.assert_allclose(
            (mode_measurement(x + dx, mode)[0] - z) / eps, H[:, k], atol=1e-6
        )
    assert z[0] == pytest.approx(np.hypot(0.6, -0.4))


def test_drone_p_controller_saturates_and_converges():
    p = np.zeros(2)
    p1, v = drone_step(p, np.array([10.0, 0.0]), 0.1, gain=1.0, v_max=0.5)
    np.testing.assert_allclose(p1, [0.05, 0.0])
    assert np.hypot(*v) == pytest.approx(0.5)
    for _ in range(400):
        p, _ = drone_step(p, np.array([1.0, -2.0]), 0.05, gain=1.5, v_max=0.6)
    np.testing.assert_allclose(p, [1.0, -2.0], atol=1e-6)
