"""Zenoh sessions on explicit endpoints, one inbox per process, liveliness-based presence.

Topology used by ``relloc team up``: the launcher opens a ``peer`` session that *listens* on
one explicit loopback endpoint (``tcp/127.0.0.1:<port>``, ``tls/...`` with ``--secure``); the
clock and every robot process open a ``peer`` session that *connects* to it and listens on an
ephemeral loopback port, so Zenoh's gossip can link peers directly. A session given neither
``listen`` endpoints nor a configuration file listens on ``tcp/127.0.0.1:0`` only (loopback,
never all interfaces: pass ``listen`` to be reachable from another machine). Multicast scouting
is off unless asked for, so nothing leaves loopback and two teams on one machine never meet. Any
Zenoh JSON5 configuration file (TLS, access control, other transports; ``relloc certs`` writes
one per team member, see :mod:`relloc.runtime.access`) can be loaded first with
``config_file``; the explicit fields override it.

Each process has a single :class:`Inbox`: Zenoh callbacks (run on Zenoh's threads) only append
``(key, payload)`` records to a bounded thread-safe queue; the process' main loop consumes it, so
all estimator work is single-threaded and deterministic given the arrival order. A payload larger
than the message limit is dropped in the callback, before it is copied or queued (counted
``oversized``), and the queue is bounded both in records and in bytes: a full inbox drops the
record and counts it (``overflow``) instead of blocking Zenoh or growing without bound.

Presence: each member declares a liveliness token ``relloc/<team>/alive/<id>``; a liveliness
subscriber with ``history=True`` reports the members already there and then every appearance
and disappearance (a killed process' token vanishes when its transport closes or its lease
expires). No home-made discovery. A process that drives a team (the clock, the air-ground
world) keeps who is present and who is ready in one :class:`Roll`.
"""

from __future__ import annotations

import json
import queue
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

from relloc.core.checks import number
from relloc.errors import ConfigError, require
from relloc.runtime import keys
from relloc.runtime.certs import check_tls_files

Mode = Literal["peer", "client", "router"]
DEFAULT_LISTEN = "tcp/127.0.0.1:0"
"""Where a session listens when nothing else is configured: an ephemeral loopback port."""
INBOX_RECORDS = 100_000
INBOX_BYTES = 32 * 2**20
RECORD_OVERHEAD_BYTES = 256
"""What one queued record is charged on top of its payload (the record object itself)."""


@dataclass(frozen=True, kw_only=True)
class TransportSettings:
    """How one process joins the Zenoh network.

    ``listen``/``connect`` are Zenoh endpoints such as ``tcp/127.0.0.1:7447`` (``tls/...`` with a
    TLS ``config_file``). ``lease_s`` is how long a silent peer is kept before its liveliness
    tokens are dropped (a clean kill is noticed at once because the TCP link closes). An
    endpoint that does not answer yet (a hub started later) is retried every 50–500 ms.
    """

    mode: Mode = "peer"
    listen: tuple[str, ...] = ()
    connect: tuple[str, ...] = ()
    multicast_scouting: bool = False
    lease_s: float = 10.0
    config_file: Path | None = None

    def __post_init__(self) -> None:
        if self.mode not in ("peer", "client", "router"):
            raise ConfigError(f"transport.mode: {self.mode!r} is not peer, client or router")
        for name in ("listen", "connect"):
            endpoints = getattr(self, name)
            if not isinstance(endpoints, tuple) or not all(
                isinstance(e, str) and "/" in e for e in endpoints
            ):
                raise ConfigError(f"transport.{name}: expected endpoints like 'tcp/127.0.0.1:7447'")
        if self.mode == "client" and not self.connect:
            raise ConfigError("transport.connect: a client needs at least one endpoint")
        number(self.lease_s, "transport.lease_s (s)", low=0.1, high=600.0)
        if self.config_file is not None and not Path(self.config_file).is_file():
            raise ConfigError(f"transport.config_file: {self.config_file} does not exist")

    def zenoh_config(self) -> Any:
        """The ``zenoh.Config`` these settings describe."""
        zenoh = require("zenoh", "runtime")
        if self.config_file is not None:
            try:
                conf = zenoh.Config.from_file(str(self.config_file))
            except zenoh.ZError as exc:
                raise ConfigError(f"transport.config_file: {self.config_file}: {exc}") from exc
            check_tls_files(conf, f"transport.config_file {self.config_file}")
        else:
            conf = zenoh.Config()
        conf.insert_json5("mode", json.dumps(self.mode))
        if self.listen:
            conf.insert_json5("listen/endpoints", json.dumps(list(self.listen)))
        elif self.config_file is None:
            conf.insert_json5("listen/endpoints", json.dumps([DEFAULT_LISTEN]))
        if self.connect:
            conf.insert_json5("connect/endpoints", json.dumps(list(self.connect)))
        conf.insert_json5("scouting/multicast/enabled", json.dumps(self.multicast_scouting))
        conf.insert_json5("transport/link/tx/lease", str(int(self.lease_s * 1000)))
        retry = {"period_init_ms": 50, "period_max_ms": 500, "period_increase_factor": 2}
        conf.insert_json5("connect/retry", json.dumps(retry))
        return conf


def declare_publisher(session: Any, key_expr: str) -> Any:
    """A reliable publisher that *blocks* rather than drops when Zenoh's queues are full.

    Zenoh's default congestion control for data drops samples under pressure; the runtime's
    streams (odometry the filters need, the clock barrier, the collector's reports) must not
    vanish silently, so every relloc publisher blocks instead; samples are sent at once
    (``express``: no batching — a batch waiting to fill added up to half a second of latency
    at robot rates). Loss is injected on purpose by
    :mod:`relloc.runtime.faults`, where it is counted.
    """
    zenoh = require("zenoh", "runtime")
    return session.declare_publisher(
        key_expr,
        congestion_control=zenoh.CongestionControl.BLOCK,
        reliability=zenoh.Reliability.RELIABLE,
        express=True,
    )


def loopback_endpoint(port: int, protocol: Literal["tcp", "tls"] = "tcp") -> str:
    """``tcp/127.0.0.1:<port>`` (or ``tls/...``)."""
    if not (0 <= port <= 65535):
        raise ConfigError(f"port: {port} outside 0–65535")
    return f"{protocol}/127.0.0.1:{port}"


def free_loopback_port() -> int:
    """A TCP port on 127.0.0.1 that is free right now (for tests and the team launcher)."""
    import socket

    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def open_session(settings: TransportSettings) -> Any:
    """Open a Zenoh session; a bad endpoint or a port in use becomes a ConfigError."""
    zenoh = require("zenoh", "runtime")
    try:
        return zenoh.open(settings.zenoh_config())
    except zenoh.ZError as exc:
        raise ConfigError(f"transport: cannot open a Zenoh session ({settings}): {exc}") from exc


@dataclass(frozen=True)
class Incoming:
    """One record in the inbox: a data sample or a presence change."""

    key: str
    payload: bytes
    presence: Literal["data", "joined", "left"] = "data"
    recv_wall_ns: int = field(default_factory=time.time_ns)


class Inbox:
    """The single, bounded message queue of a process (see module docstring).

    ``max_message_bytes`` is the largest payload accepted; ``capacity`` and ``capacity_bytes``
    bound the queue (payload plus :data:`RECORD_OVERHEAD_BYTES` per record).
    """

    def __init__(
        self,
        capacity: int = INBOX_RECORDS,
        *,
        max_message_bytes: int | None = None,
        capacity_bytes: int = INBOX_BYTES,
    ) -> None:
        if capacity < 1 or capacity_bytes < 1:
            raise ConfigError(f"inbox capacity: {capacity} records, {capacity_bytes} bytes < 1")
        self._queue: queue.Queue[Incoming] = queue.Queue(maxsize=capacity)
        self.max_message_bytes = max_message_bytes
        self.capacity_bytes = capacity_bytes
        self.overflow = 0
        self.oversized = 0
        self._bytes = 0
        self._lock = threading.Lock()
        self._handles: list[Any] = []

    def _push(self, item: Incoming) -> None:
        size = len(item.payload) + RECORD_OVERHEAD_BYTES
        with self._lock:
            if self._bytes + size > self.capacity_bytes:
                self.overflow += 1
                return
            try:
                self._queue.put_nowait(item)
            except queue.Full:
                self.overflow += 1
                return
            self._bytes += size

    def _taken(self, item: Incoming) -> Incoming:
        with self._lock:
            self._bytes -= len(item.payload) + RECORD_OVERHEAD_BYTES
        return item

    @property
    def queued_bytes(self) -> int:
        return self._bytes

    def subscribe(self, session: Any, key_expr: str, *, remote_only: bool = False) -> None:
        """Deliver every sample on ``key_expr`` to this inbox (oversized payloads are counted
        and dropped here, before they are copied). ``remote_only``: not the samples this
        session publishes itself (Zenoh's ``Locality.REMOTE``) — a robot that subscribes to
        every robot's keys then hears on its own keys only what another process sent there."""
        zenoh = require("zenoh", "runtime")

        def on_sample(sample: Any) -> None:
            payload = sample.payload
            if self.max_message_bytes is not None and len(payload) > self.max_message_bytes:
                with self._lock:
                    self.oversized += 1
                return
            self._push(Incoming(str(sample.key_expr), payload.to_bytes()))

        origin = zenoh.Locality.REMOTE if remote_only else zenoh.Locality.ANY
        self._handles.append(session.declare_subscriber(key_expr, on_sample, allowed_origin=origin))

    def watch_presence(self, session: Any, key_expr: str) -> None:
        """Deliver liveliness appearances/disappearances on ``key_expr`` (history included)."""
        zenoh = require("zenoh", "runtime")

        def on_token(sample: Any) -> None:
            joined = sample.kind == zenoh.SampleKind.PUT
            self._push(Incoming(str(sample.key_expr), b"", "joined" if joined else "left"))

        self._handles.append(
            session.liveliness().declare_subscriber(key_expr, on_token, history=True)
        )

    def get(self, timeout: float | None) -> Incoming | None:
        """Next record, waiting up to ``timeout`` seconds (None = forever); None if none came."""
        try:
            return self._taken(self._queue.get(timeout=timeout))
        except queue.Empty:
            return None

    def wait_until(
        self, done: Callable[[], bool], handle: Callable[[Incoming], None], timeout_s: float
    ) -> bool:
        """Pass each record to ``handle`` until ``done()`` holds (True) or ``timeout_s`` of
        wall time has passed (False); ``done`` is checked before the first wait."""
        deadline = time.monotonic() + timeout_s
        while not done():
            left = deadline - time.monotonic()
            if left <= 0:
                return False
            item = self.get(timeout=min(left, 0.5))
            if item is not None:
                handle(item)
        return True

    def drain(self) -> list[Incoming]:
        """Every record waiting now, without blocking."""
        items: list[Incoming] = []
        while True:
            try:
                items.append(self._taken(self._queue.get_nowait()))
            except queue.Empty:
                return items

    def close(self) -> None:
        """Undeclare the subscribers (before the session closes)."""
        for handle in self._handles:
            handle.undeclare()
        self._handles.clear()


class Roll:
    """Who of a roster is *present* (holds its ``alive`` token) and who is *ready* (holds its
    ``ready`` token, :func:`relloc.runtime.keys.ready_key`), from the presence records of
    :meth:`Inbox.watch_presence`.

    A member declares ``ready`` after ``alive``, but the two tokens reach a watcher through two
    liveliness subscribers with no order between them. So ``ready ⊆ present`` is kept: a
    ``ready`` that arrives first makes its member present too, and an ``alive`` that leaves
    takes the member's readiness with it (its ``ready`` token died with it). A driver that
    resumes once a restarted member is ready therefore finds it among the present members its
    barrier waits for — the member's first tick is awaited, not stepped over.
    """

    def __init__(self, roster: Sequence[str]) -> None:
        self.roster = frozenset(roster)
        self.present: set[str] = set()
        self.ready: set[str] = set()

    def update(self, item: Incoming) -> tuple[str, str, bool] | None:
        """Apply one presence record: ``(token kind, member, joined)``, or None for a member
        off the roster (ignored)."""
        parsed = keys.parse_presence_key(item.key)
        if parsed is None or parsed[1] not in self.roster:
            return None
        token, member = parsed
        joined = item.presence == "joined"
        if joined:
            self.present.add(member)
            if token == "ready":
                self.ready.add(member)
        else:
            self.ready.discard(member)
            if token != "ready":
                self.present.discard(member)
        return token, member, joined

    def renew_ready(self) -> None:
        """Count no member ready until its ``ready`` token is declared again: a ``joined`` of
        that token heard after this call makes it ready anew (presence is kept). A driver
        that calls this before it announces a restart, and then waits until every present
        member is ready, waits for tokens declared after the announcement."""
        self.ready.clear()
