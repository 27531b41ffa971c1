"""Bounds on what the network can make a receiver keep or do, without processes.

- sequence numbers: a huge seq (anyone holding the sender's certificate can send one) is
  rejected as ``seq_jump`` and no longer makes the genuine stream look old; losses, partitions
  and a restarted sender's new incarnation stay accepted;
"""

from __future__ import annotations

import numpy as np
import pytest

from relloc.runtime import keys
from relloc.runtime.launcher import TeamLauncher, TeamSettings
from relloc.runtime.messages import MessageRejected, encode
from relloc.runtime.quota import OBJECT_BYTES, REPORT_BYTES_PER_SUBJECT_S, REPORT_SLACK_S
from relloc.runtime.teammates import SeenSequences
from relloc.runtime.transport import Incoming

ROSTER = ("observer", "flyer", "rover")
TEAM = "team"


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


def _est(n: int, target: str = "flyer") -> dict:
    return {
        "target": target,
        "track": "",
        "frame": "relative_pose4",
        "stamps": np.arange(n) * 0.01,  # inside the 4 s run
        "means": np.zeros((n, 4)),
        "covs": np.broadcast_to(np.eye(4), (n, 4, 4)).copy(),
        "ages": np.zeros(n),
        "update_stamps": [],
        "update_ages": [],
        "nis": [],
        "update_dofs": [],
        "cond_r": [],
        "cond_s": [],
        "info_names": [],
        "info": [],
    }


def test_the_collector_keeps_at_most_a_quota_of_reports_per_sender(tmp_path):
    launcher = TeamLauncher(TeamSettings(scenario="default", out_dir=tmp_path), ROSTER, 4.0)
    quota = launcher._quota.limit
    assert quota == REPORT_BYTES_PER_SUBJECT_S * len(ROSTER) * (4.0 + REPORT_SLACK_S)
    flood = encode("est", "observer", 0, 1.0, _est(200))
    key = keys.robot_key(TEAM, "observer", "est")
    sent = 3 * quota // len(flood)
    for _ in range(sent):
        launcher._on_item(Incoming(key, flood))
    kept = len(launcher.collected.estimates)
    assert kept == quota // len(flood)
    assert dict(launcher.collected.rejected_by_reason) == {"report_quota": sent - kept}
    # a report of another sender is still kept: the quota is per sender
    launcher._on_item(
        Incoming(keys.robot_key(TEAM, "rover", "est"), encode("est", "rover", 0, 1.0, _est(3)))
    )
    assert launcher.collected.estimates[-1][0] == "rover"
    # events cost their objects too: a flood of small evt messages is bounded the same way
    evt = {"stamps": np.arange(500) * 0.01, "targets": ["flyer"] * 500, "kinds": ["created"] * 500}
    payload = encode("evt", "flyer", 0, 1.0, evt)
    for _ in range(50):
        launcher._on_item(Incoming(keys.robot_key(TEAM, "flyer", "evt"), payload))
    per_message = len(payload) + OBJECT_BYTES * 1000
    assert len(launcher.collected.events) == 500 * (quota // per_message)


def test_the_collector_refuses_estimates_it_could_not_join_or_score(tmp_path):
    """One spoofed ``est`` once aborted the whole run's summary: a series whose increments
    change frame cannot be joined, a frame other than the team's cannot be scored, and a
    record outside the run has no ground truth. Each is counted, the genuine ones kept."""
    launcher = TeamLauncher(
        TeamSettings(scenario="default", out_dir=tmp_path),
        ROSTER,
        4.0,
        est_frame="relative_pose4",
    )
    key = keys.robot_key(TEAM, "observer", "est")

    def send(seq: int, **changes: object) -> None:
        body = _est(2) | changes
        launcher._on_item(Incoming(key, encode("est", "observer", seq, 1.0, body)))

    send(0)
    send(1, frame="world_pose2", means=np.zeros((2, 3)), covs=np.tile(np.eye(3), (2, 1, 1)))
    send(2, stamps=[1.0, 1e12])
    send(3, stamps=[-1e12, 1.0])
    send(4)
    assert len(launcher.collected.estimates) == 2
    assert dict(launcher.collected.rejected_by_reason) == {
        "wrong_frame": 1,
        "future": 1,
        "past": 1,
    }
    # without a team frame, a series keeps the frame of its first increment
    free = TeamLauncher(TeamSettings(scenario="default", out_dir=tmp_path), ROSTER, 4.0)
    for seq, frame, dim in ((0, "relative_pose4", 4), (1, "world_pose2", 3)):
        body = _est(2) | {"frame": frame, "means": np.zeros((2, dim))}
        body["covs"] = np.tile(np.eye(dim), (2, 1, 1))
        free._on_item(Incoming(key, encode("est", "observer", seq, 1.0, body)))
    assert len(free.collected.estimates) == 1
    assert dict(free.collected.rejected_by_reason) == {"frame_changed": 1}
