"""The timing-driven branches of a robot node's message handling, each made to happen on purpose:
windows before the estimator's start, late readings and odometry re-filtered (or not) from the
checkpoints, a restarted agent's late readings of before its hand-off, a window forced through
while its talking teammate's progress is missing and the mail that comes after it, a ``sync``
reply too large for one message, a held ack of a restarted talker and the last instant of a
live source whose clock left.

A real :class:`~relloc.runtime.node.RobotNode` is driven by hand (``node_harness``): ticks and
the teammates' messages are handed over one at a time in the order each situation needs, so
the timing is deterministic. The estimator's side is watched where the robot node hands it
readings (:class:`relloc.runtime.estimation._Wired`) and messages.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator
from typing import Any

import numpy as np
import pytest
from node_harness import DT, DURATION_S, TEAM, hand_node, odom, tick

from relloc.core.recording import Measurements, empty_measurements, kind_code
from relloc.experiments.team_sources import (
    SHARMA_RECORD_RATE_HZ,
    named_node_parts,
    sharma_node_parts,
    sharma_sim,
)
from relloc.runtime import estimation, keys
from relloc.runtime.estimation import WindowDriver, grid_record_times
from relloc.runtime.mail import mail_body
from relloc.runtime.messages import DEFAULT_MAX_BYTES, encode
from relloc.runtime.node import NodeParts, RobotNode
from relloc.runtime.shared_rows import rows_body
from relloc.runtime.sources import LiveSource
from relloc.runtime.transport import Incoming

TOL = 1e-9
SEED, RUN = 5, 0


@pytest.fixture(scope="module")
def sim() -> Any:
    """Seed 001's simulation the agents of :func:`_agent` are built from (the teammates'
    readings and the team prior come from it)."""
    return sharma_sim(SEED, RUN, DURATION_S)[1]


@pytest.fixture
def fed(monkeypatch: pytest.MonkeyPatch) -> list[tuple[float, Measurements]]:
    """Every batch of readings the estimator of a node is given, with the event it is given
    at: ``(event time, rows)``."""
    batches: list[tuple[float, Measurements]] = []
    measure = estimation._Wired.measure

    def spy(self: Any, batch: Measurements) -> None:
        batches.append((self.t, batch))
        measure(self, batch)

    monkeypatch.setattr(estimation._Wired, "measure", spy)
    return batches


def _rows_fed(fed: list[tuple[float, Measurements]]) -> Iterator[tuple[float, float, int]]:
    """``(event time, reading's stamp, reading's observer)`` of every reading fed."""
    for t, batch in fed:
        for stamp, observer in zip(batch.t, batch.observer, strict=True):
            yield t, float(stamp), int(observer)


class _Mates:
    """The teammates of a hand-driven node: their messages of tick ``k`` carry sequence number
    ``k − 1`` (one message of each kind a tick) and header time ``t_k``."""

    def __init__(self, node: RobotNode) -> None:
        self.node = node
        self.roster = node.s.roster
        self.names = [r for r in self.roster if r != node.s.robot]

    def odom(self, mate: str, k: int) -> None:
        self.node._on_incoming(odom(mate, k - 1, k * DT))

    def rows(self, mate: str, k: int, rows: Measurements | None = None) -> None:
        body = rows_body(empty_measurements() if rows is None else rows, self.roster)
        key = keys.robot_key(TEAM, mate, "rows")
        self.node._on_incoming(Incoming(key, encode("rows", mate, k - 1, k * DT, body)))

    def tick(self, k: int, *, silent: tuple[str, ...] = ()) -> None:
        """Tick ``k``, then every teammate's odometry and (no) readings of it but ``silent``'s."""
        tick(self.node, k)
        for m in self.names:
            if m not in silent:
                self.odom(m, k)
                self.rows(m, k)


def _readings(sim: Any, mate: str, t0: float, t1: float) -> Measurements:
    """Teammate ``mate``'s readings stamped in ``[t0, t1)``."""
    m = sim.recording.measurements
    mine = (m.observer == sim.recording.index(mate)) & (m.t >= t0 - TOL) & (m.t < t1 - TOL)
    return m.select(mine)


def _agent(session: Any, robot: str = "1", **driver: Any) -> tuple[RobotNode, _Mates]:
    """Seed 001's agent ``robot`` (sharing readings); ``driver``: its driver built again with
    these arguments (``start``, ``checkpoint_windows``)."""
    parts = sharma_node_parts(robot, SEED, RUN, DURATION_S, "two_landmarks")
    if driver:
        old = parts.driver
        new = WindowDriver(
            old.estimator,
            old.roster,
            robot,
            record_times=grid_record_times(SHARMA_RECORD_RATE_HZ, 0.0),
            checkpoint_windows=driver.pop("checkpoint_windows", old.checkpoint_windows),
            **driver,
        )
        parts = dataclasses.replace(parts, driver=new)
    node = hand_node(parts, robot, session, share_rows=True)
    return node, _Mates(node)


# ------------------------------------------------------------------ the estimator's start
def test_readings_before_the_estimators_start_are_counted_and_never_fused(session, fed):
    """Nothing before the driver's ``start`` is filtered (a recorded team whose filter starts
    after its first windows): the readings of the windows before it, and those of the window
    it falls in that come before it, are counted ``rows_before_start``; the later ones fused."""
    start = 0.25
    node, mates = _agent(session, start=start)
    for k in range(1, 5):
        mates.tick(k)
    assert node._filtered_until == pytest.approx(0.4)
    own = node.source.rows(0.0, 0.4)
    counters = node.final_counters()
    assert counters["tracks.rows_before_start"] == int(np.sum(own.t < start)) > 0
    stamps = [stamp for _, stamp, _ in _rows_fed(fed)]
    assert stamps and min(stamps) >= start
    assert len(stamps) == int(np.sum(own.t >= start))  # those after it are all fused


def test_late_readings_before_the_estimators_start_are_counted_not_refiltered(session, sim, fed):
    """A teammate's readings of the window holding ``start`` that arrive after it was filtered
    are re-filtered from its checkpoint — but those stamped before ``start`` are no more fused
    then than on time: counted ``rows_before_start``, not ``rows_refiltered``, and never given
    to the estimator (they were fused at the first event after ``start``, at the wrong time)."""
    start = 0.25
    node, mates = _agent(session, start=start)
    late = _readings(sim, "3", 0.2, 0.3)
    assert late.size and np.all(late.t < start)
    for k in range(1, 5):
        mates.tick(k, silent=("3",))
        mates.odom("3", k)
        if k != 3:  # its readings of [0.2, 0.3) are on their way
            mates.rows("3", k)
    assert node._filtered_until == pytest.approx(0.4)
    before = node.estimator.counters()["rows_before_start"]
    fed.clear()
    mates.rows("3", 3, late)
    counters = node.estimator.counters()
    assert node.counters["rows_late"] == late.size
    assert counters["rows_before_start"] == before + late.size
    assert counters["rows_refiltered"] == 0 and counters["rows_late_lost"] == 0
    assert all(stamp >= start for _, stamp, _ in _rows_fed(fed))


def test_refiltering_windows_that_hold_no_event_still_reaches_their_end(session):
    """Windows wholly before ``start`` hold no event. A teammate's odometry sample that comes
    after its window was filtered is re-filtered from the checkpoint (``odometry_refiltered``),
    and when every window re-planned holds no event the driver has still got to the end of the
    last one: its progress is that end, as before the sample came."""
    node, mates = _agent(session, start=0.55)
    for k in range(1, 5):
        mates.tick(k, silent=("3",))
        if k != 2:  # its odometry of [0.1, 0.2) comes after its window was filtered
            mates.odom("3", k)
        mates.rows("3", k)
    driver = node.estimator
    assert node._filtered_until == pytest.approx(0.4) and driver.time is None
    assert driver.progress == pytest.approx(0.4)
    mates.odom("3", 2)
    assert node.final_counters()["late_samples"] == 1
    assert driver.counters()["odometry_refiltered"] == 1
    assert not driver.busy and driver.progress == pytest.approx(0.4)


def test_a_driver_asked_to_run_before_any_window_has_nothing_to_do():
    """:meth:`WindowDriver.run` before a window was planned: finished, nothing processed (a
    node always plans a window first; the driver's own contract)."""
    driver = named_node_parts("desilva2015", "L1", SEED, RUN, DURATION_S).driver
    assert driver.run() is True and driver.run(until=1.0) is True
    assert driver.time is None and not driver.busy and driver.beliefs() == []
    assert not driver.take_new().beliefs


# ------------------------------------------------------------------ late data and checkpoints
def test_late_data_older_than_every_checkpoint_is_counted_lost_and_the_rest_refiltered(
    session, sim, fed
):
    """Teammate 3 is silent until the node forces its first windows through (overdue); then
    its backlog comes, in order. With one checkpoint kept (the window ``[0.2, 0.3)``), what
    belongs to the windows before it cannot be re-filtered — counted ``odometry_late_lost``
    and ``rows_late_lost``, never fused — and what belongs to it is re-filtered."""
    node, mates = _agent(session, checkpoint_windows=1)
    for k in range(1, 9):
        mates.tick(k, silent=("3",))
    assert node.counters["overdue_windows"] == 3
    assert node._filtered_until == pytest.approx(0.3)
    lost_rows, refiltered_rows = _readings(sim, "3", 0.0, 0.2), _readings(sim, "3", 0.2, 0.3)
    assert lost_rows.size and refiltered_rows.size
    fed.clear()
    for k in range(1, 4):  # its messages of the windows filtered without them
        mates.odom("3", k)
        mates.rows("3", k, _readings(sim, "3", (k - 1) * DT, k * DT))
    counters = node.final_counters()
    assert counters["late_samples"] == 3 and counters["late_rows"] == 0
    assert node.counters["rows_late"] == lost_rows.size + refiltered_rows.size
    assert counters["tracks.odometry_late_lost"] == 2  # stamped 0.05 and 0.15
    assert counters["tracks.odometry_refiltered"] == 1  # stamped 0.25
    assert counters["tracks.rows_late_lost"] == lost_rows.size
    assert counters["tracks.rows_refiltered"] == refiltered_rows.size
    third = sim.recording.index("3")
    fused = sorted(stamp for _, stamp, observer in _rows_fed(fed) if observer == third)
    assert fused == sorted(refiltered_rows.t.tolist())


def _restarted(session: Any, sim: Any, **settings: Any) -> tuple[RobotNode, _Mates]:
    """Agent 1 restarted: the first tick it hears is tick 3; it asks agent 2 for the team
    belief (``sync``), which has not answered yet."""
    parts = sharma_node_parts("1", SEED, RUN, DURATION_S, "two_landmarks")
    node = hand_node(parts, "1", session, share_rows=True, **settings)
    mates = _Mates(node)
    mates.tick(3)
    assert node._handoff.waiting and node.counters["sent.sync"] == 1
    return node, mates


def _sync_reply(node: RobotNode, sim: Any, stamp: float, sender: str = "2") -> None:
    """The answer of the teammate asked: the team belief at its event ``stamp``."""
    body = {"target": "1", "stamp": stamp, "mean": sim.prior.mean, "cov": sim.prior.cov}
    key = keys.robot_key(TEAM, sender, "sync")
    node._on_incoming(Incoming(key, encode("sync", sender, 0, node._t, body)))


def test_late_readings_of_before_the_handoff_are_counted_not_fused_again(session, sim, fed):
    """A restarted agent continues from agent 2's team belief at 0.3 s; agent 3's readings of
    ``[0.1, 0.2)`` then arrive (reordered): late, but already in the belief handed over —
    counted ``rows_before_handoff``, neither re-filtered nor lost, never fused."""
    node, mates = _restarted(session, sim)
    _sync_reply(node, sim, 0.3)
    assert node.counters["sync.resumed"] == 1 and node._filtered_until == pytest.approx(0.3)
    mates.tick(4)
    driver = node.estimator
    before = driver.counters()["rows_before_handoff"]
    late = _readings(sim, "3", 0.1, 0.2)
    assert late.size
    fed.clear()
    mates.rows("3", 2, late)
    counters = driver.counters()
    assert node.counters["rows_late"] == late.size
    assert counters["rows_before_handoff"] == before + late.size
    assert counters["rows_refiltered"] == 0 and counters["rows_late_lost"] == 0
    assert not any(stamp <= 0.3 + TOL for _, stamp, _ in _rows_fed(fed))


# ------------------------------------------------------------------ talking leaders
def _leader(session: Any) -> tuple[RobotNode, list[str]]:
    """Seed 002's leader L1, every teammate present; L2 (the other talker) has sent nothing."""
    parts = named_node_parts("desilva2015", "L1", SEED, RUN, DURATION_S)
    node = hand_node(parts, "L1", session, talkers=parts.talkers)
    return node, [r for r in parts.roster if r != "L1"]


def _leader_ticks(node: RobotNode, mates: list[str], ks: range) -> None:
    for k in ks:
        tick(node, k)
        for m in mates:
            node._on_incoming(odom(m, k - 1, k * DT))


def _mail(node: RobotNode, progress: float, sent: list[tuple[float, Any]], seq: int = 0) -> None:
    body = mail_body(progress, sent, node.s.roster, DEFAULT_MAX_BYTES)[0]
    key = keys.robot_key(TEAM, "L2", "mail")
    node._on_incoming(Incoming(key, encode("mail", "L2", seq, node._t, body)))


def test_a_window_forced_through_while_the_teammates_progress_is_missing_is_counted(session):
    """L1 has every odometry sample but none of L2's progress: its windows start and wait for
    it; each that is ``max_lag_ticks`` overdue is filtered anyway (the run goes on) and counted
    ``overdue_windows.waiting_for_mail`` — its inputs were in, so not ``overdue_windows``."""
    node, mates = _leader(session)
    _leader_ticks(node, mates, range(1, 6))
    assert node._filtered_until == pytest.approx(0.0) and node.estimator.busy
    assert node.counters["overdue_windows.waiting_for_mail"] == 0
    _leader_ticks(node, mates, range(6, 9))  # the windows ending at 0.1, 0.2, 0.3 are overdue
    assert node._filtered_until == pytest.approx(0.3)
    assert node.counters["overdue_windows.waiting_for_mail"] == 3
    assert node.counters["overdue_windows"] == 0


def _equivalent_measurement(t: float) -> Any:
    """An equivalent measurement of L2 (index 1) about P1 (index 2) sent at ``t``."""
    from relloc.fusion.messages import EquivalentMeasurement

    means = np.array([[1.0, 0.5, 0.0, 0.1], [1.2, 0.4, 0.0, 0.2]])
    covs = np.stack([np.eye(4) * 0.1] * 2)
    return EquivalentMeasurement(
        sender=1,
        subject=2,
        time=t,
        means=means,
        covs=covs,
        prior_means=means + 0.1,
        prior_covs=covs * 2,
        weights=np.array([1.0, 2.0]),
    )


def test_mail_stamped_before_what_was_forced_through_is_counted_late_and_fused_next(
    session, monkeypatch
):
    """L1 forced its first windows through without L2's progress (overdue); L2's mail then
    comes with a message L2 sent at 0.05 s, before events L1 has processed: counted
    ``messages_late`` and handed to L1's estimator at its next event — after that event, not
    at the event after 0.05 s where the in-process run would have."""
    from relloc.fusion.gaussian_sum_estimator import GaussianSumEstimator

    received: list[tuple[float | None, int]] = []
    receive = GaussianSumEstimator.receive

    def spy(self: Any, messages: Any) -> None:
        received.append((self._t, len(messages)))
        receive(self, messages)

    monkeypatch.setattr(GaussianSumEstimator, "receive", spy)
    node, mates = _leader(session)
    _leader_ticks(node, mates, range(1, 9))
    done = node.estimator.time
    assert done is not None and done > 0.05 and not received
    _mail(node, 0.8, [(0.05, _equivalent_measurement(0.05))])
    driver = node.estimator
    assert driver.counters()["messages_late"] == 1
    assert received == [(done, 1)]  # before the first event after ``done``
    driver.take_new()
    fused = {k: v for k, v in driver.counters().items() if k.startswith("messages_fused:")}
    assert sum(fused.values()) == 1, fused


def test_mail_stamped_after_what_was_processed_is_not_late(session):
    """The contrast: L2's progress and a message stamped after L1's latest event are on time."""
    node, mates = _leader(session)
    _leader_ticks(node, mates, range(1, 9))
    done = node.estimator.time
    assert done is not None
    _mail(node, 0.8, [(done + 0.01, _equivalent_measurement(done + 0.01))])
    assert node.estimator.counters()["messages_late"] == 0


# ------------------------------------------------------------------ sync and acks
@pytest.mark.parametrize(("max_bytes", "sent"), [(2048, 0), (DEFAULT_MAX_BYTES, 1)])
def test_a_sync_reply_too_large_for_one_message_is_counted_and_the_node_goes_on(
    session, max_bytes, sent
):
    """Agent 2 is asked for the team belief (5 robots: a 15-vector and its 15×15 covariance,
    about 2.3 kB packed); under a 2 kB message limit the reply cannot go — counted
    ``sync.too_large``, nothing sent, the node goes on filtering and acknowledging."""
    node, mates = _agent(session, "2")
    node.s = dataclasses.replace(node.s, max_bytes=max_bytes)
    request = {"target": "2", "stamp": 0.2, "mean": np.zeros(0), "cov": np.zeros((0, 0))}
    for k in range(1, 6):
        mates.tick(k)
        if k == 2:
            key = keys.robot_key(TEAM, "1", "sync")
            node._on_incoming(Incoming(key, encode("sync", "1", 0, k * DT, request)))
    assert node.counters["sync.requests_received"] == node.counters["sync.replies_due"] == 1
    assert node.counters["sent.sync"] == sent
    assert node.counters["sync.too_large"] == 1 - sent
    assert node._filtered_until == pytest.approx(0.5) and node.counters["sent.ack"] == 5


def test_a_restarted_talker_waiting_for_the_team_belief_holds_its_acks_until_it_comes(session, sim):
    """A restarted agent whose estimator talks (``talkers``) filters nothing until the team
    belief comes; from the tick at which its oldest window is overdue it holds every ack —
    without a wall-time bound (``acks_held`` stays 0), as the clock must not run ahead of a
    talker that owes its progress — and sends them all once the belief came and its windows
    were filtered."""
    node, mates = _restarted(session, sim, talkers=("1",))
    for k in range(4, 11):  # the window [0.2, 0.3) is overdue at the tick of 0.8 s
        mates.tick(k)
    assert node._handoff.waiting and node._pending
    assert node.counters["sent.ack"] == 5  # ticks 3..7
    assert node.counters["acks_held"] == 0 and node._hold_deadline is None
    assert node.counters["sent.sync"] == 2  # agent 2 did not answer: agent 3 asked at 0.8 s
    _sync_reply(node, sim, 1.0, sender="3")
    assert node.counters["sync.resumed"] == 1 and not node._pending
    assert node.counters["sent.ack"] == 8


# ------------------------------------------------------------------ a live source's last instant
@pytest.mark.parametrize("waiting", [True, False])
def test_a_live_node_whose_clock_leaves_fuses_the_readings_of_its_last_instant(
    session, fed, waiting
):
    """A node on a live source (no recorded ``rows``: its readings come as range/azimuth/
    elevation batches) whose clock leaves after tick 5: the run ends at 0.5 s and the readings
    taken then are fused, as rows of the right observer and targets — whether its last window
    still waited for a teammate (it ends the run, holding them) or was filtered already (the
    instant is a window of its own: before, they were neither fused nor counted)."""
    from relloc.estimators.track_manager import TrackManagerSettings, track_manager_of
    from relloc.runtime.scenario import load_team

    rec = load_team("default", 0).recording
    robot = rec.robots[0]
    i = rec.index(robot)
    live = LiveSource(robot, odometry_sigma=rec.odometry[i].sigma)
    od = rec.odometry[i]
    for t, u in zip(od.t, od.velocity, strict=True):
        if t <= 0.5 + TOL:
            live.push_odometry(float(t), u)
    m = rec.measurements
    mine = (m.observer == i) & (m.kind == kind_code("range_bearing_elevation")) & (m.target >= 0)
    for q in np.flatnonzero(mine & (m.t <= 0.5 + TOL)):
        live.push_measurement(float(m.t[q]), rec.robots[m.target[q]], m.value[q], m.sigma[q])
    last = mine & (np.abs(m.t - 0.5) < TOL)
    assert last.any()
    manager = track_manager_of(rec, robot, TrackManagerSettings(), rng=np.random.default_rng(0))
    driver = WindowDriver(manager, rec.robots, robot, record_times=grid_record_times(10.0))
    node = hand_node(NodeParts(rec.robots, live, driver), robot, session)
    mates = [r for r in rec.robots if r != robot]
    for k in range(1, 6):
        tick(node, k)
        for mate in mates:
            if k < 5 or mate != mates[-1] or not waiting:  # the last one's of [0.4, 0.5) is late
                node._on_incoming(odom(mate, k - 1, k * DT))
    assert node._filtered_until == pytest.approx(0.4 if waiting else 0.5)
    node._on_incoming(Incoming(keys.alive_key(TEAM, "clock"), b"", presence="left"))
    assert node.counters["exit.clock_left"] == 1 and not node._pending
    at_end = [(observer, t) for t, stamp, observer in _rows_fed(fed) if abs(stamp - 0.5) < TOL]
    assert at_end == [(i, pytest.approx(0.5))] * int(last.sum())
    targets = sorted(int(tg) for t, b in fed for tg in b.target[np.abs(b.t - 0.5) < TOL])
    assert targets == sorted(m.target[last].tolist())
