"""Hostile ``rows`` and ``mail`` payloads through a robot node's whole receive path.

A real :class:`~relloc.runtime.node.RobotNode` — seed 001's agent (sharing ``rows``) and seed
002's leader (exchanging ``mail``) — with its estimator and a real, unconnected Zenoh session
for its publications, is handed the clock's ticks and a teammate's messages exactly as its
inbox would: decode, admission (roles, time bound, rate), sequence numbers, the link, the
``rows``/``mail`` decoders, and the estimator, which filters the windows they land in (or
re-filters the past for late readings). Hypothesis draws payloads that decode — any kind, any
subject and landmark or sensor index, extreme and tiny values and σ, absurd and unsorted
stamps, non-positive-definite covariances, wrong lengths — and the node must count each as
rejected or use it, never raise, and keep filtering to the end of the run (run with
``-W error::RuntimeWarning`` these tests also show that no overflow reaches a filter).

The same path with well-formed messages from a teammate whose appearance (its liveliness
token) has not reached the node yet — liveliness and data travel separately, so a restarted
teammate's first messages can come first: they are held and delivered, in order, when it
appears, and counted as not delivered if it never does.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import msgpack
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from node_harness import DT, DURATION_S, TEAM, TICKS, hand_node, odom, tick

from relloc.core.recording import KIND_NAMES, KINDS
from relloc.experiments.team_sources import named_node_parts, sharma_node_parts
from relloc.runtime import keys
from relloc.runtime.messages import SCHEMA, SCHEMA_VERSION
from relloc.runtime.node import HELD_FROM_ABSENT, RobotNode
from relloc.runtime.transport import Incoming

EXTREME = [0.0, -0.0, 1.0, -1.0, 1e-300, -1e-300, 1e300, -1e300, 2.0**63, 1e12, -1e12, 0.5]
numbers = st.one_of(st.sampled_from(EXTREME), st.floats(-1e3, 1e3, allow_nan=False))
offsets = st.one_of(
    st.sampled_from([-1e12, -1.0, -0.7, -0.1, -0.05, 0.0, 0.05, 0.1, 1e12]),
    st.floats(-1.5, 2.5, allow_nan=False),
)
"""Stamps as offsets from the tick they are sent at."""
SHARED_FIELDS = tuple(SCHEMA["rows"])


def _raw(kind: str, sender: str, seq: int, t: float, body: dict[str, Any]) -> bytes:
    """A payload as a hostile sender packs it (no validation on the way out)."""
    header = {"v": SCHEMA_VERSION, "type": kind, "sender": sender, "seq": seq, "t": t, "wall_ns": 1}
    return msgpack.packb(header | body, use_bin_type=True)


def _run(node: RobotNode, sender: str, kind: str, drawn: list[tuple[dict, int, float]]) -> None:
    """Ticks 1..n; after each of the first ticks ``k``, one hostile payload ``(body, seq,
    header time offset)`` whose stamps are offsets from ``t_k`` (so that they land in past,
    pending and future windows): each is rejected (counted) or taken in; every window is
    filtered by the end (overdue ones too: the teammates send nothing else)."""
    key = keys.robot_key(TEAM, sender, kind)
    for k in range(1, TICKS + 1):
        tick(node, k)
        if k <= len(drawn):
            body, seq, offset = drawn[k - 1]
            body = body | {"stamps": [k * DT + s for s in body["stamps"]]}
            if "progress" in body:
                body["progress"] = k * DT + body["progress"]
            payload = _raw(kind, sender, seq, max(0.0, k * DT + offset), body)
            before = (node.counters["rejected"], node.counters[f"wire.{kind}"])
            node._on_incoming(Incoming(key, payload))
            after = (node.counters["rejected"], node.counters[f"wire.{kind}"])
            assert after != before, dict(node.counters)
    node._finish()
    assert node.counters["final"] == 1 and not node._pending
    assert node.counters["ticks"] == TICKS


@st.composite
def valid_rows(draw: Any, roster: tuple[str, ...]) -> dict[str, Any]:
    """Readings a well-formed sender could send, with extreme values and σ, any robot or
    landmark (known or not) as subject, stamps around the current tick."""
    times = sorted(draw(st.lists(offsets, min_size=1, max_size=4, unique=True)))
    out: dict[str, list[Any]] = {name: [] for name in SHARED_FIELDS}
    for t in times:
        kind = draw(st.sampled_from(("bearing", "bearing", "pose", "range_bearing", "range")))
        landmark = draw(st.sampled_from([-1.0, -1.0, 0.0, 1.0, 7.0, 1e6]))
        subject = "" if landmark >= 0 else draw(st.sampled_from([*roster, ""]))
        dim = KINDS[kind].dim
        values = draw(st.lists(numbers, min_size=dim, max_size=dim))
        if kind in ("range", "range_bearing"):
            values[0] = abs(values[0]) or 1.0
        out["stamps"].append(t)
        out["kinds"].append(kind)
        out["subjects"].append(subject)
        out["landmarks"].append(landmark)
        out["sensors"].append(draw(st.sampled_from([0.0, 0.0, 3.0, 1e6])))
        out["values"] += values
        sigma = st.sampled_from([0.01, 0.1, -1.0, 1e-300, 1e-9, 1e300])
        out["sigmas"] += draw(st.lists(sigma, min_size=dim, max_size=dim))
    return out


@st.composite
def rows_bodies(draw: Any, roster: tuple[str, ...]) -> dict[str, Any]:
    """A valid body, perhaps with one field replaced by hostile content."""
    body = draw(valid_rows(roster))
    if draw(st.booleans()):
        name = draw(st.sampled_from(SHARED_FIELDS))
        strings = st.lists(st.sampled_from([*roster, "", "x", *KIND_NAMES]), max_size=5)
        junk = st.lists(
            st.one_of(numbers, st.sampled_from([-2.0, 0.5, 1e300, 2.0**62])), max_size=9
        )
        body[name] = draw(strings if name in ("kinds", "subjects") else junk)
    return body


@settings(
    derandomize=True,
    max_examples=25,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)
@given(data=st.data())
def test_hostile_rows_are_counted_or_fused_and_never_crash_an_agent(session, data):
    parts = sharma_node_parts("1", 5, 0, DURATION_S, "two_landmarks")
    node = hand_node(parts, "1", session, share_rows=True)
    drawn = data.draw(
        st.lists(
            st.tuples(rows_bodies(parts.roster), st.integers(0, 40), offsets),
            min_size=1,
            max_size=8,
        )
    )
    _run(node, "2", "rows", drawn)


_ROWS = {
    "stamps": [0.1, 0.2],
    "kinds": ["range", "bearing"],
    "subjects": ["2", ""],
    "landmarks": [-1.0, 0.0],
    "sensors": [0.0, 0.0],
    "values": [3.0, 0.5],
    "sigmas": [0.1, -1.0],
}


@pytest.mark.parametrize(
    ("change", "reason", "what"),
    [
        ({"subjects": ["9", ""]}, "unknown_target", "rows: subjects ['9'] are not on the roster"),
        ({"landmarks": [-1.0, 0.5]}, "malformed", "landmarks and sensors must be integers"),
        ({"landmarks": [-2.0, 0.0]}, "malformed", "landmarks and sensors must be integers"),
        ({"sensors": [0.0, 2.0**40]}, "malformed", "landmarks and sensors must be integers"),
        ({"sigmas": [0.1, 0.0]}, "malformed", "rows: sigma must be > 0"),
        ({"sigmas": [-0.5, -1.0]}, "malformed", "rows: sigma must be > 0"),
    ],
)
def test_a_hostile_rows_table_is_refused_naming_the_rule(change, reason, what):
    """Tables that pass the wire check but no robot writes: a subject off the roster, a
    fractional, negative or huge landmark or sensor index, a σ ≤ 0 other than −1 (not
    stated)."""
    from relloc.runtime.messages import MessageRejected, decode
    from relloc.runtime.shared_rows import rows_from_body

    roster = ("1", "2", "3")
    assert (
        rows_from_body(
            decode(_raw("rows", "1", 0, 0.2, _ROWS), roster=roster).body, roster, "1"
        ).size
        == 2
    )
    body = decode(_raw("rows", "1", 0, 0.2, _ROWS | change), roster=roster).body
    with pytest.raises(MessageRejected) as info:
        rows_from_body(body, roster, "1")
    assert info.value.reason == reason and what in str(info.value)


def _matrix(kind: str, scale: float) -> list[list[float]]:
    """A 4×4 symmetric matrix with non-negative diagonal: positive definite, singular, or
    indefinite (what decode lets through)."""
    m = np.eye(4) * scale
    if kind == "singular":
        m[0, 0] = 0.0
    elif kind == "indefinite":
        m[0, 1] = m[1, 0] = 2.0 * scale
    return m.tolist()


@st.composite
def mail_bodies(draw: Any, roster: tuple[str, ...]) -> dict[str, Any]:
    """A mail of 1–3 equivalent measurements with extreme means, covariances that need not be
    positive definite, any subject and absurd progress."""
    m = draw(st.integers(1, 3))
    sizes = draw(st.lists(st.integers(1, 2), min_size=m, max_size=m))
    k = sum(sizes)
    shape = draw(st.sampled_from(["pd", "pd", "pd", "singular", "indefinite"]))
    matrices = st.builds(_matrix, st.just(shape), st.sampled_from([1e-300, 1e-6, 1.0, 1e300]))
    vectors = st.lists(numbers, min_size=4, max_size=4)
    return {
        "progress": draw(st.one_of(offsets, st.sampled_from([1e300, -1e300]))),
        "stamps": sorted(draw(st.lists(offsets, min_size=m, max_size=m))),
        "subjects": draw(st.lists(st.sampled_from([*roster, "x"]), min_size=m, max_size=m)),
        "sizes": [float(s) for s in sizes],
        "means": draw(st.lists(vectors, min_size=k, max_size=k)),
        "covs": draw(st.lists(matrices, min_size=k, max_size=k)),
        "prior_means": draw(st.lists(vectors, min_size=k, max_size=k)),
        "prior_covs": draw(st.lists(matrices, min_size=k, max_size=k)),
        "weights": draw(
            st.lists(st.sampled_from([0.0, 1e-300, 0.5, 1.0, 1e300]), min_size=k, max_size=k)
        ),
    }


@settings(
    derandomize=True,
    max_examples=15,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)
@given(data=st.data())
def test_hostile_mail_is_counted_or_fused_and_never_crashes_a_leader(session, data):
    parts = named_node_parts("desilva2015", "L1", 5, 0, DURATION_S)
    node = hand_node(parts, "L1", session, talkers=parts.talkers)
    drawn = data.draw(
        st.lists(
            st.tuples(mail_bodies(parts.roster), st.integers(0, 40), offsets),
            min_size=1,
            max_size=8,
        )
    )
    _run(node, "L2", "mail", drawn)


@st.composite
def odom_bodies(draw: Any) -> dict[str, Any]:
    """A teammate's odometry: 1–3 samples at stamps around the current tick, velocities of
    any size (absurd ones included) and, for half of them, with lateral or vertical velocity
    (what seed 001's unicycle filter cannot take)."""
    n = draw(st.integers(1, 3))
    stamps = sorted(draw(st.lists(offsets, min_size=n, max_size=n, unique=True)))
    u = draw(st.lists(st.lists(numbers, min_size=4, max_size=4), min_size=n, max_size=n))
    if draw(st.booleans()):
        for row in u:
            row[1] = row[2] = 0.0
    return {"stamps": stamps, "u": u}


def _node_of(which: str, session: Any) -> tuple[RobotNode, str]:
    """Seed 001's agent ``1`` (a unicycle team filter, teammate ``2``) or seed 002's leader
    ``L1`` with a pod ``P1`` or a leader ``L2`` as the teammate."""
    if which == "sharma":
        return hand_node(
            sharma_node_parts("1", 5, 0, DURATION_S, "two_landmarks"), "1", session
        ), "2"
    parts = named_node_parts("desilva2015", "L1", 5, 0, DURATION_S)
    return hand_node(parts, "L1", session, talkers=parts.talkers), which


@settings(
    derandomize=True,
    max_examples=30,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)
@given(data=st.data())
def test_hostile_odometry_is_counted_or_used_and_never_crashes_a_node(session, data):
    """One teammate's decodable odometry once killed a node: a lateral velocity raised in seed
    001's unicycle filter, and 1e154 m/s reached seed 002's fuser as NaN. Now every such
    message is refused (``not_unicycle``, ``out_of_range``, ``past``) or used, the node
    filters to the end and its beliefs stay finite."""
    node, sender = _node_of(data.draw(st.sampled_from(["sharma", "P1", "L2"])), session)
    drawn = data.draw(
        st.lists(st.tuples(odom_bodies(), st.integers(0, 40), offsets), min_size=1, max_size=8)
    )
    _run(node, sender, "odom", drawn)
    for belief in node.estimator.beliefs():
        assert np.all(np.isfinite(belief.mean)) and np.all(np.isfinite(belief.cov))


def test_a_lateral_velocity_is_refused_for_a_unicycle_team_and_a_repeated_stamp_counted(session):
    node, sender = _node_of("sharma", session)
    key = keys.robot_key(TEAM, sender, "odom")
    tick(node, 1)
    lateral = {"stamps": [0.05], "u": [[0.1, 0.05, 0.0, 0.0]]}
    node._on_incoming(Incoming(key, _raw("odom", sender, 0, 0.1, lateral)))
    assert node.counters["rejected.not_unicycle"] == 1 and node.counters["delivered.odom"] == 0
    for seq, v in ((1, 0.1), (2, 0.2)):  # two messages, one stamp: the second is not filed
        node._on_incoming(
            Incoming(
                key,
                _raw("odom", sender, seq, 0.1, {"stamps": [0.06]} | {"u": [[v, 0.0, 0.0, 0.0]]}),
            )
        )
    for k in range(2, TICKS + 1):
        tick(node, k)
    node._finish()
    counters = node.final_counters()
    assert counters["delivered.odom"] == 2 and counters["duplicate_samples"] == 1
    assert node.teammates[sender].odometry.held_at(np.array([0.07]))[0, 0] == 0.1


def test_a_teammate_heard_before_its_appearance_is_delivered_when_it_appears(session):
    parts = sharma_node_parts("1", 5, 0, DURATION_S, "two_landmarks")
    node = hand_node(parts, "1", session, share_rows=True)
    for k in (1, 2, 3):
        tick(node, k)
    node._on_presence("3", False)  # killed: its token went
    mate = node.teammates["3"]
    assert not mate.present and node.counters["teammate.departures"] == 1
    tick(node, 4)
    delivered = node.counters["delivered.odom"]
    # restarted: its first messages (sequence numbers from 0 again) before its token
    node._on_incoming(odom("3", 0, 0.4))
    node._on_incoming(odom("3", 1, 0.5))
    assert node.counters["held_from_absent.odom"] == 2
    assert node.counters["delivered.odom"] == delivered and mate.heard_until_s is None
    node._on_presence("3", True)
    assert node.counters["delivered.odom"] == delivered + 2 and mate.held == []
    assert mate.heard_until_s == 0.5 and mate.odometry.last_stamp == 0.45
    assert node.counters["from_absent.odom"] == 0


def test_what_a_teammate_that_never_appears_again_sent_is_counted_at_the_end(session):
    parts = sharma_node_parts("1", 5, 0, DURATION_S, "two_landmarks")
    node = hand_node(parts, "1", session, share_rows=True)
    tick(node, 1)
    node._on_presence("3", False)
    node._on_incoming(odom("3", 0, 0.2))  # sent before it died, heard after its token went
    for k in range(2, TICKS + 1):
        tick(node, k)
    node._finish()
    assert node.counters["held_from_absent.odom"] == 1
    assert node.counters["from_absent.odom"] == 1 and node.teammates["3"].held == []


def test_what_is_held_for_an_absent_teammate_is_bounded(session):
    """An impostor (or a teammate whose token never comes) sending at its rate budget fills at
    most :data:`HELD_FROM_ABSENT` messages; the rest are dropped and counted."""
    parts = sharma_node_parts("1", 5, 0, DURATION_S, "two_landmarks")
    node = hand_node(parts, "1", session, share_rows=True)
    tick(node, 1)
    node._on_presence("3", False)
    sent = 0
    for k in range(2, 12):
        tick(node, k)
        for _ in range(30):
            node._on_incoming(odom("3", sent, k * DT))
            sent += 1
    assert sent > HELD_FROM_ABSENT and node.counters["rejected"] == 0
    assert len(node.teammates["3"].held) == HELD_FROM_ABSENT
    assert node.counters["held_from_absent.odom"] == HELD_FROM_ABSENT
    assert node.counters["from_absent.odom"] == sent - HELD_FROM_ABSENT


def test_a_token_of_a_stranger_is_counted_and_changes_nobodys_presence(session):
    parts = sharma_node_parts("1", 5, 0, DURATION_S, "two_landmarks")
    node = hand_node(parts, "1", session)
    present = {r: m.present for r, m in node.teammates.items()}
    for member, change in (("mallory", "joined"), ("1", "joined"), ("mallory", "left")):
        node._on_incoming(Incoming(keys.alive_key(TEAM, member), b"", presence=change))
    assert node.counters["presence.unknown_member"] == 2  # its own token is no stranger's
    assert {r: m.present for r, m in node.teammates.items()} == present


def test_mail_stamped_before_a_restarted_leader_started_is_counted_not_fused(session):
    """A leader that joins at tick 5 has no state before ``t_4``: a teammate's messages of an
    earlier event cannot reach its estimator; they are counted ``mail_before_start``."""
    from relloc.fusion.messages import EquivalentMeasurement
    from relloc.runtime.mail import mail_body
    from relloc.runtime.messages import encode

    parts = named_node_parts("desilva2015", "L1", 5, 0, DURATION_S)
    node = hand_node(parts, "L1", session, talkers=parts.talkers)
    tick(node, 5)
    roster = parts.roster
    em = EquivalentMeasurement(
        sender=roster.index("L2"),
        subject=roster.index("P1"),
        time=0.2,
        means=np.zeros((1, 4)),
        covs=np.eye(4)[None],
        prior_means=np.zeros((1, 4)),
        prior_covs=2 * np.eye(4)[None],
        weights=np.ones(1),
    )
    sent = [(0.2, em), (0.5, dataclasses.replace(em, time=0.5))]
    for seq, body in enumerate(mail_body(0.5, sent, roster, 65_536)):
        payload = encode("mail", "L2", seq, 0.5, body)
        node._on_incoming(Incoming(keys.robot_key(TEAM, "L2", "mail"), payload))
    assert node.counters["delivered.mail"] == 1 and node.counters["mail_before_start"] == 1
    assert node.teammates["L2"].progress == 0.5
    assert [stamp for stamp, *_ in node.estimator._inbox] == [0.5]  # the later one only
