"""A robot hears on its own keys only what another process sent there: its subscriptions to
the team's robot keys are remote-only (Zenoh's ``Locality.REMOTE``), so a message on them
claims its identity — a spoofer, or a second process started with the same id — and is
counted (``rejected.own_key``), not dropped as the robot's own echo."""

from __future__ import annotations

import time

from node_harness import TEAM, hand_node, odom, tick

from relloc.experiments.team_sources import sharma_node_parts
from relloc.runtime import keys
from relloc.runtime.airground import LeaderRole, RobotProcess, RobotSettings
from relloc.runtime.messages import encode
from relloc.runtime.transport import (
    Inbox,
    Incoming,
    TransportSettings,
    declare_publisher,
    free_loopback_port,
    open_session,
)
from relloc.sim.airground import AirGroundScenario


def test_a_remote_only_subscription_hears_other_sessions_and_not_its_own():
    endpoint = f"tcp/127.0.0.1:{free_loopback_port()}"
    here = open_session(TransportSettings(listen=(endpoint,)))
    there = open_session(TransportSettings(connect=(endpoint,)))
    remote, every = Inbox(), Inbox()
    key = keys.robot_key(TEAM, "r1", "odom")
    try:
        remote.subscribe(here, keys.robot_wildcard(TEAM, "odom"), remote_only=True)
        every.subscribe(here, keys.robot_wildcard(TEAM, "odom"))
        mine = declare_publisher(here, key)
        theirs = declare_publisher(there, key)
        heard: list[bytes] = []
        deadline = time.monotonic() + 10.0
        while not heard and time.monotonic() < deadline:  # until the sessions are linked
            theirs.put(b"there")
            item = remote.get(timeout=0.2)
            heard += [] if item is None else [item.payload]
        assert heard and set(heard) == {b"there"}
        while remote.get(timeout=0.2) is not None:  # the rest of the link's warm-up
            pass
        while every.get(timeout=0.05) is not None:
            pass
        mine.put(b"here")
        theirs.put(b"there")
        assert [remote.get(timeout=2.0).payload, remote.get(timeout=0.5)] == [b"there", None]
        both = {every.get(timeout=2.0).payload, every.get(timeout=2.0).payload}
        assert both == {b"here", b"there"}
    finally:
        remote.close()
        every.close()
        there.close()
        here.close()


def test_a_node_counts_a_message_on_its_own_key(session):
    parts = sharma_node_parts("1", 5, 0, 2.0, "two_landmarks")
    node = hand_node(parts, "1", session, share_rows=True)
    tick(node, 1)
    delivered = node.counters["delivered.odom"]
    node._on_incoming(odom("1", 0, 0.1))  # "1"'s odometry, not sent by this process
    assert node.counters["rejected.own_key"] == 1
    assert node.counters["delivered.odom"] == delivered
    node._on_incoming(odom("3", 0, 0.1))  # a teammate's is used as before
    assert node.counters["delivered.odom"] == delivered + 1


def test_an_air_ground_robot_counts_a_message_on_its_own_key(session):
    sc = AirGroundScenario(offsets=((0.5, 0.5), (-0.5, 0.5)), offset_frame="global", duration=0.5)
    settings = RobotSettings(team=TEAM, robot="R_0", transport=TransportSettings())
    proc = RobotProcess(settings, sc, LeaderRole(sc))
    for kind in ("rows", "odom", "cmd", "est", "stats"):
        proc._pubs[kind] = declare_publisher(session, keys.robot_key(TEAM, "xR_0", kind))
    body = {"stamps": [0.05], "u": [[0.1, 0.0, 0.0, 0.0]]}
    proc._handle(Incoming(keys.robot_key(TEAM, "R_0", "odom"), encode("odom", "R_0", 0, 0.1, body)))
    assert proc.counters["rejected.own_key"] == 1 and proc.counters["rejected"] == 1
