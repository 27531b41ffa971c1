"""Admission of received messages by time, tick order and rate (``relloc.runtime.admission``),
at the edges of each documented bound."""

from __future__ import annotations

import numpy as np
import pytest

from relloc.runtime import keys
from relloc.runtime.admission import SenderBudget, TickGuard, admit, check_stamps
from relloc.runtime.messages import Message, MessageRejected, encode

ROSTER = ("observer", "flyer", "rover")
TEAM = "team"


def _tick(k: int, t: float, n: int = 40, dt: float = 0.1) -> Message:
    payload = encode("tick", "clock", k, t, {"k": k, "n": n, "dt": dt})
    return admit(keys.clock_key(TEAM, "tick"), payload, roster=ROSTER)


def _odom(t: float, stamps: list[float]) -> Message:
    body = {"stamps": stamps, "u": np.zeros((len(stamps), 4))}
    payload = encode("odom", "flyer", 0, t, body)
    return admit(keys.robot_key(TEAM, "flyer", "odom"), payload, roster=ROSTER)


def _est(t: float, update_stamps: list[float]) -> Message:
    m = len(update_stamps)
    body = {
        "target": "rover",
        "track": "",
        "frame": "relative_pose4",
        "stamps": [],
        "means": np.zeros((0, 4)),
        "covs": np.zeros((0, 4, 4)),
        "ages": [],
        "update_stamps": update_stamps,
        "update_ages": [0.0] * m,
        "nis": [1.0] * m,
        "update_dofs": [2] * m,
        "cond_r": [1.0] * m,
        "cond_s": [1.0] * m,
        "info_names": [],
        "info": [],
    }
    payload = encode("est", "flyer", 0, t, body)
    return admit(keys.robot_key(TEAM, "flyer", "est"), payload, roster=ROSTER)


def _reason(fn, *args, **kwargs) -> str:
    with pytest.raises(MessageRejected) as info:
        fn(*args, **kwargs)
    return info.value.reason


def test_data_up_to_two_seconds_ahead_of_the_clock_is_taken():
    check_stamps(_odom(3.0, [2.5, 3.0]), now_s=1.0)  # exactly the bound
    assert _reason(check_stamps, _odom(3.02, [2.5, 3.02]), now_s=1.0) == "future"
    assert _reason(check_stamps, _odom(1.0, [1.0, 3.02]), now_s=1.0) == "future"


def test_the_header_time_counts_even_when_the_stamps_are_fine():
    assert _reason(check_stamps, _odom(9.0, [0.5, 0.6]), now_s=1.0) == "future"
    assert _reason(check_stamps, _odom(0.0, [0.5, 9.0]), now_s=1.0) == "future"


def test_a_stamp_a_little_before_the_runs_start_is_past():
    assert _reason(check_stamps, _odom(1.0, [-0.1, 0.5]), now_s=1.0) == "past"


def test_update_stamps_of_an_estimate_are_checked_too():
    check_stamps(_est(1.0, [0.5, 1.0]), now_s=1.0)
    assert _reason(check_stamps, _est(1.0, [0.5, 50.0]), now_s=1.0) == "future"
    assert _reason(check_stamps, _est(1.0, [-5.0, 0.5]), now_s=1.0) == "past"


def test_a_first_tick_beyond_the_run_or_longer_than_ten_seconds_is_refused():
    assert _reason(TickGuard().check, _tick(3, 4.1, n=40, dt=0.1)) == "bad_tick"  # n·dt = 4
    TickGuard().check(_tick(40, 4.0, n=40, dt=0.1))
    assert _reason(TickGuard().check, _tick(1, 20.0, n=2, dt=20.0)) == "bad_tick"
    TickGuard().check(_tick(1, 10.0, n=2, dt=10.0))


def test_a_tick_at_most_one_period_after_the_nodes_own_data_ends():
    TickGuard(end_s=1.0).check(_tick(11, 1.1))
    assert _reason(TickGuard(end_s=1.0).check, _tick(12, 1.2)) == "bad_tick"


def test_ticks_advance_one_at_a_time_from_the_first_one_heard():
    guard = TickGuard()
    guard.check(_tick(1, 0.1))
    assert _reason(guard.check, _tick(3, 0.2)) == "bad_tick"  # k skips one
    assert _reason(guard.check, _tick(2, 0.5)) == "bad_tick"  # t jumps
    assert _reason(guard.check, _tick(2, 0.3, dt=0.2)) == "bad_tick"  # dt changes
    guard.check(_tick(2, 0.2))
    # a node that joins mid-run (restarted) hears tick 50 first and follows from there
    late = TickGuard()
    late.check(_tick(50, 5.0, n=100))
    late.check(_tick(51, 5.1, n=100))
    assert late.k == 51


def test_the_end_is_premature_until_the_last_tick_itself():
    end = admit(
        keys.clock_key(TEAM, "ctl"),
        encode("ctl", "clock", 0, 4.0, {"action": "end", "robot": ""}),
        roster=ROSTER,
    )
    guard = TickGuard()
    for k in range(1, 40):
        guard.check(_tick(k, k * 0.1))
    assert _reason(guard.check_end, end) == "premature_end"
    guard.check(_tick(40, 4.0))
    guard.check_end(end)


def test_a_team_of_three_may_send_32_data_messages_per_sender_and_tick():
    # 2 ticks' worth (odom + meas + N−1 eqm each: 2(N + 1) = 8), twice that, plus 16
    assert SenderBudget.for_team(3).capacity == 32
    assert SenderBudget.for_team(1).capacity == 24
