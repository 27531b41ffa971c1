"""A seed-003 (``airground_follower``) belief as ROS poses, written out by hand: the leader's
pose and the observer's own heading, both in ``owner/common``."""

from __future__ import annotations

import math

import numpy as np

from relloc.core.estimates import BeliefSeries, Estimates
from relloc.core.recording import Odometry, Recording, empty_measurements
from relloc.pipeline.export.poses import pose_set

U = 1.0e6


def _poses():  # type: ignore[no-untyped-def]
    still = Odometry(t=np.zeros(0), velocity=np.zeros((0, 4)), sigma=np.zeros(4))
    rec = Recording(
        robots=("f", "l"),
        platforms=("ground", "aerial"),
        odometry=(still, still),
        measurements=empty_measurements(),
        truth=None,
        source="hand-made",
        meta={},
    )
    # state (r_x, r_y, θ_i, θ_0); covariance diag(1, 2, 3, 4) with one correlation x–θ_0
    cov = np.diag([1.0, 2.0, 3.0, 4.0])
    cov[0, 3] = cov[3, 0] = 0.5
    s = BeliefSeries(
        owner="f",
        subject="l",
        track="",
        frame="airground_follower",
        t=np.array([1.0]),
        mean=np.array([[2.0, -1.0, 0.25, 3.0 * math.pi / 2]]),
        cov=cov[None],
        age=np.array([0.0]),
    )
    return pose_set(Estimates(estimator="hand", beliefs=(s,)), rec)


def test_the_leader_pose_and_the_observer_heading_have_their_own_labels_and_topics():
    poses = _poses()
    assert [(p.label, p.topic, p.frame_id, p.trajectory) for p in poses.poses] == [
        ("f->l", "/f/estimates/l", "f/common", True),
        ("f->l/observer_heading", "/f/estimates/l/observer_heading", "f/common", False),
    ]
    assert poses.common_frame_owners == ("f",)


def test_the_leader_pose_takes_r_and_theta_0_wrapped():
    leader = _poses().poses[0]
    assert leader.position.tolist() == [[2.0, -1.0, 0.0]]
    np.testing.assert_allclose(leader.yaw, [-math.pi / 2], atol=1e-15)
    expected = np.diag([1.0, 2.0, U, U, U, 4.0])
    expected[0, 5] = expected[5, 0] = 0.5
    np.testing.assert_array_equal(leader.cov[0], expected)


def test_the_observer_heading_sits_exactly_at_the_origin():
    heading = _poses().poses[1]
    assert heading.position.tolist() == [[0.0, 0.0, 0.0]]
    assert heading.yaw.tolist() == [0.25]
    np.testing.assert_array_equal(heading.cov[0], np.diag([0.0, 0.0, 0.0, U, U, 3.0]))
