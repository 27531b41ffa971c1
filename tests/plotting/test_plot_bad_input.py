"""Degenerate series on logarithmic axes: with no positive value the axis stays linear (matplotlib
cannot log-scale it, and warns), as :func:`relloc.plotting.cooperative.plot_grouped_bars` does."""

from __future__ import annotations

import io
import warnings

import numpy as np
import pytest

from relloc.plotting.cooperative import plot_case_series, plot_grouped_bars
from relloc.plotting.setup import pyplot
from relloc.plotting.wanasinghe import plot_rmse_vs_bound

T = np.arange(5.0)


@pytest.mark.parametrize("values", [np.zeros(5), -np.ones(5), np.full(5, np.nan)])
def test_log_axes_without_a_positive_value_stay_linear_and_draw_quietly(values):
    plt = pyplot()
    fig, axes = plt.subplots(1, 6)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            plot_case_series(axes[0], T, {"a": values}, ylabel="e", log=True)
            plot_rmse_vs_bound(axes[1:5], T, np.stack([values] * 4, 1), np.zeros((5, 4)), label="x")
            plot_grouped_bars(axes[5], ["g"], {"a": [values[0]]}, ylabel="e")
            fig.savefig(io.BytesIO(), format="png")
        assert all(ax.get_yscale() == "linear" for ax in axes)
    finally:
        plt.close(fig)


def test_log_axes_with_a_positive_value_are_logarithmic():
    plt = pyplot()
    fig, axes = plt.subplots(1, 5)
    try:
        values = np.array([0.0, 1.0, 2.0, 0.0, 3.0])  # the zeros are left out of the axis
        plot_case_series(axes[0], T, {"a": values}, ylabel="e", log=True)
        plot_rmse_vs_bound(axes[1:], T, np.stack([values] * 4, 1), np.ones((5, 4)), label="x")
        assert all(ax.get_yscale() == "log" for ax in axes)
    finally:
        plt.close(fig)
