"""PSD-safe linear algebra and the belief containers."""

import numpy as np
import pytest

from relloc.core import (
    Gaussian,
    GaussianMixture,
    condition_log10,
    mahalanobis_sq,
    wrap_angle,
)
from relloc.errors import ModelError


def test_wrap_angle_range_and_scalars():
    a = np.linspace(-20, 20, 1001)
    w = wrap_angle(a)
    assert np.all(w >= -np.pi) and np.all(w < np.pi)
    assert np.allclose(np.sin(w), np.sin(a)) and np.allclose(np.cos(w), np.cos(a))
    assert isinstance(wrap_angle(3 * np.pi), float)


def test_information_round_trip_and_mahalanobis():
    g = Gaussian(mean=np.array([1.0, -2.0]), cov=np.array([[2.0, 0.3], [0.3, 1.0]]))
    back = g.to_information().to_gaussian()
    assert np.allclose(back.mean, g.mean) and np.allclose(back.cov, g.cov)
    nu = np.array([0.5, 0.1])
    assert np.isclose(mahalanobis_sq(nu, g.cov), nu @ np.linalg.solve(g.cov, nu))


def test_not_positive_definite_is_model_error():
    with pytest.raises(ModelError, match="pair 1-2"):
        mahalanobis_sq(np.ones(2), -np.eye(2), where="pair 1-2")
    assert condition_log10(np.diag([1.0, 100.0])) == pytest.approx(2.0)


def test_mixture_moments_and_validation():
    mix = GaussianMixture(
        means=np.array([[0.0], [2.0]]), covs=np.array([[[1.0]], [[1.0]]]), weights=np.array([1, 1])
    )
    m = mix.moments()
    assert np.isclose(m.mean[0], 1.0) and np.isclose(m.cov[0, 0], 2.0)
    with pytest.raises(ModelError):
        GaussianMixture(means=np.zeros((2, 1)), covs=np.ones((2, 1, 1)), weights=np.array([-1, 2]))
    with pytest.raises(ModelError, match="non-finite"):
        Gaussian(mean=np.array([np.nan]), cov=np.eye(1))
