"""Fault injection for the robot runtime: loss, delay/jitter, duplicates, reordering, partitions,
link stalls, and robot kills/restarts.

Network faults are applied by each *receiving* node to the robot-to-robot data streams
(``odom``, ``meas``, ``eqm``) through its own :class:`LinkEmulator`, so every link loses, delays
and reorders independently — like a shared wireless channel heard by several robots. Clock ticks,
acknowledgements and the collector's monitoring streams are infrastructure and are never faulted.
All times are **simulated** seconds (the clock process may run faster than real time, so a delay
in wall-clock milliseconds would mean nothing to the estimators):

- ``drop`` p: each message is lost with probability p;
- ``delay_ms`` d and ``jitter_ms`` j: a message is released ``max(0, d + j·n)`` ms of simulated
  time after it arrived, ``n ~ N(0, 1)`` (jitter alone reorders messages too);
- ``duplicate`` p: a message is delivered twice (the receiver must recognise the copy);
- ``reorder`` p: a message is held back and released only after the next message from the same
  sender (or after ``reorder_hold_s``), i.e. swapped with its successor;
- ``partitions``: during ``[start, end)`` the listed robots and the rest of the team cannot hear
  each other (the side lists are robot ids; everyone not listed is on the other side). Liveliness
  is not cut — the processes are alive — so the estimators see silence, not a departure;
- ``stalls``: a link that stops for a moment and then delivers everything — a starved process,
  a congested or retransmitting link (:class:`Stall`). Its hold is in *wall* seconds, and it
  loses, duplicates and reorders nothing, so a team with stalls alone still counts as a perfect
  network (:attr:`FaultSettings.network_faulty` is false): its robots must still reproduce the
  in-process run. It is how the runtime's guard against a clock running ahead of a waiting
  window (:meth:`relloc.runtime.node.RobotNode._send_due_acks`) is shown end to end;
- ``kills``/``restarts``: the clock process asks the launcher to SIGKILL a robot's process at a
  simulated time and to start it again later (``ROBOT@SECONDS``); the node's liveliness token
  vanishes with the process, which is how teammates notice.

Randomness comes only from the ``np.random.Generator`` given to the emulator.
"""

from __future__ import annotations

import heapq
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from relloc.core.checks import number
from relloc.errors import ConfigError
from relloc.runtime.keys import check_id

FAULTED_KINDS = frozenset({"odom", "meas", "rows", "eqm", "mail", "sync"})


@dataclass(frozen=True, kw_only=True)
class Partition:
    """Robots ``side`` are cut off from the rest of the team during ``[start_s, end_s)``."""

    side: tuple[str, ...]
    start_s: float
    end_s: float

    def __post_init__(self) -> None:
        if not self.side:
            raise ConfigError("partition.side: list at least one robot")
        for r in self.side:
            check_id(r, "partition.side")
        number(self.start_s, "partition: start (s)", low=0.0)
        number(self.end_s, "partition: end (s)")
        if not self.start_s < self.end_s:
            raise ConfigError(f"partition: need 0 ≤ start < end, got {self.start_s}–{self.end_s} s")

    @property
    def arg(self) -> str:
        """Its ``--partition`` argument, ``A,B@T1-T2`` (parses back to the same partition)."""
        return f"{','.join(self.side)}@{self.start_s!r}-{self.end_s!r}"

    def separates(self, a: str, b: str, t: float) -> bool:
        """True if ``a`` and ``b`` cannot hear each other at simulated time ``t``."""
        return self.start_s <= t < self.end_s and ((a in self.side) != (b in self.side))


MAX_STALL_S = 60.0
"""Longest stall, wall seconds."""


@dataclass(frozen=True, kw_only=True)
class Stall:
    """From the first message robot ``receiver`` gets from ``sender`` once its clock has reached
    ``at_s`` (simulated s), every message of that link is held for ``wall_s`` wall seconds and
    then delivered, in order (module docstring)."""

    sender: str
    receiver: str
    at_s: float
    wall_s: float

    def __post_init__(self) -> None:
        check_id(self.sender, "stall sender")
        check_id(self.receiver, "stall receiver")
        if self.sender == self.receiver:
            raise ConfigError(f"stall: sender and receiver are both {self.sender!r}")
        number(self.at_s, "stall: time (s)", low=0.0)
        number(self.wall_s, "stall: wall time (s)", low=0.0, high=MAX_STALL_S, open_low=True)

    @property
    def arg(self) -> str:
        """Its ``--stall`` argument, ``SENDER,RECEIVER@T:WALL_S`` (parses back to it)."""
        return f"{self.sender},{self.receiver}@{self.at_s!r}:{self.wall_s!r}"


@dataclass(frozen=True, kw_only=True)
class RobotEvent:
    """A robot process killed or restarted at simulated time ``at_s``."""

    robot: str
    at_s: float

    def __post_init__(self) -> None:
        check_id(self.robot, "robot event")
        number(self.at_s, f"robot event {self.robot}: time (s)", low=0.0)

    @property
    def arg(self) -> str:
        """Its ``--kill``/``--restart`` argument, ``ROBOT@SECONDS`` (parses back to it)."""
        return f"{self.robot}@{self.at_s!r}"


@dataclass(frozen=True, kw_only=True)
class FaultSettings:
    """Every fault of one run (all zero/empty: a perfect network)."""

    drop: float = 0.0
    delay_ms: float = 0.0
    jitter_ms: float = 0.0
    duplicate: float = 0.0
    reorder: float = 0.0
    reorder_hold_s: float = 0.5
    partitions: tuple[Partition, ...] = ()
    stalls: tuple[Stall, ...] = ()
    kills: tuple[RobotEvent, ...] = ()
    restarts: tuple[RobotEvent, ...] = ()

    def __post_init__(self) -> None:
        for name in ("drop", "duplicate", "reorder"):
            number(
                getattr(self, name),
                f"faults.{name} (a probability)",
                low=0.0,
                high=1.0,
                open_high=True,
            )
        for name in ("delay_ms", "jitter_ms"):
            number(getattr(self, name), f"faults.{name}", low=0.0)
        number(self.reorder_hold_s, "faults.reorder_hold_s", low=0.0, high=60.0, open_low=True)
        self._check_robot_events()

    def _check_robot_events(self) -> None:
        """Each robot's kills and restarts alternate in time, a kill first: a kill of a robot
        that is down or a restart of one that is up would do nothing. (At one instant a
        restart comes first: a kill and a restart at the same time restart nothing.)"""
        events = sorted(
            [(e.at_s, "kill", e) for e in self.kills]
            + [(e.at_s, "restart", e) for e in self.restarts],
            key=lambda x: (x[0], x[1] == "kill"),
        )
        down: dict[str, float] = {}  # robot → when it was killed
        up_since: dict[str, float] = {}  # robot → when it was restarted
        for at_s, action, e in events:
            if action == "kill" and e.robot in down:
                when = f"killed at {down[e.robot]:g} s"
                raise ConfigError(f"--kill {e.arg}: {e.robot} is already down then ({when})")
            if action == "restart" and e.robot not in down:
                since = up_since.get(e.robot)
                why = "no earlier --kill" if since is None else f"restarted at {since:g} s"
                raise ConfigError(f"--restart {e.arg}: {e.robot} is not down then ({why})")
            if action == "kill":
                down[e.robot] = at_s
            else:
                del down[e.robot]
                up_since[e.robot] = at_s

    @property
    def network_faulty(self) -> bool:
        """Whether messages are lost, delayed in simulated time, duplicated, reordered or cut
        off (stalls are not: they deliver everything, in order)."""
        return bool(
            self.drop or self.delay_ms or self.jitter_ms or self.duplicate or self.reorder
        ) or bool(self.partitions)

    def check_robots(self, roster: tuple[str, ...]) -> None:
        """Every robot named by an event, partition or stall must be on the team, and a
        partition must leave someone on the other side."""
        named = [e.robot for e in (*self.kills, *self.restarts)]
        named += [r for p in self.partitions for r in p.side]
        named += [r for st in self.stalls for r in (st.sender, st.receiver)]
        for robot in named:
            if robot not in roster:
                raise ConfigError(
                    f"faults: unknown robot {robot!r}; the team is {', '.join(roster)}"
                )
        for p in self.partitions:
            if set(roster) <= set(p.side):
                raise ConfigError(
                    f"--partition {p.arg}: its side holds the whole team, so it separates nobody"
                )

    def check_times(self, duration_s: float) -> None:
        """Every event, partition and stall must begin before the run's end (``duration_s``,
        simulated s): one after it would never happen."""
        starts = [(f"--kill {e.arg}", e.at_s) for e in self.kills]
        starts += [(f"--restart {e.arg}", e.at_s) for e in self.restarts]
        starts += [(f"--partition {p.arg}", p.start_s) for p in self.partitions]
        starts += [(f"--stall {st.arg}", st.at_s) for st in self.stalls]
        for flag, start in starts:
            if start >= duration_s:
                raise ConfigError(
                    f"{flag}: begins at or after the run's end ({duration_s:g} s), so it would "
                    "never happen"
                )

    def to_dict(self) -> dict[str, object]:
        """Plain form for summary.json."""
        return {
            "drop": self.drop,
            "delay_ms": self.delay_ms,
            "jitter_ms": self.jitter_ms,
            "duplicate": self.duplicate,
            "reorder": self.reorder,
            "partitions": [
                {"side": list(p.side), "start_s": p.start_s, "end_s": p.end_s}
                for p in self.partitions
            ],
            "stalls": [
                {"sender": st.sender, "receiver": st.receiver, "at_s": st.at_s, "wall_s": st.wall_s}
                for st in self.stalls
            ],
            "kills": [{"robot": e.robot, "at_s": e.at_s} for e in self.kills],
            "restarts": [{"robot": e.robot, "at_s": e.at_s} for e in self.restarts],
        }


def parse_robot_event(text: str, flag: str) -> RobotEvent:
    """``ROBOT@SECONDS`` → :class:`RobotEvent` (ConfigError naming ``flag`` otherwise)."""
    robot, sep, at = text.partition("@")
    try:
        if not sep:
            raise ValueError("missing '@'")
        return RobotEvent(robot=robot, at_s=float(at))
    except (ValueError, ConfigError) as exc:
        raise ConfigError(f"{flag}: expected ROBOT@SECONDS, got {text!r} ({exc})") from None


def parse_partition(text: str) -> Partition:
    """``A,B@T1-T2`` → robots A and B cut off from the rest during [T1, T2) s."""
    side, sep, span = text.partition("@")
    start, dash, end = span.partition("-")
    try:
        if not (sep and dash):
            raise ValueError("missing '@' or '-'")
        return Partition(
            side=tuple(s.strip() for s in side.split(",") if s.strip()),
            start_s=float(start),
            end_s=float(end),
        )
    except (ValueError, ConfigError) as exc:
        raise ConfigError(f"--partition: expected A,B@T1-T2, got {text!r} ({exc})") from None


def parse_stall(text: str) -> Stall:
    """``SENDER,RECEIVER@T:WALL_S`` → what RECEIVER gets from SENDER held for WALL_S wall
    seconds from simulated time T (:class:`Stall`)."""
    pair, sep, when = text.partition("@")
    at, colon, wall = when.partition(":")
    sender, comma, receiver = pair.partition(",")
    try:
        if not (sep and colon and comma):
            raise ValueError("missing ',', '@' or ':'")
        return Stall(
            sender=sender.strip(), receiver=receiver.strip(), at_s=float(at), wall_s=float(wall)
        )
    except (ValueError, ConfigError) as exc:
        raise ConfigError(
            f"--stall: expected SENDER,RECEIVER@T:WALL_S, got {text!r} ({exc})"
        ) from None


class LinkStall:
    """The stalls of the links into robot ``owner``, in wall time (module docstring).

    ``hold(sender, now_s, item, wall_s, size)`` takes ``item`` (True) while the link from
    ``sender`` is stalled — a stall starts with the first message heard at or after its
    ``at_s``; ``due(wall_s)`` returns what a stall that has run out held, in arrival order
    (``due(None)``: everything held, at the end of a run); ``next_due`` is the wall time of the
    next release. What is held is bounded like the node's inbox (``max_records``, ``max_bytes``
    of ``size`` each): a sender that floods a stalled link has the excess dropped and counted
    (``dropped``), never held without bound.
    """

    def __init__(
        self, owner: str, stalls: Sequence[Stall], *, max_records: int, max_bytes: int
    ) -> None:
        self._waiting = sorted((st for st in stalls if st.receiver == owner), key=lambda s: s.at_s)
        self._active: dict[str, tuple[float, list[Any]]] = {}
        self._max = (max_records, max_bytes)
        self._records = self._bytes = 0
        self.held = 0
        self.dropped = 0

    def hold(self, sender: str, now_s: float, item: Any, wall_s: float, size: int) -> bool:
        if sender not in self._active:
            start = next(
                (st for st in self._waiting if st.sender == sender and st.at_s <= now_s), None
            )
            if start is None:
                return False
            self._waiting.remove(start)
            self._active[sender] = (wall_s + start.wall_s, [])
        if self._records >= self._max[0] or self._bytes + size > self._max[1]:
            self.dropped += 1
            return True
        self._active[sender][1].append((item, size))
        self._records += 1
        self._bytes += size
        self.held += 1
        return True

    def due(self, wall_s: float | None) -> list[Any]:
        out: list[Any] = []
        for sender, (until, items) in list(self._active.items()):
            if wall_s is None or wall_s >= until:
                del self._active[sender]
                out += [item for item, _ in items]
                self._records -= len(items)
                self._bytes -= sum(size for _, size in items)
        return out

    @property
    def next_due(self) -> float | None:
        return min((until for until, _ in self._active.values()), default=None)


@dataclass
class LinkCounters:
    """What the emulator did to the messages it saw."""

    seen: int = 0
    dropped: int = 0
    partitioned: int = 0
    duplicated: int = 0
    reordered: int = 0
    delayed: int = 0

    def as_dict(self) -> dict[str, int]:
        return dict(self.__dict__)


@dataclass(order=True)
class _Pending:
    release_s: float
    order: int
    sender: str = field(compare=False)
    payload: Any = field(compare=False)


class LinkEmulator:
    """The receive side of an imperfect network, in simulated time (see module docstring).

    ``admit(item, sender, now_s)`` takes a (decoded) message as it arrives; ``release(now_s)``
    returns the items due by ``now_s`` in release order. With :class:`FaultSettings()` every
    message is released at once, unchanged and in order.
    """

    def __init__(self, owner: str, settings: FaultSettings, rng: np.random.Generator) -> None:
        self.owner = owner
        self.settings = settings
        self.rng = rng
        self.counters = LinkCounters()
        self._heap: list[_Pending] = []
        self._held: dict[str, tuple[float, Any]] = {}
        self._order = 0

    @classmethod
    def of_member(
        cls, owner: str, settings: FaultSettings, seed: int, roster: Sequence[str]
    ) -> LinkEmulator:
        """The link of roster member ``owner``: its own stream of the team's fault ``seed``
        (``SeedSequence([seed, roster index])``), so members draw independently."""
        ss = np.random.SeedSequence([seed, list(roster).index(owner)])
        return cls(owner, settings, np.random.default_rng(ss))

    def admit(self, payload: Any, sender: str, now_s: float) -> None:
        s = self.settings
        self.counters.seen += 1
        if any(p.separates(self.owner, sender, now_s) for p in s.partitions):
            self.counters.partitioned += 1
            return
        if s.drop and self.rng.random() < s.drop:
            self.counters.dropped += 1
            return
        copies = 2 if (s.duplicate and self.rng.random() < s.duplicate) else 1
        self.counters.duplicated += copies - 1
        for _ in range(copies):
            delay_s = 0.0
            if s.delay_ms or s.jitter_ms:
                delay_s = max(0.0, s.delay_ms + s.jitter_ms * self.rng.standard_normal()) / 1e3
                self.counters.delayed += 1
            if s.reorder and sender not in self._held and self.rng.random() < s.reorder:
                self.counters.reordered += 1
                self._held[sender] = (now_s + delay_s + s.reorder_hold_s, payload)
                continue
            self._push(now_s + delay_s, sender, payload)

    def _push(self, release_s: float, sender: str, payload: Any) -> None:
        self._order += 1
        heapq.heappush(self._heap, _Pending(release_s, self._order, sender, payload))

    def release(self, now_s: float) -> list[Any]:
        """Payloads due by ``now_s``; a held (reordered) message follows its sender's next one."""
        for sender, (deadline, payload) in list(self._held.items()):
            if deadline <= now_s:
                del self._held[sender]
                self._push(deadline, sender, payload)
        out: list[Any] = []
        while self._heap and self._heap[0].release_s <= now_s:
            item = heapq.heappop(self._heap)
            out.append(item.payload)
            held = self._held.pop(item.sender, None)
            if held is not None:
                out.append(held[1])
        return out
