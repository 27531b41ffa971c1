"""Thresholds and closed forms of the numeric observability code that the other tests leave free:
the strict "above rtol" rank rule and the level of RANK_RTOL, the RPMG's inclusive range and
field-of-view limits, and the unicycle-team PCRLB without measurements (the prior propagated by
finite-difference Jacobians, per-robot input noise, unequal and zero-length steps)."""

import numpy as np
import pytest

from relloc.models.motion import VelocityNoise
from relloc.models.planar_measurement import empty_rows
from relloc.models.unicycle import unicycle_step
from relloc.observability.pcrlb import relative_pair_pcrlb, unicycle_team_pcrlb
from relloc.observability.rank import numeric_rank, rank_from_singular_values
from relloc.observability.rpmg import SensorSettings, build_rpmg


def test_rank_counts_singular_values_strictly_above_the_threshold() -> None:
    assert rank_from_singular_values(np.array([2.0, 1.0]), rtol=0.5) == 1
    assert rank_from_singular_values(np.array([2.0, 1.0 + 1e-12]), rtol=0.5) == 2
    assert rank_from_singular_values(np.zeros(3)) == 0


def test_default_rank_tolerance_sits_between_1e_10_and_1e_7() -> None:
    # rows (1, 0) and (1, ε) (already unit length up to O(ε²)): σ₂/σ₁ ≈ ε/2
    assert numeric_rank(np.array([[1.0, 0.0], [1.0, 1e-7]])) == 2  # ratio 5e-8
    assert numeric_rank(np.array([[1.0, 0.0], [1.0, 1e-10]])) == 1  # ratio 5e-11


def test_rpmg_edges_include_the_range_and_field_of_view_limits() -> None:
    poses = np.array([[0.0, 0.0, 0.0], [5.0, 0.0, 0.0], [0.0, 3.0, np.pi]])
    G = build_rpmg(poses, np.zeros((0, 2)), SensorSettings(sensing_range=5.0, fov=np.pi))
    # robot 0 sees robot 1 at exactly the sensing range (bearing 0) and robot 2 at exactly the
    # edge of its field of view (bearing +π/2 = fov/2)
    assert G.has_edge(0, 1)
    assert G.has_edge(0, 2)
    assert G.edges[0, 2]["bearing"] == pytest.approx(np.pi / 2)
    # robot 1 (heading +x) has robot 0 behind it: outside a π field of view
    assert not G.has_edge(1, 0)
    # just beyond the range: no edge
    far = build_rpmg(poses, np.zeros((0, 2)), SensorSettings(sensing_range=5.0 - 1e-9, fov=np.pi))
    assert not far.has_edge(0, 1)


def _fd_jacobians(pose: np.ndarray, u: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    eps = 1e-6
    F = np.empty((3, 3))
    G = np.empty((3, 2))
    for j in range(3):
        d = np.zeros(3)
        d[j] = eps
        F[:, j] = (unicycle_step(pose + d, u, dt) - unicycle_step(pose - d, u, dt)) / (2 * eps)
    for j in range(2):
        d = np.zeros(2)
        d[j] = eps
        G[:, j] = (unicycle_step(pose, u + d, dt) - unicycle_step(pose, u - d, dt)) / (2 * eps)
    return F, G


def test_team_pcrlb_without_measurements_propagates_the_prior() -> None:
    # two robots, no measurements: B_{k+1} = F_k B_k F_kᵀ + G_k diag(σ_v², σ_ω²) G_kᵀ per robot
    rng = np.random.default_rng(8)
    T, n = 3, 2
    poses = rng.normal(size=(T, n, 3))
    u = np.array([[[0.9, 0.7], [1.4, -0.5]]] * T)
    steps = [0.1, 0.45]
    sigma = np.array([[0.2, 0.05], [0.08, 0.3]])
    P0 = np.diag([0.3, 0.2, 0.1, 0.25, 0.15, 0.05])
    B = unicycle_team_pcrlb(poses, u, steps, [empty_rows()] * T, input_sigma=sigma, P0=P0)
    expected = P0.copy()
    np.testing.assert_allclose(B[0], expected, atol=1e-12)
    for k, dt in enumerate(steps):
        nxt = np.zeros((6, 6))
        for i in range(n):
            F, G = _fd_jacobians(poses[k, i], u[k, i], dt)
            blk = slice(3 * i, 3 * i + 3)
            nxt[blk, blk] = F @ expected[blk, blk] @ F.T + G @ np.diag(sigma[i] ** 2) @ G.T
        expected = nxt
        np.testing.assert_allclose(B[k + 1], expected, rtol=1e-6, atol=1e-10)


def test_relative_pcrlb_accepts_a_zero_length_step() -> None:
    # dt = 0: no motion and no process noise, the bound stays at the prior
    X = np.tile([2.0, 1.0, 0.5, 0.3], (3, 1))
    u = np.tile([0.4, -0.2, 0.1, 0.3], (3, 1))
    noise = VelocityNoise(observer=(0.1,) * 4, observed=(0.2,) * 4)
    P0 = np.diag([0.5, 0.4, 0.3, 0.2])
    B = relative_pair_pcrlb(
        X,
        u,
        u,
        [0.0, 0.1],
        np.zeros(3, dtype=bool),
        sigma_r=0.1,
        sigma_theta=0.1,
        sigma_alpha=0.1,
        velocity_noise=noise,
        P0=P0,
    )
    np.testing.assert_allclose(B[1], P0, atol=1e-12)
    assert np.all(np.diag(B[2]) > np.diag(P0))
