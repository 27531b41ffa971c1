"""The hand-unrolled kernels equal the general matrix composition of the models.

General version: ``relative_step`` + ``F P Fᵀ + G Σ Gᵀ`` for the predict, and
:func:`kalman_update` (Joseph form) with the models' ``h``/``H``/``R`` for the updates.
"""

import numpy as np
import pytest

from relloc.core.angles import wrap_angle
from relloc.estimators.relative import (
    kalman_update,
    predict_arrays,
    update_plkf_arrays,
    update_plkf_bc_arrays,
    update_tekf_arrays,
)
from relloc.models.measurement import (
    RangeBearingNoise,
    pseudo_linear_covariance,
    pseudo_linear_matrix,
    pseudo_linear_measurement,
    range_bearing,
    range_bearing_jacobian,
)
from relloc.models.motion import VelocityNoise, process_noise, relative_jacobians, relative_step

MOTION = VelocityNoise(observer=(0.05, 0.04, 0.01, 0.02), observed=(0.06, 0.05, 0.02, 0.03))
NOISY = RangeBearingNoise(sigma_r=0.1466, sigma_azimuth=0.1, sigma_elevation=0.1)


def _case(seed: int = 0, n: int = 6):  # type: ignore[no-untyped-def]
    rng = np.random.default_rng(seed)
    m = rng.normal(size=(n, 4)) * [2, 2, 1, 1] + [3, 0, 1, 0]
    A = rng.normal(size=(n, 4, 4)) * 0.2
    P = A @ np.swapaxes(A, -1, -2) + 0.01 * np.eye(4)
    u_l, u_c = rng.normal(size=(n, 4)), rng.normal(size=(n, 4))
    u_l[0, 3] = 0.0
    z = range_bearing(m + rng.normal(size=(n, 4)) * 0.2)
    return m, P, u_l, u_c, z


@pytest.mark.parametrize("batched", [True, False])
def test_predict_kernel_equals_matrix_form(batched: bool) -> None:
    m, P, u_l, u_c, _ = _case()
    F, G = relative_jacobians(m, u_l, u_c, 0.1)
    ref_mean = relative_step(m, u_l, u_c, 0.1)
    ref_cov = F @ P @ np.swapaxes(F, -1, -2) + process_noise(G, MOTION)
    if batched:
        mean, cov = predict_arrays(m, P, u_l, u_c, 0.1, MOTION)
    else:
        pairs = [predict_arrays(m[i], P[i], u_l[i], u_c[i], 0.1, MOTION) for i in range(len(m))]
        mean, cov = np.array([p[0] for p in pairs]), np.array([p[1] for p in pairs])
    np.testing.assert_allclose(mean, ref_mean, atol=1e-14)
    np.testing.assert_allclose(cov, ref_cov, atol=1e-14)


def test_tekf_kernel_equals_matrix_form() -> None:
    m, P, _, _, z = _case(1)
    residual = z - range_bearing(m)
    residual[..., 1:] = wrap_angle(residual[..., 1:])
    R = np.broadcast_to(NOISY.covariance, (len(m), 3, 3))
    ref = kalman_update(m, P, residual, range_bearing_jacobian(m), R)
    got = update_tekf_arrays(m, P, z, NOISY)
    for a, b in zip(got[:2], ref[:2], strict=True):
        np.testing.assert_allclose(a, b, atol=1e-12)
    np.testing.assert_allclose(got[2].nis, ref[2].nis, rtol=1e-10)
    np.testing.assert_allclose(got[2].cov, ref[2].cov, atol=1e-12)
    np.testing.assert_allclose(got[2].meas_cov, R)


@pytest.mark.parametrize("kind", ["simplified", "full"])
def test_plkf_kernel_equals_matrix_form(kind: str) -> None:
    m, P, _, _, z = _case(2)
    H = pseudo_linear_matrix(z)
    residual = pseudo_linear_measurement(z) - np.einsum("bij,bj->bi", H, m)
    R = pseudo_linear_covariance(m, z, NOISY, kind)  # type: ignore[arg-type]
    ref = kalman_update(m, P, residual, H, R)
    got = update_plkf_arrays(m, P, z, NOISY, covariance=kind)  # type: ignore[arg-type]
    for a, b in zip(got[:2], ref[:2], strict=True):
        np.testing.assert_allclose(a, b, atol=1e-12)
    np.testing.assert_allclose(got[2].residual, residual, atol=1e-14)
    np.testing.assert_allclose(got[2].meas_cov, R, atol=1e-14)
    np.testing.assert_allclose(got[2].nis, ref[2].nis, rtol=1e-10)


def test_bias_compensation_equals_cubature_of_the_gain_times_noise() -> None:
    """``b̂ = 1/6 Σ_j K_j ν_j`` at ``ẑ ± √3 σ_i e_i`` written with the general models."""
    m, P, _, _, z = _case(3)
    plain_mean, plain_cov, _ = update_plkf_arrays(m, P, z, NOISY)
    bc_mean, bc_cov, _ = update_plkf_bc_arrays(m, P, z, NOISY)
    z_hat = range_bearing(plain_mean)
    bias = np.zeros_like(m)
    for i in range(3):
        for sign in (1.0, -1.0):
            zj = z_hat.copy()
            zj[:, i] += sign * np.sqrt(3.0 * NOISY.variances[i])
            H = pseudo_linear_matrix(zj)
            S = H @ P @ np.swapaxes(H, -1, -2) + pseudo_linear_covariance(m, zj, NOISY)
            K = P @ np.swapaxes(H, -1, -2) @ np.linalg.inv(S)
            nu = pseudo_linear_measurement(zj) - np.einsum("bij,bj->bi", H, plain_mean)
            bias += np.einsum("bij,bj->bi", K, nu) / 6.0
    np.testing.assert_allclose(bc_mean, plain_mean - bias, atol=1e-12)
    np.testing.assert_allclose(bc_cov, plain_cov)
    assert np.abs(bias).max() > 1e-4  # the compensation is not trivially zero here
