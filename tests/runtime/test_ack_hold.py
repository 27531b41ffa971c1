"""The ack a node holds so that the clock never runs ``max_lag_ticks`` ahead of a window still
waiting for inputs that are on their way (:meth:`relloc.runtime.node.RobotNode._send_due_acks`).

A real node is driven by hand (``node_harness``): ticks, its teammates' odometry and, for a
talking leader, its teammate's progress. With ``max_lag_ticks`` L = 5 and Δt = 0.1 s, a window
ending at 0.4 s is overdue at the tick of 0.9 s, so the ack of the tick of 0.8 s is the one
held while it still waits.
"""

from __future__ import annotations

import time
from typing import Any

import pytest
from node_harness import DT, DURATION_S, TEAM, hand_node, odom, tick

from relloc.experiments.team_sources import named_node_parts, sharma_node_parts
from relloc.runtime import keys
from relloc.runtime import node as node_module
from relloc.runtime.faults import FaultSettings
from relloc.runtime.mail import mail_body
from relloc.runtime.messages import DEFAULT_MAX_BYTES, encode
from relloc.runtime.node import RobotNode
from relloc.runtime.transport import Incoming

HELD_TICK = 8


def _agent(session: Any, **extra: Any) -> tuple[RobotNode, list[str]]:
    parts = sharma_node_parts("1", 5, 0, DURATION_S, "two_landmarks")
    node = hand_node(parts, "1", session, **extra)
    return node, [r for r in parts.roster if r != "1"]


def _ticks(node: RobotNode, mates: list[str], ks: range, silent: str = "") -> None:
    """Ticks ``ks``, each followed by every teammate's odometry of it but ``silent``'s."""
    for k in ks:
        tick(node, k)
        for m in mates:
            if m != silent:
                node._on_incoming(odom(m, k - 1, k * DT))


def test_a_window_waiting_for_a_teammate_holds_the_ack_until_its_odometry_arrives(session):
    node, mates = _agent(session)
    _ticks(node, mates, range(1, 4))
    _ticks(node, mates, range(4, HELD_TICK + 1), silent="3")  # "3"'s link stalls from 0.3 s
    assert node.counters["sent.ack"] == HELD_TICK - 1 and node.counters["acks_held"] == 1
    for k in range(4, HELD_TICK + 1):  # the stall ends: its messages come, in order
        node._on_incoming(odom("3", k - 1, k * DT))
    assert node.counters["sent.ack"] == HELD_TICK
    assert node.counters["overdue_windows"] == 0 and node.counters["acks_held_expired"] == 0
    assert node._filtered_until == pytest.approx(HELD_TICK * DT)


def test_a_held_ack_goes_after_its_wall_time_and_the_window_is_then_overdue(session, monkeypatch):
    monkeypatch.setattr(node_module, "ACK_HOLD_S", 0.05)
    node, mates = _agent(session)
    _ticks(node, mates, range(1, 4))
    _ticks(node, mates, range(4, HELD_TICK + 1), silent="3")
    assert node.counters["sent.ack"] == HELD_TICK - 1
    time.sleep(0.06)
    node._send_due_acks()  # what the node's loop does when the hold's time is up
    assert node.counters["sent.ack"] == HELD_TICK and node.counters["acks_held_expired"] == 1
    _ticks(node, mates, range(HELD_TICK + 1, HELD_TICK + 2), silent="3")
    assert node.counters["overdue_windows"] == 1  # filtered without "3"'s odometry, counted


def test_a_departure_releases_the_held_ack(session):
    node, mates = _agent(session)
    _ticks(node, mates, range(1, 4))
    _ticks(node, mates, range(4, HELD_TICK + 1), silent="3")
    assert node.counters["sent.ack"] == HELD_TICK - 1
    node._on_presence("3", False)  # killed: nothing more will come from it
    assert node.counters["sent.ack"] == HELD_TICK and node.counters["overdue_windows"] == 0


def test_with_emulated_faults_no_ack_is_held(session):
    """The emulator releases what it delays only at ticks: a hold would stall the team."""
    node, mates = _agent(session, faults=FaultSettings(delay_ms=1.0))
    _ticks(node, mates, range(1, HELD_TICK + 3), silent="3")
    assert node.counters["sent.ack"] == HELD_TICK + 2 and node.counters["acks_held"] == 0


def test_a_restarted_agent_waiting_for_the_team_belief_holds_no_ack(session):
    """Its handoff retries count ticks, so it must not stop them."""
    node, mates = _agent(session)
    _ticks(node, mates, range(3, 3 + 2 * HELD_TICK))  # first tick heard: 3, nobody answers
    assert node._handoff.waiting and node.counters["sent.ack"] == 2 * HELD_TICK
    assert node.counters["acks_held"] == 0


def test_a_leader_waiting_for_the_other_leaders_progress_holds_the_ack_until_it_comes(session):
    parts = named_node_parts("desilva2015", "L1", 5, 0, DURATION_S)
    node = hand_node(parts, "L1", session, talkers=parts.talkers)
    mates = [r for r in parts.roster if r != "L1"]

    def progress(seq: int, t: float) -> None:
        body = mail_body(t, [], parts.roster, DEFAULT_MAX_BYTES)[0]
        key = keys.robot_key(TEAM, "L2", "mail")
        node._on_incoming(Incoming(key, encode("mail", "L2", seq, t, body)))

    for k in range(1, 4):
        _ticks(node, mates, range(k, k + 1))
        progress(k - 1, k * DT)
    _ticks(node, mates, range(4, HELD_TICK + 1))  # L2's progress stalls at 0.3 s
    assert node.counters["sent.ack"] == HELD_TICK - 1 and node.counters["acks_held"] == 1
    progress(3, HELD_TICK * DT)
    assert node.counters["sent.ack"] == HELD_TICK and node.counters["overdue_windows"] == 0
