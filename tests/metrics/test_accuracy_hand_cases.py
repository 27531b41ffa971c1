"""Hand-computed edge cases of the accuracy metrics: the last valid angle index, an all-NaN RMSE
slice, convergence strictly below the threshold and on |error|, a zero RMSE in the paper
thresholds, and the conditioning of a covariance that is not exactly symmetric."""

import math

import numpy as np
import pytest

from relloc.errors import ConfigError
from relloc.metrics import (
    condition_log10_batch,
    paper_thresholds,
    rmse,
    state_errors,
    updates_to_converge,
)


def test_an_angle_index_one_past_the_state_is_a_config_error():
    est, tru = np.zeros(4), np.zeros(4)
    with pytest.raises(ConfigError, match="beyond the 4 entries"):
        state_errors(est, tru, angle_indices=[4])
    # the last entry itself is an angle like any other: 3π/2 wraps to −π/2
    err = state_errors(np.array([0.0, 0.0, 0.0, 1.5 * np.pi]), tru, angle_indices=[3])
    assert err[3] == pytest.approx(-0.5 * np.pi)


def test_rmse_of_an_all_missing_slice_is_nan():
    e = np.array([[np.nan, 1.0], [np.nan, 3.0]])
    out = rmse(e, axis=0)
    assert math.isnan(out[0])
    assert out[1] == pytest.approx(math.sqrt((1.0 + 9.0) / 2.0))


def test_convergence_needs_the_error_strictly_below_the_threshold():
    # errors equal to the threshold have not converged (strictly below, module docstring)
    assert updates_to_converge([0.2, 0.1, 0.1], 0.1) is None
    assert updates_to_converge([0.2, 0.1, 0.05], 0.1) == 3


def test_convergence_judges_the_magnitude_of_negative_errors():
    # |−1| is above 0.05: converged after the second update, not the first
    assert updates_to_converge([-1.0, 0.01], 0.05) == 2
    assert updates_to_converge([0.01, -1.0, -0.01], 0.05) == 3


def test_paper_thresholds_accept_a_zero_rmse():
    # an RMSE of 0 (e.g. a known state at the first update) is a valid RMSE, not a negative one
    case1 = np.array([[0.0, 0.1], [0.2, 0.0]])
    np.testing.assert_allclose(paper_thresholds(case1), 1.05 * np.array([0.2, 0.1]))


def test_conditioning_uses_the_symmetric_part_of_the_matrix():
    # [[2, 1], [0, 2]] has symmetric part [[2, 0.5], [0.5, 2]] with eigenvalues 1.5 and 2.5,
    # whichever triangle holds the off-diagonal entry
    expected = math.log10(2.5 / 1.5)
    upper = np.array([[2.0, 1.0], [0.0, 2.0]])
    np.testing.assert_allclose(condition_log10_batch(upper), expected, rtol=1e-12)
    np.testing.assert_allclose(condition_log10_batch(upper.T), expected, rtol=1e-12)
