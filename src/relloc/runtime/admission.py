"""Admission of received messages: who may send which kind on which key, how often, how far ahead.

:func:`relloc.runtime.messages.decode` checks that a payload is a well-formed message of the
team; this module adds the checks that depend on the key it arrived on and on the receiver's
state. Every check raises :class:`~relloc.runtime.messages.MessageRejected` with a stable
reason, which the receiver counts (``rejected_by_reason`` in the summary):

- **roles** (:func:`admit`): a robot kind (``odom``, ``meas``, ``eqm``, ``est``, ``evt``,
  ``stats``, ``ack``, ``cmd``) is accepted only on ``relloc/<team>/robot/<id>/<kind>`` of a
  roster robot ``id`` and only from that robot; ``tick``, ``ctl`` and ``sense`` only on
  ``relloc/<team>/clock/<kind>``
  and only from the infrastructure sender ``clock``; the message type must be its key's kind
  (``unknown_key``, ``unknown_sender``, ``spoofed``, ``wrong_kind``); a robot subscribes to
  its teammates' keys remote-only, so what it hears on its own keys was sent by another process
  claiming its identity — a spoofer, or a second process started with the same id
  (``own_key``). In ``--secure`` mode Zenoh's
  access control enforces the same layout at the transport (a robot's certificate may publish
  only under its own prefix, only the launcher's certificate under ``clock/``), so a spoofed
  message does not even reach this code; without TLS anyone on the network can still claim a
  roster robot's identity on that robot's own keys, and these checks only keep a node safe and
  bounded, not authenticated.
- **time** (:func:`check_stamps`): a teammate's data stamped more than
  :data:`FUTURE_BOUND_S` ahead of the receiver's clock is rejected (``future``) — teammates are
  at most one tick ahead under the clock's barrier, and kept future samples would never be
  released — and so is data stamped before the run's start at robot time 0 (``past``: held
  odometry of an age beyond the run would inflate a filter's noise without bound); the
  collector checks ``est`` and ``evt`` against the run's end;
- **ticks** (:class:`TickGuard`): ticks advance one at a time (``k`` by one, ``t`` by ``dt``,
  the same ``n`` and ``dt``, ``t`` within the run) — a tick at t = 10¹² would make the node
  publish every remaining sample in one message (``bad_tick``); ``ctl(end)`` is accepted only
  after the last tick (``premature_end``);
- **rate** (:class:`SenderBudget`): at most ``capacity`` data messages per sender between two of
  the receiver's ticks (``rate_limited``).

Sizes are bounded before anything is queued (:class:`relloc.runtime.transport.Inbox`).
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Collection

import numpy as np

from relloc.runtime import keys
from relloc.runtime.messages import (
    DEFAULT_MAX_BYTES,
    INFRASTRUCTURE_SENDERS,
    Message,
    MessageRejected,
    decode,
)

CLOCK_KINDS = frozenset(keys.CLOCK_KINDS)
"""Kinds only the infrastructure sender may send (``sense``: the air-ground world process)."""
MAX_TICK_S = 10.0
"""Longest tick accepted (s): the ``--tick`` limit of ``relloc team up``."""
FUTURE_BOUND_S = 2.0
"""How far ahead of the receiver's latest tick a teammate's message may be stamped (s)."""
TIME_TOL = 1e-9


def admit(
    key: str,
    payload: bytes,
    *,
    roster: Collection[str],
    max_bytes: int = DEFAULT_MAX_BYTES,
) -> Message:
    """Decode ``payload`` received on ``key`` and check the sender's role (module docstring)."""
    parsed = keys.parse_robot_key(key)
    if parsed is not None:
        key_sender, key_kind = parsed
        if key_sender not in roster:
            raise MessageRejected("unknown_sender", f"key {key!r}: {key_sender!r} is not a robot")
    elif keys.parse_clock_key(key) is not None:
        key_sender, key_kind = keys.CLOCK_ID, keys.parse_clock_key(key) or ""
    else:
        raise MessageRejected("unknown_key", f"key {key!r} is not a team stream")
    msg = decode(payload, roster=roster, key_sender=key_sender, max_bytes=max_bytes)
    if msg.kind != key_kind:
        raise MessageRejected("wrong_kind", f"a {msg.kind!r} message on key {key!r}")
    if (msg.sender in INFRASTRUCTURE_SENDERS) != (msg.kind in CLOCK_KINDS):
        raise MessageRejected("spoofed", f"{msg.sender!r} may not send {msg.kind!r}")
    return msg


def check_stamps(msg: Message, now_s: float, bound_s: float = FUTURE_BOUND_S) -> None:
    """Reject a message whose header time or any stamp is before the run's start (robot time
    0: ``past``) or more than ``bound_s`` after ``now_s`` (``future``): the receiver's latest
    tick time, or the run's end for a collector, which hears no ticks."""
    times = [np.array([msg.t])]
    for name in ("stamps", "update_stamps"):
        stamps = msg.body.get(name)
        if isinstance(stamps, np.ndarray) and stamps.size:
            times.append(stamps)
    every = np.concatenate(times)
    earliest, latest = float(every.min()), float(every.max())
    if latest > now_s + bound_s + TIME_TOL:
        raise MessageRejected(
            "future", f"{msg.kind} from {msg.sender!r} stamped {latest:g} s, clock at {now_s:g} s"
        )
    if earliest < -TIME_TOL:
        raise MessageRejected(
            "past", f"{msg.kind} from {msg.sender!r} stamped {earliest:g} s, before the start"
        )


class TickGuard:
    """Ticks must advance one at a time: after the first tick heard, ``k`` is the previous one
    plus one, ``n`` and ``dt`` are unchanged and ``t`` is the previous time plus ``dt``; every
    tick has ``dt ≤`` :data:`MAX_TICK_S` and ``t ≤ min(n·dt, end_s + dt)`` (``end_s``: the
    end of the node's own sensor stream, when it has one). A node filters and publishes one
    window ``[t_{k−1}, t_k)`` per tick, so these bounds keep every window one tick long."""

    def __init__(self, end_s: float | None = None) -> None:
        self.end_s = end_s
        self.k: int | None = None
        self.n = 0
        self.dt = 0.0
        self.t = 0.0

    def check(self, msg: Message) -> None:
        """Accept ``msg`` (a validated ``tick``) and remember it, or raise ``bad_tick``."""
        k, n, dt, t = int(msg.body["k"]), int(msg.body["n"]), float(msg.body["dt"]), msg.t
        tol = TIME_TOL * max(1.0, abs(t), n * dt)
        ok = dt <= MAX_TICK_S and t <= n * dt + tol
        if self.end_s is not None:
            ok = ok and t <= self.end_s + dt + tol
        if self.k is not None:
            ok = (
                ok
                and k == self.k + 1
                and n == self.n
                and abs(dt - self.dt) <= tol
                and abs(t - (self.t + dt)) <= tol + TIME_TOL * 1e3 * dt
            )
        if not ok:
            raise MessageRejected("bad_tick", f"tick k={k}/{n} t={t:g} after k={self.k}")
        self.k, self.n, self.dt, self.t = k, n, dt, t

    @property
    def last_tick_seen(self) -> bool:
        return self.k is not None and self.k >= self.n

    def check_end(self, msg: Message) -> None:
        """``ctl(end)`` is accepted only after the last tick."""
        if not self.last_tick_seen:
            raise MessageRejected("premature_end", f"ctl(end) at tick {self.k} of {self.n}")


class SenderBudget:
    """At most ``capacity`` data messages per sender per interval (the receiver starts a new
    interval at each of its ticks).

    Under the clock's barrier a teammate is at most one tick ahead, so between two of the
    receiver's ticks it sends at most two ticks' worth: ``odom`` + ``meas`` + up to ``N − 1``
    ``eqm`` per tick, i.e. ``2(N + 1)`` for a team of ``N``. :meth:`for_team` allows twice that
    plus a margin, so genuine traffic is never limited while a flood is cut to that rate.
    """

    def __init__(self, capacity: int) -> None:
        self.capacity = capacity
        self._used: Counter[str] = Counter()

    @classmethod
    def for_team(cls, team_size: int) -> SenderBudget:
        return cls(4 * (team_size + 1) + 16)

    def take(self, sender: str) -> None:
        """Count one message of ``sender``; raise ``rate_limited`` beyond the budget."""
        if self._used[sender] >= self.capacity:
            raise MessageRejected("rate_limited", f"{sender!r}: over {self.capacity} per tick")
        self._used[sender] += 1

    def new_interval(self) -> None:
        self._used.clear()
