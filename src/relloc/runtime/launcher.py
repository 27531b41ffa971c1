"""``relloc team up``: a whole team as separate OS processes on this machine.

The launcher process is the Zenoh hub and the collector: it *listens* on one explicit loopback
endpoint; the clock/simulator process and every robot process *connect* to it and listen on
loopback only (multicast scouting off). With ``--secure`` every process speaks mutual TLS only,
with one certificate per robot and one for the launcher and clock, and Zenoh access control
(:mod:`relloc.runtime.access`). It then

- starts ``relloc team clock`` (the clock/simulator process) and one ``relloc node`` per robot,
  each robot simulating the same seeded scenario and reading only its own sensor slice;
- collects every robot's ``est`` batches and ``stats`` counters, and watches liveliness (only
  messages that pass :func:`relloc.runtime.admission.admit`, and reports within each sender's
  memory quota, :mod:`relloc.runtime.quota`; rejections counted by reason);
- executes the clock's ``kill`` events with a real ``SIGKILL`` of the robot's process and its
  ``restart`` events by starting the robot again (it rejoins mid-run at the current tick) —
  only events of its own fault schedule, each once;
- once the clock process has exited (after its ``ctl(end)``), waits for every robot to exit,
  then scores the collected estimates with
  the same functions as the in-process run (:mod:`relloc.runtime.summary`).

Children are started through a ``forkserver`` that has imported relloc once (a fresh interpreter
per robot would spend seconds importing numpy/scipy on a small machine); each child runs exactly
``relloc node ...`` / ``relloc team clock ...`` (the printed commands work by hand too) in its own
OS process with its own Zenoh session. Every child is killed in a ``finally`` block whatever
happens; each one's output goes to ``<out>/logs/<robot>.log``.
"""

from __future__ import annotations

import multiprocessing
import os
import signal
import sys
import time
from collections import Counter
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from relloc.core.checks import count, number, positive, probability
from relloc.errors import ConfigError, RellocError
from relloc.runtime import CLOCK_TICK_S, keys
from relloc.runtime.access import SecureTeam, secure_team
from relloc.runtime.admission import admit, check_stamps
from relloc.runtime.faults import FaultSettings, RobotEvent
from relloc.runtime.messages import DEFAULT_MAX_BYTES, Message, MessageRejected
from relloc.runtime.quota import ReportQuota
from relloc.runtime.scenario import check_source
from relloc.runtime.transport import (
    DEFAULT_LISTEN,
    Inbox,
    TransportSettings,
    free_loopback_port,
    loopback_endpoint,
    open_session,
)


def check_pacing(settings: TeamSettings | ProcessTeam) -> None:
    """The clock step, wall-time limit, pacing and security flags that :class:`TeamSettings`
    and :class:`ProcessTeam` share, each a ConfigError naming its flag."""
    number(settings.tick_s, "--tick", low=0.001, high=10.0)
    positive(settings.wall_timeout_s, "--timeout")
    number(settings.realtime_factor, "--realtime", low=0.0)
    if settings.certs_dir is not None and not settings.secure:
        raise ConfigError("--certs: only with --secure")


DEFAULT_FILTER = "plkf"
"""The track managers' filter of ``relloc node`` not given ``--filter`` (and of a team)."""


@dataclass(frozen=True, kw_only=True)
class TeamSettings:
    """One ``team up`` run. ``scenario`` is a team source: ``"default"``, a scenario TOML file or
    a dataset folder (see :mod:`relloc.runtime.scenario`)."""

    scenario: str
    out_dir: Path
    seed: int = 0
    team: str = "team"
    tick_s: float = CLOCK_TICK_S
    faults: FaultSettings = field(default_factory=FaultSettings)
    realtime_factor: float = 0.0
    port: int | None = None
    wall_timeout_s: float = 300.0
    filter_kind: str = DEFAULT_FILTER
    gate_probability: float | None = None
    """The track managers' NIS gate (``--gate``; :class:`TrackManagerSettings`), or none."""
    secure: bool = False
    """Mutual TLS and access control (:mod:`relloc.runtime.access`) for every process."""
    certs_dir: Path | None = None
    """The team's certificate folder (``relloc certs``); made in ``<out>/certs`` if None."""
    node_args: tuple[str, ...] = ()
    """Extra ``relloc node`` arguments of every robot (a reproduction's run and duration)."""
    preload: tuple[str, ...] = ()
    """Modules the robot processes need beyond :data:`PRELOAD` (a reproduction's team names
    its own), imported once by the fork server."""

    def __post_init__(self) -> None:
        keys.check_id(self.team, "--team")
        check_source(self.scenario)
        count(self.seed, "--seed", low=0)
        check_pacing(self)  # before any process starts
        if self.gate_probability is not None:
            probability(self.gate_probability, "--gate")


@dataclass
class Collected:
    """Everything the collector received."""

    estimates: list[tuple[str, Mapping[str, Any]]] = field(default_factory=list)
    """``(sender, body)`` of every ``est`` message, in arrival order."""
    events: list[tuple[float, str, str, str]] = field(default_factory=list)
    """Track events ``(t, observer, target, kind)``."""
    stats: dict[str, list[dict[str, int]]] = field(default_factory=dict)
    """Per robot, the counters of each process incarnation (a restart starts a new one)."""
    rejected: int = 0
    rejected_by_reason: Counter[str] = field(default_factory=Counter)
    """What the collector rejected (:mod:`relloc.runtime.admission` reasons, ``unscheduled``
    control events, ``report_quota``: :mod:`relloc.runtime.quota`)."""
    presence: list[dict[str, Any]] = field(default_factory=list)
    kills: list[dict[str, Any]] = field(default_factory=list)
    restarts: list[dict[str, Any]] = field(default_factory=list)
    exit_codes: dict[str, list[int | None]] = field(default_factory=dict)
    """Per child name, the exit code of each of its processes (SIGKILLed: ``-9``)."""
    wall_s: float = 0.0


def transport_arguments(endpoint: str, secure: SecureTeam | None, member: str) -> list[str]:
    """Connect to the launcher; listen on loopback only (TLS only when secure)."""
    if secure is None:
        return ["--connect", endpoint, "--listen", DEFAULT_LISTEN]
    return ["--connect", endpoint, *secure.arguments(member)]


def node_command(
    settings: TeamSettings, robot: str, endpoint: str, secure: SecureTeam | None = None
) -> list[str]:
    """The ``relloc`` arguments of one robot process (``relloc node ...``)."""
    f = settings.faults
    cmd = [
        "node",
        "--robot",
        robot,
        "--dataset" if Path(settings.scenario).is_dir() else "--scenario",
        settings.scenario,
        "--seed",
        str(settings.seed),
        "--team",
        settings.team,
        *transport_arguments(endpoint, secure, robot),
        "--drop",
        repr(f.drop),
        "--delay",
        repr(f.delay_ms),
        "--jitter",
        repr(f.jitter_ms),
        "--duplicate",
        repr(f.duplicate),
        "--reorder",
        repr(f.reorder),
    ]
    for p in f.partitions:
        cmd += ["--partition", p.arg]
    for st in f.stalls:
        cmd += ["--stall", st.arg]
    if settings.realtime_factor > 0:
        cmd += ["--paced", repr(settings.realtime_factor)]
    if settings.filter_kind != DEFAULT_FILTER:  # the node's own default otherwise: a
        cmd += ["--filter", settings.filter_kind]  # reproduction's robot refuses the flag
    if settings.gate_probability is not None:
        cmd += ["--gate", repr(settings.gate_probability)]
    return cmd + list(settings.node_args)


def clock_command(
    settings: TeamSettings,
    roster: tuple[str, ...],
    duration_s: float,
    endpoint: str,
    report: Path,
    secure: SecureTeam | None = None,
) -> list[str]:
    """The ``relloc`` arguments of the clock/simulator process (``relloc team clock ...``)."""
    cmd = [
        "team",
        "clock",
        "--team",
        settings.team,
        "--roster",
        ",".join(roster),
        "--tick",
        repr(settings.tick_s),
        "--duration",
        repr(duration_s),
        "--realtime",
        repr(settings.realtime_factor),
        *transport_arguments(endpoint, secure, "launcher"),
        "--report",
        str(report),
    ]
    for e in settings.faults.kills:
        cmd += ["--kill", e.arg]
    for e in settings.faults.restarts:
        cmd += ["--restart", e.arg]
    return cmd


FINAL_REPORT_GRACE_S = 5.0
"""Wall seconds the collector waits, after every process exited, for final reports in flight."""

PRELOAD = [
    "relloc.cli",
    "relloc.cli.node",
    "relloc.cli.team",
    "relloc.runtime.node",
    "relloc.runtime.clock",
    "relloc.runtime.scenario",
    "relloc.runtime.estimation",
    "relloc.runtime.team",
]
"""Modules the fork server imports once, so robot processes start in milliseconds instead of
each paying numpy/scipy imports (zenoh is imported by each child: its runtime must not be
inherited across fork)."""


@dataclass(frozen=True, kw_only=True)
class ProcessTeam:
    """How a reproduction's team runs as robot processes: the clock step, the faults, the team
    name, the wall-time limit, the pacing (0: as fast as the team goes) and the network's
    security (``secure``: mutual TLS and access control, certificates from ``certs_dir`` or
    made in each run's folder). Settings of a reproduction's team extend it with what the
    reproduction needs."""

    tick_s: float = CLOCK_TICK_S
    faults: FaultSettings = field(default_factory=FaultSettings)
    team: str = "team"
    wall_timeout_s: float = 300.0
    realtime_factor: float = 0.0
    secure: bool = False
    certs_dir: Path | None = None

    def __post_init__(self) -> None:
        check_pacing(self)

    def launch(
        self,
        *,
        scenario: str,
        out_dir: Path,
        seed: int,
        preload: tuple[str, ...],
        node_args: tuple[str, ...],
    ) -> TeamSettings:
        """The launcher's settings of one run of this team."""
        return TeamSettings(
            scenario=scenario,
            out_dir=out_dir,
            seed=seed,
            team=self.team,
            tick_s=self.tick_s,
            faults=self.faults,
            wall_timeout_s=self.wall_timeout_s,
            realtime_factor=self.realtime_factor,
            secure=self.secure,
            certs_dir=self.certs_dir,
            preload=preload,
            node_args=node_args,
        )


def _child_main(argv: list[str], log_path: str) -> None:
    """Entry of a child process: ``relloc <argv>`` with stdout/stderr to ``log_path``."""
    fd = os.open(log_path, os.O_WRONLY | os.O_CREAT | os.O_APPEND, 0o644)
    os.dup2(fd, 1)
    os.dup2(fd, 2)
    os.close(fd)
    sys.stdout = open(1, "w", buffering=1, closefd=False)
    sys.stderr = open(2, "w", buffering=1, closefd=False)
    from relloc.cli import main

    code = main(argv)
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)


def _fork_context(extra: tuple[str, ...]) -> Any:
    """A ``forkserver`` multiprocessing context preloading :data:`PRELOAD` and ``extra`` (the
    server starts once per process: the first team's list holds; preloading only saves time)."""
    ctx = multiprocessing.get_context("forkserver")
    ctx.set_forkserver_preload([*PRELOAD, *extra])
    return ctx


class TeamLauncher:
    """Start, supervise and collect a team (see module docstring)."""

    def __init__(
        self,
        settings: TeamSettings,
        roster: tuple[str, ...],
        duration_s: float,
        *,
        est_frame: str | None = None,
    ) -> None:
        settings.faults.check_robots(roster)  # a fault naming no robot of the team, or
        settings.faults.check_times(duration_s)  # beginning after the run, is refused
        self.s = settings
        self.roster = roster
        self.duration_s = duration_s
        self.logs = settings.out_dir / "logs"
        self.procs: dict[str, Any] = {}
        self.incarnation: dict[str, int] = dict.fromkeys(roster, 0)
        self.collected = Collected()
        self.endpoint = ""
        self._start = time.monotonic()
        self._finished: list[tuple[str, Any]] = []
        self._dead: set[str] = set()
        self._received: Counter[tuple[str, str]] = Counter()
        self._frames: dict[tuple[str, str, str], str] = {}
        self.est_frame = est_frame
        """The frame of every robot's estimates, where the team's estimators share one."""
        self._scheduled: dict[str, list[RobotEvent]] = {
            "kill": sorted(settings.faults.kills, key=lambda e: e.at_s),
            "restart": sorted(settings.faults.restarts, key=lambda e: e.at_s),
        }
        self.secure: SecureTeam | None = None
        self._quota = ReportQuota(len(roster), duration_s)
        self.context = _fork_context(settings.preload)

    def _spawn(self, name: str, argv: list[str]) -> Any:
        """Start ``relloc <argv>`` as a separate OS process (forked by the fork server)."""
        n = self.incarnation.get(name, 0)
        log = self.logs / (f"{name}.{n}.log" if n else f"{name}.log")
        proc = self.context.Process(target=_child_main, args=(argv, str(log)), name=name)
        proc.start()
        return proc

    def run(self) -> Collected:
        """Run the team to the end (or the wall timeout) and return what was collected."""
        self.logs.mkdir(parents=True, exist_ok=True)
        port = self.s.port or free_loopback_port()
        if self.s.secure:
            self.secure = secure_team(self.s.out_dir, self.s.team, self.roster, self.s.certs_dir)
            endpoint = self.endpoint = loopback_endpoint(port, "tls")
            transport = TransportSettings(
                listen=(endpoint,), config_file=self.secure.config("launcher")
            )
        else:
            endpoint = self.endpoint = loopback_endpoint(port)
            transport = TransportSettings(listen=(endpoint,))
        session = open_session(transport)
        inbox = Inbox(max_message_bytes=DEFAULT_MAX_BYTES)
        start = self._start = time.monotonic()
        try:
            for kind in ("est", "evt", "stats"):
                inbox.subscribe(session, keys.robot_wildcard(self.s.team, kind))
            inbox.subscribe(session, keys.clock_key(self.s.team, "ctl"))
            inbox.watch_presence(session, keys.alive_wildcard(self.s.team))
            self.procs["clock"] = self._spawn(
                "clock",
                clock_command(
                    self.s,
                    self.roster,
                    self.duration_s,
                    endpoint,
                    self.s.out_dir / "clock.json",
                    self.secure,
                ),
            )
            for robot in self.roster:
                self.procs[robot] = self._spawn(
                    robot, node_command(self.s, robot, endpoint, self.secure)
                )
            self._collect(inbox, start)
        finally:
            self._stop_all()
            inbox.close()
            session.close()
        self.collected.wall_s = time.monotonic() - start
        return self.collected

    def _collect(self, inbox: Inbox, start: float) -> None:
        """Collect until the clock process has exited (after its ``ctl(end)``: the launcher goes
        by its own child's exit, which no message can fake) and every robot has."""
        end_wall = None
        while True:
            now = time.monotonic()
            if now - start > self.s.wall_timeout_s:
                raise RellocError(
                    f"team up: not finished after {self.s.wall_timeout_s:g} s of wall time; "
                    f"see the logs in {self.logs}"
                )
            for name, proc in self.procs.items():
                if proc.exitcode not in (None, 0) and name not in self._dead:
                    raise RellocError(
                        f"team up: the {name} process failed (exit {proc.exitcode}); "
                        f"see its log in {self.logs}"
                    )
            if self.procs["clock"].exitcode is not None:
                end_wall = now if end_wall is None else end_wall
                alive = [r for r in self.roster if self.procs[r].exitcode is None]
                if not alive:
                    break
                if now - end_wall > 30.0:
                    raise RellocError(f"team up: robots {alive} did not exit after the end")
            item = inbox.get(timeout=0.2)
            if item is not None:
                self._on_item(item)
        # a robot's last report may still be in flight when its process has exited
        deadline = time.monotonic() + FINAL_REPORT_GRACE_S
        while not self._final_reports_in() and time.monotonic() < deadline:
            item = inbox.get(timeout=0.05)
            if item is not None:
                self._on_item(item)
        for item in inbox.drain():
            self._on_item(item)

    def _final_reports_in(self) -> bool:
        """Whether every robot's current process has sent its final counters, and every
        ``est``/``evt`` message the counters say were sent has arrived (callbacks of different
        subscriptions may hand messages over in a slightly different order)."""
        for robot in self.roster:
            lives = self.collected.stats.get(robot, [])
            index = self.incarnation[robot]
            if robot not in self._dead and (len(lives) <= index or not lives[index].get("final")):
                return False
            for kind in ("est", "evt"):
                sent = sum(life.get(f"sent.{kind}", 0) for life in lives)
                if self._received[(robot, kind)] < sent:
                    return False
        return True

    def _on_item(self, item: Any) -> None:
        """File one record (a message that fails admission is counted by reason)."""
        if item.presence != "data":
            parsed = keys.parse_presence_key(item.key)
            if parsed is None:  # a token of another layout (keys.parse_presence_key)
                return
            token, member = parsed
            self.collected.presence.append(
                {
                    "member": member,
                    "token": token,
                    "event": item.presence,
                    "wall_s": time.monotonic() - self._start,
                }
            )
            return
        try:
            msg = admit(item.key, item.payload, roster=self.roster)
            if msg.kind == "ctl":
                self._on_control(msg.body["action"], msg.body["robot"], msg.t)
                return
            self._received[(msg.sender, msg.kind)] += 1
            if msg.kind in ("est", "evt"):
                self._quota.take(msg, len(item.payload))
                check_stamps(msg, self.duration_s)
            if msg.kind == "est":
                self._check_frame(msg)
        except MessageRejected as exc:
            self._reject(exc.reason)
            return
        if msg.kind == "est":
            self.collected.estimates.append((msg.sender, msg.body))
        elif msg.kind == "evt":
            b = msg.body
            for t, target, kind in zip(b["stamps"].tolist(), b["targets"], b["kinds"], strict=True):
                self.collected.events.append((t, msg.sender, target, kind))
        elif msg.kind == "stats":
            per_robot = self.collected.stats.setdefault(msg.sender, [])
            index = self.incarnation[msg.sender]
            while len(per_robot) <= index:
                per_robot.append({})
            per_robot[index] = dict(msg.body["counters"])

    def _check_frame(self, msg: Message) -> None:
        """An ``est`` is in the team's frame, where it has one (``wrong_frame``), and every
        ``est`` of one series (sender, target, track) in the frame of its first
        (``frame_changed``): the collected increments are joined into one series."""
        b = msg.body
        if self.est_frame is not None and b["frame"] != self.est_frame:
            raise MessageRejected(
                "wrong_frame", f"est of {msg.sender}→{b['target']} in {b['frame']!r}"
            )
        first = self._frames.setdefault((msg.sender, b["target"], b["track"]), b["frame"])
        if b["frame"] != first:
            raise MessageRejected(
                "frame_changed",
                f"est of {msg.sender}→{b['target']} in {b['frame']!r} after {first!r}",
            )

    def _reject(self, reason: str) -> None:
        self.collected.rejected += 1
        self.collected.rejected_by_reason[reason] += 1

    def _on_control(self, action: str, robot: str, t: float) -> None:
        """Execute a scheduled kill or restart: each event of the fault schedule once, when
        the clock announces it (at or after its time), for a robot in the right state;
        anything else raises ``unscheduled`` (``end`` is the clock process' exit)."""
        if action == "end":
            return
        pending = self._scheduled[action]
        due = [e for e in pending if e.robot == robot and e.at_s <= t + 1e-6]
        alive = robot not in self._dead
        if not due or alive != (action == "kill"):
            raise MessageRejected("unscheduled", f"ctl {action} {robot!r} at {t:g} s")
        pending.remove(due[0])
        proc = self.procs.get(robot)
        if action == "kill" and proc is not None:
            os.kill(proc.pid, signal.SIGKILL)
            proc.join(timeout=30)
            self._finished.append((robot, proc))
            self._dead.add(robot)
            self.collected.kills.append({"robot": robot, "at_s": t, "pid": proc.pid})
        elif action == "restart":
            self.incarnation[robot] += 1
            self._dead.discard(robot)
            self.procs[robot] = self._spawn(
                robot, node_command(self.s, robot, self.endpoint, self.secure)
            )
            self.collected.restarts.append(
                {"robot": robot, "at_s": t, "pid": self.procs[robot].pid}
            )

    def _stop_all(self) -> None:
        """Terminate every child still running; SIGKILL those that do not stop in 5 s."""
        for proc in self.procs.values():
            if proc.exitcode is None:
                proc.terminate()
        deadline = time.monotonic() + 5.0
        for proc in self.procs.values():
            proc.join(timeout=max(0.1, deadline - time.monotonic()))
            if proc.exitcode is None:
                proc.kill()
                proc.join(timeout=5.0)
        for name, proc in [*self._finished, *self.procs.items()]:
            self.collected.exit_codes.setdefault(name, []).append(proc.exitcode)
