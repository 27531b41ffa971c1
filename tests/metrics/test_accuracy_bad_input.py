"""Bad arguments to the accuracy metrics (state errors, RMSE, batched conditioning): a
ConfigError or ModelError naming the argument, never a raw numpy error."""

from __future__ import annotations

import numpy as np
import pytest

from relloc.errors import ConfigError, ModelError
from relloc.metrics import condition_log10_batch, rmse, state_errors


@pytest.mark.parametrize(
    ("angles", "message"),
    [
        ((5,), r"angle_indices\[0\] = 5 is beyond the 4 entries"),  # was a raw IndexError
        ((-5,), r"angle_indices\[0\]: must be ≥ -4"),
        ((1.0,), r"angle_indices\[0\]: expected an integer"),  # was a raw IndexError
        (3, "angle_indices must be a sequence"),  # was TypeError: 'int' object is not iterable
        ("3", "angle_indices must be a sequence"),
    ],
)
def test_state_errors_refuses_bad_angle_indices(angles, message) -> None:
    with pytest.raises(ConfigError, match=f"state_errors: {message}"):
        state_errors(np.zeros((3, 4)), np.zeros((3, 4)), angle_indices=angles)


def test_state_errors_takes_negative_and_array_angle_indices() -> None:
    est, tru = np.array([[0.0, 0.0, 0.0, 3.0]]), np.array([[0.0, 0.0, 0.0, -3.0]])
    expected = [[0.0, 0.0, 0.0, 6.0 - 2 * np.pi]]
    np.testing.assert_allclose(state_errors(est, tru, angle_indices=(-1,)), expected)
    np.testing.assert_allclose(state_errors(est, tru, angle_indices=np.array([3])), expected)


@pytest.mark.parametrize(
    ("axis", "message"),
    [
        (5, "axis 5 is beyond the 2 axes"),  # was an AxisError
        (-3, "axis: must be ≥ -2"),
        (1.0, "axis: expected an integer"),  # was a raw TypeError
        ("0", "axis: expected an integer"),
        ((0, 0), r"axis \(0, 0\) names axis 0 twice"),  # was a raw ValueError
        ((0, -2), r"axis \(0, -2\) names axis 0 twice"),
        ((), "axis must name at least one axis"),
    ],
)
def test_rmse_refuses_a_bad_axis(axis, message) -> None:
    with pytest.raises(ConfigError, match=f"rmse: {message}"):
        rmse(np.zeros((3, 4)), axis=axis)


def test_rmse_of_valid_axes_is_unchanged() -> None:
    e = np.array([[3.0, 0.0], [4.0, np.nan]])
    np.testing.assert_allclose(rmse(e, axis=-2), [np.sqrt(12.5), 0.0])
    assert rmse(e, axis=None) == pytest.approx(np.sqrt(25.0 / 3.0))


@pytest.mark.parametrize(
    "M",
    [
        np.zeros((0, 0)),  # was a raw IndexError
        np.zeros((3, 0, 0)),
        np.ones((2, 1, 3)),  # was silently broadcast to (2, 3, 3)
        np.ones(3),
    ],
)
def test_condition_log10_batch_refuses_empty_or_non_square_matrices(M) -> None:
    with pytest.raises(ModelError, match="condition_log10_batch: expected square matrices"):
        condition_log10_batch(M)


def test_condition_log10_batch_of_no_matrices_is_empty() -> None:
    assert condition_log10_batch(np.zeros((0, 2, 2))).shape == (0,)
