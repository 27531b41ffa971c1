"""Live operation: a robot node on wall time instead of the clock process' lockstep ticks.

:class:`WallClockNode` is a :class:`~relloc.runtime.node.RobotNode` that ticks itself every
``tick_s`` wall seconds: at wall time ``start + k·tick_s + lag_s`` it takes its own sensors'
window ``[t_{k−1}, t_k)`` (robot time ``t_k = t0 + k·tick_s``; ``lag_s`` is the allowance for a
reading to reach the node after it was taken), publishes it and filters what is ready — the
very steps of a clock tick. Its sensors come from a :class:`~relloc.runtime.sources.LiveSource`:
a real robot's drivers push into it (the sensor-source API, see the README), or a
:class:`~relloc.runtime.sources.ReplayFeeder` pushes a recorded dataset's samples at the wall
time they were recorded. Teammates are other processes on the network or, for a dataset replay
run alone, their recorded odometry read at each tick (``teammates`` — their streams as they
would have arrived, no process behind them).

Timing reported (``final_counters``): ``latency_ms.p50/p99`` — from the wall time a reading
was taken (its stamp on the wall clock) to the wall time the estimate that fused it was made;
``deadline.windows`` / ``deadline.missed`` — windows filtered more than ``deadline_s`` after
their end on the wall clock; ``deadline.late_ticks`` — ticks the node itself started more than
one tick late (it could not keep up); ``source.late`` — readings pushed after their window was
taken (not used).
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from relloc.core.checks import number, positive
from relloc.errors import ConfigError
from relloc.runtime.estimation import WindowDriver
from relloc.runtime.node import NodeSettings, RobotNode, _Window
from relloc.runtime.sources import LiveSource, RecordingSource, ReplayFeeder
from relloc.runtime.timing import EstimateTiming
from relloc.runtime.transport import Inbox


@dataclass(frozen=True, kw_only=True)
class WallClockSettings:
    """``duration_s`` of robot time from ``t0``, a tick every ``tick_s`` wall seconds."""

    duration_s: float
    t0: float = 0.0
    tick_s: float = 0.1
    lag_s: float = 0.05
    deadline_s: float = 0.1

    def __post_init__(self) -> None:
        for name in ("duration_s", "tick_s", "deadline_s"):
            positive(getattr(self, name), f"realtime.{name}")
        number(self.t0, "realtime.t0")
        number(self.lag_s, "realtime.lag_s", low=0.0, high=10.0)
        if self.tick_s > self.duration_s:
            raise ConfigError("realtime.tick_s: longer than the duration")


class WallClockNode(RobotNode):
    """A robot node ticking on wall time (module docstring)."""

    def __init__(
        self,
        settings: NodeSettings,
        source: LiveSource,
        driver: WindowDriver,
        wall: WallClockSettings,
        *,
        feeder: ReplayFeeder | None = None,
        teammates: Mapping[str, RecordingSource] | None = None,
    ) -> None:
        super().__init__(settings, source, driver)
        self.wall = wall
        self.feeder = feeder
        self.replayed = dict(teammates or {})
        self._start = 0.0
        self.timing = EstimateTiming(wall.deadline_s)

    def _wall_of(self, t: float) -> float:
        """The wall time (monotonic) at which robot time ``t`` happens."""
        return self._start + (t - self.wall.t0)

    def _loop(self, inbox: Inbox) -> None:
        w = self.wall
        n = int(np.rint(w.duration_s / w.tick_s))
        self._start = time.monotonic()
        for robot in self.replayed:
            self._on_presence(robot, joined=True)
        if self.feeder is not None:
            self.feeder.start(self._start)
        self.counters["deadline.late_ticks"] += 0
        previous = w.t0
        try:
            for k in range(1, n + 1):
                due = self._start + k * w.tick_s + w.lag_s
                while (left := due - time.monotonic()) > 0:
                    item = inbox.get(timeout=left)
                    if item is not None:
                        self._on_incoming(item)
                if time.monotonic() - due > w.tick_s:
                    self.counters["deadline.late_ticks"] += 1
                t = w.t0 + k * w.tick_s
                for robot, src in self.replayed.items():
                    mate = self.teammates[robot]
                    mate.odometry.add(*src.odometry(previous, t))
                    mate.heard_until_s = t
                self._tick(k, n, t, w.tick_s)
                previous = t
            self._deliver(self.link.release(self._t))
            self._filter_ready(force=False)
            self._finish()
        finally:
            if self.feeder is not None:
                self.feeder.stop()
        self.counters["wall_ms"] = int((time.monotonic() - self._start) * 1000)

    def _window_done(self, window: _Window) -> None:
        own = window.rows[0]
        taken = self._start + (own.t - self.wall.t0)
        self.timing.window_done(taken, self._wall_of(window.end), time.monotonic())

    def final_counters(self) -> dict[str, int]:
        out = super().final_counters()
        src = self.source
        if isinstance(src, LiveSource):
            out["source.late"] = src.late
        return out | self.timing.counters()
