"""Bad input to covariance intersection, de-correlated fusion and equivalent-measurement
messages: a DataError (or ModelError for a covariance) naming where, never a NaN result or a
raw numpy exception."""

import numpy as np
import pytest
from gaussian_sum_samples import one_track_message

from relloc.errors import DataError, ModelError
from relloc.fusion.covariance_intersection import covariance_intersection
from relloc.fusion.decorrelation import decorrelated_fusion

I2, I4 = np.eye(2), np.eye(4)


def test_covariance_intersection_of_identical_estimates_returns_them():
    x, P, _ = covariance_intersection(np.ones(2), I2, np.ones(2), I2)
    np.testing.assert_allclose(x, np.ones(2))
    np.testing.assert_allclose(P, I2)


def test_covariance_intersection_refuses_a_nan_mean():
    with pytest.raises(DataError, match="covariance_intersection: the mean of estimate 1"):
        covariance_intersection(np.zeros(2), I2, np.array([np.nan, 0.0]), I2)


def test_covariance_intersection_refuses_mismatched_shapes():
    with pytest.raises(DataError, match="covariance_intersection: estimate 0"):
        covariance_intersection(np.zeros(3), I2, np.zeros(2), I2)


def test_covariance_intersection_refuses_a_singular_covariance():
    with pytest.raises(ModelError, match="covariance_intersection"):
        covariance_intersection(np.zeros(2), np.zeros((2, 2)), np.zeros(2), I2)


def test_decorrelated_fusion_refuses_a_nan_mean():
    with pytest.raises(DataError, match="decorrelated_fusion: the mean of estimate 2"):
        decorrelated_fusion(
            np.zeros(4), I4, np.zeros(4), I4, np.array([0.0, np.nan, 0.0, 0.0]), 2 * I4
        )


def test_decorrelated_fusion_refuses_mismatched_shapes():
    with pytest.raises(DataError, match="decorrelated_fusion: estimate 1"):
        decorrelated_fusion(np.zeros(4), I4, np.zeros(3), I4, np.zeros(4), 2 * I4)


TWO = {"means": np.zeros((2, 4)), "covs": np.stack([I4, I4])}
TWO |= {"prior_means": TWO["means"], "prior_covs": TWO["covs"]}


@pytest.mark.parametrize(
    ("changes", "match"),
    [
        ({"sender": "a"}, "sender"),
        ({"subject": None}, "subject"),
        ({"sender": -1}, "sender"),
        ({"time": "x"}, "time"),
        ({"means": np.zeros((1, 2)), "prior_means": np.zeros((1, 2))}, "means"),
        ({"means": np.zeros((1, 1, 4))}, "means"),
        ({"means": np.array([["a"] * 4])}, "means: expected real numbers"),
        ({"covs": np.array([[[1, 5, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]]])}, "symm"),
        ({"weights": np.array([1e308, 1e308]), **TWO}, "finite total"),
    ],
)
def test_a_malformed_message_is_a_data_error(changes, match):
    with pytest.raises(DataError, match=match), np.errstate(over="ignore"):
        one_track_message(**changes)
