"""A real :class:`~relloc.runtime.node.RobotNode` driven by hand: its estimator, its publishers
on a real, unconnected Zenoh session, and what its inbox would hand it — the clock's ticks, the
teammates' appearances and messages — given one by one (no clock or teammate process)."""

from __future__ import annotations

from typing import Any

import numpy as np

from relloc.runtime import keys
from relloc.runtime.messages import encode
from relloc.runtime.node import NodeSettings, RobotNode
from relloc.runtime.transport import Incoming, TransportSettings, declare_publisher

TEAM = "team"
DT = 0.1
TICKS = 20
DURATION_S = DT * TICKS


def hand_node(parts: Any, robot: str, session: Any, **extra: Any) -> RobotNode:
    """The node of ``robot`` with every teammate and the clock present."""
    s = NodeSettings(
        team=TEAM,
        robot=robot,
        roster=parts.roster,
        transport=TransportSettings(),
        **extra,
    )
    node = RobotNode(s, parts.source, parts.driver)
    node._session = session
    for kind in keys.ROBOT_KINDS:
        node._pubs[kind] = declare_publisher(session, keys.robot_key(TEAM, f"fuzz{robot}", kind))
    node._on_presence("clock", True)
    for mate in parts.roster:
        if mate != robot:
            node._on_presence(mate, True)
    return node


def tick(node: RobotNode, k: int) -> None:
    """The clock's tick ``k`` of :data:`TICKS` (``t_k = k·DT``)."""
    body = {"k": k, "n": TICKS, "dt": DT}
    node._on_incoming(
        Incoming(keys.clock_key(TEAM, "tick"), encode("tick", "clock", k, k * DT, body))
    )


UNICYCLE = (0.1, 0.0, 0.0, 0.05)
"""The velocity ``(v_x, v_y, v_z, ω)`` of every odometry sample :func:`odom` sends."""


def odom(sender: str, seq: int, t: float) -> Incoming:
    """Teammate ``sender``'s odometry message sent at ``t``: one sample half a tick before, at
    :data:`UNICYCLE` (a velocity every estimator models)."""
    body = {"stamps": [t - DT / 2], "u": np.array([UNICYCLE])}
    return Incoming(keys.robot_key(TEAM, sender, "odom"), encode("odom", sender, seq, t, body))
