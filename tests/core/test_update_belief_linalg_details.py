"""Behaviour of the core Kalman update, beliefs and linear algebra that the other tests leave
free: each test asserts a documented or derived fact (an invariance, a tolerance stated in a
docstring, a hand-computed value)."""

import warnings

import numpy as np
import pytest

from relloc.core.gaussian import Gaussian, GaussianMixture
from relloc.core.kalman import kalman_update
from relloc.core.linalg import cholesky, condition_log10, symmetric_within
from relloc.errors import ModelError


def test_the_update_sees_only_the_symmetric_part_of_r():
    # a covariance's antisymmetric part carries no meaning: R and (R + Rᵀ)/2 give one update
    rng = np.random.default_rng(11)
    A = rng.normal(size=(3, 3))
    P = A @ A.T + np.eye(3)
    H = rng.normal(size=(2, 3))
    x, nu = rng.normal(size=3), rng.normal(size=2)
    R = np.array([[1.0, 0.6], [0.0, 1.0]])
    mean, cov, inn = kalman_update(x, P, nu, H, R)
    mean_s, cov_s, inn_s = kalman_update(x, P, nu, H, 0.5 * (R + R.T))
    np.testing.assert_allclose(mean, mean_s, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(cov, cov_s, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(inn.cov, inn_s.cov, rtol=1e-12, atol=1e-12)
    assert inn.nis == pytest.approx(inn_s.nis, rel=1e-12)


def test_a_gaussian_refuses_an_asymmetry_beyond_psd_tol_times_the_largest_variance():
    # PSD_TOL = 1e-6 and the largest variance is 1: |P_01 − P_10| = 1.5e-6 is refused, 0.5e-6
    # is rounding and symmetrised away
    with pytest.raises(ModelError, match="not symmetric"):
        Gaussian(np.zeros(2), np.array([[1.0, 0.0], [1.5e-6, 1.0]]))
    g = Gaussian(np.zeros(2), np.array([[1.0, 0.0], [0.5e-6, 1.0]]))
    assert g.cov[0, 1] == g.cov[1, 0] == pytest.approx(0.25e-6)


def test_a_mixture_judges_a_negative_variance_relative_to_its_largest_variance():
    # −1e-3 next to a variance of 1e4 is rounding (PSD_TOL · 1e4 = 1e-2) ...
    GaussianMixture(means=np.zeros((1, 2)), covs=np.diag([1e4, -1e-3])[None], weights=np.ones(1))
    # ... while −1e-9 next to 1e-4 is not (PSD_TOL · 1e-4 = 1e-10)
    with pytest.raises(ModelError, match="negative variance"):
        GaussianMixture(
            means=np.zeros((1, 2)), covs=np.diag([1e-4, -1e-9])[None], weights=np.ones(1)
        )


def test_every_rectangular_mixture_needs_a_positive_weight():
    covs = np.broadcast_to(np.eye(2), (2, 2, 2, 2))
    with pytest.raises(ModelError, match="weight > 0"):
        GaussianMixture(
            means=np.zeros((2, 2, 2)), covs=covs, weights=np.array([[1.0, 0.0], [0.0, 0.0]])
        )


def test_a_flat_mixture_of_total_weight_zero_keeps_its_zeros():
    mix = GaussianMixture(
        means=np.zeros((3, 2)),
        covs=np.broadcast_to(np.eye(2), (3, 2, 2)),
        weights=np.array([2.0, 0.0, 0.0]),
        groups=np.array([0, 1, 1]),
    )
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        w = mix.normalised_weights()
    np.testing.assert_array_equal(w, [1.0, 0.0, 0.0])


def test_symmetry_tolerance_scales_with_the_standard_deviations():
    # |P_ij − P_ji| ≤ rtol √(P_ii P_jj): with variances 1e4 the bound is 1e-9 · 1e4 = 1e-5
    big = np.array([[1e4, 1.0], [1.0 + 1e-4, 1e4]])
    assert not symmetric_within(big)
    assert symmetric_within(np.array([[1e4, 1.0], [1.0 + 1e-6, 1e4]]))
    # with variances 1e-4 the bound is 1e-13
    small = np.array([[1e-4, 0.0], [1e-14, 1e-4]])
    assert symmetric_within(small)
    assert not symmetric_within(np.array([[1e-4, 0.0], [1e-12, 1e-4]]))


def test_cholesky_factors_the_symmetrised_matrix_unless_told_it_is_symmetric():
    P = np.array([[4.0, 2.0], [0.0, 3.0]])  # symmetric part [[4, 1], [1, 3]]
    L = cholesky(P)
    np.testing.assert_allclose(L @ L.T, [[4.0, 1.0], [1.0, 3.0]], rtol=1e-14)
    assert L[1, 0] == pytest.approx(0.5)  # 1 / √4


def test_condition_of_a_singular_matrix_is_infinite_without_a_warning():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert condition_log10(np.zeros((2, 2))) == np.inf
        assert condition_log10(np.diag([1.0, 0.0])) == np.inf
