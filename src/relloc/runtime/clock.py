"""The clock/simulator process: drives simulated time for a team of robot processes.

Protocol (key expressions in :mod:`relloc.runtime.keys`):

1. Wait until every robot on the roster holds its ``ready`` liveliness token (declared once it has
   seen every teammate's ``alive`` token, so all subscriptions are known everywhere — see
   :func:`relloc.runtime.keys.ready_key`).
2. For ``k = 1 … K``: apply the robot events due by ``t_k = k·Δt`` (a ``kill`` is published on
   ``clock/ctl`` and the clock waits until the victim's token is gone; a ``restart`` is
   published and the clock waits until the robot's token is back), publish ``tick(k, t_k)`` and
   wait until every *present* robot has acknowledged ``k`` — a barrier, so the team runs as fast
   as its slowest member. With ``realtime_factor > 0`` ticks are additionally paced to
   ``Δt / realtime_factor`` of wall time (``1`` = real time; used by the benchmark to check that
   robots keep their rates).
3. Publish ``ctl(end)`` and wait (bounded) for the robots to leave, so none of them misses it.

The barrier is what makes a distributed run comparable with the in-process run: everything a
robot published for ``[t_{k−1}, t_k)`` left before its ``ack(k)``, and nodes filter one tick
behind the clock, so in a perfect network every input has normally arrived before it is needed;
a node whose window still waits when the next tick would find it overdue holds its ack until
the input comes (bounded: :meth:`relloc.runtime.node.RobotNode._send_due_acks`).
A robot that does not acknowledge within ``ack_timeout_s`` of wall time is not waited for (the
clock counts it); a robot that disappears is dropped from the barrier.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from relloc.core.checks import number, positive
from relloc.errors import ConfigError, RellocError
from relloc.pipeline.output import write_json_file
from relloc.runtime import keys
from relloc.runtime.admission import admit
from relloc.runtime.faults import FaultSettings, RobotEvent
from relloc.runtime.messages import DEFAULT_MAX_BYTES, MessageRejected, encode
from relloc.runtime.transport import (
    Inbox,
    Roll,
    TransportSettings,
    declare_publisher,
    open_session,
)


@dataclass(frozen=True, kw_only=True)
class ClockSettings:
    """One clock run. ``tick_s`` is the simulated period of a tick (the odometry/measurement
    publication period of every robot); ``duration_s`` the simulated end time."""

    team: str
    roster: tuple[str, ...]
    tick_s: float
    duration_s: float
    transport: TransportSettings
    realtime_factor: float = 0.0
    ack_timeout_s: float = 10.0
    startup_timeout_s: float = 60.0
    kills: tuple[RobotEvent, ...] = ()
    restarts: tuple[RobotEvent, ...] = ()

    def __post_init__(self) -> None:
        keys.check_id(self.team, "clock.team")
        if not self.roster:
            raise ConfigError("clock.roster: no robots")
        for r in self.roster:
            keys.check_robot_id(r, "clock.roster")
        if len(set(self.roster)) != len(self.roster):
            raise ConfigError(f"clock.roster: a robot named twice in {','.join(self.roster)}")
        # a kill of a robot off the roster would keep the clock waiting for it forever
        FaultSettings(kills=self.kills, restarts=self.restarts).check_robots(self.roster)
        duration = positive(self.duration_s, "--duration")
        number(
            self.tick_s, "clock.tick_s (at most duration_s)", low=0.0, high=duration, open_low=True
        )
        number(self.realtime_factor, "--realtime", low=0.0)
        for name in ("ack_timeout_s", "startup_timeout_s"):
            positive(getattr(self, name), f"clock.{name}")

    @property
    def n_ticks(self) -> int:
        return int(np.rint(self.duration_s / self.tick_s))


@dataclass
class ClockReport:
    """What the clock observed; written to ``clock.json`` by the launcher."""

    ticks: int = 0
    wall_s: float = 0.0
    startup_wall_s: float = 0.0
    ack_timeouts: dict[str, int] = field(default_factory=dict)
    departures: list[dict[str, Any]] = field(default_factory=list)
    arrivals: list[dict[str, Any]] = field(default_factory=list)
    events: list[dict[str, Any]] = field(default_factory=list)
    max_tick_lag_s: float = 0.0
    rejected: int = 0
    rejected_by_reason: dict[str, int] = field(default_factory=dict)

    def as_dict(self) -> dict[str, Any]:
        return dict(self.__dict__)


class Clock:
    """Runs the protocol of the module docstring over one Zenoh session."""

    def __init__(self, settings: ClockSettings) -> None:
        self.s = settings
        self.report = ClockReport()
        self.roll = Roll(settings.roster)
        self._acks: set[str] = set()
        self._seq = 0
        self._t = 0.0

    def _publish(self, pub: Any, kind: str, body: dict[str, Any]) -> None:
        pub.put(encode(kind, keys.CLOCK_ID, self._seq, self._t, body))
        self._seq += 1

    def _handle(self, item: Any, waiting_k: int | None) -> None:
        if item.presence != "data":
            change = self.roll.update(item)
            if change is not None and change[0] == "alive":
                _, member, joined = change
                record = self.report.arrivals if joined else self.report.departures
                record.append({"robot": member, "t": self._t})
            return
        try:
            msg = admit(item.key, item.payload, roster=self.s.roster)
        except MessageRejected as exc:
            self.report.rejected += 1
            reasons = self.report.rejected_by_reason
            reasons[exc.reason] = reasons.get(exc.reason, 0) + 1
            return
        if msg.kind == "ack" and msg.body["k"] == waiting_k:
            self._acks.add(msg.sender)

    def _wait(self, inbox: Inbox, done: Any, timeout_s: float, waiting_k: int | None) -> bool:
        return inbox.wait_until(done, lambda item: self._handle(item, waiting_k), timeout_s)

    def run(self) -> ClockReport:
        s = self.s
        session = open_session(s.transport)
        inbox = Inbox(max_message_bytes=DEFAULT_MAX_BYTES)
        try:
            inbox.watch_presence(session, keys.alive_wildcard(s.team))
            inbox.watch_presence(session, keys.ready_wildcard(s.team))
            inbox.subscribe(session, keys.robot_wildcard(s.team, "ack"))
            tick_pub = declare_publisher(session, keys.clock_key(s.team, "tick"))
            ctl_pub = declare_publisher(session, keys.clock_key(s.team, "ctl"))
            token = session.liveliness().declare_token(keys.alive_key(s.team, keys.CLOCK_ID))
            start = time.monotonic()
            everyone = set(s.roster)
            if not self._wait(
                inbox, lambda: everyone <= self.roll.ready, s.startup_timeout_s, None
            ):
                missing = sorted(everyone - self.roll.ready)
                raise RellocError(f"clock: robots {missing} did not start within the timeout")
            self.report.startup_wall_s = time.monotonic() - start
            self._loop(inbox, tick_pub, ctl_pub)
            self._publish(ctl_pub, "ctl", {"action": "end", "robot": ""})
            self._wait(inbox, lambda: not self.roll.present, s.ack_timeout_s, None)
            token.undeclare()
        finally:
            inbox.close()
            session.close()
        return self.report

    def _loop(self, inbox: Inbox, tick_pub: Any, ctl_pub: Any) -> None:
        s = self.s
        pending = sorted(
            [("kill", e) for e in s.kills] + [("restart", e) for e in s.restarts],
            key=lambda item: item[1].at_s,
        )
        start = time.monotonic()
        for k in range(1, s.n_ticks + 1):
            self._t = k * s.tick_s
            while pending and pending[0][1].at_s <= self._t + 1e-9:
                action, event = pending.pop(0)
                self._robot_event(inbox, ctl_pub, action, event)
            if s.realtime_factor > 0:
                due = start + self._t / s.realtime_factor
                lag = time.monotonic() - due
                self.report.max_tick_lag_s = max(self.report.max_tick_lag_s, lag)
                if lag < 0:
                    time.sleep(-lag)
            self._acks = set()
            expected = set(self.roll.present)
            self._publish(tick_pub, "tick", {"k": k, "n": s.n_ticks, "dt": s.tick_s})
            acked = self._wait(
                inbox, lambda e=expected: e & self.roll.present <= self._acks, s.ack_timeout_s, k
            )
            if not acked:
                for robot in sorted((expected & self.roll.present) - self._acks):
                    self.report.ack_timeouts[robot] = self.report.ack_timeouts.get(robot, 0) + 1
            self.report.ticks = k
        self.report.wall_s = time.monotonic() - start

    def _robot_event(self, inbox: Inbox, ctl_pub: Any, action: str, event: RobotEvent) -> None:
        wall = time.monotonic()
        self._publish(ctl_pub, "ctl", {"action": action, "robot": event.robot})
        if action == "kill":
            ok = self._wait(inbox, lambda: event.robot not in self.roll.present, 30.0, None)
        else:
            ok = self._wait(inbox, lambda: event.robot in self.roll.ready, 60.0, None)
        self.report.events.append(
            {
                "action": action,
                "robot": event.robot,
                "at_s": self._t,
                "completed": ok,
                "wall_s": time.monotonic() - wall,
            }
        )


def run_clock(settings: ClockSettings, report_path: Path | None = None) -> ClockReport:
    """Run a clock to the end; optionally write its report as JSON."""
    report = Clock(settings).run()
    if report_path is not None:
        write_json_file(report_path, report.as_dict(), "--report")
    return report
