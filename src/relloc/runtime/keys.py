"""Zenoh key expressions of a relloc team (the documented wire layout).

| key expression                          | payload (see :mod:`relloc.runtime.messages`) |
|-----------------------------------------|----------------------------------------------|
| ``relloc/<team>/robot/<id>/odom``       | ``odom``: the robot's body velocities        |
| ``relloc/<team>/robot/<id>/meas``       | ``meas``: its range/azimuth/elevation of a teammate |
| ``relloc/<team>/robot/<id>/eqm``        | ``eqm``: its belief of a teammate (1 Hz broadcast) |
| ``relloc/<team>/robot/<id>/rows``       | ``rows``: its readings, shared (seed 001) |
| ``relloc/<team>/robot/<id>/mail``       | ``mail``: its estimator's messages to teammates |
| ``relloc/<team>/robot/<id>/sync``       | ``sync``: team belief asked for / handed over |
| ``relloc/<team>/robot/<id>/est``        | ``est``: its estimates, for the collector    |
| ``relloc/<team>/robot/<id>/evt``        | ``evt``: its track events, for the collector |
| ``relloc/<team>/robot/<id>/stats``      | ``stats``: its message and estimate counters |
| ``relloc/<team>/robot/<id>/ack``        | ``ack``: it finished a clock tick            |
| ``relloc/<team>/robot/<id>/cmd``        | ``cmd``: its command to the world (seed 003) |
| ``relloc/<team>/clock/tick``            | ``tick``: simulated time from the clock      |
| ``relloc/<team>/clock/ctl``             | ``ctl``: kill / restart / end events         |
| ``relloc/<team>/clock/sense``           | ``sense``: a robot's readings (seed 003)     |
| ``relloc/<team>/alive/<id>`` (liveliness) | token held while the process lives          |
| ``relloc/<team>/ready/<id>`` (liveliness) | held once the robot has seen every teammate |

Robot and team ids are restricted to ``[A-Za-z0-9_-]`` so they can never inject the wildcard or
separator characters of a key expression; no robot may be named ``clock`` (:data:`CLOCK_ID`).
"""

from __future__ import annotations

import re

from relloc.errors import ConfigError

ROBOT_KINDS = ("odom", "meas", "rows", "eqm", "mail", "est", "evt", "stats", "ack", "cmd", "sync")
CLOCK_KINDS = ("tick", "ctl", "sense")
PRESENCE_TOKENS = ("alive", "ready")
CLOCK_ID = "clock"
"""The id of the clock (or world) process: its ``alive`` token and the sender of its messages.
No robot may take it."""
_ID = re.compile(r"[A-Za-z0-9_-]{1,64}")


def check_id(value: str, field: str) -> str:
    """Return ``value`` if it is a valid team/robot id, else raise ConfigError naming ``field``."""
    if not isinstance(value, str) or not _ID.fullmatch(value):
        raise ConfigError(f"{field}: {value!r} is not a valid id (letters, digits, '_', '-')")
    return value


def check_robot_id(value: str, field: str) -> str:
    """:func:`check_id`, and not :data:`CLOCK_ID`: a robot of that id would be taken for the
    clock process (its token, its messages)."""
    check_id(value, field)
    if value == CLOCK_ID:
        raise ConfigError(f"{field}: {value!r} is reserved for the clock process")
    return value


def robot_key(team: str, robot: str, kind: str) -> str:
    """``relloc/<team>/robot/<robot>/<kind>``."""
    if kind not in ROBOT_KINDS:
        raise ConfigError(f"robot_key: unknown kind {kind!r}")
    return f"relloc/{team}/robot/{robot}/{kind}"


def robot_wildcard(team: str, kind: str) -> str:
    """Every robot's ``kind`` stream: ``relloc/<team>/robot/*/<kind>``."""
    return robot_key(team, "*", kind)


def clock_key(team: str, kind: str) -> str:
    """``relloc/<team>/clock/<kind>`` for a kind of :data:`CLOCK_KINDS`."""
    if kind not in CLOCK_KINDS:
        raise ConfigError(f"clock_key: unknown kind {kind!r}")
    return f"relloc/{team}/clock/{kind}"


def alive_key(team: str, member: str) -> str:
    """Liveliness token of one team member (a robot id or ``clock``)."""
    return f"relloc/{team}/alive/{member}"


def alive_wildcard(team: str) -> str:
    return f"relloc/{team}/alive/*"


def ready_key(team: str, member: str) -> str:
    """Liveliness token a robot declares once it has seen every teammate's ``alive`` token.

    Zenoh propagates a session's declarations in order and a robot declares its subscribers
    before its ``alive`` token, so a robot that has seen a teammate's token also knows that
    teammate's subscriptions: once every robot is ready, no first message is lost to a
    subscription still in flight. Seeing a teammate's token says nothing about whether the
    teammate knows this robot's subscriptions, so a robot of the air-ground team declares its
    token again when a teammate's ``alive`` token appears after it was ready (a restart), and
    the world resumes once every present robot has done so
    (:mod:`relloc.runtime.airground`).
    """
    return f"relloc/{team}/ready/{member}"


def ready_wildcard(team: str) -> str:
    return f"relloc/{team}/ready/*"


def parse_robot_key(key: str) -> tuple[str, str] | None:
    """``(robot, kind)`` of a robot key expression, or None if it is not one."""
    if not isinstance(key, str):
        return None
    parts = key.split("/")
    if len(parts) == 5 and parts[0] == "relloc" and parts[2] == "robot" and parts[4] in ROBOT_KINDS:
        return parts[3], parts[4]
    return None


def parse_clock_key(key: str) -> str | None:
    """The kind (one of :data:`CLOCK_KINDS`) of a clock key expression, or None if it is not
    one."""
    if not isinstance(key, str):
        return None
    parts = key.split("/")
    if len(parts) == 4 and parts[0] == "relloc" and parts[2] == "clock":
        if parts[3] in CLOCK_KINDS:
            return parts[3]
    return None


def parse_presence_key(key: str) -> tuple[str, str] | None:
    """``(token kind, member)`` of a liveliness key ``relloc/<team>/<kind>/<member>`` (kind
    ``alive`` or ``ready``), or None for any other key: a liveliness subscriber of
    :func:`alive_wildcard` hears every token whose key overlaps it, so a peer's wildcard token
    (``relloc/<team>/**``) reaches it too, and is ignored like a member off the roster."""
    parts = key.split("/") if isinstance(key, str) else []
    if len(parts) != 4 or parts[0] != "relloc" or parts[2] not in PRESENCE_TOKENS:
        return None
    if any(not part or "*" in part for part in parts):
        return None
    return parts[2], parts[3]
