"""Seed 003's air-ground team as processes, in closed loop: a world process and one process per
robot (leader, followers, drones).

The **world process** steps :class:`relloc.sim.airground.AirGroundWorld` — the robots' true
motion and every sensor — and plays the clock. The **robot processes** run the very objects
:func:`relloc.sim.airground.simulate_airground` runs in one process: the leader its path, each
drone its :class:`~relloc.sim.airground.DroneGuidance`, each follower its
:class:`~relloc.sim.airground.FollowerAgent` (switching EKF and formation controller).

Start-up. A robot process first prepares its role — everything it does once: a follower builds
its filter, whose χ² gate quantiles are computed then (the first computation imports
scipy.stats, about half a second of CPU) — and only then joins: it declares its subscribers,
its ``alive`` token and, once it has seen the world's and every teammate's, its ``ready`` token
(:func:`relloc.runtime.keys.ready_key`, as a node does for the clock). The world starts when
every robot is ready. After a restart it resumes once the restarted robot is ready again (a
robot counted ready is counted present: :class:`~relloc.runtime.transport.Roll`, so the
restarted robot's first tick is awaited) *and* every other present robot is ready anew: a
robot that sees a teammate's ``alive`` token appear after it declared ``ready`` declares its
``ready`` token again (:meth:`RobotProcess._renew_ready`). Seeing a token proves only that the
token's holder's declarations have arrived, not that the holder has this robot's: the
restarted robot's ``ready`` says it knows its teammates' subscriptions, and only their renewed
tokens say that they know its own — without them a teammate could publish its readings or the
leader its command of the restarted robot's first tick before that robot's subscription
reached it, and the robot would wait ``input_timeout_s`` for an input that never comes. So the
world's wait for a command (``cmd_timeout_s``) covers one tick's work, never a robot's one-off
set-up (which, under load, could take longer than the timeout) nor a subscription in
flight.

Per tick ``k = 0 … K`` (``t_k = k dt``; key expressions in :mod:`relloc.runtime.keys`):

1. the world publishes ``sense(k)`` to every robot: the readings it took at ``t_k`` (a UGV's
   UWB ranges to the higher-numbered UGVs, a drone's ``pair_sighting`` rows), a drone's own
   position and its camera's marker fix (none at ``k = 0``);
2. every robot shares its readings as ``rows`` (stamped ``t_k``, sent even when empty: it tells
   the receivers that the sender's readings of ``t_k`` are all out); the leader also broadcasts
   its command of tick ``k`` as ``odom``;
3. a drone, once the leader's command of tick ``k`` has arrived, re-anchors its leader track on
   its fix and commands its velocity; a follower, once every present teammate's ``rows`` of
   ``t_k`` and the leader's command have arrived, runs its filter's event at ``t_k`` (with its
   own and the leader's commands of tick ``k − 1`` and the readings of ``t_k``, concatenated in
   roster order — the order of the in-process batch) and then its controller; every robot sends
   its command of tick ``k`` to the world as ``cmd``;
4. the world waits for the ``cmd`` of every present robot and steps to ``t_{k+1}``.

So a command acts on the very tick it was computed for: there is no command delay, and on a
perfect network every follower's belief equals the in-process one (the same functions on the
same numbers; msgpack carries float64 exactly). After ``sense(K)`` (the last event, no command)
the world publishes ``ctl(end)``; every robot acts on its last tick (a teammate that exits after
its own is still awaited for it: its departure may overtake its last readings), ships its last
report and exits; a robot whose world has gone acts on its pending tick with what came
(``inputs_missing_at_end``).

Robustness. Network faults (:class:`~relloc.runtime.faults.LinkEmulator`) act on the
robot-to-robot streams (``rows``, ``odom``) at each receiver; a robot's own sensing
(``sense``) and actuation (``cmd``) are not network links and are never faulted. An input is
*in* once its message has arrived — whether the emulator then delivered, dropped, delayed or
partitioned it — or its sender has left; what the emulator holds back is released at its time,
and readings released after their tick are counted (``late_rows``), not fused (the filter runs
in time order). A drone or follower without the leader's latest command holds the last one it
heard. An input that never arrives (a sender that hangs) is waited for at most
``input_timeout_s`` of wall time (counted). The world gives a robot whose process is gone a zero
command (its motors stop; a drone hovers), and waits at most ``cmd_timeout_s`` for a present
robot's command (then zero, counted). Kills and restarts are announced on ``ctl`` as the clock
does (:mod:`relloc.runtime.clock`) and executed by the launcher. A restarted follower has lost
its filter: it starts again from its start-of-run guess with the covariance of
:data:`RESTART_SIGMAS` (it does not know where it is) and is re-found through the drones'
sightings; a restarted drone hovers until its camera fixes a marker; the leader has no state.
Every message passes :func:`relloc.runtime.admission.admit` (roster and role), teammates'
messages also :func:`~relloc.runtime.admission.check_stamps` and a per-tick
:class:`~relloc.runtime.admission.SenderBudget`; rejections are counted by reason.
"""

from __future__ import annotations

import lzma
import time
import zlib
from collections import Counter
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any
from zipfile import BadZipFile

import numpy as np

from relloc.core.checks import count, floats, number, positive
from relloc.core.estimates import Recorder
from relloc.core.gaussian import Gaussian
from relloc.core.recording import Measurements, Recording, empty_measurements
from relloc.errors import ConfigError, DataError, RellocError
from relloc.estimators.switching_ekf import FRAME
from relloc.pipeline.output import replace_file, write_json_file
from relloc.runtime import keys
from relloc.runtime.admission import SenderBudget, admit, check_stamps
from relloc.runtime.faults import FaultSettings, LinkEmulator, RobotEvent
from relloc.runtime.messages import (
    DEFAULT_MAX_BYTES,
    MAX_MESSAGE_BYTES,
    MIN_MESSAGE_BYTES,
    Message,
    MessageRejected,
    encode,
    est_bodies,
)
from relloc.runtime.shared_rows import rows_body, rows_from_body
from relloc.runtime.teammates import SeenSequences
from relloc.runtime.transport import (
    Inbox,
    Roll,
    TransportSettings,
    declare_publisher,
    open_session,
)
from relloc.sim.airground import (
    AirGroundScenario,
    AirGroundWorld,
    DroneGuidance,
    FollowerAgent,
    MarkerFix,
    airground_recording,
    own_velocities,
    robot_names,
    tick_times,
    ugv_velocity,
)

TIME_TOL = 1e-9
RESTART_SIGMAS = (2.0, 2.0, np.pi / 2, np.pi / 2)
"""Prior σ of a restarted follower's filter ``(r_x, r_y [m], θ_i, θ_0 [rad])``."""
REPORT_EVERY_TICKS = 5
"""A follower ships its new estimates and every robot its counters every 5 ticks (0.25 s; a
killed process loses what it had not shipped)."""


# ---------------------------------------------------------------------------- the world process
@dataclass(frozen=True, kw_only=True)
class WorldSettings:
    """One world process: the team, its transport, the robot events it announces."""

    team: str
    transport: TransportSettings
    kills: tuple[RobotEvent, ...] = ()
    restarts: tuple[RobotEvent, ...] = ()
    cmd_timeout_s: float = 10.0
    startup_timeout_s: float = 120.0
    realtime_factor: float = 0.0
    """Pace the ticks at this multiple of real time (0: as fast as the team goes)."""

    def __post_init__(self) -> None:
        keys.check_id(self.team, "world.team")
        number(self.realtime_factor, "world.realtime_factor", low=0.0)
        for name in ("cmd_timeout_s", "startup_timeout_s"):
            positive(getattr(self, name), f"world.{name}")


@dataclass
class WorldReport:
    """What the world process observed (written as JSON beside its truth file)."""

    ticks: int = 0
    wall_s: float = 0.0
    startup_wall_s: float = 0.0
    sent: dict[str, int] = field(default_factory=dict)
    cmd_received: dict[str, int] = field(default_factory=dict)
    cmd_missing: dict[str, int] = field(default_factory=dict)
    """Ticks at which a present robot's command did not come within the timeout."""
    cmd_absent: dict[str, int] = field(default_factory=dict)
    """Ticks at which a robot's process was gone (zero command)."""
    rejected: int = 0
    rejected_by_reason: dict[str, int] = field(default_factory=dict)
    events: list[dict[str, Any]] = field(default_factory=list)
    max_tick_lag_s: float = 0.0
    """On a paced run: how late the world got behind real time at worst."""

    def as_dict(self) -> dict[str, Any]:
        return dict(self.__dict__)


def sense_body(world: AirGroundWorld, robot: int, k: int, *, drone: int | None) -> dict[str, Any]:
    """``sense(k)`` of robot ``robot`` (module docstring, step 1)."""
    names = world.names
    body: dict[str, Any] = {
        "k": k,
        "n": world.sc.n_steps,
        "dt": world.sc.dt,
        "target": names[robot],
        "position": np.zeros(0),
        "fix_subject": "",
        "fix": np.zeros(0),
        **rows_body(world.readings_of(robot), names),
    }
    if drone is not None:
        body["position"] = world.drone_position(drone)
        fix = world.fixes[drone]
        if fix is not None:
            body["fix_subject"] = names[fix.subject]
            extra = [] if fix.heading is None else [fix.heading]
            body["fix"] = np.array([*fix.position, *extra])
    return body


class WorldProcess:
    """Steps the world under the robots' commands (module docstring)."""

    def __init__(self, settings: WorldSettings, world: AirGroundWorld) -> None:
        self.s = settings
        self.world = world
        self.roster = world.names
        # as team up: no event of a robot off the team, no restart without a kill before it
        FaultSettings(kills=settings.kills, restarts=settings.restarts).check_robots(self.roster)
        self.report = WorldReport()
        self.roll = Roll(self.roster)
        self._cmds: dict[str, np.ndarray] = {}
        self._k = 0
        self._seq: Counter[str] = Counter()
        self._pubs: dict[str, Any] = {}

    def _publish(self, kind: str, body: Mapping[str, Any], t: float) -> None:
        self._pubs[kind].put(encode(kind, keys.CLOCK_ID, self._seq[kind], t, body))
        self._seq[kind] += 1
        self.report.sent[kind] = self.report.sent.get(kind, 0) + 1

    def _handle(self, item: Any) -> None:
        if item.presence != "data":
            self.roll.update(item)
            return
        try:
            msg = admit(item.key, item.payload, roster=self.roster)
            if msg.kind != "cmd":
                raise MessageRejected("wrong_kind", f"the world takes only cmd, not {msg.kind}")
            if int(msg.body["k"]) != self._k:
                raise MessageRejected("stale", f"cmd of tick {msg.body['k']} at tick {self._k}")
        except MessageRejected as exc:
            self.report.rejected += 1
            reasons = self.report.rejected_by_reason
            reasons[exc.reason] = reasons.get(exc.reason, 0) + 1
            return
        self._cmds[msg.sender] = msg.body["u"]
        self.report.cmd_received[msg.sender] = self.report.cmd_received.get(msg.sender, 0) + 1

    def _wait(self, inbox: Inbox, done: Callable[[], bool], timeout_s: float) -> bool:
        return inbox.wait_until(done, self._handle, timeout_s)

    def run(self) -> WorldReport:
        s = self.s
        session = open_session(s.transport)
        inbox = Inbox(max_message_bytes=DEFAULT_MAX_BYTES)
        try:
            inbox.watch_presence(session, keys.alive_wildcard(s.team))
            inbox.watch_presence(session, keys.ready_wildcard(s.team))
            inbox.subscribe(session, keys.robot_wildcard(s.team, "cmd"))
            for kind in ("sense", "ctl"):
                self._pubs[kind] = declare_publisher(session, keys.clock_key(s.team, kind))
            token = session.liveliness().declare_token(keys.alive_key(s.team, keys.CLOCK_ID))
            start = time.monotonic()
            everyone = set(self.roster)
            if not self._wait(inbox, lambda: everyone <= self.roll.ready, s.startup_timeout_s):
                missing = sorted(everyone - self.roll.ready)
                raise RellocError(f"world: robots {missing} did not start within the timeout")
            self.report.startup_wall_s = time.monotonic() - start
            self._loop(inbox)
            self._publish("ctl", {"action": "end", "robot": ""}, self._t)
            self._wait(inbox, lambda: not self.roll.present, s.cmd_timeout_s)
            token.undeclare()
        finally:
            inbox.close()
            session.close()
        return self.report

    @property
    def _t(self) -> float:
        return float(self.world.times[self._k])

    def _loop(self, inbox: Inbox) -> None:
        sc, world = self.world.sc, self.world
        n_ugv = sc.n_followers + 1
        pending = sorted(
            [("kill", e) for e in self.s.kills] + [("restart", e) for e in self.s.restarts],
            key=lambda item: item[1].at_s,
        )
        start = time.monotonic()
        for k in range(sc.n_steps + 1):
            self._k = k
            while pending and pending[0][1].at_s <= self._t + TIME_TOL:
                self._robot_event(inbox, *pending.pop(0))
            if self.s.realtime_factor > 0:
                lag = time.monotonic() - (start + self._t / self.s.realtime_factor)
                self.report.max_tick_lag_s = max(self.report.max_tick_lag_s, lag)
                if lag < 0:
                    time.sleep(-lag)
            self._cmds = {}
            for r in range(len(self.roster)):
                drone = r - n_ugv if r >= n_ugv else None
                self._publish("sense", sense_body(world, r, k, drone=drone), self._t)
            self.report.ticks = k
            if world.done:
                break
            expected = set(self.roll.present)

            def all_in(e: set[str] = expected) -> bool:
                return e & self.roll.present <= set(self._cmds)

            if not self._wait(inbox, all_in, self.s.cmd_timeout_s):
                for robot in sorted((expected & self.roll.present) - set(self._cmds)):
                    self.report.cmd_missing[robot] = self.report.cmd_missing.get(robot, 0) + 1
            u = np.zeros((len(self.roster), 4))
            for r, name in enumerate(self.roster):
                if name in self._cmds:
                    u[r] = self._cmds[name]
                elif name not in self.roll.present:
                    self.report.cmd_absent[name] = self.report.cmd_absent.get(name, 0) + 1
            world.step(u[:n_ugv][:, [0, 3]], u[n_ugv:, :2])
        self.report.wall_s = time.monotonic() - start

    def _robot_event(self, inbox: Inbox, action: str, event: RobotEvent) -> None:
        """Announce a kill or restart (the launcher executes it) and wait until it happened: a
        killed robot's ``alive`` token is gone; a restarted robot is ready, and every present
        robot has declared its ``ready`` token since the announcement — the others renew
        theirs once they have seen the restarted robot's ``alive`` token, so all of them know
        its subscriptions before the next ``sense`` (module docstring)."""
        wall = time.monotonic()
        if action == "restart":
            self.roll.renew_ready()
        self._publish("ctl", {"action": action, "robot": event.robot}, self._t)
        if action == "kill":
            ok = self._wait(inbox, lambda: event.robot not in self.roll.present, 30.0)
        else:
            roll = self.roll
            ok = self._wait(
                inbox, lambda: event.robot in roll.ready and roll.present <= roll.ready, 60.0
            )
        self.report.events.append(
            {
                "action": action,
                "robot": event.robot,
                "at_s": self._t,
                "completed": ok,
                "wall_s": time.monotonic() - wall,
            }
        )


MEASUREMENT_FIELDS = ("t", "kind", "observer", "target", "value", "sigma", "landmark", "origin")


def save_world(world: AirGroundWorld, path: Path) -> None:
    """The run's truth, commands, readings and formation error as ``.npz`` (for scoring only:
    the world process is the only one that knows the truth)."""
    rec = world.recording()
    m = rec.measurements
    assert rec.truth is not None  # a simulation always has it
    arrays = {
        "truth": np.stack([g.pose for g in rec.truth], axis=1),
        "commands": np.stack([o.velocity for o in rec.odometry], axis=1),
        "formation_error": world.formation_error,
        **{f"m_{name}": getattr(m, name) for name in MEASUREMENT_FIELDS},
    }

    def write(tmp: Path) -> None:
        with tmp.open("wb") as f:  # a file object: np.savez would add ".npz" to a name
            np.savez(f, **arrays)

    replace_file(path, "--world-out", write)


def load_world(path: Path, sc: AirGroundScenario) -> tuple[Recording, np.ndarray]:
    """The recording and the formation error that :func:`save_world` wrote: for ``K`` ticks
    (``K ≤ sc.n_steps``) of the ``R`` robots and ``N`` followers of ``sc``, truth
    ``(K+1, R, 4)``, commands ``(K, R, 4)`` and the formation error ``(K, N, 2)``, all finite,
    and readings that :class:`Measurements` accepts. Anything else is a DataError naming the
    file."""
    try:
        with np.load(path) as f:
            data = {k: f[k] for k in f.files}
    except (OSError, ValueError, EOFError, BadZipFile, zlib.error, lzma.LZMAError) as exc:
        raise DataError(f"{path}: not a world file ({exc})") from exc
    except NotImplementedError as exc:  # zipfile: a compression method or feature
        raise DataError(f"{path}: not a world file (unsupported zip: {exc})") from exc
    except RuntimeError as exc:  # zipfile: an encrypted member
        if "encrypted" not in str(exc):
            raise
        raise DataError(f"{path}: not a world file (unsupported zip: {exc})") from exc
    missing = {"truth", "commands", "formation_error", *(f"m_{n}" for n in MEASUREMENT_FIELDS)}
    missing -= set(data)
    if missing:
        raise DataError(f"{path}: missing {sorted(missing)}")
    names = robot_names(sc)
    arrays = {n: floats(data[n], f"{path}: {n}") for n in ("commands", "truth", "formation_error")}
    commands = arrays["commands"]
    if commands.ndim != 3:
        raise DataError(f"{path}: commands: expected shape (K, R, 4), got {commands.shape}")
    ticks = commands.shape[0]
    if ticks > sc.n_steps:
        raise DataError(f"{path}: commands: {ticks} ticks, more than the run's {sc.n_steps}")
    shapes = {
        "commands": ("(K, R, 4)", (ticks, len(names), 4)),
        "truth": ("(K+1, R, 4)", (ticks + 1, len(names), 4)),
        "formation_error": ("(K, N, 2)", (ticks, sc.n_followers, 2)),
    }
    for name, (layout, shape) in shapes.items():
        if arrays[name].shape != shape:
            raise DataError(
                f"{path}: {name}: expected shape {layout} = {shape} (R = {len(names)} robots, "
                f"N = {sc.n_followers} followers), got {arrays[name].shape}"
            )
    if not np.all(np.isfinite(arrays["formation_error"])):
        raise DataError(f"{path}: formation_error: holds NaN or inf")
    try:
        readings = Measurements(**{n: data[f"m_{n}"] for n in MEASUREMENT_FIELDS})
        recording = airground_recording(
            sc, names, tick_times(sc)[: ticks + 1], arrays["truth"], commands, [readings]
        )
    except DataError as exc:
        raise DataError(f"{path}: {exc}") from None
    return recording, arrays["formation_error"]


# ---------------------------------------------------------------------------- robot processes
@dataclass(frozen=True, kw_only=True)
class RobotSettings:
    """One robot process of the air-ground team."""

    team: str
    robot: str
    transport: TransportSettings
    faults: FaultSettings = field(default_factory=FaultSettings)
    fault_seed: int = 0
    input_timeout_s: float = 10.0
    max_bytes: int = DEFAULT_MAX_BYTES

    def __post_init__(self) -> None:
        keys.check_id(self.team, "robot.team")
        keys.check_robot_id(self.robot, "--robot")
        count(self.fault_seed, "robot.fault_seed", low=0)
        positive(self.input_timeout_s, "robot.input_timeout_s")
        count(self.max_bytes, "robot.max_bytes", low=MIN_MESSAGE_BYTES, high=MAX_MESSAGE_BYTES)
        if self.faults.stalls:
            raise ConfigError("--stall: the air-ground team's robots do not emulate link stalls")


@dataclass(frozen=True)
class Sensed:
    """A validated ``sense`` of this robot: tick ``k`` at ``t``, its readings, a drone's
    position and marker fix."""

    k: int
    t: float
    readings: Measurements
    position: np.ndarray
    fix: MarkerFix | None


class Received:
    """What a robot has heard from its teammates: readings per sender and the leader's
    commands (time-stamped: a command is in force from its stamp to the next)."""

    def __init__(self) -> None:
        self.rows: dict[str, list[Measurements]] = {}
        self.leader_u: list[tuple[float, tuple[float, float]]] = []

    def leader_command(self, t: float) -> tuple[float, float] | None:
        """The leader's latest command stamped at or before ``t`` (None: never heard)."""
        best = None
        best_t = -np.inf
        for stamp, u in self.leader_u:
            if best_t < stamp <= t + TIME_TOL:
                best, best_t = u, stamp
        return best

    def rows_at(self, sender: str, t: float) -> list[Measurements]:
        """``sender``'s readings stamped ``t`` (taken out; later ones are kept: a teammate may
        be a tick ahead)."""
        parts = self.rows.pop(sender, [])
        later = [p.select(p.t > t + TIME_TOL) for p in parts]
        self.rows[sender] = [p for p in later if p.size]
        return [p.select(np.abs(p.t - t) <= TIME_TOL) for p in parts]


class LeaderRole:
    """The leader: its path command each tick, broadcast to the team."""

    listens: tuple[str, ...] = ()
    broadcasts_command = True

    def __init__(self, sc: AirGroundScenario) -> None:
        self.sc = sc

    def prepare(self) -> None:
        """Nothing is done once."""

    def inputs(self, k: int, roster: tuple[str, ...]) -> list[tuple[str, str]]:
        return []

    def act(self, s: Sensed, heard: Received) -> np.ndarray | None:
        if s.k >= self.sc.n_steps:
            return None
        return ugv_velocity(*self.sc.leader.command(s.t))

    def counts(self) -> dict[str, int]:
        return {}


class DroneRole:
    """Drone ``D_j``: its guidance from its fixes and the leader's broadcast command."""

    listens = ("odom",)
    broadcasts_command = False

    def __init__(self, sc: AirGroundScenario, drone: int) -> None:
        self.sc = sc
        self.drone = drone
        self.guidance: DroneGuidance | None = None
        self.held = (0.0, 0.0)

    def prepare(self) -> None:
        """Nothing is done once (the guidance is cheap, and a restarted drone's differs)."""

    def inputs(self, k: int, roster: tuple[str, ...]) -> list[tuple[str, str]]:
        """The leader's command of tick ``k`` (none at the last tick: nothing is commanded)."""
        return [(roster[0], "odom")] if k < self.sc.n_steps else []

    def act(self, s: Sensed, heard: Received) -> np.ndarray | None:
        if self.guidance is None:  # a restarted drone has lost its leader track
            first = s.k == 0
            self.guidance = (
                DroneGuidance.at_start(self.sc, self.drone)
                if first
                else DroneGuidance(self.sc, self.drone, None)
            )
        self.guidance.apply_fix(s.fix)
        if s.k >= self.sc.n_steps:
            return None
        self.held = heard.leader_command(s.t) or self.held
        v = self.guidance.velocity(s.k, self.held, s.position[:2])
        return np.array([v[0], v[1], 0.0, 0.0])

    def counts(self) -> dict[str, int]:
        return {}


class FollowerRole:
    """Follower ``R_i``: its filter's event at each tick and its command."""

    listens = ("odom", "rows")
    broadcasts_command = False

    def __init__(
        self,
        sc: AirGroundScenario,
        follower: int,
        make_agent: Callable[[Gaussian], FollowerAgent],
        prior: Gaussian,
    ) -> None:
        self.sc = sc
        self.follower = follower
        self.make_agent = make_agent
        self.prior = prior
        self.agent: FollowerAgent | None = None
        self.recorder: Recorder | None = None
        self.first_k: int | None = None
        """The first tick this process acted on (0, or later for a restarted follower)."""
        self.times = tick_times(sc)
        self.roster = robot_names(sc)
        self.own_u = np.zeros(4)
        self.held_u: tuple[float, float] = (0.0, 0.0)

    def prepare(self) -> None:
        """Build the filter of a start at tick 0 (its gate quantiles with it): the one-off work
        is done before the process declares ready. A follower restarted mid-run replaces it
        with a broad-prior one at its first tick (:meth:`act`), then at a tick's cost."""
        self.agent = self._start(0)

    def inputs(self, k: int, roster: tuple[str, ...]) -> list[tuple[str, str]]:
        """Every teammate's readings of tick ``k`` and the leader's command (none at the last
        tick)."""
        me = roster[self.follower]
        command = [(roster[0], "odom")] if k < self.sc.n_steps else []
        return command + [(r, "rows") for r in roster if r != me]

    def _start(self, k: int) -> FollowerAgent:
        prior = self.prior
        if k > 0:  # restarted: it does not know where it is
            prior = Gaussian(prior.mean, np.diag(np.square(RESTART_SIGMAS)))
        agent = self.make_agent(prior)
        self.recorder = Recorder(agent.estimator.name)
        return agent

    def act(self, s: Sensed, heard: Received) -> np.ndarray | None:
        if self.first_k is None:
            self.first_k = s.k
            if self.agent is None or s.k > 0:
                self.agent = self._start(s.k)
        assert self.agent is not None and self.recorder is not None
        if s.k >= 1:
            parts = []
            for r, name in enumerate(self.roster):
                parts += [s.readings] if r == self.follower else heard.rows_at(name, s.t)
            batch = Measurements.concatenate(parts) if parts else empty_measurements()
            prev = float(self.times[s.k - 1])
            leader_prev = heard.leader_command(prev) or self.held_u
            u = own_velocities(
                len(self.roster), {self.follower: self.own_u, 0: ugv_velocity(*leader_prev)}
            )
            self.agent.estimate(prev, s.t, u, batch, self.recorder)
        if s.k >= self.sc.n_steps:
            return None
        self.held_u = heard.leader_command(s.t) or self.held_u
        self.own_u = ugv_velocity(*self.agent.command(s.t, self.held_u))
        return self.own_u

    def counts(self) -> dict[str, int]:
        if self.recorder is None:
            return {}
        return {f"ekf.{k}": v for k, v in self.recorder.results().counts.items()}


Role = LeaderRole | DroneRole | FollowerRole


class RobotProcess:
    """One robot's process (module docstring)."""

    def __init__(self, settings: RobotSettings, sc: AirGroundScenario, role: Role) -> None:
        self.s = settings
        self.sc = sc
        self.role = role
        self.roster = robot_names(sc)
        if settings.robot not in self.roster:
            raise ConfigError(f"--robot: {settings.robot!r} is not in the team {self.roster}")
        self.times = tick_times(sc)
        self.counters: Counter[str] = Counter()
        self.heard = Received()
        self.link = LinkEmulator.of_member(
            settings.robot, settings.faults, settings.fault_seed, self.roster
        )
        self.present: set[str] = set()
        self._clock_seen = False
        self._clock_wall = 0.0
        self._present_at_tick: set[str] = set()
        self._session: Any = None
        self._ready_token: Any = None
        self._arrived: dict[tuple[str, str], float] = {}
        self._budget = SenderBudget.for_team(len(self.roster))
        self._seen = SeenSequences(per_tick=self._budget.capacity)
        self._tick: Sensed | None = None
        self._tick_wall = 0.0
        self._last_k: int | None = None
        self._seq: Counter[str] = Counter()
        self._pubs: dict[str, Any] = {}
        self._done = False
        self._ending = False
        self._world_gone = False

    # ------------------------------------------------------------------ main loop
    def run(self) -> dict[str, int]:
        s = self.s
        self.role.prepare()  # before the process joins: ready means able to act at a tick's cost
        session = open_session(s.transport)
        inbox = Inbox(max_message_bytes=s.max_bytes)
        self._session = session
        tokens = []
        try:
            for kind in self.role.listens:
                inbox.subscribe(session, keys.robot_wildcard(s.team, kind), remote_only=True)
            inbox.subscribe(session, keys.clock_key(s.team, "sense"))
            inbox.subscribe(session, keys.clock_key(s.team, "ctl"))
            inbox.watch_presence(session, keys.alive_wildcard(s.team))
            for kind in ("rows", "odom", "cmd", "est", "stats"):
                self._pubs[kind] = declare_publisher(session, keys.robot_key(s.team, s.robot, kind))
            tokens.append(session.liveliness().declare_token(keys.alive_key(s.team, s.robot)))
            while not self._done:
                item = inbox.get(timeout=0.1)
                if item is not None:
                    self._handle(item)
                self._declare_ready()
                self._progress()
                last = self._last_k == self.sc.n_steps
                over = self._world_gone or (self._ending and last)
                self._done = over and self._tick is None
            self._report(final=True)
        finally:
            for token in [*tokens, self._ready_token]:
                if token is not None:
                    token.undeclare()
            inbox.close()
            session.close()
        return dict(self.counters)

    def _declare_ready(self) -> None:
        """Ready once the world's and every teammate's token were seen (a robot restarted
        mid-run, whose dead teammates never appear: one second after the world's)."""
        if self._ready_token is not None or not self._clock_seen:
            return
        everyone = set(self.roster) - {self.s.robot} <= self.present
        if everyone or time.monotonic() - self._clock_wall > 1.0:
            self._ready_token = self._new_ready_token()

    def _renew_ready(self) -> None:
        """Declare the ``ready`` token again, if it was declared: called when a teammate's
        ``alive`` token appears (a restarted teammate), whose subscriptions this robot's
        session knows by then — Zenoh propagates a session's declarations in order and a robot
        declares its subscribers before its ``alive`` token. The world, resuming after a
        restart, waits for every present robot's renewed token (module docstring)."""
        if self._ready_token is None:
            return
        self._ready_token.undeclare()
        self._ready_token = self._new_ready_token()

    def _new_ready_token(self) -> Any:
        return self._session.liveliness().declare_token(keys.ready_key(self.s.team, self.s.robot))

    def _handle(self, item: Any) -> None:
        if item.presence != "data":
            parsed = keys.parse_presence_key(item.key)
            member = None if parsed is None else parsed[1]  # None: a token of another layout
            if member == keys.CLOCK_ID:
                if item.presence == "joined" and not self._clock_seen:
                    self._clock_seen, self._clock_wall = True, time.monotonic()
                elif item.presence == "left":
                    self._world_gone = True  # nothing more will come
            elif member in self.roster and member != self.s.robot:
                if item.presence == "joined":
                    if member not in self.present:
                        self.present.add(member)
                        self._renew_ready()
                else:
                    self.present.discard(member)
                    self._seen.forget(member)
            return
        try:
            msg = admit(item.key, item.payload, roster=self.roster, max_bytes=self.s.max_bytes)
            if msg.kind == "sense":
                self._on_sense(msg)
            elif msg.kind == "ctl":
                self._on_ctl(msg)
            elif msg.sender == self.s.robot:  # remote-only: another process speaks as it
                raise MessageRejected("own_key", f"a {msg.kind!r} message on {item.key!r}")
            else:
                self._on_teammate(msg)
        except MessageRejected as exc:
            self.counters["rejected"] += 1
            self.counters[f"rejected.{exc.reason}"] += 1

    def _on_sense(self, msg: Message) -> None:
        b = msg.body
        if b["target"] != self.s.robot:
            return  # another robot's readings
        k, n = int(b["k"]), int(b["n"])
        expected_k = 0 if self._last_k is None else self._last_k + 1
        if (self._last_k is not None and k != expected_k) or n != self.sc.n_steps:
            raise MessageRejected("bad_tick", f"sense k={k}/{n} after k={self._last_k}")
        if abs(float(b["dt"]) - self.sc.dt) > TIME_TOL or abs(msg.t - self.times[k]) > 1e-6:
            raise MessageRejected("bad_tick", f"sense k={k} at t={msg.t:g}, dt={b['dt']:g}")
        if self._tick is not None:
            raise MessageRejected("bad_tick", f"sense k={k} before tick {self._tick.k} was done")
        fix = self._checked_fix(b)
        readings = rows_from_body(b, self.roster, self.s.robot)
        self._last_k = k
        self._budget.new_interval()
        self.counters["ticks"] += 1
        t = float(self.times[k])
        self._tick = Sensed(k, t, readings, b["position"], fix)
        self._present_at_tick = set(self.present)
        self._tick_wall = time.monotonic()
        self._send("rows", rows_body(readings, self.roster), t)
        if self.role.broadcasts_command and k < self.sc.n_steps:
            u = self.role.act(self._tick, self.heard)
            assert u is not None
            self._send("odom", {"stamps": np.array([t]), "u": u[None]}, t)
            self._send("cmd", {"k": k, "u": u}, t)
            self._tick_done()

    def _checked_fix(self, b: Mapping[str, Any]) -> MarkerFix | None:
        """The marker fix of a ``sense`` body once the body's position and fix are checked
        against the team: a drone has its position (3 numbers) and may have a fix of a UGV —
        the leader with its heading, a follower without — and a UGV has neither
        (``MessageRejected``, ``shape``)."""
        ugvs = self.sc.n_followers + 1
        drone = self.roster.index(self.s.robot) >= ugvs
        if b["position"].size != (3 if drone else 0):
            raise MessageRejected(
                "shape", f"sense: position of {self.s.robot} has {b['position'].size} numbers"
            )
        if not b["fix_subject"]:
            return None
        subject = self.roster.index(b["fix_subject"])
        f = b["fix"]
        if not drone or subject >= ugvs or f.size != (3 if subject == 0 else 2):
            raise MessageRejected(
                "shape",
                f"sense: {self.s.robot} cannot have a fix of {b['fix_subject']} of {f.size} values",
            )
        return MarkerFix(subject, f[:2].copy(), float(f[2]) if subject == 0 else None)

    def _on_ctl(self, msg: Message) -> None:
        if msg.body["action"] != "end":
            return  # kills and restarts are the launcher's
        # ``sense`` and ``ctl`` are two streams: the end may overtake the last readings, so it
        # is only noted here; the robot finishes once it has acted on the last tick
        self._ending = True

    def _on_teammate(self, msg: Message) -> None:
        now = self._tick.t if self._tick is not None else self._last_t()
        check_stamps(msg, now)
        self._budget.take(msg.sender)
        self.counters[f"wire.{msg.kind}"] += 1
        key = (msg.sender, msg.kind)
        self._arrived[key] = max(self._arrived.get(key, -np.inf), msg.t)
        self.link.admit(msg, msg.sender, now)

    def _last_t(self) -> float:
        return 0.0 if self._last_k is None else float(self.times[self._last_k])

    def _deliver(self, messages: list[Message], t: float) -> None:
        """File the released teammates' messages of the tick at ``t``; one rejected message
        (counted by reason) does not hold back the others."""
        for msg in messages:
            try:
                self._deliver_one(msg, t)
            except MessageRejected as exc:
                self.counters["rejected"] += 1
                self.counters[f"rejected.{exc.reason}"] += 1

    def _deliver_one(self, msg: Message, t: float) -> None:
        if not self._seen.is_new(msg.sender, msg.kind, msg.seq, self._last_k or 0):
            self.counters["duplicates"] += 1
            return
        self.counters[f"delivered.{msg.kind}"] += 1
        if msg.kind == "odom" and msg.sender == self.roster[0]:
            stamps, u = msg.body["stamps"], msg.body["u"]
            for stamp, row in zip(stamps.tolist(), u, strict=True):
                self.heard.leader_u.append((stamp, (float(row[0]), float(row[3]))))
            self.heard.leader_u = self.heard.leader_u[-8:]
        elif msg.kind == "rows":
            rows = rows_from_body(msg.body, self.roster, msg.sender)
            late = rows.t < t - TIME_TOL
            if late.any():
                self.counters["late_rows"] += int(late.sum())
                rows = rows.select(~late)
            self.heard.rows.setdefault(msg.sender, []).append(rows)

    def _inputs_in(self, s: Sensed) -> bool:
        """Every expected input of the tick has arrived: from the teammates present — and, at
        the last tick, also from those present when it began (a teammate done with its last
        tick exits, and its departure may overtake its last readings)."""
        final = s.k >= self.sc.n_steps
        for sender, kind in self.role.inputs(s.k, self.roster):
            expected = sender in self.present or (final and sender in self._present_at_tick)
            if expected and self._arrived.get((sender, kind), -np.inf) < s.t - 1e-6:
                return False
        return True

    def _progress(self) -> None:
        """Act on the pending tick once its inputs are in (module docstring, step 3)."""
        s = self._tick
        if s is None:
            return
        if not self._inputs_in(s):
            if self._world_gone:  # what has come is all there will be
                self.counters["inputs_missing_at_end"] += 1
            elif time.monotonic() - self._tick_wall < self.s.input_timeout_s:
                return
            else:
                self.counters["input_timeouts"] += 1
        self._deliver(self.link.release(s.t), s.t)
        u = self.role.act(s, self.heard)
        if u is not None:
            self._send("cmd", {"k": s.k, "u": u}, s.t)
        self._tick_done()

    def _tick_done(self) -> None:
        s = self._tick
        assert s is not None
        self._tick = None
        if s.k % REPORT_EVERY_TICKS == 0 and s.k < self.sc.n_steps:
            self._report(final=False)

    # ------------------------------------------------------------------ reports
    def _report(self, *, final: bool) -> None:
        t = self._last_t()
        recorder = getattr(self.role, "recorder", None)
        if recorder is not None:
            for body in est_bodies(recorder.take_new(), frame=FRAME):
                self.counters["estimates"] += int(body["stamps"].size)
                self._send("est", body, t)
        if final:
            self.counters["final"] = 1
        self._send("stats", {"counters": self.final_counters()}, t)

    def final_counters(self) -> dict[str, int]:
        out = dict(self.counters)
        for name, value in self.link.counters.as_dict().items():
            out[f"fault.{name}"] = value
        out |= self.role.counts()
        out["cpu_ms"] = int(time.process_time() * 1000)
        return out

    def _send(self, kind: str, body: Mapping[str, Any], t: float) -> None:
        data = encode(kind, self.s.robot, self._seq[kind], t, body, max_bytes=self.s.max_bytes)
        self._seq[kind] += 1
        self.counters[f"sent.{kind}"] += 1
        self._pubs[kind].put(data)


def write_report(path: Path, report: WorldReport) -> None:
    """The world's report as JSON."""
    write_json_file(path, report.as_dict(), "--report")
