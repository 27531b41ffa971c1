"""A robot node's estimator: the same :class:`~relloc.estimators.track_manager.TrackManager` as the
in-process run, fed window by window from what the node has (its own sensors, teammates'
odometry as received).

For a window ``[t0, t1)`` the event times are — exactly as in
:func:`relloc.estimators.track_manager.track_log` — the union of the recording grid, this
robot's measurement times and every robot's odometry stamps (teammates': those *received*).
Between events every track is predicted with each robot's last velocity (zero-order hold); at an
event its measurements are fused, stale tracks expire (seed 000 §6.2 keep window) and on the grid
beliefs are recorded. With a perfect network the node therefore performs the same arithmetic as
the in-process run; a lost or late odometry sample only changes which velocity is held.

Measurements of a teammate whose process is gone (its liveliness token vanished) are not fused —
its motion can no longer be predicted — and are counted; its track then expires after the keep
window (``deleted``) and is re-created when the teammate is back and seen again (``recreated``,
i.e. re-found).

:meth:`TrackManagerEstimator.take_new` returns only what is *new* since its last call (estimates,
updates, track events); a node ships it every report period, so a node that is killed mid-run
has already shipped everything up to its last report.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from relloc.core.gaussian import Gaussian
from relloc.estimators.track_manager import (
    PairEstimates,
    TrackEvent,
    TrackManager,
    TrackManagerSettings,
    TruthFn,
)
from relloc.runtime.sources import MeasurementBatch
from relloc.runtime.teammates import ReceivedOdometry
from relloc.sim.log import Measurements

Array = NDArray[np.float64]
TIME_TOL = 1e-9
"""Event times closer than this are one event (as in the in-process run)."""


@dataclass(frozen=True)
class PairIncrement:
    """New rows of one (this robot → target) pair: records and measurement updates."""

    target: str
    t: Array
    mean: Array
    cov: Array
    age: Array
    update_t: Array
    update_age: Array
    nis: Array
    cond_r: Array
    cond_s: Array


@dataclass(frozen=True)
class EstimateBatch:
    """What one window produced."""

    pairs: tuple[PairIncrement, ...] = ()
    events: tuple[TrackEvent, ...] = ()

    @property
    def n_estimates(self) -> int:
        return sum(int(p.t.size) for p in self.pairs)


@dataclass
class _Sent:
    records: dict[str, int] = field(default_factory=dict)
    updates: dict[str, int] = field(default_factory=dict)
    events: int = 0


class TrackManagerEstimator:
    """Window-by-window driver of one observer's :class:`TrackManager` (module docstring)."""

    def __init__(
        self,
        settings: TrackManagerSettings,
        *,
        robot: str,
        roster: Sequence[str],
        odometry_sigma: Sequence[Sequence[float]],
        t0: float,
        record_rate_hz: float = 10.0,
        record_origin: float = 0.0,
        rng: np.random.Generator | None = None,
        truth_fn: TruthFn | None = None,
    ) -> None:
        self.robot = robot
        self.roster = tuple(roster)
        self.me = self.roster.index(robot)
        self.record_period = 1.0 / record_rate_hz
        self.record_origin = record_origin
        self.manager = TrackManager(
            settings,
            robots=self.roster,
            odometry_sigma=odometry_sigma,
            t0=t0,
            truth_fn=truth_fn,
            rng=rng,
        )
        self._sent = _Sent()
        self._counts = {"created": 0, "deleted": 0, "recreated": 0, "skipped_absent": 0}

    def _record_times(self, t0: float, t1: float, inclusive: bool) -> Array:
        """The recording grid ``origin + i / record_rate_hz`` inside the window."""
        first = np.ceil((t0 - self.record_origin) / self.record_period - TIME_TOL)
        last = np.floor((t1 - self.record_origin) / self.record_period + TIME_TOL)
        grid = self.record_origin + np.arange(first, last + 1) * self.record_period
        upper = grid <= t1 + TIME_TOL if inclusive else grid < t1 - TIME_TOL
        return np.asarray(grid[(grid >= t0 - TIME_TOL) & upper], dtype=float)

    def advance(
        self,
        t0: float,
        t1: float,
        *,
        own: ReceivedOdometry,
        teammates: Mapping[str, ReceivedOdometry],
        measurements: Sequence[MeasurementBatch],
        present: set[str],
        inclusive: bool = False,
    ) -> int:
        """Filter ``[t0, t1)`` (``[t0, t1]`` with ``inclusive``, for the end of the run); returns
        the number of measurements not fused because their target is absent."""
        streams = [own if r == self.robot else teammates[r] for r in self.roster]
        batches = [b for b in measurements if b.size]
        m_t = np.concatenate([b.t for b in batches]) if batches else np.zeros(0)
        m_targets = [tgt for b in batches for tgt in b.targets]
        m_z = np.concatenate([b.z for b in batches]) if batches else np.zeros((0, 3))
        m_s = np.concatenate([b.sigma for b in batches]) if batches else np.zeros((0, 3))
        record_times = self._record_times(t0, t1, inclusive)
        pieces = [record_times, m_t] + [s.stamps_between(t0, t1, inclusive) for s in streams]
        times = _merge_times(np.concatenate(pieces))
        m = self.manager
        times = times[times >= m.t - TIME_TOL]
        skipped = 0
        if times.size:
            # velocity in force from each event to the next; row 0 is the manager's current time
            anchors = np.concatenate([[m.t], times])
            held = np.stack([s.held_at(anchors + TIME_TOL) for s in streams], axis=1)
            live = np.array([tgt in present for tgt in m_targets], dtype=bool)
            skipped = int((~live).sum())
            fused = Measurements(
                t=m_t[live],
                observer=np.full(int(live.sum()), self.me, dtype=np.int64),
                observed=np.array(
                    [self.roster.index(tgt) for tgt, ok in zip(m_targets, live, strict=True) if ok],
                    dtype=np.int64,
                ),
                z=m_z[live],
                sigma=m_s[live],
            )
            m.replay(times, held, fused, record_times)
        self._counts["skipped_absent"] += skipped
        return skipped

    def take_new(self) -> EstimateBatch:
        """Everything recorded since the previous call (this robot's pairs only)."""
        results = self.manager.results()
        pairs = []
        for p in results.pairs:
            if p.observer != self.robot:
                continue
            pairs.append(self._new_rows(p))
        events = results.events[self._sent.events :]
        self._sent.events = len(results.events)
        for e in events:
            self._counts[e.kind] += 1
        return EstimateBatch(
            pairs=tuple(p for p in pairs if p.t.size or p.update_t.size), events=tuple(events)
        )

    def _new_rows(self, p: PairEstimates) -> PairIncrement:
        r0 = self._sent.records.get(p.observed, 0)
        u0 = self._sent.updates.get(p.observed, 0)
        self._sent.records[p.observed] = p.t.size
        self._sent.updates[p.observed] = p.update_t.size
        return PairIncrement(
            target=p.observed,
            t=p.t[r0:],
            mean=p.mean[r0:],
            cov=p.cov[r0:],
            age=p.age[r0:],
            update_t=p.update_t[u0:],
            update_age=p.update_age[u0:],
            nis=p.nis[u0:],
            cond_r=p.cond_r[u0:],
            cond_s=p.cond_s[u0:],
        )

    def beliefs(self) -> dict[str, Gaussian]:
        """Current belief of every live track of this robot (what it broadcasts as ``eqm``)."""
        return {
            self.roster[j]: self.manager.belief(i, j)
            for i, j in self.manager.live_pairs
            if i == self.me
        }

    def counters(self) -> dict[str, int]:
        return dict(self._counts)


def _merge_times(t: Array) -> Array:
    t = np.unique(t)
    if t.size < 2:
        return t
    return t[np.concatenate([[True], np.diff(t) > TIME_TOL])]
