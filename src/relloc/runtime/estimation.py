"""A robot node's estimator: its own :class:`~relloc.estimators.track_manager.TrackManager` —
the very one the in-process run gives that robot — driven window by window by the one event
loop, :func:`relloc.core.events.run_events`, on what the node has (its own sensors,
teammates' odometry as received).

For a window ``[t0, t1)`` the event times are — exactly as in
:func:`relloc.pipeline.replay.replay` — the union of the recording grid, this robot's
measurement times and every robot's odometry stamps (teammates': those *received*). Each event
uses every robot's last velocity before it (zero-order hold). With a perfect network the node
therefore performs the same arithmetic as the in-process run; a lost or late odometry sample
only changes which velocity is held.

Measurements of a teammate whose process is gone (its liveliness token vanished) are not fused —
its motion can no longer be predicted — and are counted; its track then expires after the keep
window (``deleted``) and is re-created when the teammate is back and seen again (``recreated``,
i.e. re-found).

A :class:`~relloc.core.estimates.Recorder` collects what the manager believed and did;
:meth:`TrackManagerEstimator.take_new` returns only what is *new* since its last call (an
:class:`~relloc.core.estimates.Estimates` increment); a node ships it every report period,
so a node that is killed mid-run has already shipped everything up to its last report.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
from numpy.typing import NDArray

from relloc.core.contract import Belief
from relloc.core.estimates import Estimates, Recorder
from relloc.core.events import TIME_TOL, run_events
from relloc.core.recording import measurement_rows
from relloc.estimators.relative import MEASUREMENT_KIND
from relloc.estimators.track_manager import TrackManager
from relloc.pipeline.replay import merge_times
from relloc.runtime.sources import MeasurementBatch
from relloc.runtime.teammates import ReceivedOdometry

Array = NDArray[np.float64]


class TrackManagerEstimator:
    """Window-by-window driver of one robot's :class:`TrackManager` (module docstring).

    Beliefs are recorded on the grid ``record_origin + i / record_rate_hz``.
    """

    def __init__(
        self, manager: TrackManager, *, record_rate_hz: float = 10.0, record_origin: float = 0.0
    ) -> None:
        self.manager = manager
        self.robot = manager.owner
        self.roster = manager.robots
        self.record_period = 1.0 / record_rate_hz
        self.record_origin = record_origin
        self._recorder = Recorder(manager.name)
        self._counts = {"created": 0, "deleted": 0, "recreated": 0, "skipped_absent": 0}
        self._rows_not_used: dict[str, int] = {}

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
        times = merge_times(*pieces)
        now = self.manager.t
        if now is not None:
            times = times[times >= now - TIME_TOL]
        live = np.array([tgt in present for tgt in m_targets], dtype=bool)
        skipped = int((~live).sum())
        self._counts["skipped_absent"] += skipped
        if not times.size:
            return skipped
        # the velocity in force up to each event: the one held at the previous event (for the
        # first event, at the manager's current time)
        before = np.concatenate([[times[0] if now is None else now], times[:-1]]) + TIME_TOL
        held = np.stack([s.held_at(before) for s in streams], axis=1)
        stamps = np.stack([s.stamp_at(before) for s in streams], axis=1)
        fused = measurement_rows(
            MEASUREMENT_KIND,
            t=m_t[live],
            observer=self.roster.index(self.robot),
            target=np.array(
                [self.roster.index(tgt) for tgt, ok in zip(m_targets, live, strict=True) if ok],
                dtype=np.int64,
            ),
            value=m_z[live],
            sigma=m_s[live],
        )
        run_events([self.manager], times, held, stamps, fused, record_times, self._recorder)
        return skipped

    def take_new(self) -> Estimates:
        """Everything recorded since the previous call: beliefs, updates, track events."""
        new = self._recorder.take_new()
        for e in new.events:
            self._counts[e.kind] += 1
        self._rows_not_used = dict(new.counts)
        return new

    def beliefs(self) -> list[Belief]:
        """Current belief of every live track (what the node broadcasts as ``eqm``)."""
        return [] if self.manager.t is None else self.manager.beliefs()

    def counters(self) -> dict[str, int]:
        """Track events shipped, measurements of absent teammates, and the rows the manager
        could not use (by reason, as of the latest :meth:`take_new`)."""
        return {**self._counts, **self._rows_not_used}
