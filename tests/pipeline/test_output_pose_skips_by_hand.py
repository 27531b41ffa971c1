"""What pose_set skips and counts, on hand-made beliefs: non-finite means or covariances."""

from __future__ import annotations

import math

import numpy as np
from export_helpers import standing_pair

from relloc.core.estimates import BeliefSeries, Estimates
from relloc.core.recording import Recording
from relloc.pipeline.export.poses import pose_set

NAN = math.nan


def _recording() -> Recording:
    return standing_pair((0.0, 10.0), [0.0, 0.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0])


def _world(subject: str, mean: np.ndarray, cov: np.ndarray) -> BeliefSeries:
    t = np.arange(1.0, 1.0 + mean.shape[0])
    return BeliefSeries(
        owner="team",
        subject=subject,
        track="",
        frame="world_pose2",
        t=t,
        mean=mean,
        cov=cov,
        age=t - 1.0,
    )


def test_a_record_with_a_non_finite_covariance_is_skipped_and_counted():
    cov = np.stack([np.eye(3)] * 3)
    cov[1, 0, 2] = NAN
    s = _world("b", np.array([[1.0, 0.0, 0.0], [2.0, 0.0, 0.0], [3.0, 0.0, 0.0]]), cov)
    poses = pose_set(Estimates(estimator="hand", beliefs=(s,)), _recording())
    assert dict(poses.skipped) == {"non-finite belief": 1}
    (p,) = poses.poses
    assert p.t.tolist() == [1.0, 3.0]
    assert p.position.tolist() == [[1.0, 0.0, 0.0], [3.0, 0.0, 0.0]]


def test_non_finite_records_of_several_series_add_up():
    mean_a = np.array([[NAN, 0.0, 0.0], [1.0, 0.0, 0.0]])
    mean_b = np.array([[1.0, 0.0, 0.0], [1.0, NAN, 0.0], [1.0, 0.0, math.inf]])
    beliefs = (
        _world("a", mean_a, np.stack([np.eye(3)] * 2)),
        _world("b", mean_b, np.stack([np.eye(3)] * 3)),
    )
    poses = pose_set(Estimates(estimator="hand", beliefs=beliefs), _recording())
    assert dict(poses.skipped) == {"non-finite belief": 3}
    assert [p.t.size for p in poses.poses] == [1, 1]
