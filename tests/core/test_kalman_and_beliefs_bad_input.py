"""Bad input to the Kalman update, the Cholesky factor and the belief containers: a ModelError
naming where, never a raw numpy error or a silently wrong (broadcast, NaN) result."""

from __future__ import annotations

import numpy as np
import pytest

from relloc.core.gaussian import PSD_TOL, Gaussian, GaussianMixture, InformationState
from relloc.core.kalman import gated_update, kalman_update
from relloc.core.linalg import cholesky
from relloc.errors import ConfigError, ModelError

NAN = float("nan")


def _block():  # type: ignore[no-untyped-def]
    """A 2-state prior and a 1-D measurement of its first state."""
    return np.zeros(2), np.eye(2), np.array([1.0]), np.array([[1.0, 0.0]]), np.eye(1)


@pytest.mark.parametrize("update", ["kalman", "gated"])
@pytest.mark.parametrize(
    "bad",
    [
        {"residual": np.array([1.0, 5.0])},  # was broadcast: mean [3, 0], NIS 18
        {"H": np.array([[1.0, 0.0, 0.0]])},  # was a raw matmul ValueError
        {"R": np.eye(2)},
        {"cov": np.eye(3)},
        {"mean": np.zeros(3)},
    ],
)
def test_shapes_that_do_not_fit_are_a_model_error_naming_the_place(update, bad) -> None:
    x, P, nu, H, R = _block()
    args = {"mean": x, "cov": P, "residual": nu, "H": H, "R": R, **bad}
    with pytest.raises(ModelError, match="at pair 3: shapes"):
        if update == "kalman":
            kalman_update(**args, where="pair 3")
        else:
            gated_update(**args, probability=0.99, where="pair 3")


def test_batches_that_do_not_broadcast_are_refused_and_those_that_do_are_updated() -> None:
    _, P, _, H, R = _block()
    with pytest.raises(ModelError, match="at bank: shapes"):
        kalman_update(np.zeros((3, 2)), P, np.zeros((4, 1)), H, R, where="bank")
    # one H, R and P shared by three priors and residuals: three ordinary updates
    means, residuals = np.arange(6.0).reshape(3, 2), np.array([[1.0], [-2.0], [0.5]])
    mean, cov, inn = kalman_update(means, P, residuals, H, R, where="bank")
    cov = np.broadcast_to(cov, (3, 2, 2))  # (one, shared, when P, H and R are)
    for k in range(3):
        one = kalman_update(means[k], P, residuals[k], H, R)
        np.testing.assert_allclose(mean[k], one[0], rtol=1e-14)
        np.testing.assert_allclose(cov[k], one[1], rtol=1e-14)
        assert inn.nis[k] == pytest.approx(float(one[2].nis), rel=1e-14)  # type: ignore[index]


def test_a_nan_residual_is_not_accepted_by_the_gate() -> None:
    x, P, _, H, R = _block()
    with pytest.raises(ModelError, match="at range team: non-finite NIS"):
        gated_update(x, P, np.array([NAN]), H, R, 0.99, where="range team")
    with pytest.raises(ModelError, match="non-finite NIS"):
        gated_update(x, P, np.array([NAN]), H, R, None, where="range team")


@pytest.mark.parametrize(
    "bad",
    [
        {"residual": np.array([NAN])},
        {"cov": np.array([[1.0, 0.0], [0.0, NAN]])},  # a state the measurement does not see
        {"cov": np.full((2, 2), NAN)},
        {"R": np.array([[NAN]])},
        {"R": np.array([[np.inf]])},  # S infinite, NIS 0: the covariance would come out NaN
        {"H": np.array([[NAN, 0.0]])},
    ],
)
def test_nan_or_infinity_in_an_update_is_a_model_error_naming_the_place(bad) -> None:
    x, P, nu, H, R = _block()
    args = {"mean": x, "cov": P, "residual": nu, "H": H, "R": R, **bad}
    with pytest.raises(ModelError, match="at pair 5"):
        kalman_update(**args, where="pair 5")
    batched = {k: np.stack([v, v]) for k, v in args.items()}
    with pytest.raises(ModelError, match="at pair 5"):
        kalman_update(**batched, where="pair 5")


@pytest.mark.parametrize(
    "P", [np.full((2, 2), NAN), np.array([[1.0, NAN], [NAN, 1.0]]), np.diag([np.inf, 1.0])]
)
def test_cholesky_of_a_non_finite_matrix_is_a_model_error(P) -> None:
    with pytest.raises(ModelError, match="not finite at X"):
        cholesky(P, where="X")
    with pytest.raises(ModelError, match="not finite at X"):
        cholesky(np.stack([np.eye(2), P]), where="X")


@pytest.mark.parametrize(
    ("cov", "match"),
    [
        (-np.eye(2), "positive semi-definite"),
        (np.diag([1.0, -1e-3]), "positive semi-definite"),
        (np.array([[1.0, 2.0], [2.0, 1.0]]), "positive semi-definite"),  # eigenvalue −1
        (np.array([[1.0, 5.0], [-5.0, 1.0]]), "not symmetric"),  # was symmetrised to I
        (np.array([[1.0, NAN], [NAN, 1.0]]), "non-finite"),
    ],
)
def test_a_gaussian_refuses_a_covariance_that_is_not_one(cov, match) -> None:
    with pytest.raises(ModelError, match=f"Gaussian: .*{match}"):
        Gaussian(mean=np.zeros(2), cov=cov)
    with pytest.raises(ModelError, match=f"InformationState: .*{match}"):
        InformationState(info_vector=np.zeros(2), info_matrix=cov)


def test_a_gaussian_keeps_rounding_and_semi_definite_covariances() -> None:
    # an asymmetry and a negative eigenvalue of rounding size are symmetrised / accepted
    tiny = 0.1 * PSD_TOL
    g = Gaussian(mean=np.zeros(2), cov=np.array([[4.0, 1.0 + tiny], [1.0, 2.0]]))
    np.testing.assert_array_equal(g.cov, g.cov.T)
    Gaussian(mean=np.zeros(2), cov=np.array([[1.0, 1.0 + tiny], [1.0 + tiny, 1.0]]))
    for psd in (np.ones((2, 2)), np.zeros((2, 2)), np.diag([1e-12, 1e6])):  # singular, scaled
        np.testing.assert_array_equal(Gaussian(mean=np.zeros(2), cov=psd).cov, psd)
    with pytest.raises(ModelError, match=r"InformationState: .*positive semi-definite"):
        InformationState.from_symmetric(np.zeros(2), -np.eye(2))


@pytest.mark.parametrize(
    ("means", "covs", "match"),
    [
        (np.array([[NAN, 0.0]]), np.eye(2)[None], "non-finite"),
        (np.zeros((1, 2)), np.full((1, 2, 2), np.inf), "non-finite"),
        (np.zeros((1, 2)), -np.eye(2)[None], "negative variance"),
        (np.zeros((2, 2)), np.stack([np.eye(2), np.diag([1.0, -1e-3])]), "negative variance"),
    ],
)
def test_a_mixture_refuses_nan_means_and_negative_variances(means, covs, match) -> None:
    with pytest.raises(ModelError, match=f"GaussianMixture: {match}"):
        GaussianMixture(means=means, covs=covs, weights=np.ones(means.shape[0]))
    # a rounding-size negative variance is kept, as in Gaussian
    GaussianMixture(
        means=np.zeros((1, 2)), covs=np.diag([1.0, -0.1 * PSD_TOL])[None], weights=np.ones(1)
    )


@pytest.mark.parametrize(("dim", "p"), [(2.5, 0.9), ("2", 0.9), (0, 0.9), (2, 1.0), (2, "0.9")])
def test_chi2_threshold_names_a_bad_dimension_or_probability(dim, p) -> None:
    """A dimension of 2.5 was accepted, and "2" raised a raw TypeError."""
    from relloc.core.kalman import chi2_threshold

    with pytest.raises(ConfigError, match="chi2_threshold: "):
        chi2_threshold(dim, p)
