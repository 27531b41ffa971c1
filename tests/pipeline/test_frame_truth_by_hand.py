"""True states of the named frames and their wrapped angle errors, worked out by hand for two
robots at fixed poses: ``world_pose2`` takes the yaw (not z) and wraps the heading error;
``airground_follower`` rotates ``p_leader − p_follower`` into the common frame and wraps both
heading errors."""

from __future__ import annotations

import math

import numpy as np
import pytest

from relloc.core.estimates import BeliefSeries
from relloc.core.recording import GroundTruth, Odometry, Recording, measurement_rows
from relloc.pipeline.evaluation import series_errors


def _recording(meta: dict[str, float]) -> Recording:
    t = np.array([0.0, 1.0])
    still = Odometry(t=np.zeros(0), velocity=np.zeros((0, 4)), sigma=(0, 0, 0, 0))
    truth = (
        GroundTruth(t=t, pose=np.tile([1.0, 2.0, 0.5, 3.0], (2, 1))),
        GroundTruth(t=t, pose=np.tile([4.0, 6.0, 1.5, -3.0], (2, 1))),
    )
    rows = measurement_rows("range", t=t, observer=1, target=0, value=np.ones(2))
    return Recording(
        robots=("a", "b"),
        platforms=("ground",) * 2,
        odometry=(still, still),
        measurements=rows,
        truth=truth,
        meta=meta,
    )


def _series(frame: str, mean: list[float]) -> BeliefSeries:
    d = len(mean)
    return BeliefSeries(
        owner="a",
        subject="b",
        frame=frame,
        t=np.array([0.5]),
        mean=np.array([mean]),
        cov=np.eye(d)[None],
        age=np.array([1.0]),
    )


def test_world_pose2_error_uses_the_yaw_and_wraps_it() -> None:
    err = series_errors(_series("world_pose2", [4.5, 5.0, 3.0]), _recording({}))
    # truth (4, 6, ψ = −3): heading error 3 − (−3) = 6 rad, wrapped to 6 − 2π
    np.testing.assert_allclose(err[0], [0.5, -1.0, 6.0 - 2 * math.pi], atol=1e-12)


def test_airground_follower_truth_in_a_turned_common_frame() -> None:
    yaw = 0.5
    c, s = math.cos(yaw), math.sin(yaw)
    # r = R(−yaw)(p_b − p_a) with p_b − p_a = (3, 4); headings minus the frame's yaw
    r = (3 * c + 4 * s, -3 * s + 4 * c)
    mean = [r[0] + 0.1, r[1] - 0.2, 2.5 + 0.3, 2.7]
    err = series_errors(_series("airground_follower", mean), _recording({"common_frame_yaw": yaw}))
    # θ_0 truth −3 − 0.5 = −3.5: error 2.7 + 3.5 = 6.2 rad, wrapped to 6.2 − 2π
    np.testing.assert_allclose(err[0], [0.1, -0.2, 0.3, 6.2 - 2 * math.pi], atol=1e-12)
    assert err[0, 3] == pytest.approx(-0.0831853, abs=1e-6)
