"""Bounds on what the network can make a receiver keep or do, without processes.

- sequence numbers: a huge seq (anyone holding the sender's certificate can send one) is
  rejected as ``seq_jump`` and no longer makes the genuine stream look old; losses, partitions
  and a restarted sender's new incarnation stay accepted;
"""

from __future__ import annotations

import pytest

from relloc.runtime.messages import MessageRejected
from relloc.runtime.teammates import SeenSequences


def _jump(seen: SeenSequences, seq: int, tick: int, sender: str = "rover") -> str:
    with pytest.raises(MessageRejected) as info:
        seen.is_new(sender, "odom", seq, tick)
    return info.value.reason


def test_a_huge_sequence_number_is_rejected_and_the_genuine_stream_goes_on():
    seen = SeenSequences(per_tick=8)
    for k in range(20):
        assert seen.is_new("rover", "odom", k, tick=k)
    assert _jump(seen, 10**9, tick=20) == "seq_jump"
    # the genuine stream: new, and its copies still duplicates
    for k in range(20, 40):
        assert seen.is_new("rover", "odom", k, tick=k)
        assert not seen.is_new("rover", "odom", k, tick=k)
    # the bound grows with the receiver's ticks since the last accepted seq, by per_tick each
    assert _jump(seen, 39 + 8 * 2 + 1, tick=39) == "seq_jump"
    assert seen.is_new("rover", "odom", 39 + 8 * 2, tick=39)


def test_losses_partitions_and_restarts_stay_within_the_bound():
    seen = SeenSequences(per_tick=4)
    assert seen.is_new("flyer", "mail", 0, tick=3)
    # 200 ticks without a message (a partition), the sender at its full rate meanwhile
    assert seen.is_new("flyer", "mail", 4 * 200, tick=203)
    # a sender first heard mid-run (this receiver restarted): bounded by the run's ticks
    assert seen.is_new("rover", "odom", 4 * (50 + 2) - 1, tick=50)
    assert _jump(seen, 4 * (50 + 2), tick=50, sender="observer") == "seq_jump"
    # a restarted sender counts from 0: below its largest seq, no jump; new once forgotten
    assert not seen.is_new("flyer", "mail", 0, tick=204)
    seen.forget("flyer")
    assert [seen.is_new("flyer", "mail", s, tick=205) for s in (0, 1, 1)] == [True, True, False]


def test_remembered_sequence_numbers_are_bounded():
    seen = SeenSequences(per_tick=2, window=16)
    for k in range(1000):
        assert seen.is_new("rover", "odom", k, tick=k)
    assert len(seen._recent[("rover", "odom")]) == 16
