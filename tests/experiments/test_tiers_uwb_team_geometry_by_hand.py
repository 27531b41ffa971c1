"""tiers-uwb's team geometry on hand-built recordings: which robots stand, the latest range per
link in a window, the median per pair, the start positions moved onto the anchors (by a rotation
or a reflection), the mirror image in two anchors' line, and the NEES after aligning a team."""

from __future__ import annotations

import numpy as np
import pytest

from relloc.core.recording import GroundTruth, Odometry, Recording, measurement_rows
from relloc.datasets.bag_mapping import parse_mapping
from relloc.experiments.tiers_uwb_team import (
    TeamTrack,
    _best_mirror,
    latest_ranges,
    median_distances,
    mirrored,
    score_positions,
    standing_robots,
    team_start,
)

T = np.arange(0.0, 5.01, 0.1)


def _recording(
    xy: list[tuple[float, float]], ranges: list[tuple[float, int, int, float]], **kw: object
) -> Recording:
    """Robots standing at ``xy``; ``ranges`` rows ``(t, observer, target, metres)`` (a target
    ≥ len(xy) is landmark target − len(xy))."""
    n = len(xy)
    still = Odometry(t=np.zeros(0), velocity=np.zeros((0, 4)), sigma=np.zeros(4))
    t, obs, tgt, value = (np.array(c) for c in zip(*ranges, strict=True))
    robot = tgt < n
    rows = measurement_rows(
        "range",
        t=t,
        observer=obs.astype(int),
        target=np.where(robot, tgt, -1).astype(int),
        landmark=np.where(robot, -1, tgt - n).astype(int),
        value=value[:, None],
    )
    truth = kw.pop("truth", None) or tuple(
        GroundTruth(t=T, pose=np.tile([x, y, 0.0, 0.0], (T.size, 1))) for x, y in xy
    )
    return Recording(
        robots=tuple("abcdefg"[:n]),
        platforms=("ground",) * n,
        odometry=(still,) * n,
        measurements=rows,
        truth=truth,
        **kw,  # type: ignore[arg-type]
    )


def test_a_robot_whose_motion_capture_stays_within_10_cm_stands() -> None:
    wiggle = np.tile([1.0, 1.0, 0.0, 0.0], (T.size, 1))
    wiggle[T > 2.0, 0] = 1.09
    drive = np.tile([0.0, 0.0, 0.0, 0.0], (T.size, 1))
    drive[:, 0] = 0.1 * T  # 0.5 m in 5 s
    rec = _recording(
        [(1.0, 1.0), (0.0, 0.0)],
        [(1.0, 0, 1, 1.4)],
        truth=(GroundTruth(t=T, pose=wiggle), GroundTruth(t=T, pose=drive)),
    )
    assert standing_robots(rec, parse_mapping('[[robots]]\nname = "a"\n', "m.toml")) == [0]


def test_the_latest_range_per_link_in_the_window_ends_included_a_landmark_after_the_robots() -> (
    None
):
    rec = _recording(
        [(0.0, 0.0), (1.0, 0.0)],
        [(0.4, 0, 1, 9.0), (0.5, 0, 1, 1.0), (0.8, 1, 2, 3.0), (1.0, 1, 0, 2.0), (1.1, 0, 1, 7.0)],
        landmarks=np.array([[0.0, 5.0, 0.0]]),
    )
    # [0.5, 1.0] s: a–b last read at 1.0 s (2.0 m), b to landmark 0 (index 2 + 0) at 0.8 s
    assert latest_ranges(rec, 1.0, 0.5) == {(0, 1): 2.0, (1, 2): 3.0}


def test_the_distance_of_a_pair_is_the_median_of_its_ranges_in_the_window() -> None:
    rec = _recording(
        [(0.0, 0.0), (1.0, 0.0), (5.0, 5.0)],
        [(0.0, 0, 1, 1.0), (0.5, 1, 0, 2.0), (1.0, 0, 1, 6.0), (1.5, 0, 1, 50.0)],
    )
    D = median_distances(rec, 0.0, 1.0)
    assert D[0, 1] == D[1, 0] == 2.0
    assert np.isnan(D[0, 2]) and np.isnan(D[1, 2]) and D[2, 2] == 0.0


SQUARE = [(0.0, 0.0), (4.0, 0.0), (0.0, 3.0), (4.0, 3.0)]


def _exact_ranges(xy: list[tuple[float, float]], t: float) -> list[tuple[float, int, int, float]]:
    return [
        (t + 0.01 * (i * 4 + j), i, j, float(np.hypot(*np.subtract(xy[i], xy[j]))))
        for i in range(len(xy))
        for j in range(i + 1, len(xy))
    ]


@pytest.mark.parametrize("mirror", [1.0, -1.0])
def test_the_start_is_the_true_layout_moved_onto_three_anchors_by_a_rotation_or_reflection(
    mirror: float,
) -> None:
    """Exact ranges in the first second (later ones 1 m long, past INIT_S = 1 s): the layout
    and its mirror image have the same distances, so one of the two needs a reflection."""
    xy = [(x, mirror * y) for x, y in SQUARE]
    late = [(3.0 + 0.01 * k, i, j, 1.0) for k, (i, j) in enumerate([(0, 1), (0, 2), (1, 3)] * 3)]
    rec = _recording(xy, _exact_ranges(xy, 0.2) + _exact_ranges(xy, 0.5) + late)
    np.testing.assert_allclose(team_start(rec, 0.2, [0, 1, 2]), xy, atol=1e-9)


def test_the_mirror_image_in_a_line_and_its_covariance() -> None:
    line = np.array([[0.0, 0.0], [1.0, 1.0]])
    np.testing.assert_allclose(mirrored(np.array([[[0.5, 2.0]]]), line), [[[2.0, 0.5]]])
    truth = _recording([(0.0, 0.0), (1.0, 0.0), (0.5, -1.0)], [(0.0, 0, 1, 1.0)])
    cov = np.tile(np.array([[1.0, 0.5], [0.5, 2.0]]), (1, 3, 1, 1))
    wrong = TeamTrack(np.zeros(1), np.array([[[0.0, 0.0], [1.0, 0.0], [0.5, 1.0]]]), cov)
    flipped, taken = _best_mirror(truth, wrong, [0, 1], [2], 0.0)
    assert taken
    np.testing.assert_allclose(flipped.mean[0, 2], [0.5, -1.0])
    np.testing.assert_allclose(flipped.cov[0, 2], [[1.0, -0.5], [-0.5, 2.0]])


def test_an_image_as_far_from_motion_capture_as_the_estimate_is_not_taken() -> None:
    on_line = _recording([(0.0, 0.0), (1.0, 0.0), (0.5, 0.0)], [(0.0, 0, 1, 1.0)])
    track = TeamTrack(
        np.zeros(1), np.array([[[0.0, 0.0], [1.0, 0.0], [0.5, 1.0]]]), np.zeros((1, 3, 2, 2))
    )
    assert _best_mirror(on_line, track, [0, 1], [2], 0.0) == (track, False)


def test_aligned_scoring_takes_a_mirror_image_and_turns_the_covariance_with_it() -> None:
    """Three robots on the x axis at −1, 0, 1 m, estimated at twice that turned a quarter turn,
    σ 0.1 m along the estimate's x and 1 m along its y: aligned back, each end robot is 1 m off
    along the truth's x, where the turned covariance has σ 1 m (NEES 1, not 100)."""
    truth = np.array([[[-1.0, 0.0], [0.0, 0.0], [1.0, 0.0]]])
    est = np.array([[[0.0, -2.0], [0.0, 0.0], [0.0, 2.0]]])
    cov = np.tile(np.diag([0.01, 1.0]), (1, 3, 1, 1))
    got = score_positions(np.zeros(1), est, cov, truth, [0, 1, 2], align=True)
    assert got["pos_rmse_m"] == pytest.approx(np.sqrt(2 / 3))
    assert got["nees_pct_beyond"] == 0.0
    mirror = np.array([[[-1.0, 0.0], [0.0, 1.0], [1.0, 0.0]]])
    flat = np.tile(np.eye(2), (1, 3, 1, 1))
    image = mirror * [1.0, -1.0] + [0.0, 5.0]
    got = score_positions(np.zeros(1), image, flat, mirror, [0, 1, 2], align=True)
    assert got["pos_rmse_m"] == pytest.approx(0.0, abs=1e-9)


def test_the_anchors_start_at_their_motion_capture_positions_even_when_the_ranges_disagree() -> (
    None
):
    """a–d read 0.5 m long: no layout fits every range, yet the anchors a, b, c start exactly
    where motion capture has them."""
    ranges = [
        (t, i, j, d + (0.5 if (i, j) == (0, 3) else 0.0))
        for t, i, j, d in _exact_ranges(SQUARE, 0.2)
    ]
    start = team_start(_recording(SQUARE, ranges), 0.2, [0, 1, 2])
    np.testing.assert_array_equal(start[:3], SQUARE[:3])
    assert np.hypot(*(start[3] - SQUARE[3])) > 0.01  # the free robot absorbs the misfit
