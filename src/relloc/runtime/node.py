"""One robot process: its own sensors in, its estimates out, teammates over Zenoh.

Start-up: the node subscribes to its teammates' streams and the clock, then declares its
``alive`` liveliness token; once it has seen the ``alive`` token of every teammate and of the
clock it declares ``ready`` (see :func:`relloc.runtime.keys.ready_key`). The clock starts when
every robot is ready. The node's estimator is built before the node joins, and its one-off work
is done then: a gating estimator computes its χ² gate quantiles when it is built
(:func:`relloc.core.kalman.prepare_gates`; the first imports ``scipy.stats``), so that a ready
node's first filtered window costs what a later one does and does not hold up an ``ack``.

Per clock tick ``k`` (simulated time ``t_k``; see :mod:`relloc.runtime.clock`) a node

1. releases what its :class:`~relloc.runtime.faults.LinkEmulator` holds for ``t_k``, files
   teammates' odometry and counts their measurements and equivalent measurements (duplicates
   recognised by sequence number, a sequence number that jumps further ahead than the sender's
   rate allows rejected as ``seq_jump``: :class:`~relloc.runtime.teammates.SeenSequences`;
   late samples counted); where the estimator keeps checkpoints (seed 001), readings and
   odometry samples that arrive after their window was filtered are re-filtered from the
   checkpoint before them (:meth:`~relloc.runtime.estimation.WindowDriver.refilter`);
2. publishes its own odometry and measurements of the window ``[t_{k−1}, t_k)`` — one ``odom``
   and one ``meas`` batch per tick: the configured publication rate is the tick rate;
3. filters every pending window whose inputs are in, through its estimator's
   :class:`~relloc.runtime.estimation.WindowDriver` (any estimator of the contract): a window
   ``[a, b)`` is started once every present teammate has published odometry up to ``b``
   (normally at the next tick) or once it is ``max_lag_ticks`` overdue (then the missing
   velocities are held, and the window is counted). Where the estimators talk (the
   ``talkers``: seed 002's leaders), what the estimator sends leaves as ``mail`` stamped with
   its event, together with the node's progress, and the node processes an event only once
   every present talking teammate's progress has reached it (see
   :mod:`relloc.runtime.estimation`); what arrives between ticks is filed at once and a window
   whose inputs are in is filtered then, not at the next tick;
4. every ``eqm_period_s`` broadcasts its belief of each teammate as an equivalent measurement
   (monitoring, 1 Hz); every ``report_period_s`` ships its new estimates (``est``), track events
   (``evt``) and counters (``stats``) to the collector; finally it acknowledges ``k`` — at
   once, unless a window of its still waits for inputs on their way and would be overdue at
   the next tick (then, on a network without emulated faults, the ack waits for them, at most
   :data:`ACK_HOLD_S`: :meth:`RobotNode._send_due_acks`).

The last tick's window is ``[t_{n−1}, t_n]``: it holds the run's last instant.

A node that joins a running team (restarted: its first tick is not the first) and whose
estimator runs the team's filter asks a teammate for its team belief (``sync``) and filters
nothing until it continues from it (:mod:`relloc.runtime.handoff`); every node answers such
requests once its estimator has reached the time asked for.

Teammates appear and disappear through Zenoh liveliness. Measurements of a teammate that is gone
are not fused (its motion cannot be predicted without its odometry), so its track expires after
the keep window; when it is back and seen again the track is re-found. Liveliness and data
travel separately, so a restarted teammate's first messages can arrive before its appearance
is heard: they are held (up to :data:`HELD_FROM_ABSENT`, counted ``held_from_absent``) and
delivered, in order, when it is; what is still held at the end is counted ``from_absent``.

A message that fails validation is dropped and counted by reason (see
:mod:`relloc.runtime.messages` and :mod:`relloc.runtime.admission`: roles, ticks, time bound,
rate); nothing a teammate — or anyone else on the network — sends can crash the node. On
``ctl(end)`` — or if the clock vanishes — the node filters what is left, ships its last report
and exits cleanly. :attr:`RobotNode.reached_end` says whether the run ended (its last tick or
``ctl(end)`` heard) or the node gave up on a clock that left or fell silent before it; the
``node`` command exits non-zero then.
"""

from __future__ import annotations

import time
from collections import Counter, deque
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from relloc.core.checks import count, number, positive
from relloc.core.recording import Measurements, Recording, empty_measurements
from relloc.errors import ConfigError, DataError
from relloc.estimators.relative import FRAME
from relloc.runtime import keys
from relloc.runtime.admission import SenderBudget, TickGuard, admit, check_stamps
from relloc.runtime.estimation import WindowDriver
from relloc.runtime.faults import FAULTED_KINDS, FaultSettings, LinkEmulator, LinkStall
from relloc.runtime.handoff import Handoff
from relloc.runtime.mail import mail_body, mail_items
from relloc.runtime.messages import (
    DEFAULT_MAX_BYTES,
    MAX_MESSAGE_BYTES,
    MIN_MESSAGE_BYTES,
    STATE_DIM,
    Message,
    MessageRejected,
    encode,
    est_bodies,
)
from relloc.runtime.shared_rows import rows_body, rows_from_body
from relloc.runtime.sources import SensorSource, batch_rows
from relloc.runtime.teammates import ReceivedOdometry, SeenSequences, Teammate
from relloc.runtime.timing import EstimateTiming
from relloc.runtime.transport import (
    INBOX_BYTES,
    INBOX_RECORDS,
    Inbox,
    Incoming,
    TransportSettings,
    declare_publisher,
    open_session,
)

LATENCY_SAMPLES = 200_000
HELD_FROM_ABSENT = 256
"""Messages kept per teammate that arrive while it is not present (a restarted teammate's
first messages can arrive before its liveliness token is heard); beyond that, dropped and
counted (``from_absent``). At a teammate's usual two or three messages a tick that is about
ten seconds of a liveliness lag (0.3 s held 43 in a test), and at most 256 × the message size
limit of memory per teammate, whatever an impostor sends."""
ACK_HOLD_S = 5.0
"""Wall seconds a node on a network without emulated faults holds the ack of a tick whose next
tick would find a window of its overdue (:meth:`RobotNode._send_due_acks`); half the clock's
ack timeout, so that a held ack is never counted as timed out."""
END_DRAIN_S = 3.0
"""Wall seconds a node waits after ``ctl(end)`` for teammates' last odometry."""
TIME_TOL = 1e-9


def window_overdue(window_end: float, t: float, dt: float, max_lag_ticks: int) -> bool:
    """Whether a window ending at ``window_end`` is overdue at the tick of time ``t``: it ended
    ``max_lag_ticks`` ticks or more before, ``t ≥ window_end + max_lag_ticks·dt``. An overdue
    window is filtered with what has arrived (held velocities, no teammate progress)."""
    return t >= window_end + max_lag_ticks * dt - TIME_TOL


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
    talkers: tuple[str, ...] = ()
    """Robots whose estimators exchange messages (``outbox``/``receive``) with one another."""
    share_rows: bool = False
    """Every robot shares its readings (``rows``) and every estimator fuses the team's (seed
    001)."""
    paced_factor: float = 0.0
    """The clock paces its ticks at this multiple of real time (``team up --realtime``; 0: as
    fast as the team goes). When paced, the node reports measurement-to-estimate latency and
    missed deadlines (:mod:`relloc.runtime.timing`, deadline: one tick of wall time)."""
    only_needed_streams: bool = False
    """Subscribe to teammates' data only if this robot uses it: it makes readings (seed 000's
    relative filters need the observed robots' odometry), talks or shares readings. A robot
    that only moves then decodes nothing of its teammates' (each robot decoding every
    teammate's stream is what grows as n² with the team)."""

    def __post_init__(self) -> None:
        keys.check_id(self.team, "node.team")
        keys.check_robot_id(self.robot, "node.robot")
        for r in self.roster:
            keys.check_robot_id(r, "node.roster")
        if self.robot not in self.roster:
            raise ConfigError(f"node.robot: {self.robot!r} is not on the roster {self.roster}")
        if len(set(self.roster)) != len(self.roster):
            raise ConfigError(f"node.roster: duplicate robot ids in {self.roster}")
        if not set(self.talkers) <= set(self.roster):
            raise ConfigError(f"node.talkers: {self.talkers} are not all on the roster")
        count(self.fault_seed, "node.fault_seed", low=0)
        for name in ("eqm_period_s", "report_period_s", "clock_timeout_s"):
            positive(getattr(self, name), f"node.{name}")
        number(self.paced_factor, "--paced", low=0.0)
        count(self.max_lag_ticks, "node.max_lag_ticks", high=1000)
        count(self.max_bytes, "node.max_bytes", low=MIN_MESSAGE_BYTES, high=MAX_MESSAGE_BYTES)


@dataclass(frozen=True)
class NodeParts:
    """What a robot process runs: the team roster, its own sensors, its estimator's driver and
    the robots whose estimators talk to one another (:attr:`NodeSettings.talkers`)."""

    roster: tuple[str, ...]
    source: SensorSource
    driver: WindowDriver
    talkers: tuple[str, ...] = ()
    share_rows: bool = False
    recording: Recording | None = None
    """The recording the source reads (a replay), if any."""


@dataclass
class _Window:
    start: float
    end: float
    rows: list[Measurements]
    final: bool = False
    started: bool = False


class RobotNode:
    """The robot process (see module docstring). ``run()`` returns the final counters."""

    def __init__(
        self, settings: NodeSettings, source: SensorSource, estimator: WindowDriver
    ) -> None:
        self.s = settings
        self.source = source
        self.estimator = estimator
        self.talks = settings.robot in settings.talkers
        readings = getattr(source, "rows", None)
        makes_readings = readings is None or readings(-np.inf, np.inf, inclusive=True).size > 0
        self.listens = not settings.only_needed_streams or (
            self.talks or settings.share_rows or makes_readings
        )
        if self.talks:
            estimator.mark_talking()
        self._acks_due: deque[tuple[int, float]] = deque()
        self._hold_deadline: float | None = None
        """Wall time (monotonic) at which a held ack goes anyway (:data:`ACK_HOLD_S`)."""
        self._tick_wall: dict[float, float] = {}
        self.paced = (
            EstimateTiming(1.0 / settings.paced_factor) if settings.paced_factor > 0 else None
        )
        self._mail_progress = -np.inf
        self.counters: Counter[str] = Counter()
        self.teammates = {r: Teammate(r) for r in settings.roster if r != settings.robot}
        self.own_odometry = ReceivedOdometry()
        self.link = LinkEmulator.of_member(
            settings.robot, settings.faults, settings.fault_seed, settings.roster
        )
        self.stall = LinkStall(
            settings.robot, settings.faults.stalls, max_records=INBOX_RECORDS, max_bytes=INBOX_BYTES
        )
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
        self._start_s: float | None = None
        """Where this process' first window starts (set at its first tick)."""
        self._filtered_until: float | None = None
        self._next_eqm_s = 0.0
        self._next_report_s = 0.0
        self._done = False
        self._end_deadline: float | None = None
        self._last_tick_seen = False
        self._ticks = TickGuard(end_s=getattr(source, "end_time", None))
        self._budget = SenderBudget.for_team(len(settings.roster))
        self._seen = SeenSequences(per_tick=self._budget.capacity)
        self._inbox: Inbox | None = None
        self._handoff = Handoff(settings.robot, settings.roster, self.counters)

    # ------------------------------------------------------------------ process main loop
    def run(self) -> dict[str, int]:
        s = self.s
        self._session = session = open_session(s.transport)
        inbox = self._inbox = Inbox(max_message_bytes=s.max_bytes)
        try:
            if self.listens:
                for kind in ("odom", "meas", "rows", "eqm", "mail", "sync"):
                    inbox.subscribe(session, keys.robot_wildcard(s.team, kind), remote_only=True)
            inbox.subscribe(session, keys.clock_key(s.team, "tick"))
            inbox.subscribe(session, keys.clock_key(s.team, "ctl"))
            inbox.watch_presence(session, keys.alive_wildcard(s.team))
            for kind in keys.ROBOT_KINDS:
                self._pubs[kind] = declare_publisher(session, keys.robot_key(s.team, s.robot, kind))
            self._tokens.append(session.liveliness().declare_token(keys.alive_key(s.team, s.robot)))
            self._loop(inbox)
            self._report()
        finally:
            for token in self._tokens:
                token.undeclare()
            inbox.close()
            session.close()
        return self.final_counters()

    def _loop(self, inbox: Inbox) -> None:
        """Handle what arrives until the run ends (clock ticks drive the node)."""
        s = self.s
        while not self._done:
            if self._end_deadline is not None:
                # what teammates sent before their last ack is due now: file it and filter
                self._release_stalled(time.monotonic())
                self._deliver(self.link.release(self._t))
                self._filter_ready(force=False)
                wait = self._end_deadline - time.monotonic()
                if wait <= 0 or not self._pending:
                    self._finish()
                    break
                item = inbox.get(timeout=min(wait, 0.05))
            else:
                # wake up when a held ack or a stalled link is due: that is no silent clock
                due = [d for d in (self._hold_deadline, self.stall.next_due) if d is not None]
                timeout = s.clock_timeout_s
                if due:
                    timeout = min(timeout, max(0.0, min(due) - time.monotonic()))
                item = inbox.get(timeout=timeout)
                self._release_stalled(time.monotonic())
                if item is None and due:
                    self._send_due_acks()
                    continue
                if item is None:
                    self.counters["exit.clock_silent"] += 1
                    self._finish()
                    break
            if item is not None:
                self._on_incoming(item)

    def _release_stalled(self, wall_s: float | None) -> None:
        """Handle what a stalled link held, once its stall has run out (``None``: at once)."""
        for item in self.stall.due(wall_s):
            self._receive(item)

    def _on_incoming(self, item: Incoming) -> None:
        """One record of the inbox: held if its link is stalled (:mod:`relloc.runtime.faults`),
        else handled."""
        parsed = keys.parse_robot_key(item.key) if item.presence == "data" else None
        if (
            parsed is not None
            and parsed[1] in FAULTED_KINDS
            and self.stall.hold(parsed[0], self._t, item, time.monotonic(), len(item.payload))
        ):
            return
        self._receive(item)

    def _receive(self, item: Incoming) -> None:
        if item.presence != "data":
            parsed = keys.parse_presence_key(item.key)
            if parsed is not None:  # None: a token of another layout
                self._on_presence(parsed[1], item.presence == "joined")
            return
        parsed = keys.parse_robot_key(item.key)
        if parsed is not None and parsed[0] == self.s.robot:
            # the subscriptions are remote-only: another process speaks as this robot
            self._count_rejected(MessageRejected("own_key", f"a message on {item.key!r}"))
            return
        try:
            msg = admit(item.key, item.payload, roster=self.s.roster, max_bytes=self.s.max_bytes)
            if msg.kind == "tick":
                self._ticks.check(msg)
            elif msg.kind == "ctl" and msg.body["action"] == "end":
                self._ticks.check_end(msg)
            elif msg.kind in FAULTED_KINDS:
                check_stamps(msg, self._t)
                self._budget.take(msg.sender)
        except MessageRejected as exc:
            self._count_rejected(exc)
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
            # what is due now (all of it on a perfect network) is filed at once, and a window
            # whose inputs are in is filtered between ticks, not at the next one
            self._deliver(self.link.release(self._t))
            self._filter_ready(force=False)
        else:
            self.counters[f"ignored.{msg.kind}"] += 1

    def _on_presence(self, member: str, joined: bool) -> None:
        if member == keys.CLOCK_ID:
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
                if mate.held:  # what it sent before its appearance reached us, in order
                    held, mate.held = mate.held, []
                    self._deliver(held)
                    self._filter_ready(force=False)
            elif (
                not joined
                and mate.present
                and (self._last_tick_seen or self._end_deadline is not None)
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
                if self._session is not None:  # windows that waited for it need it no more
                    self._filter_ready(force=False)
        everyone = self._clock_seen and all(m.joins for m in self.teammates.values())
        if everyone and len(self._tokens) == 1 and self._session is not None:
            ready = keys.ready_key(self.s.team, self.s.robot)
            self._tokens.append(self._session.liveliness().declare_token(ready))

    # ------------------------------------------------------------------ one clock tick
    def _on_tick(self, msg: Message) -> None:
        if self.paced is not None:  # when the clock sent t_k: its wall time on a paced clock
            self._tick_wall[msg.t] = msg.wall_ns / 1e9
        self._tick(int(msg.body["k"]), int(msg.body["n"]), msg.t, float(msg.body["dt"]))

    def _tick(self, k: int, n: int, t: float, dt: float) -> None:
        """Tick ``k`` of ``n`` at robot time ``t`` (module docstring)."""
        self._dt = dt
        self._t = t
        self._budget.new_interval()
        self.counters["ticks"] += 1
        self._last_tick_seen = k >= n
        if self._window_start is None:  # first tick heard (a restarted node joins mid-run)
            self._window_start = self._filtered_until = self._start_s = t - self._dt
            self._next_eqm_s = self._next_report_s = t
            if k > 1 and self.listens and self.estimator.hands_off:
                self._handoff.begin(after=t)  # rejoin the team's estimate (module handoff)
        request = self._handoff.request([r for r, m in self.teammates.items() if m.present])
        if request is not None:
            self._send("sync", request)
        self._deliver(self.link.release(t))
        # the run's last instant belongs to the last window
        final = self._last_tick_seen
        rows = self._publish_own_sensors(self._window_start, t, final=final)
        self._pending.append(_Window(self._window_start, t, [rows], final=final))
        self._window_start = t
        self._filter_ready(force=False)
        if t + TIME_TOL >= self._next_eqm_s:
            self._broadcast_beliefs()
            self._next_eqm_s += self.s.eqm_period_s
        if t + TIME_TOL >= self._next_report_s:
            self._report()
            self._next_report_s += self.s.report_period_s
        if self.estimator.busy:  # waiting for a teammate: repeat our progress, in case the
            self._send_mail(repeat=True)  # teammate waits for it and the last one was lost
        self._acks_due.append((k, t))
        self._send_due_acks()

    @property
    def reached_end(self) -> bool:
        """Whether the node heard the run's last tick or ``ctl(end)``: else it stopped because
        the clock left or was silent for ``clock_timeout_s`` before the run ended."""
        return self._last_tick_seen or self._end_deadline is not None

    def _finish(self) -> None:
        """End of run: filter everything left (teammates published it before their last ack)."""
        if self._done:
            return
        self._release_stalled(None)
        self._deliver(self.link.release(np.inf))
        self._handoff.give_up()
        last = self._pending[-1] if self._pending else None
        if last is not None and not (last.final or last.started):
            # the clock left before its last tick: the last instant we have ends the run
            last.final = True
            last.rows.append(self._own_rows(last.end, last.end, inclusive=True))
        elif self._window_start is not None and not self._last_tick_seen:
            # ... and its last window is filtered already (or under way): the instant is a
            # window of its own, so that what was read then is fused whatever the timing
            t = self._window_start
            rows = self._own_rows(t, t, inclusive=True)
            self._pending.append(_Window(t, t, [rows], final=True))
        self._filter_ready(force=True)
        for mate in self.teammates.values():  # never heard appearing: not delivered
            for msg in mate.held:
                self.counters[f"from_absent.{msg.kind}"] += 1
            mate.held = []
        self.counters["final"] = 1
        self._done = True

    def _deliver(self, messages: list[Message]) -> None:
        late_rows: list[Measurements] = []
        late_odometry: list[np.ndarray] = []
        for msg in messages:
            mate = self.teammates[msg.sender]
            if not mate.present:  # its appearance is not heard yet: held until it is
                if len(mate.held) < HELD_FROM_ABSENT:
                    mate.held.append(msg)
                    self.counters[f"held_from_absent.{msg.kind}"] += 1
                else:
                    self.counters[f"from_absent.{msg.kind}"] += 1
                continue
            try:
                new = self._seen.is_new(msg.sender, msg.kind, msg.seq, self._ticks.k or 0)
            except MessageRejected as exc:
                self._count_rejected(exc)
                continue
            if not new:
                self.counters["duplicates"] += 1
                continue
            if msg.kind == "odom" and self.estimator.refuses_odometry(msg.body["u"]):
                self._count_rejected(
                    MessageRejected("not_unicycle", f"odom of {msg.sender}: lateral velocity")
                )
                continue
            self.counters[f"delivered.{msg.kind}"] += 1
            if msg.kind == "odom":
                stamps, u = mate.odometry.add(msg.body["stamps"], msg.body["u"])
                if stamps.size and self.estimator.checkpoint_windows:
                    mate.odometry.file_late(stamps, u)  # re-filtered below
                    late_odometry.append(stamps)
                mate.heard_until_s = max(mate.heard_until_s or -np.inf, msg.t)
            elif msg.kind == "rows" and self.s.share_rows:
                try:
                    rows = rows_from_body(
                        msg.body,
                        self.s.roster,
                        msg.sender,
                        getattr(self.source, "landmark_count", None),
                    )
                except MessageRejected as exc:
                    self._count_rejected(exc)
                    continue
                mate.rows_until = max(mate.rows_until, msg.t)
                late = rows.t < self._unstarted_from() - TIME_TOL
                if late.any():  # its window is filtered: fuse it at its time stamp anyway
                    self.counters["rows_late"] += int(late.sum())
                    late_rows.append(rows.select(late))
                    rows = rows.select(~late)
                mate.rows.append(rows)
            elif msg.kind == "mail" and self.talks:
                try:
                    parcels = mail_items(msg.body, self.s.roster, msg.sender)
                except MessageRejected as exc:
                    self._count_rejected(exc)
                    continue
                mate.progress = max(mate.progress, float(msg.body["progress"]))
                # what was sent before this process started cannot reach its estimator,
                # which had no state then (a restarted node; or a hostile stamp)
                start = np.inf if self._start_s is None else self._start_s
                for stamp, items in parcels:
                    if stamp < start - TIME_TOL:
                        self.counters["mail_before_start"] += len(items)
                        continue
                    self.estimator.deliver(stamp, msg.sender, items)
            elif msg.kind == "sync" and msg.body["target"] == self.s.robot:
                self._on_sync(msg)
        if late_rows or late_odometry:
            self.estimator.refilter(
                Measurements.concatenate(late_rows) if late_rows else empty_measurements(),
                odometry=np.concatenate(late_odometry) if late_odometry else None,
            )

    def _on_sync(self, msg: Message) -> None:
        """A teammate asks for the team belief, or answers this node's request
        (:mod:`relloc.runtime.handoff`)."""
        if msg.body["mean"].size == 0:
            if self.estimator.hands_off:
                self._handoff.note_request(msg.sender, msg.body)
            return
        handed = self._handoff.accept(msg.sender, msg.body, self._t, self._dt)
        if handed is not None:
            self.estimator.resume(*handed)
            self._handoff.resumed()

    def _send_replies(self) -> None:
        """Answer the teammates whose requested time this node's estimator has reached."""
        for body in self._handoff.replies(self.estimator):
            try:
                self._send("sync", body)
            except DataError:  # a team too large for one message: the asker times out
                self.counters["sync.too_large"] += 1

    def _count_rejected(self, exc: MessageRejected) -> None:
        self.counters[f"rejected.{exc.reason}"] += 1
        self.counters["rejected"] += 1

    def _unstarted_from(self) -> float:
        """Where the windows not yet started begin (readings before it are late)."""
        for w in self._pending:
            if not w.started:
                return w.start
        return -np.inf if self._window_start is None else self._window_start

    def _own_rows(self, t0: float, t1: float, *, inclusive: bool = False) -> Measurements:
        """This robot's readings of a window as measurement rows."""
        rows = getattr(self.source, "rows", None)
        if rows is not None:
            return rows(t0, t1, inclusive=inclusive)  # type: ignore[no-any-return]
        batch = self.source.measurements(t0, t1, inclusive=inclusive)
        return batch_rows(batch, self.s.roster, self.s.robot)

    def _publish_own_sensors(self, t0: float, t1: float, *, final: bool) -> Measurements:
        """Publish the window's odometry, its readings (``meas``; and ``rows`` where the team
        shares them) and return the readings as rows (``[t0, t1]`` for the ``final`` window)."""
        stamps, u = self.source.odometry(t0, t1)
        self.own_odometry.add(stamps, u)
        self._send("odom", {"stamps": stamps, "u": u})
        batch = self.source.measurements(t0, t1, inclusive=final)
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
        if hasattr(self.source, "rows"):
            rows = self._own_rows(t0, t1, inclusive=final)
        else:
            rows = batch_rows(batch, self.s.roster, self.s.robot)
        if self.s.share_rows:
            self._send("rows", rows_body(rows, self.s.roster))
        return rows

    def _inputs_in(self, window: _Window) -> bool:
        """Every present teammate's odometry (and shared readings) up to the window's end is
        in (a node that does not listen needs none)."""
        return not self.listens or all(
            (m.heard_until_s or -np.inf) >= window.end - TIME_TOL
            and (not self.s.share_rows or m.rows_until >= window.end - TIME_TOL)
            for m in self.teammates.values()
            if m.present
        )

    def _window_rows(self, w: _Window) -> Measurements:
        """The window's readings: this robot's and, where the team shares them, its
        teammates', in time order and, at one time, in robot order."""
        parts = list(w.rows)
        if self.s.share_rows:
            for mate in self.teammates.values():
                parts += mate.take_rows(w.start, w.end, inclusive=w.final)
        rows = Measurements.concatenate(parts)
        if len(parts) > 1 and rows.size:
            order = np.lexsort((rows.observer, rows.t))
            if np.any(np.diff(order) < 0):
                rows = rows.select(order)
        return rows

    def _filter_ready(self, *, force: bool) -> None:
        """Filter what can be filtered (module docstring, step 3), then ship the progress. A
        restarted node waiting for a teammate's team belief filters nothing."""
        if force:
            self._handoff.give_up()
        while self._pending and not self._handoff.waiting:
            w = self._pending[0]
            overdue = window_overdue(w.end, self._t, self._dt, self.s.max_lag_ticks)
            if not w.started:
                ready = self._inputs_in(w)
                if not (force or overdue or ready):
                    break
                if overdue and not (force or ready):
                    self.counters["overdue_windows"] += 1
                self.estimator.start_window(
                    w.start,
                    w.end,
                    streams=[
                        self.own_odometry if r == self.s.robot else self.teammates[r].odometry
                        for r in self.s.roster
                    ],
                    rows=self._window_rows(w),
                    present={r for r, m in self.teammates.items() if m.present},
                    inclusive=w.final,
                )
                w.started = True
            done = self.estimator.run(None if force else self._talk_progress())
            if not done and overdue:  # a talking teammate's progress is late: go on, counted
                self.counters["overdue_windows.waiting_for_mail"] += 1
                done = self.estimator.run()
            if not done:
                break
            self._pending.popleft()
            self._window_done(w)
            keep = self.estimator.history_from  # the samples re-filtering may need
            for mate in self.teammates.values():
                mate.odometry.consume_until(w.end, keep)
            self.own_odometry.consume_until(w.end, keep)
            self._filtered_until = w.end
        self._send_replies()
        self._send_mail()
        self._send_due_acks()

    def _send_due_acks(self) -> None:
        """Acknowledge the ticks that are done; two rules hold an ack back.

        - A node whose estimator talks holds the ack of tick ``k`` while its oldest pending
          window is overdue at ``t_k`` (:func:`window_overdue`). Overdue windows are filtered
          at the tick, before its ack, so this holds only while the node waits for a
          teammate's team belief (a restarted node: :mod:`relloc.runtime.handoff`).
        - On a network without emulated faults (``faults.network_faulty`` false) any node
          holds the ack of tick ``k`` while its oldest pending window would be overdue at the
          next tick, ``t_k + Δt``, for at most :data:`ACK_HOLD_S` of wall time (counted
          ``acks_held``; ``acks_held_expired`` when the time ran out). Its missing inputs —
          a teammate's odometry or, for a talker, its progress — were sent before the
          teammate's ack of an earlier tick and are on their way: the hold keeps a link that
          stalls for a moment (a starved process, a busy core) from letting the clock run
          ``max_lag_ticks`` ahead, so that the window is never filtered without them and the
          run still performs the in-process arithmetic. Not while the node waits for a team
          belief (its retries count ticks), and not where faults are emulated: the emulator
          releases what it delays at ticks, and a lost progress mail is repeated only at a
          tick, so a hold there would stall the team (tried without the time bound and on
          talkers only: ``team up desilva2015 --drop 0.2 --duration 10`` took 86 s and 8 of
          the clock's ack timeouts, against 7 s).
        """
        while self._acks_due:
            k, t = self._acks_due[0]
            if (
                self.talks
                and self._pending
                and window_overdue(self._pending[0].end, t, self._dt, self.s.max_lag_ticks)
            ):
                self._hold_deadline = None  # held by this rule alone: nothing to wake up for
                return
            if self._hold_for_next_tick(t):
                now = time.monotonic()
                if self._hold_deadline is None:
                    self._hold_deadline = now + ACK_HOLD_S
                    self.counters["acks_held"] += 1
                if now < self._hold_deadline:
                    return
                self.counters["acks_held_expired"] += 1
            self._hold_deadline = None
            self._acks_due.popleft()
            self._send("ack", {"k": k})

    def _hold_for_next_tick(self, t: float) -> bool:
        """Whether the second rule of :meth:`_send_due_acks` holds the ack of the tick at
        ``t``."""
        return (
            not self.s.faults.network_faulty
            and not self._handoff.waiting
            and bool(self._pending)
            and window_overdue(self._pending[0].end, t + self._dt, self._dt, self.s.max_lag_ticks)
        )

    def _window_done(self, window: _Window) -> None:
        """A window was filtered: on a paced clock, time it (module :mod:`~relloc.runtime.timing`;
        a reading at ``t`` was taken ``(t_k − t) / factor`` before the clock sent ``t_k``)."""
        end_wall = self._tick_wall.pop(window.end, None)
        if self.paced is None or end_wall is None:
            return
        factor = self.s.paced_factor
        taken = end_wall - (window.end - window.rows[0].t) / factor
        self.paced.deadline_s = self._dt / factor
        self.paced.window_done(taken, end_wall, time.time())

    def _talk_progress(self) -> float | None:
        """How far every present talking teammate has got (None: nobody to wait for)."""
        if not self.talks:
            return None
        mates = [m.progress for r, m in self.teammates.items() if r in self.s.talkers and m.present]
        return min(mates) if mates else None

    def _send_mail(self, *, repeat: bool = False) -> None:
        """Publish what the estimator sent and this node's progress, if either is new (or to
        ``repeat`` the progress)."""
        if not self.talks or not self._pubs:
            return
        sent = self.estimator.take_sent()
        progress = self.estimator.progress
        if not sent and not progress > self._mail_progress and not repeat:
            return
        if not np.isfinite(progress):  # nothing processed yet; the messages wait for it
            self.estimator.sent[:0] = sent
            return
        self._mail_progress = progress
        for body in mail_body(progress, sent, self.s.roster, self.s.max_bytes):
            self._send("mail", body)

    def _broadcast_beliefs(self) -> None:
        """Every relative-pose belief as an ``eqm`` (monitoring; a team filter's world poses
        are not relative poses and are not sent)."""
        for belief in self.estimator.beliefs():
            if belief.mean.size != STATE_DIM:
                continue
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
        out["duplicate_samples"] = sum(
            m.odometry.duplicate_samples for m in self.teammates.values()
        )
        out["late_rows"] = sum(m.late_rows for m in self.teammates.values())
        out["listens"] = int(self.listens)
        if self.paced is not None:
            out |= self.paced.counters()
        out["cpu_ms"] = int(time.process_time() * 1000)
        for name, value in self.link.counters.as_dict().items():
            out[f"fault.{name}"] = value
        out["fault.stalled"] = self.stall.held
        out["fault.stall_dropped"] = self.stall.dropped
        for name, value in self.estimator.counters().items():
            out[f"tracks.{name}"] = value
        if self._latency_us:
            p50, p99 = np.percentile(self._latency_us, [50, 99])
            out["latency_us.p50"] = int(np.rint(p50))
            out["latency_us.p99"] = int(np.rint(p99))
            out["latency_us.samples"] = len(self._latency_us)
        return out
