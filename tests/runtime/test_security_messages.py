"""Hostile input without processes: every attack that crashed a receiver on the message path.

- ``decode``/``admit`` fuzzed with hostile payloads on team keys: a Message or a counted
  ``MessageRejected``, never a raw exception;
- roles: the infrastructure sender on a robot key, a robot kind on a clock key, a kind on
  another kind's key, ``ctl`` about a robot off the roster;
- ticks that jump (t = 10¹²), premature ``ctl(end)``, future-stamped odometry, per-sender rate;
- the launcher's collector: ``ctl restart robot="nobody"`` and ``stats`` from ``clock`` (both
  ``KeyError`` before), spoofed kills/restarts outside the fault schedule;
- the inbox drops oversized payloads before queueing and is bounded in bytes (real Zenoh).
"""

from __future__ import annotations

import time

import msgpack
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from relloc.runtime import keys
from relloc.runtime.admission import SenderBudget, TickGuard, admit, check_stamps
from relloc.runtime.faults import FaultSettings, parse_robot_event
from relloc.runtime.launcher import TeamLauncher, TeamSettings
from relloc.runtime.messages import Message, MessageRejected, encode
from relloc.runtime.transport import Inbox, Incoming, TransportSettings, open_session

ROSTER = ("observer", "flyer", "rover")
TEAM = "team"
ODOM = {"stamps": np.array([0.0, 0.05]), "u": np.zeros((2, 4))}


def _tick(k: int, t: float, n: int = 40, dt: float = 0.1) -> bytes:
    return encode("tick", "clock", k, t, {"k": k, "n": n, "dt": dt})


def _rejected(key: str, payload: bytes) -> str:
    with pytest.raises(MessageRejected) as info:
        admit(key, payload, roster=ROSTER)
    return info.value.reason


KEYS = [keys.robot_key(TEAM, r, k) for r in (*ROSTER, "clock", "nobody") for k in keys.ROBOT_KINDS]
KEYS += [keys.clock_key(TEAM, "tick"), keys.clock_key(TEAM, "ctl"), "relloc/team/robot/x"]
VALID = [
    encode("odom", "flyer", 1, 0.1, ODOM),
    encode("ctl", "clock", 2, 1.0, {"action": "kill", "robot": "flyer"}),
    _tick(3, 0.3),
    encode("stats", "rover", 0, 1.0, {"counters": {"sent.odom": 3}}),
]
scalars = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(min_value=-(2**63), max_value=2**64 - 1),
    st.floats(allow_nan=True, allow_infinity=True),
    st.text(max_size=12),
    st.binary(max_size=12),
)
documents = st.recursive(
    scalars,
    lambda inner: (
        st.lists(inner, max_size=5) | st.dictionaries(st.text(max_size=8), inner, max_size=6)
    ),
    max_leaves=30,
)


def _hostile_map(base: bytes, field: str, value: object) -> bytes:
    doc = msgpack.unpackb(base)
    doc[field] = value
    return msgpack.packb(doc, use_bin_type=True)


@settings(derandomize=True, max_examples=150, deadline=None)
@given(
    key=st.sampled_from(KEYS),
    payload=st.one_of(
        st.binary(max_size=200),
        documents.map(lambda d: msgpack.packb(d, use_bin_type=True)),
        st.tuples(
            st.sampled_from(VALID),
            st.sampled_from(["v", "type", "sender", "seq", "t", "stamps", "u", "robot", "k"]),
            documents,
        ).map(lambda a: _hostile_map(*a)),
    ),
)
def test_hostile_payloads_are_a_message_or_a_counted_rejection(key, payload):
    try:
        msg = admit(key, payload, roster=ROSTER)
    except MessageRejected as exc:
        assert exc.reason and " " not in exc.reason
        return
    assert isinstance(msg, Message) and msg.sender in (*ROSTER, "clock")


def test_roles_follow_the_key_layout():
    odom = encode("odom", "clock", 0, 0.1, ODOM)
    assert _rejected("relloc/team/robot/clock/odom", odom) == "unknown_sender"  # was KeyError
    eqm = {"target": "flyer", "mean": np.zeros(4), "cov": np.eye(4)}
    assert _rejected(keys.clock_key(TEAM, "tick"), encode("eqm", "clock", 0, 0.1, eqm)) in (
        "wrong_kind"
    )
    flyer_tick = encode("tick", "flyer", 0, 0.1, {"k": 1, "n": 2, "dt": 0.1})
    assert _rejected(keys.clock_key(TEAM, "tick"), flyer_tick) == "spoofed"
    assert _rejected(keys.robot_key(TEAM, "flyer", "odom"), flyer_tick) == "wrong_kind"
    nobody = encode("ctl", "clock", 0, 1.0, {"action": "restart", "robot": "nobody"})
    assert _rejected(keys.clock_key(TEAM, "ctl"), nobody) == "unknown_target"
    blank = encode("ctl", "clock", 0, 1.0, {"action": "kill", "robot": ""})
    assert _rejected(keys.clock_key(TEAM, "ctl"), blank) == "malformed"
    assert _rejected("relloc/team/elsewhere", VALID[0]) == "unknown_key"
    assert admit(keys.robot_key(TEAM, "flyer", "odom"), VALID[0], roster=ROSTER).sender == "flyer"


def _msg(payload: bytes, key: str) -> Message:
    return admit(key, payload, roster=ROSTER)


def test_ticks_advance_one_at_a_time_and_end_only_after_the_last():
    key = keys.clock_key(TEAM, "tick")
    guard = TickGuard(end_s=4.0)
    for k in (1, 2):
        guard.check(_msg(_tick(k, k * 0.1), key))
    for bad in (_tick(3, 1e12, n=10**13), _tick(3, 0.3, n=41), _tick(5, 0.5), _tick(2, 0.2)):
        with pytest.raises(MessageRejected, match="bad_tick"):
            guard.check(_msg(bad, key))
    end = _msg(
        encode("ctl", "clock", 9, 0.2, {"action": "end", "robot": ""}), keys.clock_key(TEAM, "ctl")
    )
    with pytest.raises(MessageRejected, match="premature_end"):
        guard.check_end(end)
    with pytest.raises(MessageRejected, match="bad_tick"):  # first tick beyond the run
        TickGuard(end_s=4.0).check(_msg(_tick(1, 1e12, n=10**13, dt=0.1), key))
    with pytest.raises(MessageRejected, match="bad_tick"):  # a window of 10^6 s
        TickGuard().check(_msg(_tick(1, 1e6, n=2, dt=1e6), key))
    last = TickGuard()
    for k in range(1, 41):
        last.check(_msg(_tick(k, k * 0.1), key))
    last.check_end(end)


def test_future_and_past_stamps_and_floods_are_refused():
    key = keys.robot_key(TEAM, "flyer", "odom")
    future = _msg(
        encode("odom", "flyer", 0, 1.0, {"stamps": [1.0, 9e6], "u": np.zeros((2, 4))}), key
    )
    with pytest.raises(MessageRejected, match="future"):
        check_stamps(future, now_s=1.0)
    check_stamps(_msg(VALID[0], key), now_s=0.0)
    # held from before the run's start, a sample would be stale by an unbounded age
    past = _msg(encode("odom", "flyer", 0, 1.0, {"stamps": [-1e12], "u": np.zeros((1, 4))}), key)
    with pytest.raises(MessageRejected, match="past"):
        check_stamps(past, now_s=1.0)
    budget = SenderBudget.for_team(3)
    for _ in range(budget.capacity):
        budget.take("flyer")
    with pytest.raises(MessageRejected, match="rate_limited"):
        budget.take("flyer")
    budget.take("rover")  # per sender
    budget.new_interval()
    budget.take("flyer")


def test_collector_survives_hostile_control_and_counts_it(tmp_path):
    faults = FaultSettings(
        kills=(parse_robot_event("flyer@1.0", "--kill"),),
        restarts=(parse_robot_event("flyer@2.0", "--restart"),),
    )
    launcher = TeamLauncher(
        TeamSettings(scenario="default", out_dir=tmp_path, faults=faults), ROSTER, 4.0
    )
    ctl = keys.clock_key(TEAM, "ctl")

    def ctl_msg(action: str, robot: str, t: float) -> Incoming:
        return Incoming(ctl, encode("ctl", "clock", 0, t, {"action": action, "robot": robot}))

    hostile = [
        ctl_msg("restart", "nobody", 1.0),  # KeyError before
        Incoming(
            "relloc/team/robot/clock/stats", encode("stats", "clock", 0, 1.0, {"counters": {}})
        ),
        ctl_msg("kill", "rover", 1.0),  # not scheduled
        ctl_msg("kill", "flyer", 0.5),  # before its time
        *[ctl_msg("restart", "flyer", 3.0) for _ in range(5)],  # flyer is alive: no restart
    ]
    for item in hostile:
        launcher._on_item(item)
    assert launcher.procs == {} and launcher.collected.kills == []
    assert dict(launcher.collected.rejected_by_reason) == {
        "unknown_target": 1,
        "unknown_sender": 1,
        "unscheduled": 7,
    }


def test_inbox_drops_oversized_payloads_before_queueing_and_is_bounded_in_bytes():
    session = open_session(TransportSettings())
    inbox = Inbox(max_message_bytes=1000, capacity_bytes=10 * (500 + 256))
    try:
        inbox.subscribe(session, "relloc/fuzz/**")
        time.sleep(0.2)
        for _ in range(3):
            session.put("relloc/fuzz/big", b"\x00" * 5_000_000)
        for _ in range(20):
            session.put("relloc/fuzz/small", b"\x00" * 500)
        deadline = time.monotonic() + 10
        while inbox.oversized + inbox.overflow < 13 and time.monotonic() < deadline:
            time.sleep(0.05)
        assert inbox.oversized == 3
        assert inbox.overflow == 10 and inbox.queued_bytes == 10 * (500 + 256)
        assert len(inbox.drain()) == 10 and inbox.queued_bytes == 0
    finally:
        inbox.close()
        session.close()
