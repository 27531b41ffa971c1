"""The team-figure helpers: track gaps from events, estimates drawn in the world frame, style."""

from __future__ import annotations

import numpy as np

from relloc.core.contract import TrackEvent
from relloc.plotting.setup import pyplot
from relloc.plotting.style import integer_ticks, legend_outside, plain_log_ticks
from relloc.plotting.team import (
    estimated_world_path,
    plot_convergence,
    plot_team_paths,
    track_gaps,
)


def test_track_gaps_pair_deletions_with_the_next_creation():
    events = [
        TrackEvent(0.1, "o", "a", "created"),
        TrackEvent(4.0, "o", "a", "deleted"),
        TrackEvent(5.0, "o", "b", "created"),
        TrackEvent(6.5, "o", "a", "recreated"),
        TrackEvent(9.0, "o", "a", "deleted"),
    ]
    assert track_gaps(events, "o", "a", 12.0) == [(4.0, 6.5), (9.0, 12.0)]
    assert track_gaps(events, "o", "b", 12.0) == []


def test_estimated_world_path_rotates_the_error_out_of_the_observer_frame():
    t = np.array([0.0, 1.0])
    owner = np.array([[0.0, 0.0, 0.0, np.pi / 2], [0.0, 0.0, 0.0, np.pi / 2]])
    subject = np.array([[1.0, 2.0, 1.5, 0.0], [2.0, 2.0, 1.5, 0.0]])
    exact = estimated_world_path(t, owner, subject, t, np.zeros((2, 4)))
    np.testing.assert_allclose(exact, subject[:, :3])
    # an error of +1 m along the observer's x axis, which points along world +y
    moved = estimated_world_path(t, owner, subject, np.array([0.5]), np.array([[1, 0, 0.2, 0]]))
    np.testing.assert_allclose(moved, [[1.5, 3.0, 1.7]], atol=1e-12)


def test_the_team_figures_draw_with_their_legends_outside(tmp_path):
    plt = pyplot()
    fig, (ax_xy, ax_z, ax_c) = plt.subplots(3, 1)
    t = np.linspace(0.0, 10.0, 101)
    path = np.column_stack([t, 2 * t, np.full_like(t, 1.5), np.zeros_like(t)])
    observer = np.column_stack([t, np.zeros_like(t), np.zeros_like(t), np.zeros_like(t)])
    estimate = (t, path[:, :3] + 0.01, "drone")
    plot_team_paths(
        ax_xy,
        ax_z,
        t,
        {"observer": observer, "drone": path},
        {"observer->drone": estimate},
        views={"observer": (90.0, 5.0)},
        arena=((0.0, 10.0), (0.0, 20.0)),
    )
    plot_convergence(ax_c, {"observer->drone": [0.5, 1.0, None]})
    labels = ax_xy.get_legend_handles_labels()[1]
    assert "observer field of view at start" in labels and "observer->drone (estimate)" in labels
    assert any("2/3 runs" in text for text in ax_c.get_legend_handles_labels()[1])
    assert ax_xy.get_legend().get_bbox_to_anchor().x0 > ax_xy.get_window_extent().x1 - 1
    ax_z.set_yscale("log")
    plain_log_ticks(ax_z)
    integer_ticks(ax_c.xaxis)
    legend_outside(ax_z)
    fig.savefig(tmp_path / "f.png")
    assert (tmp_path / "f.png").stat().st_size > 1000
    plt.close(fig)
