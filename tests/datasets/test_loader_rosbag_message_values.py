"""One ROS message → numbers (:mod:`relloc.datasets.rosbag`): the stamp, the bounds every value
must keep, the quaternion's yaw and the range checks, at their edges. Messages are stand-ins
with the fields the loader reads."""

from __future__ import annotations

import math
from types import SimpleNamespace as NS

import pytest

from relloc.core.limits import MAX_SENSOR_RANGE_M, MAX_SPEED_M_S, MAX_YAW_RATE_RAD_S
from relloc.datasets.rosbag import BadMessage, odometry_sample, range_sample, stamp_ns, yaw_of


def _stamped(sec: int, nanosec: int) -> NS:
    return NS(header=NS(stamp=NS(sec=sec, nanosec=nanosec)))


def _odometry(vx: float, wz: float) -> NS:
    return NS(
        twist=NS(twist=NS(linear=NS(x=vx, y=0.0, z=0.0), angular=NS(x=0.0, y=0.0, z=wz))),
        pose=NS(pose=NS(position=NS(x=1.0, y=2.0, z=0.0), orientation=NS(x=0, y=0, z=0, w=1))),
    )


def _range(r: float, lo: float = 0.0, hi: float = 0.0) -> NS:
    return NS(range=r, min_range=lo, max_range=hi)


def test_the_largest_nanosecond_field_is_accepted_and_one_more_is_malformed():
    assert stamp_ns(_stamped(3, 999_999_999)) == 3_999_999_999
    with pytest.raises(BadMessage, match="sec=3 nanosec=1000000000") as info:
        stamp_ns(_stamped(3, 1_000_000_000))
    assert info.value.reason == "malformed header"


def test_a_twist_at_exactly_the_speed_and_turn_rate_limits_is_kept():
    velocity, _ = odometry_sample(_odometry(-MAX_SPEED_M_S, MAX_YAW_RATE_RAD_S))
    assert velocity == (-100.0, 0.0, 0.0, 100.0)
    with pytest.raises(BadMessage) as info:
        odometry_sample(_odometry(MAX_SPEED_M_S + 0.5, 0.0))
    assert info.value.reason == "out of bounds"


def test_yaw_of_a_turn_about_the_diagonal_uses_the_xy_term():
    """(x, y, z, w) = (½, ½, ½, ½), 120° about (1, 1, 1): atan2(2(¼ + ¼), 1 − 2(¼ + ¼)) =
    atan2(1, 0) = π/2."""
    assert yaw_of(0.5, 0.5, 0.5, 0.5) == pytest.approx(math.pi / 2)


def test_a_scaled_quaternion_gives_the_yaw_of_the_unit_one():
    """(0, 0, 2, 2) is (0, 0, √½, √½) scaled: a quarter turn about z."""
    assert yaw_of(0.0, 0.0, 2.0, 2.0) == pytest.approx(math.pi / 2)
    assert yaw_of(0.0, 0.0, -3.0, 3.0) == pytest.approx(-math.pi / 2)


def test_a_range_of_zero_is_not_a_reading():
    with pytest.raises(BadMessage) as info:
        range_sample(_range(0.0))
    assert info.value.reason == "range ≤ 0"


def test_a_range_at_exactly_the_sensor_limit_is_kept():
    assert range_sample(_range(MAX_SENSOR_RANGE_M)) == 1e4
    with pytest.raises(BadMessage) as info:
        range_sample(_range(MAX_SENSOR_RANGE_M * (1 + 1e-9)))
    assert info.value.reason == "out of bounds"


def test_a_range_at_the_messages_own_bounds_is_kept():
    assert range_sample(_range(0.2, lo=0.2, hi=40.0)) == 0.2
    assert range_sample(_range(40.0, lo=0.2, hi=40.0)) == 40.0
    for r in (0.19, 40.01):
        with pytest.raises(BadMessage) as info:
            range_sample(_range(r, lo=0.2, hi=40.0))
        assert info.value.reason == "range out of bounds"


def test_a_topics_rate_counts_the_intervals_between_its_messages():
    """Five messages from 1 s to 3 s are four intervals in 2 s: 2 Hz."""
    from relloc.datasets.rosbag import TopicInfo

    assert TopicInfo("/a", "t", 5, 1.0, 3.0).rate_hz == 2.0
    assert TopicInfo("/a", "t", 1, 1.0, 1.0).rate_hz == 0.0
    assert TopicInfo("/a", "t", 3, 2.0, 2.0).rate_hz == 0.0
