"""A robot node's estimator: any estimator of the contract (:mod:`relloc.core.contract`) —
the very one the in-process run gives that robot — driven window by window by the one event
loop, :func:`relloc.core.events.run_events`, on what the node has (its own sensors, what
teammates sent).

For a window ``[t0, t1)`` (``[t0, t1]`` for the run's last one) the event times are — as in
:func:`relloc.pipeline.replay.replay` — the union of the record times, the times of the
measurement rows the node has for the window and every robot's odometry stamps (teammates':
those *received*). Each event uses every robot's last velocity before it (zero-order hold). With
a perfect network the node therefore performs the same arithmetic as the in-process run; a lost
or late odometry sample only changes which velocity is held.

Messages between estimators (:meth:`~relloc.core.contract.Estimator.outbox` /
:meth:`~relloc.core.contract.Estimator.receive`: seed 002's equivalent measurements). The
in-process loop hands what an estimator sends at event ``e`` to every other estimator right
after ``e``, so a receiver sees it before its first event after ``e``. The driver keeps that
rule across processes: every message leaves stamped with the event that produced it, a
received message is handed to :meth:`receive` just before the first event *after* its stamp,
and :meth:`WindowDriver.run` processes an event ``e`` only once every talking teammate's
*progress* — "I have processed all my events before ``p`` and sent what they produced" — has
reached ``e`` (:attr:`WindowDriver.progress` is this driver's own). A node stops inside a window
when a teammate lags, ships its own progress, and goes on when the teammate's arrives; since
every driver can always process the earliest event nobody has processed, nobody waits forever
(a window overdue by the node's maximum lag is processed anyway, and the messages that come
later are fused late — at the next event — and counted).

Measurements of a teammate whose process is gone (its liveliness token vanished) are not fused —
its motion can no longer be predicted — and are counted (``skipped_absent``); a track of it then
expires and is re-created when the teammate is back and seen again (``recreated``, re-found).
An estimator that follows lost robots (seed 001's team filter with its lost model:
:attr:`relloc.estimators.cooperative.OdometryModel.lost_speed`) still fuses what the others
measure *of* such a teammate; only the teammate's own readings are skipped.

A :class:`~relloc.core.estimates.Recorder` collects what the estimator believed and did;
:meth:`WindowDriver.take_new` returns only what is *new* since its last call (an
:class:`~relloc.core.estimates.Estimates` increment); a node ships it every report period, so a
node that is killed mid-run has already shipped everything up to its last report.
"""

from __future__ import annotations

import copy
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from relloc.core.contract import (
    Belief,
    Estimator,
    HeldOdometry,
    Silent,
    TrackEvent,
    UpdateRecord,
)
from relloc.core.estimates import Estimates, Recorder
from relloc.core.events import TIME_TOL, run_events
from relloc.core.gaussian import Gaussian
from relloc.core.recording import Measurements
from relloc.pipeline.replay import merge_times
from relloc.runtime.teammates import ReceivedOdometry

Array = NDArray[np.float64]

QUIET_HORIZON_S = 3600.0
"""How far ahead of its processed events a driver promises silence (keeps progress finite)."""

RecordTimes = Callable[[float, float, bool, Measurements], Array]
"""``(t0, t1, inclusive, rows) -> record times`` of a window (``rows``: the window's rows)."""


def grid_record_times(rate_hz: float, origin: float = 0.0, end: float = np.inf) -> RecordTimes:
    """Record on the grid ``origin + i / rate_hz`` (seed 000's 10 Hz recording grid), up to
    ``end`` (the recording's last instant: the clock's last tick may lie up to a tick beyond
    it, where there is no truth to score a record by)."""
    period = 1.0 / rate_hz

    def times(t0: float, t1: float, inclusive: bool, rows: Measurements) -> Array:
        del rows
        first = np.ceil((t0 - origin) / period - TIME_TOL)
        last = np.floor((min(t1, end) - origin) / period + TIME_TOL)
        grid = origin + np.arange(first, last + 1) * period
        upper = grid <= t1 + TIME_TOL if inclusive else grid < t1 - TIME_TOL
        return np.asarray(grid[(grid >= t0 - TIME_TOL) & upper], dtype=float)

    return times


def scan_record_times(observer: int) -> RecordTimes:
    """Record at the stamps of ``observer``'s own rows (seed 002: the leader's scan times)."""

    def times(t0: float, t1: float, inclusive: bool, rows: Measurements) -> Array:
        del t0, t1, inclusive
        return np.unique(rows.t[rows.observer == observer])

    return times


@dataclass
class _Checkpoint:
    """The estimator before a window (``state``, its time ``t`` and the end of the window before)
    and the window's plan."""

    t0: float
    t: float | None
    window_end: float
    state: Any
    plan: _Plan


@dataclass
class _Plan:
    """The events of one window and how far the driver got through them."""

    t1: float
    times: Array
    held: Array
    stamps: Array
    rows: Measurements
    record: Array
    inclusive: bool = False
    next: int = 0
    fed: int = 0

    @property
    def done(self) -> bool:
        return self.next >= self.times.size


def _in_robot_order(rows: Measurements) -> Measurements:
    """Readings in time order and, at one time, in robot order (as a node files them)."""
    order = np.lexsort((rows.observer, rows.t))
    return rows.select(order) if np.any(np.diff(order) < 0) else rows


class _Wired:
    """The estimator as :func:`run_events` sees it inside a node: received messages are handed
    over just before the first event after their stamp, and what it sends is kept (stamped
    with its event) for the node to publish, instead of going to the in-process teammates."""

    def __init__(self, inner: Estimator, driver: WindowDriver) -> None:
        self.inner = inner
        self.driver = driver
        self.owner = inner.owner
        self.name = inner.name
        self.t = float("nan")

    def advance(self, t: float, odometry: HeldOdometry) -> None:
        due = self.driver.due_messages(t)
        if due:
            self.inner.receive(due)
        self.inner.advance(t, odometry)
        self.t = t

    def measure(self, batch: Measurements) -> None:
        self.inner.measure(batch)

    def outbox(self) -> list[Any]:
        out = self.inner.outbox()
        if out:
            self.driver.sent.extend((self.t, m) for m in out)
        return []

    def receive(self, messages: Sequence[Any]) -> None:
        self.inner.receive(messages)

    def beliefs(self) -> Sequence[Belief]:
        return self.inner.beliefs()

    def take_updates(self) -> list[UpdateRecord]:
        return self.inner.take_updates()

    def take_events(self) -> list[TrackEvent]:
        return self.inner.take_events()

    def take_counts(self) -> dict[str, int]:
        take = getattr(self.inner, "take_counts", None)  # optional (see the contract)
        return {} if take is None else dict(take())


class WindowDriver:
    """Window-by-window driver of one robot's contract estimator (module docstring).

    ``roster`` names the robots in the estimator's index order (the recording's); ``robot`` is
    this node's; ``record_times`` gives each window's record times. Beliefs are recorded as
    ``robot``'s, whatever the estimator's ``owner`` (a team filter, ``"team"`` in-process, runs
    in every agent of seed 001). With ``checkpoint_windows > 0`` the state before each of the
    last that many windows is kept, so that late readings can be re-filtered
    (:meth:`refilter`). Nothing before ``start`` is filtered (the in-process run's window
    start, as :func:`relloc.pipeline.replay.replay`'s ``start``); readings before it are
    counted (``rows_before_start``).
    """

    def __init__(
        self,
        estimator: Estimator,
        roster: Sequence[str],
        robot: str,
        *,
        record_times: RecordTimes,
        checkpoint_windows: int = 0,
        start: float = -np.inf,
    ) -> None:
        self.estimator = estimator
        self.roster = tuple(roster)
        self.robot = robot
        self.index = self.roster.index(robot)
        self.record_times = record_times
        self.sent: list[tuple[float, Any]] = []
        """What the estimator sent and the node has not published yet: ``(stamp, message)``."""
        self._wired = _Wired(estimator, self)
        self._wired.owner = robot
        self._recorder = Recorder(estimator.name)
        self._inbox: list[tuple[float, int, int, Any]] = []
        self._arrivals = 0
        self._t: float | None = None
        self._plan: _Plan | None = None
        self._window_end = -np.inf
        self._counts = {
            "created": 0,
            "deleted": 0,
            "recreated": 0,
            "skipped_absent": 0,
            "messages_late": 0,
            "rows_refiltered": 0,
            "rows_late_lost": 0,
            "rows_before_start": 0,
            "odometry_refiltered": 0,
            "odometry_late_lost": 0,
            "rows_before_handoff": 0,
        }
        self._rows_not_used: dict[str, int] = {}
        self.checkpoint_windows = checkpoint_windows
        self.start = float(start)
        self._checkpoints: deque[_Checkpoint] = deque()
        self._talks = False
        self._streams: list[ReceivedOdometry] = []
        self._handed_at = -np.inf

    def mark_talking(self) -> None:
        """The estimator's messages go to teammates (no re-filtering: what it sent is out)."""
        self._talks = True

    def refuses_odometry(self, u: Array) -> bool:
        """Whether body velocities ``u`` ``(n, 4)`` cannot drive the estimator: one of planar
        unicycles (optional attribute ``planar_unicycles``: seed 001's team filter) takes no
        lateral or vertical velocity."""
        return bool(getattr(self.estimator, "planar_unicycles", False) and np.any(u[:, 1:3]))

    # ------------------------------------------------------------------ rejoining the team
    @property
    def hands_off(self) -> bool:
        """Whether the estimator can hand its team belief to a restarted teammate and start
        from one (optional ``team_belief() -> (t, Gaussian)`` and ``resumed(t, Gaussian)``:
        seed 001's team filter)."""
        return callable(getattr(self.estimator, "team_belief", None)) and callable(
            getattr(self.estimator, "resumed", None)
        )

    @property
    def time(self) -> float | None:
        """The latest event the estimator processed (None before the first)."""
        return self._t

    def team_belief(self) -> tuple[float, Gaussian]:
        """The estimator's belief of the whole team at its latest event (:attr:`hands_off`)."""
        t, belief = self.estimator.team_belief()  # type: ignore[attr-defined]
        return float(t), belief

    def resume(self, t: float, belief: Gaussian) -> None:
        """Continue from a teammate's team belief at its event ``t``: the estimator starts
        there (``resumed``) and only what comes after ``t`` is filtered — readings at or
        before ``t`` are in the belief already and are counted (``rows_before_handoff``)."""
        assert not self.busy and not self._checkpoints, "resume: windows were filtered already"
        self.estimator = self._wired.inner = self.estimator.resumed(t, belief)  # type: ignore[attr-defined]
        self._t = self._handed_at = float(t)
        self._window_end = float(t)

    # ------------------------------------------------------------------ windows
    @property
    def busy(self) -> bool:
        """Whether a window was started and not all of its events processed."""
        return self._plan is not None and not self._plan.done

    @property
    def progress(self) -> float:
        """Every message this estimator will send stamped before this time has been sent: its
        events before it are processed (module docstring) — or, for an estimator that says
        when it sends next (optional ``quiet_until() -> float``), up to that time. Capped at
        the end of the planned window plus :data:`QUIET_HORIZON_S` so that it stays finite."""
        if self.busy:
            assert self._plan is not None
            done = float(self._plan.times[self._plan.next])
        else:
            done = self._window_end
        quiet = getattr(self.estimator, "quiet_until", None)
        if quiet is not None and np.isfinite(done):
            done = max(done, min(float(quiet()), done + QUIET_HORIZON_S))
        return done

    def _filterable(self, rows: Measurements) -> Measurements:
        """``rows`` without those no window filters: before :attr:`start` (counted
        ``rows_before_start``) or in the belief handed over (:meth:`resume`; counted
        ``rows_before_handoff``)."""
        early = rows.t < self.start - TIME_TOL
        if early.any():
            self._counts["rows_before_start"] += int(early.sum())
            rows = rows.select(~early)
        handed = rows.t <= self._handed_at + TIME_TOL
        if handed.any():
            self._counts["rows_before_handoff"] += int(handed.sum())
            rows = rows.select(~handed)
        return rows

    def start_window(
        self,
        t0: float,
        t1: float,
        *,
        streams: Sequence[ReceivedOdometry],
        rows: Measurements,
        present: set[str],
        inclusive: bool = False,
    ) -> None:
        """Plan the events of ``[t0, t1)`` (``[t0, t1]`` with ``inclusive``) from every robot's
        odometry as received (``streams`` in roster order) and the window's measurement rows;
        rows of a teammate that is not ``present`` are dropped and counted."""
        assert not self.busy, "start_window: the previous window is not finished"
        self._streams = list(streams)
        live = self._filterable(self._live_rows(rows, present))
        self._plan = self._make_plan(t0, t1, live, inclusive)
        self._checkpoint(t0)
        if not self._plan.times.size:
            self._window_end = t1

    def _make_plan(self, t0: float, t1: float, rows: Measurements, inclusive: bool) -> _Plan:
        """The events of ``[t0, t1)`` (``[t0, t1]``) after the estimator's current time: the
        record times, the readings' stamps and every robot's odometry stamps in
        :attr:`_streams`, with the velocity (and its stamp) each robot holds up to each event."""
        record = self.record_times(t0, t1, inclusive, rows)
        streams = self._streams
        pieces = [record, rows.t] + [s.stamps_between(t0, t1, inclusive) for s in streams]
        times = merge_times(*pieces)
        times = times[times >= self.start - TIME_TOL]
        record = record[record >= self.start - TIME_TOL]
        if self._t is not None:  # (a window edge within TIME_TOL of the last event is that
            times = times[times >= self._t - TIME_TOL]  # event again: it is recorded there)
            record = record[record >= self._t - TIME_TOL]
        # the velocity in force up to each event: the one held at the previous event (for the
        # first event, at the estimator's current time)
        start = times[:1] if self._t is None else np.array([self._t])
        before = np.concatenate([start, times[:-1]]) + TIME_TOL
        held = np.stack([s.held_at(before) for s in streams], axis=1)
        stamps = np.stack([s.stamp_at(before) for s in streams], axis=1)
        return _Plan(t1, times, held, stamps, rows, record, inclusive)

    def run(self, until: float | None = None) -> bool:
        """Process the planned events at or before ``until`` (every one if None); True once
        the window is finished."""
        plan = self._plan
        if plan is None:
            return True
        n = plan.times.size
        stop = n if until is None else int(np.searchsorted(plan.times, until + TIME_TOL, "right"))
        if stop > plan.next:
            times = plan.times[plan.next : stop]
            fed_to = int(np.searchsorted(plan.rows.t, times[-1] + TIME_TOL, side="right"))
            batch = plan.rows.select(slice(plan.fed, fed_to))
            lo, hi = times[0] - TIME_TOL, times[-1] + TIME_TOL
            record = plan.record[(plan.record >= lo) & (plan.record <= hi)]
            held = plan.held[plan.next : stop]
            stamps = plan.stamps[plan.next : stop]
            run_events([self._wired], times, held, stamps, batch, record, self._recorder)
            plan.next, plan.fed = stop, fed_to
            self._t = float(times[-1])
        if plan.done:
            self._window_end = plan.t1
        return plan.done

    # ------------------------------------------------------------------ late readings
    def _checkpoint(self, t0: float) -> None:
        """Keep the estimator's state before the window just planned, with the plan (the last
        :attr:`checkpoint_windows` windows), for :meth:`refilter`."""
        if self.checkpoint_windows == 0:
            return
        assert self._plan is not None
        state = copy.deepcopy(self.estimator)
        self._checkpoints.append(_Checkpoint(t0, self._t, self._window_end, state, self._plan))
        while len(self._checkpoints) > self.checkpoint_windows:
            self._checkpoints.popleft()

    def refilter(self, late: Measurements, *, odometry: Array | None = None) -> int:
        """Fuse what arrived after its window was filtered at its own time stamps: readings
        ``late`` and odometry samples stamped ``odometry`` (already filed in the streams the
        driver was given: :meth:`ReceivedOdometry.file_late`). Go back to the checkpoint of
        the earliest window they belong to and plan and filter every window since again
        (re-recording the beliefs of those windows: the collector keeps the latest belief of
        each time). Returns the readings that could not be fused (older than every
        checkpoint, or the estimator talks to teammates: what it sent is out); they are
        counted (``rows_late_lost``, samples ``odometry_late_lost``), the fused ones too
        (``rows_refiltered``, ``odometry_refiltered``). Readings before :attr:`start` or in
        the belief handed over (:meth:`resume`) are not fused, as in :meth:`start_window`, and
        counted (``rows_before_start``, ``rows_before_handoff``)."""
        samples = np.zeros(0) if odometry is None else np.asarray(odometry, dtype=float)
        late = self._filterable(late)
        if late.size == 0 and samples.size == 0:
            return 0
        earliest = float(np.min(np.concatenate([late.t, samples])))
        fits = [k for k, c in enumerate(self._checkpoints) if c.t0 <= earliest + TIME_TOL]
        if self.busy or self.sent or self._talks or not fits:
            self._counts["rows_late_lost"] += late.size
            self._counts["odometry_late_lost"] += samples.size
            return late.size
        first = fits[-1]
        again = list(self._checkpoints)[first:]
        while len(self._checkpoints) > first:
            self._checkpoints.pop()
        start = again[0]
        self.estimator = self._wired.inner = copy.deepcopy(start.state)
        self._t, self._window_end = start.t, start.window_end
        for i, c in enumerate(again):
            t_next = again[i + 1].t0 if i + 1 < len(again) else np.inf
            mine = late.select((late.t >= c.t0 - TIME_TOL) & (late.t < t_next - TIME_TOL))
            rows = _in_robot_order(Measurements.concatenate([c.plan.rows, mine]))
            self._plan = self._make_plan(c.t0, c.plan.t1, rows, c.plan.inclusive)
            self._checkpoint(c.t0)
            if not self._plan.times.size:
                self._window_end = c.plan.t1
            self.run()
        self._counts["rows_refiltered"] += late.size
        self._counts["odometry_refiltered"] += samples.size
        return 0

    @property
    def history_from(self) -> float:
        """The earliest time re-filtering may plan from again (the estimator's time at the
        oldest checkpoint): the streams must keep the samples held since then."""
        if not self._checkpoints:
            return np.inf
        c = self._checkpoints[0]
        return c.t0 if c.t is None else c.t

    def _live_rows(self, rows: Measurements, present: set[str]) -> Measurements:
        """``rows`` without those of (or about) a teammate that is not present — the rows
        about it are kept where the estimator follows lost robots (optional
        ``follows_lost_robots``: seed 001's team filter, whose lost model predicts such a
        robot's motion, loosely)."""
        if rows.size == 0:
            return rows
        absent = np.array(
            [r not in present and r != self.robot for r in self.roster] + [False], dtype=bool
        )
        dead = absent[rows.observer]
        if not getattr(self.estimator, "follows_lost_robots", False):
            # index −1 (no target robot: a landmark, a bearing of unknown origin) maps to False
            dead |= absent[np.where(rows.target >= 0, rows.target, -1)]
        self._counts["skipped_absent"] += int(dead.sum())
        return rows.select(~dead) if dead.any() else rows

    # ------------------------------------------------------------------ messages
    def deliver(self, stamp: float, sender: str, messages: Sequence[Any]) -> None:
        """Teammate ``sender``'s messages sent at its event ``stamp``. One stamped before an
        event this driver already processed is fused at the next event, and counted late."""
        order = self.roster.index(sender)
        if self._t is not None and stamp < self._t - TIME_TOL:
            self._counts["messages_late"] += len(messages)
        for m in messages:
            self._inbox.append((stamp, order, self._arrivals, m))
            self._arrivals += 1

    def due_messages(self, t: float) -> list[Any]:
        """Received messages stamped before ``t``, in the in-process order (by stamp, then
        sender in roster order, then arrival)."""
        due = [m for m in self._inbox if m[0] < t - TIME_TOL]
        if not due:
            return []
        self._inbox = [m for m in self._inbox if m[0] >= t - TIME_TOL]
        return [m[3] for m in sorted(due, key=lambda m: m[:3])]

    def take_sent(self) -> list[tuple[float, Any]]:
        """What the estimator sent since the last call, ``(stamp, message)``."""
        sent, self.sent = self.sent, []
        return sent

    # ------------------------------------------------------------------ results
    def take_new(self) -> Estimates:
        """Everything recorded since the previous call: beliefs, updates, track events."""
        new = self._recorder.take_new()
        for e in new.events:
            self._counts[e.kind] += 1
        self._rows_not_used = dict(new.counts)
        return new

    def beliefs(self) -> list[Belief]:
        """Current belief of every subject (what the node broadcasts as ``eqm``)."""
        return [] if self._t is None else list(self.estimator.beliefs())

    def counters(self) -> dict[str, int]:
        """Track events shipped, rows of absent teammates, late messages, and the rows the
        estimator could not use (by reason, as of the latest :meth:`take_new`)."""
        return {**self._counts, **self._rows_not_used}


class OdometryOnly(Silent):
    """The estimator of a robot that only shares its odometry (seed 002's pods): it believes
    nothing, sends nothing and ignores what it is given."""

    name = "none"

    def __init__(self, owner: str) -> None:
        self.owner = owner

    def advance(self, t: float, odometry: HeldOdometry) -> None:
        del t, odometry

    def measure(self, batch: Measurements) -> None:
        del batch

    def beliefs(self) -> list[Belief]:
        return []
