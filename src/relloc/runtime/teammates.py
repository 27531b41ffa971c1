"""What a node knows about its teammates: presence, received odometry, duplicate messages.

The relative motion model of seed 000 (Eq. 1) needs the *observed* robot's body velocities,
which only that robot measures — so they come over the network. :class:`ReceivedOdometry`
keeps the samples that arrived and answers zero-order-hold queries exactly like
:meth:`relloc.core.recording.Odometry.held_at`: with a perfect network the node therefore feeds
its filters the very same inputs as the in-process run. A lost sample means the previous one is
held longer; a sample that arrives after the node has already propagated past its time is
counted ``late`` and handed back to the node, which files it only where it re-filters the past
(seed 001's agents, :meth:`relloc.runtime.estimation.WindowDriver.refilter`).
"""

from __future__ import annotations

import bisect
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from relloc.core.events import TIME_TOL
from relloc.core.recording import Measurements
from relloc.runtime.messages import Message, MessageRejected

Array = NDArray[np.float64]


class ReceivedOdometry:
    """Body-velocity samples of one teammate as received (sorted by stamp, no duplicates)."""

    def __init__(self) -> None:
        self._t: list[float] = []
        self._u: list[Array] = []
        self.consumed_until = -np.inf
        self.late = 0
        self.duplicate_samples = 0

    def add(self, stamps: Array, u: Array) -> tuple[Array, Array]:
        """File the samples; return those that are late (stamped before what the node has
        filtered) and were not filed: ``(stamps, u)``."""
        late: list[int] = []
        for k, (s, v) in enumerate(zip(stamps.tolist(), u, strict=True)):
            if s < self.consumed_until:
                self.late += 1
                late.append(k)
                continue
            self._insert(s, v)
        return np.asarray(stamps, dtype=float)[late], np.asarray(u, dtype=float)[late]

    def file_late(self, stamps: Array, u: Array) -> None:
        """File late samples after all (the node re-filters the windows they belong to)."""
        for s, v in zip(stamps.tolist(), u, strict=True):
            self._insert(s, v)

    def _insert(self, s: float, v: Array) -> None:
        i = bisect.bisect_left(self._t, s)
        if i < len(self._t) and self._t[i] == s:
            self.duplicate_samples += 1
            return
        self._t.insert(i, s)
        self._u.insert(i, np.asarray(v, dtype=float))

    def held_at(self, t: Array) -> Array:
        """Zero-order hold at times ``t`` (zeros before the first sample), shape ``(len(t), 4)``."""
        tq = np.atleast_1d(np.asarray(t, dtype=float))
        out = np.zeros((tq.size, 4))
        if not self._t:
            return out
        stamps = np.asarray(self._t)
        idx = np.searchsorted(stamps, tq, side="right") - 1
        ok = idx >= 0
        out[ok] = np.asarray(self._u)[idx[ok]]
        return out

    def stamp_at(self, t: Array) -> Array:
        """Stamp of the sample held at each time ``t`` (NaN before the first sample), as
        :meth:`relloc.core.recording.Odometry.stamp_at`."""
        tq = np.atleast_1d(np.asarray(t, dtype=float))
        out = np.full(tq.size, np.nan)
        if not self._t:
            return out
        stamps = np.asarray(self._t)
        idx = np.searchsorted(stamps, tq, side="right") - 1
        ok = idx >= 0
        out[ok] = stamps[idx[ok]]
        return out

    def stamps_between(self, t0: float, t1: float, inclusive: bool = False) -> Array:
        """Stamps of the samples held in ``[t0, t1)`` (``[t0, t1]`` with ``inclusive``)."""
        stamps = np.asarray(self._t, dtype=float)
        upper = stamps <= t1 if inclusive else stamps < t1
        return stamps[(stamps >= t0) & upper]

    def consume_until(self, t: float, keep_from: float | None = None) -> None:
        """The node has filtered up to ``t`` (exclusive): later arrivals stamped before ``t`` are
        late; samples older than the last one before ``keep_from`` (default ``t``: the
        velocity still held at the filter's current time; earlier where the node may
        re-filter) are no longer needed and are released."""
        self.consumed_until = max(self.consumed_until, t)
        keep = t if keep_from is None else min(t, keep_from)
        keep_from_index = max(0, bisect.bisect_left(self._t, keep) - 1)
        del self._t[:keep_from_index]
        del self._u[:keep_from_index]

    @property
    def last_stamp(self) -> float | None:
        return self._t[-1] if self._t else None


@dataclass
class Teammate:
    """One teammate as seen by a node."""

    robot: str
    present: bool = False
    joins: int = 0
    departures: int = 0
    odometry: ReceivedOdometry = field(default_factory=ReceivedOdometry)
    heard_until_s: float | None = None
    """End of the latest odometry window received (the header time of its ``odom``)."""
    progress: float = -np.inf
    """The teammate's estimator has processed every event before this time (its latest
    ``mail``; see :mod:`relloc.runtime.estimation`)."""
    rows_until: float = -np.inf
    """End of the latest window of shared readings received (the header time of its ``rows``)."""
    rows: list[Measurements] = field(default_factory=list)
    """Its shared readings received and not yet filtered."""
    held: list[Message] = field(default_factory=list)
    """Its messages that arrived while it was not present, in arrival order (delivered when
    its appearance is heard: :mod:`relloc.runtime.node`)."""

    def take_rows(self, t0: float, t1: float, *, inclusive: bool = False) -> list[Measurements]:
        """The shared readings stamped in ``[t0, t1)`` (``[t0, t1]``); earlier ones are
        dropped (their window is filtered already) and counted in :attr:`late_rows`. Both
        bounds are taken to :data:`~relloc.core.events.TIME_TOL`, as the event loop merges
        times: a reading that close below ``t1`` is at the next window's first event."""
        taken, kept = [], []
        for part in self.rows:
            before = part.t < t0 - TIME_TOL
            upper = (part.t <= t1 + TIME_TOL) if inclusive else (part.t < t1 - TIME_TOL)
            inside = ~before & upper
            self.late_rows += int(before.sum())
            if inside.any():
                taken.append(part.select(inside))
            if (~before & ~inside).any():
                kept.append(part.select(~before & ~inside))
        self.rows = kept
        return taken

    late_rows: int = 0
    """Shared readings that arrived after their window was filtered (not used)."""


class SeenSequences:
    """Per (sender, kind): duplicate messages and implausible jumps of sequence numbers.

    - **duplicates**: a seq among the last ``window`` accepted from that sender and kind (the
      link's copies arrive within a few ticks; memory stays bounded). How far a seq lies below
      the largest one accepted does not matter: judged that way, one message with a huge seq
      — sent by anyone holding the sender's certificate — would make every later genuine one
      look old and be dropped.
    - **jumps** (``seq_jump``): a sender publishes at most ``per_tick`` data messages between
      two of the receiver's ticks (the rate budget,
      :class:`relloc.runtime.admission.SenderBudget`), so after the largest accepted seq
      ``s`` (at receiver tick ``k_s``; ``s = −1`` at tick 0 for a sender not yet heard) a
      genuine seq at tick ``k`` is at most ``s + per_tick·(k − k_s + 2)`` (the 2: a teammate is
      up to one tick ahead, and one tick of slack). A larger one is rejected and leaves the
      state unchanged. Losses and partitions stay within the bound: the seqs missed were
      sent in the ticks that passed.

    A restarted sender counts from 0 again: below its old largest seq, so not a jump, and new
    once :meth:`forget` has cleared the old incarnation's seqs (the node calls it when the
    sender's liveliness token goes).
    """

    def __init__(self, per_tick: int, window: int = 4096) -> None:
        self.per_tick = per_tick
        self.window = window
        self._recent: dict[tuple[str, str], dict[int, None]] = {}
        self._top: dict[tuple[str, str], tuple[int, int]] = {}

    def is_new(self, sender: str, kind: str, seq: int, tick: int) -> bool:
        """True for a new message (remembered), False for a duplicate; ``seq_jump``
        (:class:`~relloc.runtime.messages.MessageRejected`) beyond the bound. ``tick``: the
        receiver's latest tick index (0 before the first)."""
        key = (sender, kind)
        recent = self._recent.setdefault(key, {})
        if seq in recent:
            return False
        top, top_tick = self._top.get(key, (-1, 0))
        allowed = top + self.per_tick * (max(tick - top_tick, 0) + 2)
        if seq > allowed:
            raise MessageRejected(
                "seq_jump", f"{kind} seq {seq} from {sender!r}: at most {allowed} at tick {tick}"
            )
        recent[seq] = None
        if len(recent) > self.window:
            del recent[next(iter(recent))]
        if seq > top:
            self._top[key] = (seq, tick)
        return True

    def forget(self, sender: str) -> None:
        """A restarted sender counts from 0 again."""
        for key in [k for k in self._recent if k[0] == sender]:
            del self._recent[key]
            self._top.pop(key, None)
