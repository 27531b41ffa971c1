"""Unicycle step: exact on straight lines and circles; Jacobians against finite differences."""

import numpy as np

from relloc.models.unicycle import unicycle_jacobians, unicycle_step


def test_straight_line_and_circle():
    assert np.allclose(unicycle_step(np.zeros(3), np.array([2.0, 0.0]), 0.5), [1.0, 0, 0])
    # a full circle of radius v/ω in many midpoint steps returns to the start
    pose = np.zeros(3)
    n = 2000
    for _ in range(n):
        pose = unicycle_step(pose, np.array([1.0, 2 * np.pi / n]), 1.0)
    assert np.allclose(pose[:2], 0.0, atol=1e-5)


def test_jacobians_match_finite_differences_batched():
    rng = np.random.default_rng(3)
    poses = rng.normal(size=(5, 3))
    u = rng.normal(size=(5, 2))
    dt, eps = 0.3, 1e-6
    F, G = unicycle_jacobians(poses, u, dt)
    for i in range(3):
        d = np.zeros(3)
        d[i] = eps
        num = (unicycle_step(poses + d, u, dt) - unicycle_step(poses - d, u, dt)) / (2 * eps)
        assert np.allclose(F[:, :, i], num, atol=1e-6)
    for i in range(2):
        d = np.zeros(2)
        d[i] = eps
        num = (unicycle_step(poses, u + d, dt) - unicycle_step(poses, u - d, dt)) / (2 * eps)
        assert np.allclose(G[:, :, i], num, atol=1e-6)
