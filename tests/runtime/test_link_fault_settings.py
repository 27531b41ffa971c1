"""The receive-side network emulator and the fault settings at their edges: partition and
stall bounds, release times in simulated seconds, counters, arrival order of simultaneous
messages, and what a run's length and roster allow."""

from __future__ import annotations

import numpy as np
import pytest

from relloc.errors import ConfigError
from relloc.runtime.faults import (
    FaultSettings,
    LinkEmulator,
    LinkStall,
    Partition,
    RobotEvent,
    parse_partition,
    parse_stall,
)


def test_a_partition_cuts_from_its_start_to_just_before_its_end():
    part = Partition(side=("a", "b"), start_s=10.0, end_s=20.0)
    assert part.separates("a", "c", 10.0) and part.separates("c", "b", 19.999)
    assert not part.separates("a", "c", 9.999) and not part.separates("a", "c", 20.0)
    assert not part.separates("a", "b", 15.0)  # the same side hear each other


def test_a_partition_needs_a_non_negative_start_before_its_end():
    with pytest.raises(ConfigError, match="partition"):
        Partition(side=("a",), start_s=5.0, end_s=5.0)
    with pytest.raises(ConfigError, match="partition: start"):
        Partition(side=("a",), start_s=-1.0, end_s=5.0)
    assert parse_partition(" a , b @1-2").side == ("a", "b")


def test_probabilities_stop_short_of_one_and_the_reorder_hold_is_positive():
    for name in ("drop", "duplicate", "reorder"):
        with pytest.raises(ConfigError, match=name):
            FaultSettings(**{name: 1.0})
    with pytest.raises(ConfigError, match="reorder_hold_s"):
        FaultSettings(reorder_hold_s=0.0)
    with pytest.raises(ConfigError, match="robot event"):
        RobotEvent(robot="a", at_s=-0.5)


def test_a_kill_and_a_restart_at_one_instant_restart_nothing():
    with pytest.raises(ConfigError, match="no earlier --kill"):
        FaultSettings(
            kills=(RobotEvent(robot="a", at_s=1.0),), restarts=(RobotEvent(robot="a", at_s=1.0),)
        )


def test_jitter_or_a_partition_alone_make_the_network_imperfect():
    assert FaultSettings(jitter_ms=1.0).network_faulty
    part = Partition(side=("a",), start_s=0.0, end_s=1.0)
    assert FaultSettings(partitions=(part,)).network_faulty
    assert not FaultSettings().network_faulty


def test_every_robot_a_fault_names_must_be_on_the_team():
    with pytest.raises(ConfigError, match="unknown robot 'zz'"):
        FaultSettings(stalls=(parse_stall("zz,a@1:0.5"),)).check_robots(("a", "b"))
    side = Partition(side=("a",), start_s=0.0, end_s=1.0)
    FaultSettings(partitions=(side,)).check_robots(("a", "b"))  # b is on the other side
    with pytest.raises(ConfigError, match="separates nobody"):
        FaultSettings(partitions=(side,)).check_robots(("a",))


def test_a_fault_must_begin_before_the_runs_end():
    for faults in (
        FaultSettings(stalls=(parse_stall("a,b@5:0.5"),)),
        FaultSettings(partitions=(Partition(side=("a",), start_s=5.0, end_s=6.0),)),
        FaultSettings(kills=(RobotEvent(robot="a", at_s=5.0),)),
    ):
        with pytest.raises(ConfigError, match="begins at or after the run's end"):
            faults.check_times(5.0)
        faults.check_times(5.001)


def test_fault_settings_write_every_figure():
    out = FaultSettings(drop=0.1, delay_ms=20.0, jitter_ms=5.0, duplicate=0.2).to_dict()
    assert (out["drop"], out["delay_ms"], out["jitter_ms"], out["duplicate"]) == (
        0.1,
        20.0,
        5.0,
        0.2,
    )


def test_a_stall_starts_with_the_first_message_at_its_time_and_happens_once():
    link = LinkStall("me", (parse_stall("a,me@10:0.5"),), max_records=9, max_bytes=99)
    assert link.hold("a", 10.0, "a1", wall_s=100.0, size=1)  # exactly at its time
    assert link.next_due == 100.5
    assert link.due(100.5) == ["a1"]  # exactly when it runs out
    assert not link.hold("a", 11.0, "a2", wall_s=101.0, size=1)  # over, not again


def test_the_next_release_of_two_stalled_links_is_the_earlier():
    stalls = (parse_stall("a,me@0:5"), parse_stall("b,me@0:1"))
    link = LinkStall("me", stalls, max_records=9, max_bytes=99)
    link.hold("a", 0.0, "a1", wall_s=0.0, size=1)
    link.hold("b", 0.0, "b1", wall_s=0.0, size=1)
    assert link.next_due == 1.0
    assert link.due(1.0) == ["b1"] and link.next_due == 5.0


def test_bytes_released_by_a_stall_are_free_again():
    stalls = (parse_stall("a,me@0:1"), parse_stall("b,me@0:60"))
    link = LinkStall("me", stalls, max_records=9, max_bytes=30)
    assert link.hold("a", 0.0, "a1", wall_s=0.0, size=20)
    assert link.due(1.0) == ["a1"]
    assert link.hold("b", 0.0, "b1", wall_s=1.0, size=20)
    assert link.dropped == 0 and link.held == 2


def test_a_stall_holds_up_to_max_records_exactly():
    link = LinkStall("me", (parse_stall("a,me@0:60"),), max_records=2, max_bytes=10**6)
    for i in range(3):
        link.hold("a", 0.0, f"a{i}", wall_s=0.0, size=1)
    assert (link.held, link.dropped) == (2, 1)


def test_a_delay_is_in_simulated_milliseconds_and_never_negative():
    link = LinkEmulator("me", FaultSettings(delay_ms=100.0), np.random.default_rng(0))
    link.admit(b"x", "a", now_s=1.0)
    assert link.release(1.09) == [] and link.release(1.1) == [b"x"]
    assert link.counters.delayed == 1
    jitter = LinkEmulator("me", FaultSettings(jitter_ms=1e6), np.random.default_rng(1))
    for i in range(50):
        jitter.admit(i, "a", now_s=5.0)
    # half of N(0, 1e6 ms) draws are negative: released at once, never before their arrival
    assert jitter.release(4.999) == []
    assert 10 < len(jitter.release(5.0)) < 40


def test_messages_due_at_one_instant_leave_in_arrival_order():
    link = LinkEmulator("me", FaultSettings(delay_ms=10.0), np.random.default_rng(0))
    for i in range(40):
        link.admit(i, "a" if i % 2 else "b", now_s=1.0)
    assert link.release(1.01) == list(range(40))


def test_one_message_per_sender_is_held_back_for_reordering():
    link = LinkEmulator("me", FaultSettings(reorder=0.999999), np.random.default_rng(0))
    link.admit("a1", "a", now_s=0.0)  # held
    link.admit("a2", "a", now_s=0.0)  # a1 is held already: goes on
    assert link.release(0.0) == ["a2", "a1"]
    assert link.counters.reordered == 1


def test_a_held_message_is_released_at_its_deadline_exactly():
    link = LinkEmulator("me", FaultSettings(reorder=0.999999), np.random.default_rng(0))
    link.admit("a1", "a", now_s=1.0)
    assert link.release(1.4) == [] and link.release(1.5) == ["a1"]


def test_partitioned_and_duplicated_messages_are_counted_once_each():
    part = Partition(side=("a",), start_s=0.0, end_s=1.0)
    link = LinkEmulator("me", FaultSettings(partitions=(part,)), np.random.default_rng(0))
    link.admit("x", "a", now_s=0.5)
    assert link.counters.partitioned == 1 and link.counters.seen == 1
    dup = LinkEmulator("me", FaultSettings(duplicate=0.999999), np.random.default_rng(0))
    dup.admit("y", "a", now_s=0.0)
    assert dup.release(0.0) == ["y", "y"] and dup.counters.duplicated == 1


def test_team_members_draw_their_faults_independently():
    settings = FaultSettings(drop=0.5)
    kept = []
    for owner in ("a", "b"):
        link = LinkEmulator.of_member(owner, settings, seed=7, roster=("a", "b"))
        for i in range(64):
            link.admit(i, "c", now_s=0.0)
        kept.append(link.release(0.0))
    assert kept[0] != kept[1]
