"""PCRLB wrappers on relloc's numeric models: known closed-form answers and wiring checks."""

from __future__ import annotations

import numpy as np
import pytest

from relloc.errors import DataError
from relloc.models.measurement import range_bearing_jacobian
from relloc.models.motion import VelocityNoise
from relloc.models.planar_measurement import RowKind, ScalarRows, empty_rows
from relloc.observability.pcrlb import relative_pair_pcrlb, unicycle_team_pcrlb

SIG = {"sigma_r": 0.1, "sigma_theta": 0.05, "sigma_alpha": 0.04}


def test_static_pair_bound_is_batch_information_of_all_measurements() -> None:
    """No motion and no process noise: J_k = P0⁻¹ + (number of fixes so far)·HᵀR⁻¹H."""
    T = 12
    x = np.array([2.0, -1.0, 0.5, 0.3])
    states = np.tile(x, (T, 1))
    zeros = np.zeros((T, 4))
    mask = np.arange(T) % 3 == 0
    P0 = np.diag([4.0, 4.0, 1.0, 0.5])
    quiet = VelocityNoise(observer=(0.0,) * 4, observed=(0.0,) * 4)
    bound = relative_pair_pcrlb(states, zeros, zeros, 0.1, mask, velocity_noise=quiet, P0=P0, **SIG)
    H = range_bearing_jacobian(x)
    info = H.T @ np.diag(1 / np.array([0.1, 0.05, 0.04]) ** 2) @ H
    for k in range(T):
        expected = np.linalg.inv(np.linalg.inv(P0) + np.count_nonzero(mask[: k + 1]) * info)
        np.testing.assert_allclose(bound[k], expected, rtol=1e-9, atol=1e-14)


def _moving_pair(rng: np.random.Generator, T: int):
    from relloc.models.motion import relative_step

    u_l = np.column_stack([np.full(T, 0.3), np.zeros(T), np.zeros(T), np.full(T, 0.1)])
    u_c = np.column_stack([np.full(T, 0.5), np.full(T, 0.1), np.zeros(T), np.full(T, -0.2)])
    X = np.empty((T, 4))
    X[0] = [3.0, 1.0, 0.8, 0.2]
    for k in range(T - 1):
        X[k + 1] = relative_step(X[k], u_l[k], u_c[k], 0.1)
    return X, u_l, u_c


def test_pair_bound_grows_with_sensor_noise_and_averaging_matches_single() -> None:
    rng = np.random.default_rng(0)
    T = 40
    X, u_l, u_c = _moving_pair(rng, T)
    noise = VelocityNoise(observer=(0.05, 0.05, 0.02, 0.02), observed=(0.05, 0.05, 0.02, 0.02))
    mask = np.ones(T, dtype=bool)
    P0 = np.eye(4)
    fine = relative_pair_pcrlb(X, u_l, u_c, 0.1, mask, velocity_noise=noise, P0=P0, **SIG)
    coarse_sig = {k: 3 * v for k, v in SIG.items()}
    coarse = relative_pair_pcrlb(X, u_l, u_c, 0.1, mask, velocity_noise=noise, P0=P0, **coarse_sig)
    assert np.all(np.linalg.eigvalsh(coarse[-1] - fine[-1]) > -1e-12)
    stacked = relative_pair_pcrlb(
        np.stack([X, X]),
        np.stack([u_l, u_l]),
        np.stack([u_c, u_c]),
        0.1,
        mask,
        velocity_noise=noise,
        P0=P0,
        **SIG,
    )
    np.testing.assert_allclose(stacked, fine, rtol=1e-7)
    bearing_only = relative_pair_pcrlb(
        X,
        u_l,
        u_c,
        0.1,
        mask,
        velocity_noise=noise,
        P0=P0,
        measured=("azimuth", "elevation"),
        **SIG,
    )
    assert np.all(np.diag(bearing_only[-1]) >= np.diag(fine[-1]) - 1e-12)


def test_pair_bad_input_is_reported() -> None:
    X = np.zeros((5, 4))
    X[:, 0] = 1.0
    noise = VelocityNoise(observer=(0.1,) * 4, observed=(0.1,) * 4)
    with pytest.raises(DataError, match="measurement_mask"):
        relative_pair_pcrlb(
            X, X, X, 0.1, np.ones(4, bool), velocity_noise=noise, P0=np.eye(4), **SIG
        )
    with pytest.raises(DataError, match="measured"):
        relative_pair_pcrlb(
            X,
            X,
            X,
            0.1,
            np.ones(5, bool),
            velocity_noise=noise,
            P0=np.eye(4),
            measured=("heading",),
            **SIG,
        )
    X[2, 1] = np.nan
    with pytest.raises(DataError, match="NaN"):
        relative_pair_pcrlb(
            X, X, X, 0.1, np.ones(5, bool), velocity_noise=noise, P0=np.eye(4), **SIG
        )


def _gps_rows(n: int, robot: int, sigma: float) -> ScalarRows:
    kinds = [RowKind.POSE_X, RowKind.POSE_Y, RowKind.POSE_HEADING]
    return ScalarRows(
        kind=np.array(kinds, dtype=np.int64),
        observer=np.full(3, robot, dtype=np.int64),
        target=np.full(3, -1, dtype=np.int64),
        landmark_xy=np.zeros((3, 2)),
        z=np.zeros(3),
        sigma=np.full(3, sigma),
        group=np.zeros(3, dtype=np.int64),
    )


def test_team_bound_with_gps_on_a_static_robot_is_batch_information() -> None:
    T, n = 6, 2
    poses = np.tile(np.array([[0.0, 0.0, 0.1], [5.0, 1.0, -0.4]]), (T, 1, 1))
    u = np.zeros((T, n, 2))
    rows = [_gps_rows(n, 0, 0.5) for _ in range(T)]
    P0 = 9.0 * np.eye(3 * n)
    bound = unicycle_team_pcrlb(poses, u, 0.1, rows, input_sigma=[0.0, 0.0], P0=P0)
    for k in range(T):
        np.testing.assert_allclose(bound[k, :3, :3], np.eye(3) / (1 / 9 + (k + 1) / 0.25))
        np.testing.assert_allclose(bound[k, 3:, 3:], P0[3:, 3:])


def test_team_bearing_bound_reduces_uncertainty_and_rejects_bad_rows() -> None:
    T, n = 20, 2
    poses = np.zeros((T, n, 3))
    poses[:, 1, 0] = 10.0
    poses[:, 0, 0] = np.linspace(0, 2, T)
    u = np.zeros((T, n, 2))
    u[:, 0, 0] = 1.0
    bearing = ScalarRows(
        kind=np.array([RowKind.BEARING], dtype=np.int64),
        observer=np.array([0]),
        target=np.array([1]),
        landmark_xy=np.zeros((1, 2)),
        z=np.zeros(1),
        sigma=np.array([0.05]),
        group=np.zeros(1, dtype=np.int64),
    )
    P0 = np.eye(6)
    bound = unicycle_team_pcrlb(poses, u, 0.1, [bearing] * T, input_sigma=[0.05, 0.02], P0=P0)
    blind = unicycle_team_pcrlb(poses, u, 0.1, [empty_rows()] * T, input_sigma=[0.05, 0.02], P0=P0)
    gain = np.linalg.eigvalsh(blind[-1] - bound[-1])
    assert gain.min() > -1e-10  # measurements never increase the bound
    assert gain.max() > 0.1  # and the bearings do inform some direction
    with pytest.raises(DataError, match="one per step"):
        unicycle_team_pcrlb(poses, u, 0.1, [bearing], input_sigma=[0.05, 0.02], P0=P0)


def test_irregular_step_lengths_use_each_step() -> None:
    T = 30
    X, u_l, u_c = _moving_pair(np.random.default_rng(1), T)
    noise = VelocityNoise(observer=(0.05, 0.05, 0.02, 0.02), observed=(0.05, 0.05, 0.02, 0.02))
    mask = np.ones(T, dtype=bool)
    uniform = relative_pair_pcrlb(X, u_l, u_c, 0.1, mask, velocity_noise=noise, P0=np.eye(4), **SIG)
    steps = np.full(T - 1, 0.1)
    steps[-1] = 0.5
    irregular = relative_pair_pcrlb(
        X, u_l, u_c, steps, mask, velocity_noise=noise, P0=np.eye(4), **SIG
    )
    np.testing.assert_allclose(irregular[:-1], uniform[:-1], rtol=1e-12)
    assert np.trace(irregular[-1]) > np.trace(uniform[-1])  # a longer step adds more noise
