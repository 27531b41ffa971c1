"""Range/azimuth/elevation model, its Jacobian, and the pseudo-linear form (seed 000 Eqs. 2–6)."""

import numpy as np
import pytest

from relloc.errors import ConfigError
from relloc.models.measurement import (
    RangeBearingNoise,
    pseudo_linear_covariance,
    pseudo_linear_matrix,
    pseudo_linear_measurement,
    pseudo_linear_noise_jacobian,
    range_bearing,
    range_bearing_jacobian,
)

NOISE = RangeBearingNoise(sigma_r=0.1466, sigma_azimuth=0.1, sigma_elevation=0.08)


def _states(seed: int = 4, n: int = 6) -> np.ndarray:
    x = np.random.default_rng(seed).normal(size=(n, 4)) * [3.0, 3.0, 1.5, 1.0]
    x[:, 0] += 0.5
    return x


def test_range_bearing_values() -> None:
    z = range_bearing(np.array([3.0, 4.0, 12.0, 0.7]))
    np.testing.assert_allclose(z, [13.0, np.arctan2(4, 3), np.arctan2(12, 5)])


def test_jacobian_matches_central_differences() -> None:
    x = _states()
    H = range_bearing_jacobian(x)
    eps = 1e-6
    for i in range(4):
        d = np.zeros(4)
        d[i] = eps
        num = (range_bearing(x + d) - range_bearing(x - d)) / (2 * eps)
        np.testing.assert_allclose(H[..., i], num, atol=1e-8)


def test_pseudo_linear_form_is_exact_for_true_bearings() -> None:
    x = _states()
    z = range_bearing(x)
    H = pseudo_linear_matrix(z)
    np.testing.assert_allclose(
        np.einsum("bij,bj->bi", H, x), pseudo_linear_measurement(z), atol=1e-12
    )
    # rows are the orthonormal bearing frame (u_r, u_θ, u_α); φ does not enter
    np.testing.assert_allclose(
        H[..., :3] @ np.swapaxes(H[..., :3], -1, -2), np.tile(np.eye(3), (6, 1, 1)), atol=1e-12
    )
    np.testing.assert_array_equal(H[..., 3], 0.0)


def test_noise_jacobian_matches_central_differences() -> None:
    x = _states(7)
    z = range_bearing(x) + np.random.default_rng(1).normal(size=(6, 3)) * 0.1

    def nu(zz: np.ndarray) -> np.ndarray:
        return pseudo_linear_measurement(zz) - np.einsum("bij,bj->bi", pseudo_linear_matrix(zz), x)

    J = pseudo_linear_noise_jacobian(x, z)
    eps = 1e-6
    for i in range(3):
        d = np.zeros(3)
        d[i] = eps
        np.testing.assert_allclose(J[..., i], (nu(z + d) - nu(z - d)) / (2 * eps), atol=1e-8)


def test_full_covariance_reduces_to_eq6_at_the_true_position() -> None:
    x = _states(9)
    z = range_bearing(x)
    full = pseudo_linear_covariance(x, z, NOISE, "full")
    simplified = pseudo_linear_covariance(x, z, NOISE, "simplified")
    np.testing.assert_allclose(full, simplified, atol=1e-12)
    rho2 = x[:, 0] ** 2 + x[:, 1] ** 2
    np.testing.assert_allclose(simplified[:, 1, 1], rho2 * 0.1**2)
    np.testing.assert_allclose(simplified[:, 2, 2], (rho2 + x[:, 2] ** 2) * 0.08**2)
    # away from the truth the full form is a proper covariance but differs from Eq. 6
    z_noisy = z + 0.2
    full_noisy = pseudo_linear_covariance(x, z_noisy, NOISE, "full")
    assert np.all(np.linalg.eigvalsh(full_noisy) > 0)
    assert not np.allclose(full_noisy, simplified)


def test_bad_settings_are_named() -> None:
    with pytest.raises(ConfigError, match="sigma_azimuth"):
        RangeBearingNoise(sigma_r=0.1, sigma_azimuth=0.0, sigma_elevation=0.1)
    with pytest.raises(ConfigError, match="kind"):
        pseudo_linear_covariance(np.ones(4), np.ones(3), NOISE, "diagonal")  # type: ignore[arg-type]
