"""Generic team plots: gaps in a series break the line; every helper draws into given axes."""

import numpy as np

from relloc.plotting.consistency import plot_chi2_series, plot_conditioning
from relloc.plotting.errors import (
    break_gaps,
    plot_pose_errors_with_bounds,
    plot_robot_errors,
    plot_trajectories,
)
from relloc.plotting.setup import pyplot

plt = pyplot()


def test_break_gaps_inserts_nan_only_at_missing_samples():
    t = np.array([0.0, 0.1, 0.2, 1.0, 1.1])
    y = np.arange(10.0).reshape(5, 2)
    t2, y2 = break_gaps(t, y)
    assert t2.size == 6 and np.isnan(t2[3]) and np.all(np.isnan(y2[3]))
    np.testing.assert_array_equal(t2[~np.isnan(t2)], t)
    t3, y3 = break_gaps(np.arange(5) * 0.1, y)
    assert t3.size == 5 and not np.isnan(y3).any()


def test_helpers_draw_into_the_axes_they_are_given():
    t = np.arange(50) * 0.1
    err = np.random.default_rng(0).normal(size=(50, 4)) * 0.01
    sig = np.full((50, 4), 0.01)
    fig, axes = plt.subplots(4, 1)
    plot_pose_errors_with_bounds(axes, t, err, sig)
    assert all(len(ax.lines) == 4 for ax in axes)  # error, +3σ, −3σ, zero line
    fig2, axes2 = plt.subplots(4, 1)
    plot_robot_errors(axes2, {"a": (t, err), "b": (t, 2 * err)})
    fig3, ax3 = plt.subplots()
    plot_chi2_series(ax3, t, np.full(50, 4.0), 4, n_runs=10)
    plot_chi2_series(ax3, t, np.full(50, 3.0), 4, n_runs=10, show_bound=False)
    assert len(ax3.patches) == 1  # one 95 % band for both series
    fig4, ax4 = plt.subplots()
    plot_conditioning(ax4, {"P": (t, np.ones(50))})
    plot_trajectories(ax4, {"r": np.column_stack([t, t])}, arena=((0, 10), (0, 20)))
    for f in (fig, fig2, fig3, fig4):
        plt.close(f)
