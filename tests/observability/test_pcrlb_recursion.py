"""PCRLB: equals the Kalman covariance on linear-Gaussian models; the two forms agree."""

from __future__ import annotations

import numpy as np
import pytest

from relloc.errors import DataError, ModelError
from relloc.observability.pcrlb_recursion import (
    measurement_information,
    pcrlb_covariance,
    pcrlb_information,
    pcrlb_ratio,
)


def _linear_model(rng: np.random.Generator, T: int = 30):
    n = 3
    dt = 0.1
    F = np.array([[1.0, dt, 0.5 * dt * dt], [0.0, 1.0, dt], [0.0, 0.0, 1.0]])
    A = rng.normal(size=(n, n))
    Q = 0.01 * A @ A.T + 1e-3 * np.eye(n)
    H = np.array([[1.0, 0.0, 0.0]])
    R = np.array([[0.25]])
    P0 = np.diag([4.0, 1.0, 0.5])
    mask = rng.random(T) < 0.6
    return F, Q, H, R, P0, mask


def _kalman_covariances(F, Q, H, R, P0, mask):
    T = mask.size
    out = np.empty((T, F.shape[0], F.shape[0]))
    P = P0.copy()
    for k in range(T):
        if k > 0:
            P = F @ P @ F.T + Q
        if mask[k]:
            S = H @ P @ H.T + R
            K = P @ H.T @ np.linalg.inv(S)
            P = (np.eye(P.shape[0]) - K @ H) @ P
        out[k] = P
    return out


def _stacks(F, Q, H, R, mask):
    T = mask.size
    Fs = np.broadcast_to(F, (T - 1, *F.shape)).copy()
    Qs = np.broadcast_to(Q, (T - 1, *Q.shape)).copy()
    info = measurement_information(H, R)
    I = np.where(mask[:, None, None], info, 0.0)
    return Fs, Qs, I


def test_pcrlb_equals_kalman_covariance_on_linear_gaussian_model() -> None:
    rng = np.random.default_rng(7)
    F, Q, H, R, P0, mask = _linear_model(rng)
    Fs, Qs, I = _stacks(F, Q, H, R, mask)
    bound = pcrlb_covariance(pcrlb_information(Fs, Qs, I, np.linalg.inv(P0)))
    np.testing.assert_allclose(bound, _kalman_covariances(F, Q, H, R, P0, mask), rtol=1e-9)


def test_averaged_information_form_equals_riccati_form() -> None:
    rng = np.random.default_rng(11)
    F, Q, H, R, P0, mask = _linear_model(rng)
    Fs, Qs, I = _stacks(F, Q, H, R, mask)
    J0 = np.linalg.inv(P0)
    single = pcrlb_information(Fs, Qs, I, J0)
    M = 3
    averaged = pcrlb_information(np.stack([Fs] * M), np.stack([Qs] * M), np.stack([I] * M), J0)
    np.testing.assert_allclose(averaged, single, rtol=1e-8)


def test_singular_process_noise_single_trajectory_and_error_when_averaged() -> None:
    rng = np.random.default_rng(3)
    F, _, H, R, P0, mask = _linear_model(rng, T=10)
    G = np.array([[0.0], [0.0], [0.1]])
    Q = G @ G.T  # rank one
    Fs, Qs, I = _stacks(F, Q, H, R, mask)
    bound = pcrlb_covariance(pcrlb_information(Fs, Qs, I, np.linalg.inv(P0)))
    np.testing.assert_allclose(bound, _kalman_covariances(F, Q, H, R, P0, mask), rtol=1e-9)
    with pytest.raises(ModelError, match="trajectory 0 at step 0"):
        pcrlb_information(np.stack([Fs] * 2), np.stack([Qs] * 2), np.stack([I] * 2), P0)


def test_averaging_over_trajectories_matches_mean_of_terms() -> None:
    """With two different Jacobians the D-terms are means (Tichavský Eq. 21), checked by hand."""
    F1, F2 = np.array([[1.0, 0.2], [0.0, 1.0]]), np.array([[1.0, -0.3], [0.1, 0.9]])
    Q = np.diag([0.1, 0.2])
    Qi = np.linalg.inv(Q)
    J0 = np.diag([2.0, 3.0])
    I = np.zeros((2, 2, 2, 2))
    I[:, 1] = np.diag([1.0, 0.0])
    J = pcrlb_information(np.stack([F1, F2])[:, None], np.stack([Q, Q])[:, None], I, J0)
    D11 = 0.5 * (F1.T @ Qi @ F1 + F2.T @ Qi @ F2)
    D12 = -0.5 * (F1.T + F2.T) @ Qi
    expected = Qi + np.diag([1.0, 0.0]) - D12.T @ np.linalg.inv(J0 + D11) @ D12
    np.testing.assert_allclose(J[1], expected, rtol=1e-12)


def test_ratio_is_one_for_errors_drawn_from_the_bound() -> None:
    rng = np.random.default_rng(5)
    T, n, runs = 20, 2, 4000
    B = np.broadcast_to(np.diag([0.5, 2.0]), (T, n, n)).copy()
    errors = rng.normal(size=(runs, T, n)) * np.sqrt(np.array([0.5, 2.0]))
    ratio = pcrlb_ratio(errors, B)
    # pooled over T·runs = 80 000 samples: the ratio's std is about 1/sqrt(2·80000) ≈ 0.0025
    np.testing.assert_allclose(ratio, 1.0, atol=0.02)


def test_bad_shapes_and_nan_are_reported() -> None:
    F = np.broadcast_to(np.eye(2), (4, 2, 2))
    with pytest.raises(DataError, match="meas_info"):
        pcrlb_information(F, F, np.zeros((4, 2, 2)), np.eye(2))
    bad = np.zeros((5, 2, 2))
    bad[2, 0, 0] = np.nan
    with pytest.raises(DataError, match="NaN"):
        pcrlb_information(F, F, bad, np.eye(2))
    with pytest.raises(DataError, match="do not match"):
        pcrlb_ratio(np.zeros((3, 5, 2)), np.zeros((4, 2, 2)))
