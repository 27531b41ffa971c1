"""Relative 4-DOF motion model: Jacobians, exactness against world-frame arcs, no Euler lag."""

import numpy as np
import pytest

from relloc.core.poses import relative
from relloc.errors import ConfigError
from relloc.models.motion import (
    VelocityNoise,
    process_noise,
    relative_derivative,
    relative_jacobians,
    relative_step,
)


def _inputs(rng: np.random.Generator, n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    x = rng.normal(size=(n, 4)) * [3.0, 3.0, 1.0, 2.0]
    u_l = rng.normal(size=(n, 4))
    u_c = rng.normal(size=(n, 4))
    u_l[0, 3] = 1e-6  # series branch of sinc
    u_c[1, 3] = 0.0
    return x, u_l, u_c


@pytest.mark.parametrize("dt", [0.01, 0.4])
def test_jacobians_match_central_differences(dt: float) -> None:
    x, u_l, u_c = _inputs(np.random.default_rng(11), 7)
    F, G = relative_jacobians(x, u_l, u_c, dt)
    eps = 1e-6
    for i in range(4):
        d = np.zeros(4)
        d[i] = eps
        num = (relative_step(x + d, u_l, u_c, dt) - relative_step(x - d, u_l, u_c, dt)) / (2 * eps)
        np.testing.assert_allclose(F[..., i], num, atol=1e-8)
    u = np.concatenate([u_l, u_c], axis=-1)
    for i in range(8):
        d = np.zeros(8)
        d[i] = eps
        up, um = u + d, u - d
        num = (
            relative_step(x, up[:, :4], up[:, 4:], dt) - relative_step(x, um[:, :4], um[:, 4:], dt)
        ) / (2 * eps)
        np.testing.assert_allclose(G[..., i], num, atol=1e-8)


def test_step_equals_fine_integration_of_eq1() -> None:
    x, u_l, u_c = _inputs(np.random.default_rng(5), 5)
    dt, n = 0.5, 4000
    h = dt / n
    xx = x.copy()
    for _ in range(n):  # classical RK4 on the continuous model
        k1 = relative_derivative(xx, u_l, u_c)
        k2 = relative_derivative(xx + 0.5 * h * k1, u_l, u_c)
        k3 = relative_derivative(xx + 0.5 * h * k2, u_l, u_c)
        k4 = relative_derivative(xx + h * k3, u_l, u_c)
        xx = xx + h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
    np.testing.assert_allclose(relative_step(x, u_l, u_c, dt), xx, atol=1e-11)


def _world_pose(p0: np.ndarray, u: np.ndarray, t: float) -> np.ndarray:
    """Closed-form world pose (x, y, z, ψ) of a robot holding body velocity u for time t."""
    psi0, w = p0[3], u[3]
    if abs(w) < 1e-12:
        R = np.array([[np.cos(psi0), -np.sin(psi0)], [np.sin(psi0), np.cos(psi0)]])
        dxy = t * R @ u[:2]
    else:
        # ∫ R(ψ0 + w s) v ds = (1/w) (−J) (R(ψ0 + w t) − R(ψ0)) v
        def rot(a: float) -> np.ndarray:
            return np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])

        J = np.array([[0.0, -1.0], [1.0, 0.0]])
        dxy = (-J @ (rot(psi0 + w * t) - rot(psi0)) @ u[:2]) / w
    return np.array([p0[0] + dxy[0], p0[1] + dxy[1], p0[2] + u[2] * t, psi0 + w * t])


def test_step_matches_relative_pose_of_two_world_arcs() -> None:
    """Derivation check: the model reproduces ⊖pose_l ⊕ pose_c of independently moved robots."""
    pose_l = np.array([1.0, -2.0, 0.0, 0.3])
    pose_c = np.array([4.0, 1.0, 2.0, -1.2])
    u_l = np.array([0.8, 0.1, 0.05, 0.7])
    u_c = np.array([1.1, -0.2, -0.1, -0.4])
    x = relative(pose_l, pose_c)[0]
    dt, steps = 0.01, 500
    for _ in range(steps):
        x = relative_step(x, u_l, u_c, dt)
    t = dt * steps
    expected = relative(_world_pose(pose_l, u_l, t), _world_pose(pose_c, u_c, t))[0]
    np.testing.assert_allclose(x, expected, atol=1e-10)


def _euler_step(x: np.ndarray, u_l: np.ndarray, u_c: np.ndarray, dt: float) -> np.ndarray:
    return x + dt * relative_derivative(x, u_l, u_c)


def test_exact_step_has_no_heading_lag_where_euler_does() -> None:
    """Euler moves the observed robot along φ instead of φ + ω dt/2: its path bends late."""
    x0 = np.array([3.0, 0.0, 1.0, 0.0])
    u_l = np.zeros(4)
    u_c = np.array([1.0, 0.0, 0.0, 0.5])
    dt, steps = 0.1, 20
    exact = euler = x0
    for _ in range(steps):
        exact = relative_step(exact, u_l, u_c, dt)
        euler = _euler_step(euler, u_l, u_c, dt)
    truth = relative(np.zeros(4), _world_pose(np.array([3.0, 0.0, 1.0, 0.0]), u_c, dt * steps))[0]
    np.testing.assert_allclose(exact, truth, atol=1e-12)
    # direction of travel seen from the start: Euler lags by about ω dt / 2
    lag = np.arctan2(truth[1] - x0[1], truth[0] - x0[0]) - np.arctan2(
        euler[1] - x0[1], euler[0] - x0[0]
    )
    assert lag == pytest.approx(0.5 * u_c[3] * dt, rel=0.1)


def test_process_noise_is_g_sigma_gt_and_psd() -> None:
    x, u_l, u_c = _inputs(np.random.default_rng(2), 4)
    noise = VelocityNoise(observer=(0.1, 0.05, 0.02, 0.03), observed=(0.2, 0.0, 0.01, 0.05))
    _, G = relative_jacobians(x, u_l, u_c, 0.1)
    Q = process_noise(G, noise)
    np.testing.assert_allclose(Q, G @ noise.covariance @ np.swapaxes(G, -1, -2), atol=1e-15)
    assert np.all(np.linalg.eigvalsh(Q) > -1e-15)


def test_invalid_settings_name_the_field() -> None:
    with pytest.raises(ConfigError, match="observer"):
        VelocityNoise(observer=(0.1, 0.1, 0.1), observed=(0.1, 0.1, 0.1, 0.1))  # type: ignore[arg-type]
    with pytest.raises(ConfigError, match="observed"):
        VelocityNoise(observer=(0.1,) * 4, observed=(0.1, -1.0, 0.1, 0.1))
    with pytest.raises(ConfigError, match="dt"):
        relative_step(np.zeros(4), np.zeros(4), np.zeros(4), float("nan"))
