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


def test_wrap_angle_stays_below_pi_where_the_modulo_rounds_up():
    """Just below −π, ``a + π`` is a tiny negative number whose modulo 2π rounds to 2π: the
    result must still be the same angle inside [-π, π), i.e. −π."""
    just_below = np.nextafter(-np.pi, -4.0)
    assert wrap_angle(just_below) == -np.pi
    w = wrap_angle(np.array([just_below, -np.pi, np.pi, 3.0 * np.pi]))
    assert np.all(w >= -np.pi) and np.all(w < np.pi)
    assert np.isnan(wrap_angle(np.nan))


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


def test_a_failed_factorisation_says_why():
    """The message gives the condition number exactly where every eigenvalue is positive, i.e.
    where only double precision keeps the factorisation from succeeding. Random 4×4 covariances
    with eigenvalues (1, 1e-3, two in 1e-19…1e-15); on the development machine's numpy both
    kinds of failure occur among them (before, every message said only "not positive
    definite")."""
    rng = np.random.default_rng(0)
    for _ in range(500):
        V, _ = np.linalg.qr(rng.normal(size=(4, 4)))
        d = np.array([1.0, 1e-3, *10 ** rng.uniform(-19, -15, size=2)])
        M = V @ np.diag(d) @ V.T
        M = (M + M.T) / 2
        try:
            np.linalg.cholesky(M)
        except np.linalg.LinAlgError:
            with pytest.raises(ModelError, match="not positive definite") as err:
                mahalanobis_sq(np.ones(4), M, where="pair 1-2")
            assert ("condition number" in str(err.value)) == bool(np.all(np.linalg.eigvalsh(M) > 0))


def test_mixture_layouts_weights_and_validation():
    """Rectangular batch ``(B, K)`` and flat components with ``groups``: same normalised weights;
    the heaviest component of each mixture; bad shapes or weights are ModelErrors."""
    means = np.arange(12.0).reshape(2, 3, 2)
    covs = np.broadcast_to(np.eye(2), (2, 3, 2, 2))
    weights = np.array([[1.0, 3.0, 0.0], [2.0, 2.0, 4.0]])
    batch = GaussianMixture(means=means, covs=covs, weights=weights)
    np.testing.assert_allclose(batch.normalised_weights(), [[0.25, 0.75, 0.0], [0.25, 0.25, 0.5]])
    np.testing.assert_array_equal(batch.alive, weights > 0)
    np.testing.assert_array_equal(batch.heaviest_index, [1, 2])
    mean, cov = batch.heaviest()
    np.testing.assert_array_equal(mean, [means[0, 1], means[1, 2]])
    np.testing.assert_array_equal(cov, np.broadcast_to(np.eye(2), (2, 2, 2)))
    flat = GaussianMixture(
        means=means.reshape(6, 2),
        covs=covs.reshape(6, 2, 2),
        weights=weights.reshape(6),
        groups=np.repeat([0, 1], 3),
    )
    assert flat.size == batch.size == 6
    np.testing.assert_allclose(flat.normalised_weights(), batch.normalised_weights().reshape(6))
    with pytest.raises(ModelError, match="rectangular"):
        _ = flat.heaviest_index
    with pytest.raises(ModelError, match="shapes"):
        GaussianMixture(means=np.zeros((2, 1)), covs=np.ones((2, 1, 1)), weights=np.ones(3))
    with pytest.raises(ModelError, match="≥ 0"):
        GaussianMixture(means=np.zeros((2, 1)), covs=np.ones((2, 1, 1)), weights=np.array([-1, 2]))
    with pytest.raises(ModelError, match="weight > 0"):
        GaussianMixture(means=np.zeros((2, 1)), covs=np.ones((2, 1, 1)), weights=np.zeros(2))
    with pytest.raises(ModelError, match="groups"):
        GaussianMixture(
            means=np.zeros((2, 1)), covs=np.ones((2, 1, 1)), weights=np.ones(2), groups=np.zeros(3)
        )
    with pytest.raises(ModelError, match="non-finite"):
        Gaussian(mean=np.array([np.nan]), cov=np.eye(1))


def test_a_bad_covariance_in_a_stack_is_named_alone():
    """Before: the message printed the eigenvalues of every covariance of the stack."""
    from relloc.core.linalg import cholesky

    P = np.tile(np.eye(3), (2, 500, 1, 1))
    P[1, 17, 1, 1] = -1.0
    with pytest.raises(ModelError) as err:
        cholesky(P, where="NEES")
    assert str(err.value) == (
        "covariance is not positive definite at NEES (matrix (1, 17) of a stack (2, 500)); "
        "eigenvalues: [-1.  1.  1.]"
    )
    P[0, 3, 2, 2] = np.nan
    with pytest.raises(ModelError, match=r"not finite at NEES \(matrix \(0, 3\) of a stack"):
        cholesky(P, where="NEES")
