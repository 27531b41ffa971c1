"""What a node keeps of its teammates: held odometry at sample boundaries, what it releases,
shared readings split at window bounds, and the memory of sequence numbers."""

from __future__ import annotations

import numpy as np
import pytest

from relloc.runtime.messages import MessageRejected
from relloc.runtime.shared_rows import rows_from_body
from relloc.runtime.teammates import ReceivedOdometry, SeenSequences, Teammate

ROSTER = ("1", "2", "3")


def _odometry(stamps: list[float]) -> ReceivedOdometry:
    buf = ReceivedOdometry()
    u = np.array([[k + 1.0, 0.0, 0.0, 0.0] for k in range(len(stamps))])
    buf.add(np.array(stamps), u)
    return buf


def test_a_sample_is_held_from_its_own_stamp_on():
    buf = _odometry([0.0, 0.1, 0.2])
    assert buf.held_at(np.array([0.1, 0.2]))[:, 0].tolist() == [2.0, 3.0]
    assert buf.stamp_at(np.array([0.1, 0.2])).tolist() == [0.1, 0.2]


def test_a_sample_stamped_exactly_where_the_node_filtered_to_is_not_late():
    buf = _odometry([0.0, 0.1])
    buf.consume_until(0.2)
    late_t, _ = buf.add(np.array([0.2, 0.15]), np.ones((2, 4)))
    assert late_t.tolist() == [0.15] and buf.late == 1
    assert buf.last_stamp == 0.2


def test_what_the_node_filtered_to_never_goes_back():
    buf = _odometry([0.0, 0.1])
    buf.consume_until(0.3)
    buf.consume_until(0.2)
    late_t, _ = buf.add(np.array([0.25]), np.ones((1, 4)))
    assert late_t.tolist() == [0.25]


def test_stamps_between_exclude_the_end_unless_inclusive():
    buf = _odometry([0.0, 0.1, 0.2, 0.3])
    assert buf.stamps_between(0.1, 0.3).tolist() == [0.1, 0.2]
    assert buf.stamps_between(0.1, 0.3, inclusive=True).tolist() == [0.1, 0.2, 0.3]


def test_samples_a_node_may_refilter_from_are_kept():
    buf = _odometry([0.0, 0.01, 0.02, 0.03, 0.04, 0.05])
    buf.consume_until(0.02, keep_from=0.05)  # keeping from later than filtered: from 0.02
    assert buf.held_at(np.array([0.015]))[0, 0] == 2.0
    assert buf.held_at(np.array([0.005]))[0, 0] == 0.0  # the sample of 0.0 is released
    buf.consume_until(0.05, keep_from=0.015)  # the node may re-filter from 0.015
    assert buf.held_at(np.array([0.015, 0.05]))[:, 0].tolist() == [2.0, 6.0]


def _rows(stamps: list[float]):
    body = {
        "stamps": np.array(stamps),
        "kinds": ["range"] * len(stamps),
        "subjects": ["1"] * len(stamps),
        "landmarks": np.full(len(stamps), -1.0),
        "sensors": np.zeros(len(stamps)),
        "values": np.full(len(stamps), 3.0),
        "sigmas": np.full(len(stamps), 0.1),
    }
    return rows_from_body(body, ROSTER, "2")


def test_shared_readings_are_split_at_the_window_bounds_within_a_nanosecond():
    mate = Teammate("2")
    near_t0, near_t1 = 1.0 - 5e-10, 2.0 - 5e-10
    mate.rows = [_rows([0.9, near_t0, 1.5, near_t1, 2.0, 2.5])]
    (taken,) = mate.take_rows(1.0, 2.0)
    assert taken.t.tolist() == [near_t0, 1.5]
    assert mate.late_rows == 1  # 0.9: its window is filtered already
    assert [p.t.tolist() for p in mate.rows] == [[near_t1, 2.0, 2.5]]
    (last,) = mate.take_rows(2.0, 2.5, inclusive=True)
    assert last.t.tolist() == [near_t1, 2.0, 2.5]
    assert mate.rows == [] and mate.late_rows == 1


def test_the_oldest_remembered_sequence_number_is_forgotten_first():
    seen = SeenSequences(per_tick=8, window=4)
    assert all(seen.is_new("a", "odom", s, tick=1) for s in range(6))
    assert not seen.is_new("a", "odom", 5, tick=1)  # the newest: still a copy
    assert seen.is_new("a", "odom", 1, tick=1)  # beyond the last 4: taken as new


def _jump(seen: SeenSequences, seq: int, tick: int) -> str:
    with pytest.raises(MessageRejected) as info:
        seen.is_new("a", "odom", seq, tick)
    return info.value.reason


def test_the_bound_grows_from_the_tick_of_the_largest_sequence_number():
    seen = SeenSequences(per_tick=4)
    assert seen.is_new("a", "odom", 10, tick=5)  # bound at tick 5: −1 + 4·(5 + 2) = 27
    assert seen.is_new("a", "odom", 12, tick=8)  # the largest now: 12 at tick 8
    assert _jump(seen, 12 + 4 * 3 + 1, tick=9) == "seq_jump"  # 12 + 4·(1 + 2) = 24
    assert seen.is_new("a", "odom", 24, tick=9)
    assert seen.is_new("a", "odom", 20, tick=9)  # below the largest: no jump, not a copy
    assert _jump(seen, 24 + 4 * 2 + 1, tick=9) == "seq_jump"  # from 24 at tick 9
    assert seen.is_new("a", "odom", 24 + 4 * 2, tick=9)


def test_a_forgotten_sender_is_bounded_as_if_never_heard():
    seen = SeenSequences(per_tick=4)
    assert seen.is_new("a", "odom", 40, tick=10)
    seen.forget("a")
    assert _jump(seen, 48, tick=10) == "seq_jump"  # −1 + 4·(10 + 2) = 47
    assert seen.is_new("a", "odom", 47, tick=10)
