"""The hand-unrolled kernels equal the general matrix composition of the models.

General version: ``relative_step`` + ``F P Fᵀ + G Σ Gᵀ`` for the predict, and the one Kalman
update :func:`relloc.core.kalman.kalman_update` (Joseph form) with the models' ``h``/``H``/``R``
for the updates — on the batched (array) path, the single-pair (float) path and the stateful
tracker.
"""

import numpy as np
import pytest

from relloc.core.angles import wrap_angle
from relloc.core.gaussian import Gaussian
from relloc.core.kalman import kalman_update
from relloc.errors import ModelError
from relloc.estimators.relative import (
    FilterSettings,
    RelativeTracker,
    predict_arrays,
    update_bcplkf_arrays,
    update_plkf_arrays,
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


def _assert_update_equal(got, ref, *, exact_residual: bool = True) -> None:  # type: ignore[no-untyped-def]
    """Kernel result ``(mean, cov, innovation)`` equals the core update's to rounding."""
    for a, b in zip(got[:2], ref[:2], strict=True):
        np.testing.assert_allclose(a, b, atol=1e-12)
    np.testing.assert_allclose(got[2].nis, ref[2].nis, rtol=1e-10)
    np.testing.assert_allclose(got[2].cov, ref[2].cov, atol=1e-12)
    np.testing.assert_allclose(got[2].meas_cov, ref[2].meas_cov, atol=1e-14)
    np.testing.assert_allclose(got[2].residual, ref[2].residual, atol=1e-14)


def _tekf_reference(m, P, z):  # type: ignore[no-untyped-def]
    residual = z - range_bearing(m)
    residual[..., 1:] = wrap_angle(residual[..., 1:])
    R = np.broadcast_to(NOISY.covariance, (*m.shape[:-1], 3, 3))
    return kalman_update(m, P, residual, range_bearing_jacobian(m), R)


def _plkf_reference(m, P, z, kind: str):  # type: ignore[no-untyped-def]
    H = pseudo_linear_matrix(z)
    residual = pseudo_linear_measurement(z) - np.einsum("...ij,...j->...i", H, m)
    R = pseudo_linear_covariance(m, z, NOISY, kind)  # type: ignore[arg-type]
    return kalman_update(m, P, residual, H, R)


@pytest.mark.parametrize("seed", [1, 11, 21])
def test_tekf_kernel_equals_the_core_update(seed: int) -> None:
    m, P, _, _, z = _case(seed)
    ref = _tekf_reference(m, P, z)
    _assert_update_equal(update_tekf_arrays(m, P, z, NOISY), ref)
    for i in range(len(m)):  # the float (single-pair) path of the same kernel
        one = update_tekf_arrays(m[i], P[i], z[i], NOISY)
        _assert_update_equal(one, _tekf_reference(m[i], P[i], z[i]))
        assert isinstance(one[2].nis, float)


@pytest.mark.parametrize("kind", ["simplified", "full"])
@pytest.mark.parametrize("seed", [2, 12])
def test_plkf_kernel_equals_the_core_update(kind: str, seed: int) -> None:
    m, P, _, _, z = _case(seed)
    ref = _plkf_reference(m, P, z, kind)
    _assert_update_equal(update_plkf_arrays(m, P, z, NOISY, covariance=kind), ref)  # type: ignore[arg-type]
    for i in range(len(m)):
        one = update_plkf_arrays(m[i], P[i], z[i], NOISY, covariance=kind)  # type: ignore[arg-type]
        _assert_update_equal(one, _plkf_reference(m[i], P[i], z[i], kind))


@pytest.mark.parametrize("kind", ["plkf", "tekf"])
def test_tracker_kernel_equals_the_core_update(kind: str) -> None:
    """:class:`RelativeTracker` runs the float kernels on its own state; same update."""
    m, P, _, _, z = _case(5)
    settings = FilterSettings(kind=kind, motion_noise=MOTION, sensor_noise=NOISY)  # type: ignore[arg-type]
    for i in range(len(m)):
        tracker = RelativeTracker(Gaussian(mean=m[i], cov=P[i]), settings)
        inn = tracker.update(z[i])
        if kind == "tekf":
            ref = _tekf_reference(m[i], P[i], z[i])
        else:
            ref = _plkf_reference(m[i], P[i], z[i], "simplified")
        _assert_update_equal((tracker.belief.mean, tracker.belief.cov, inn), ref)


def test_kernel_refuses_where_the_core_update_does() -> None:
    """A non-positive-definite ``S`` is a ModelError naming the place on both paths (the kernel
    checks Sylvester's criterion, the core update the Cholesky factorisation)."""
    m, P, _, _, z = _case(4, n=1)
    H = pseudo_linear_matrix(z)
    R = pseudo_linear_covariance(m, z, NOISY)
    with pytest.raises(ModelError, match="not positive definite at pair 4"):
        kalman_update(m, -P, np.zeros((1, 3)), H, R, where="pair 4")
    with pytest.raises(ModelError, match="not positive definite at pair 4"):
        update_plkf_arrays(m, -P, z, NOISY, where="pair 4")


def test_bias_compensation_equals_cubature_of_the_gain_times_noise() -> None:
    """``b̂ = 1/6 Σ_j K_j ν_j`` at ``ẑ ± √3 σ_i e_i`` written with the general models."""
    m, P, _, _, z = _case(3)
    plain_mean, plain_cov, _ = update_plkf_arrays(m, P, z, NOISY)
    bc_mean, bc_cov, _ = update_bcplkf_arrays(m, P, z, NOISY)
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
