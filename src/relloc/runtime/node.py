"""One robot process: its own sensors in, its estimates out, teammates over Zenoh.

Start-up: the node subscribes to its teammates' streams and the clock, then declares its
``alive`` liveliness token; once it has seen the ``alive`` token of every teammate and of the
clock it declares ``ready`` (see :func:`relloc.runtime.keys.ready_key`). The clock starts when
every robot is ready.

Per clock tick ``k`` (simulated time ``t_k``; see :mod:`relloc.runtime.clock`) a node

1. releases what its :class:`~relloc.runtime.faults.LinkEmulator` holds for ``t_k``, files
   teammates' odometry and counts their measurements and equivalent measurements (duplicates
   recognised by sequence number, late samples counted);
2. publishes its own odometry and measurements of the window ``[t_{k−1}, t_k)`` — one ``odom``
   and one ``meas`` batch per tick: the configured publication rate is the tick rate;
3. filters every pending window whose inputs are in: a window ``[a, b)`` is filtered once every
   present teammate has published odometry up to ``b`` (normally at the next tick) or once it is
   ``max_lag_ticks`` overdue (then the missing velocities are held, and the window is counted);
4. every ``eqm_period_s`` broadcasts its belief of each teammate as an equivalent measurement
   (seed 002: 1 Hz); every ``report_period_s`` ships its new estimates (``est``), track events
   (``evt``) and counters (``stats``) to the collector; finally it acknowledges ``k``.

Teammates appear and disappear through Zenoh liveliness. Measurements of a teammate that is gone
are not fused (its motion cannot be predicted without its odometry), so its track expires after
the keep window; when it is back and seen again the track is re-found. A message that fails
validation is dropped and counted by reason (see :mod:`relloc.runtime.messages` and
:mod:`relloc.runtime.admission`: roles, ticks, time bound, rate); nothing a teammate — or
anyone else on the network — sends can crash the node. On ``ctl(end)`` — or if the clock
vanishes — the node filters what is left, ships its last report and exits cleanly.
"""

from __future__ import annotations

import time
from collections import Counter, deque
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from relloc.errors import ConfigError
from relloc.estimators.relative import FRAME
from relloc.runtime import keys
from relloc.runtime.admission import SenderBudget, TickGuard, admit, check_not_future
from relloc.runtime.estimation import TrackManagerEstimator
from relloc.runtime.faults import FAULTED_KINDS, FaultSettings, LinkEmulator
from relloc.runtime.messages import (
    DEFAULT_MAX_BYTES,
    Message,
    MessageRejected,
    encode,
    est_bodies,
)
from relloc.runtime.sources import MeasurementBatch, SensorSource
from relloc.runtime.teammates import ReceivedOdometry, SeenSequences, Teammate
from relloc.runtime.transport import (
    Inbox,
    Incoming,
    TransportSettings,
    declare_publisher,
    open_session,
)

LATENCY_SAMPLES = 200_000
END_DRAIN_S = 3.0
"""Wall seconds a node waits after ``ctl(end)`` for teammates' last odometry."""
TIME_TOL = 1e-9


@dataclass(frozen=True, kw_only=True)
class NodeSettings:
    """One robot process. ``roster`` is the whole team (this robot included)."""

    team: str
    robot: str
    roster: tuple[str, ...]
    transport: TransportSettings
    faults: FaultSettings = field(default_factory=FaultSettings)
    fault_seed: int = 0
    eqm_period_s: float = 1.0
    report_period_s: float = 1.0
    max_lag_ticks: int = 5
    max_bytes: int = DEFAULT_MAX_BYTES
    clock_timeout_s: float = 60.0

    def __post_init__(self) -> None:
        keys.check_id(self.team, "node.team")
        keys.check_id(self.robot, "node.robot")
        for r in self.roster:
            keys.check_id(r, "node.roster")
        if self.robot not in self.roster:
            raise ConfigError(f"node.robot: {self.robot!r} is not on the roster {self.roster}")
        if len(set(self.roster)) != len(self.roster):
            raise ConfigError(f"node.roster: duplicate robot ids in {self.roster}")
        for name in ("eqm_period_s", "report_period_s", "clock_timeout_s"):
            if not getattr(self, name) > 0:
                raise ConfigError(f"node.{name}: {getattr(self, name)} must be > 0")
        if not (isinstance(self.max_lag_ticks, int) and 1 <= self.max_lag_ticks <= 1000):
            raise ConfigError(f"node.max_lag_ticks: {self.max_lag_ticks} outside [1, 1000]")
        if not (256 <= self.max_bytes <= 16 * 2**20):
            raise ConfigError(f"node.max_bytes: {self.max_bytes} outside [256, 16 MiB]")


@dataclass
class _Window:
    start: float
    end: float
    measurements: list[MeasurementBatch]


class RobotNode:
    """The robot process (see module docstring). ``run()`` returns the final counters."""

    def __init__(
        self, settings: NodeSettings, source: SensorSource, estimator: TrackManagerEstimator
    ) -> None:
        self.s = settings
        self.source = source
        self.estimator = estimator
        self.counters: Counter[str] = Counter()
        self.teammates = {r: Teammate(r) for r in settings.roster if r != settings.robot}
        self.own_odometry = ReceivedOdometry()
        self._seen = SeenSequences()
        ss = np.random.SeedSequence([settings.fault_seed, settings.roster.index(settings.robot)])
        self.link = LinkEmulator(settings.robot, settings.faults, np.random.default_rng(ss))
        self._latency_us: list[float] = []
        self._session: Any = None
        self._pubs: dict[str, Any] = {}
        self._tokens: list[Any] = []
        self._clock_seen = False
        self._seq: Counter[str] = Counter()
        self._t = 0.0
        self._dt = 0.0
        self._pending: deque[_Window] = deque()
        self._window_start: float | None = None
        self._filtered_until: float | None = None
        self._next_eqm_s = 0.0
        self._next_report_s = 0.0
        self._done = False
        self._end_deadline: float | None = None
        self._ticks = TickGuard(end_s=getattr(source, "end_time", None))
        self._budget = SenderBudget.for_team(len(settings.roster))
        self._inbox: Inbox | None = None

    # ------------------------------------------------------------------ process main loop
    def run(self) -> dict[str, int]:
        s = self.s
        self._session = session = open_session(s.transport)
        inbox = self._inbox = Inbox(max_message_bytes=s.max_bytes)
        try:
            for kind in ("odom", "meas", "eqm"):
                inbox.subscribe(session, keys.robot_wildcard(s.team, kind))
            inbox.subscribe(session, keys.clock_key(s.team, "tick"))
            inbox.subscribe(session, keys.clock_key(s.team, "ctl"))
            inbox.watch_presence(session, keys.alive_wildcard(s.team))
            for kind in keys.ROBOT_KINDS:
                self._pubs[kind] = declare_publisher(session, keys.robot_key(s.team, s.robot, kind))
            self._tokens.append(session.liveliness().declare_token(keys.alive_key(s.team, s.robot)))
            while not self._done:
                if self._end_deadline is not None:
                    wait = self._end_deadline - time.monotonic()
                    if wait <= 0 or all(self._inputs_in(w) for w in self._pending):
                        self._finish()
                        break
                    item = inbox.get(timeout=min(wait, 0.05))
                else:
                    item = inbox.get(timeout=s.clock_timeout_s)
                    if item is None:
                        self.counters["exit.clock_silent"] += 1
                        self._finish()
                        break
                if item is not None:
                    self._on_incoming(item)
            self._report()
        finally:
            for token in self._tokens:
                token.undeclare()
            inbox.close()
            session.close()
        return self.final_counters()

    def _on_incoming(self, item: Incoming) -> None:
        if item.presence != "data":
            _, member = keys.parse_presence_key(item.key)
            self._on_presence(member, item.presence == "joined")
            return
        parsed = keys.parse_robot_key(item.key)
        if parsed is not None and parsed[0] == self.s.robot:
            return  # our own publication looped back by the local session
        try:
            msg = admit(item.key, item.payload, roster=self.s.roster, max_bytes=self.s.max_bytes)
            if msg.kind == "tick":
                self._ticks.check(msg)
            elif msg.kind == "ctl" and msg.body["action"] == "end":
                self._ticks.check_end(msg)
            elif msg.kind in FAULTED_KINDS:
                check_not_future(msg, self._t)
                self._budget.take(msg.sender)
        except MessageRejected as exc:
            self.counters[f"rejected.{exc.reason}"] += 1
            self.counters["rejected"] += 1
            return
        if msg.kind == "tick":
            self._on_tick(msg)
        elif msg.kind == "ctl":
            if msg.body["action"] == "end" and self._end_deadline is None:
                # teammates sent their last odometry before their last ack, but it may still be
                # on its way on another link: wait for it (bounded), then finish
                self._end_deadline = time.monotonic() + END_DRAIN_S
        elif msg.kind in FAULTED_KINDS:
            self.counters[f"wire.{msg.kind}"] += 1
            if len(self._latency_us) < LATENCY_SAMPLES:
                self._latency_us.append((item.recv_wall_ns - msg.wall_ns) / 1e3)
            self.link.admit(msg, msg.sender, self._t)
        else:
            self.counters[f"ignored.{msg.kind}"] += 1

    def _on_presence(self, member: str, joined: bool) -> None:
        if member == "clock":
            self._clock_seen = joined
            if not joined:
                self.counters["exit.clock_left"] += 1
                self._finish()
        else:
            mate = self.teammates.get(member)
            if mate is None:
                if member != self.s.robot:
                    self.counters["presence.unknown_member"] += 1
                return
            if joined and not mate.present:
                mate.present = True
                mate.joins += 1
                self.counters["teammate.joins"] += 1
            elif (
                not joined
                and mate.present
                and (self._ticks.last_tick_seen or self._end_deadline is not None)
            ):
                # after the last tick teammates exit normally (the clock sends ctl(end) once every
                # robot acked that tick, and a teammate may leave before our ctl(end) arrives);
                # their streams are complete
                self.counters["teammate.exits_after_end"] += 1
            elif not joined and mate.present:
                mate.present = False
                mate.departures += 1
                self.counters["teammate.departures"] += 1
                self._seen.forget(member)
        everyone = self._clock_seen and all(m.joins for m in self.teammates.values())
        if everyone and len(self._tokens) == 1 and self._session is not None:
            ready = keys.ready_key(self.s.team, self.s.robot)
            self._tokens.append(self._session.liveliness().declare_token(ready))

    # ------------------------------------------------------------------ one clock tick
    def _on_tick(self, msg: Message) -> None:
        t, self._dt = msg.t, float(msg.body["dt"])
        self._t = t
        self._budget.new_interval()
        self.counters["ticks"] += 1
        if self._window_start is None:  # first tick heard (a restarted node joins mid-run)
            self._window_start = self._filtered_until = t - self._dt
            self._next_eqm_s = self._next_report_s = t
        self._deliver(self.link.release(t))
        batch = self._publish_own_sensors(self._window_start, t)
        self._pending.append(_Window(self._window_start, t, [batch]))
        self._window_start = t
        self._filter_ready(force=False)
        if t + TIME_TOL >= self._next_eqm_s:
            self._broadcast_beliefs()
            self._next_eqm_s += self.s.eqm_period_s
        if t + TIME_TOL >= self._next_report_s:
            self._report()
            self._next_report_s += self.s.report_period_s
        self._send("ack", {"k": msg.body["k"]})

    def _finish(self) -> None:
        """End of run: filter everything left (teammates published it before their last ack)."""
        if self._done:
            return
        self._deliver(self.link.release(np.inf))
        if self._pending:  # the run's last instant belongs to the last window (filtered here,
            last = self._pending[-1]  # not published: teammates are already finishing)
            last.measurements.append(self.source.measurements(last.end, last.end, inclusive=True))
        self._filter_ready(force=True)
        self.counters["final"] = 1
        self._done = True

    def _deliver(self, messages: list[Message]) -> None:
        for msg in messages:
            if not self._seen.is_new(msg.sender, msg.kind, msg.seq):
                self.counters["duplicates"] += 1
                continue
            mate = self.teammates[msg.sender]
            if not mate.present:
                self.counters[f"from_absent.{msg.kind}"] += 1
                continue
            self.counters[f"delivered.{msg.kind}"] += 1
            if msg.kind == "odom":
                mate.odometry.add(msg.body["stamps"], msg.body["u"])
                mate.heard_until_s = max(mate.heard_until_s or -np.inf, msg.t)

    def _publish_own_sensors(self, t0: float, t1: float) -> MeasurementBatch:
        stamps, u = self.source.odometry(t0, t1)
        self.own_odometry.add(stamps, u)
        self._send("odom", {"stamps": stamps, "u": u})
        batch = self.source.measurements(t0, t1)
        if batch.size:
            self._send(
                "meas",
                {
                    "stamps": batch.t,
                    "targets": list(batch.targets),
                    "z": batch.z,
                    "sigma": batch.sigma,
                },
            )
        return batch

    def _inputs_in(self, window: _Window) -> bool:
        return all(
            (m.heard_until_s or -np.inf) >= window.end - TIME_TOL
            for m in self.teammates.values()
            if m.present
        )

    def _filter_ready(self, *, force: bool) -> None:
        while self._pending:
            w = self._pending[0]
            overdue = self._t >= w.end + self.s.max_lag_ticks * self._dt - TIME_TOL
            if not (force or overdue or self._inputs_in(w)):
                return
            if overdue and not force and not self._inputs_in(w):
                self.counters["overdue_windows"] += 1
            self._pending.popleft()
            last = force and not self._pending
            self.estimator.advance(
                w.start,
                w.end,
                own=self.own_odometry,
                teammates={r: m.odometry for r, m in self.teammates.items()},
                measurements=w.measurements,
                present={r for r, m in self.teammates.items() if m.present},
                inclusive=last,
            )
            for mate in self.teammates.values():
                mate.odometry.consume_until(w.end)
            self.own_odometry.consume_until(w.end)
            self._filtered_until = w.end

    def _broadcast_beliefs(self) -> None:
        for belief in self.estimator.beliefs():
            self._send("eqm", {"target": belief.subject, "mean": belief.mean, "cov": belief.cov})

    def _report(self) -> None:
        """Ship new estimates, track events and counters to the collector."""
        if not self._pubs:
            return
        new = self.estimator.take_new()
        for body in est_bodies(new, frame=FRAME):
            self.counters["estimates"] += int(body["stamps"].size)
            self._send("est", body)
        if new.events:
            self._send(
                "evt",
                {
                    "stamps": np.array([e.t for e in new.events]),
                    "targets": [e.subject for e in new.events],
                    "kinds": [e.kind for e in new.events],
                },
            )
        self._send("stats", {"counters": self.final_counters()})

    def _send(self, kind: str, body: dict[str, Any], *, t: float | None = None) -> None:
        data = encode(
            kind,
            self.s.robot,
            self._seq[kind],
            self._t if t is None else t,
            body,
            max_bytes=self.s.max_bytes,
        )
        self._seq[kind] += 1
        self._pubs[kind].put(data)
        self.counters[f"sent.{kind}"] += 1

    def final_counters(self) -> dict[str, int]:
        """Counters, the link emulator's fault tallies, estimator track counts and latencies."""
        out = dict(self.counters)
        if self._inbox is not None:  # dropped by the inbox before queueing
            out["inbox_overflow"] = self._inbox.overflow
            if self._inbox.oversized:
                out["rejected.oversized"] = out.get("rejected.oversized", 0) + self._inbox.oversized
                out["rejected"] = out.get("rejected", 0) + self._inbox.oversized
        out["late_samples"] = sum(m.odometry.late for m in self.teammates.values())
        out["cpu_ms"] = int(time.process_time() * 1000)
        for name, value in self.link.counters.as_dict().items():
            out[f"fault.{name}"] = value
        for name, value in self.estimator.counters().items():
            out[f"tracks.{name}"] = value
        if self._latency_us:
            p50, p99 = np.percentile(self._latency_us, [50, 99])
            out["latency_us.p50"] = int(np.rint(p50))
            out["latency_us.p99"] = int(np.rint(p99))
            out["latency_us.samples"] = len(self._latency_us)
        return out
