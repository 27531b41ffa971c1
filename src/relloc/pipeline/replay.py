"""Any recording through any estimators, on the one event loop of :mod:`relloc.core.events`.

:func:`replay` turns a :class:`~relloc.core.recording.Recording` into event times — the union
of every robot's odometry time stamps, the measurement times and the record times, within the
recording's span (events closer than :data:`relloc.core.events.TIME_TOL` are one) — and hands
them to :func:`~relloc.core.events.run_events`, the loop that robot nodes also call, window by
window, on what they have received. Readings outside the replayed window are not fed, and are
counted (``Estimates.counts["rows_outside_window"]``). At each event ``t_k`` every estimator
is advanced with the velocities in force since ``t_{k−1}`` (each robot's last report at or
before ``t_{k−1}``: zero-order hold), then given the readings stamped in ``(t_{k−1}, t_k]`` that
were not given yet, then its outbox is delivered to the other estimators; at record times the
beliefs are recorded.

An estimator that runs on a fixed clock (seed 002's filter steps at 20 Hz) is replayed with
``clock``: the events are then the clock's ticks only, and every reading is fed at the first
tick at or after its stamp (several readings of one sensor may arrive at one tick, each with its
own stamp).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
from numpy.typing import NDArray

from relloc.core.checks import number, positive
from relloc.core.contract import Estimator
from relloc.core.estimates import Estimates, Recorder
from relloc.core.events import TIME_TOL, run_events
from relloc.core.recording import Recording
from relloc.errors import ConfigError

Array = NDArray[np.float64]


def feed_ticks(stamps: Array, ticks: Array) -> Array:
    """The tick at which :func:`run_events` feeds a reading stamped at each of ``stamps``: the
    first tick at or after the stamp (ConfigError for a stamp after the last tick)."""
    t = np.asarray(ticks, dtype=float)
    at = np.searchsorted(t, np.asarray(stamps, dtype=float) - TIME_TOL)
    if np.any(at >= t.size):
        raise ConfigError("feed_ticks: a reading is stamped after the last tick")
    return np.asarray(t[at])


def merge_times(*arrays: Array) -> Array:
    """Sorted union of time stamps, with stamps closer than
    :data:`relloc.core.events.TIME_TOL` merged."""
    t = np.unique(np.concatenate([np.asarray(a, dtype=float).reshape(-1) for a in arrays]))
    if t.size < 2:
        return t
    return t[np.concatenate([[True], np.diff(t) > TIME_TOL])]


MAX_RECORDS = 10_000_000
"""Most record times of one grid (a day at 100 Hz is 8.6 million)."""


def record_grid(t0: float, t1: float, rate_hz: float) -> Array:
    """``t0 + i / rate_hz`` for every ``i`` with ``t0 + i / rate_hz ≤ t1`` (at most
    :data:`MAX_RECORDS`: ConfigError beyond, and for a rate that is not a finite number > 0,
    :func:`relloc.core.checks.positive`)."""
    rate_hz = positive(rate_hz, "record_rate_hz")
    records = (t1 - t0) * rate_hz
    if not (np.isfinite(records) and records <= MAX_RECORDS):
        raise ConfigError(
            f"record_rate_hz: {rate_hz:g} Hz over [{t0:g}, {t1:g}] s is more than "
            f"{MAX_RECORDS} record times"
        )
    n = int(np.floor(records + TIME_TOL))
    return np.asarray(t0 + np.arange(n + 1) / rate_hz, dtype=float)


def replay(
    recording: Recording,
    estimators: Sequence[Estimator],
    *,
    record_times: Array | Mapping[str, Array] | None = None,
    record_rate_hz: float = 10.0,
    start: float | None = None,
    end: float | None = None,
    name: str | None = None,
    clock: Array | None = None,
) -> Estimates:
    """Run ``estimators`` over ``recording`` from ``start`` to ``end`` (default: its span).

    ``record_times`` default to a grid at ``record_rate_hz`` from ``start``; they are added to
    the event times. With a ``clock`` (strictly increasing tick times) the events are its ticks
    inside the window, the window defaults to ``[clock[0], clock[-1]]``, the record times
    (default: every tick) must be ticks, and readings are fed at the first tick at or after
    their stamp (module docstring). Returns the
    :class:`~relloc.core.estimates.Estimates` of all of them.

    ``start``, ``end`` and ``record_rate_hz`` must be numbers (ConfigError naming the argument,
    :mod:`relloc.core.checks`), the window finite and not inverted.
    """
    if not estimators:
        raise ConfigError("replay: no estimators given")
    if len({id(e) for e in estimators}) != len(estimators):  # it would be fed twice
        raise ConfigError("replay: one estimator given twice")
    ticks = None if clock is None else _clock_ticks(clock)
    span0, span1 = recording.span if ticks is None else (float(ticks[0]), float(ticks[-1]))
    t0 = span0 if start is None else number(start, "replay: start")
    t1 = span1 if end is None else number(end, "replay: end")
    if not (np.isfinite(t0) and np.isfinite(t1) and t1 >= t0):
        raise ConfigError(f"replay: the window [{t0}, {t1}] is empty or not finite")
    if ticks is not None:
        ticks = ticks[(ticks >= t0 - TIME_TOL) & (ticks <= t1 + TIME_TOL)]
        if ticks.size == 0:
            raise ConfigError(f"replay: no clock tick inside the window [{t0}, {t1}]")
    if record_times is None:
        record_times = record_grid(t0, t1, record_rate_hz) if ticks is None else ticks
    all_record = (
        np.concatenate([np.asarray(v, dtype=float) for v in record_times.values()] or [np.zeros(0)])
        if isinstance(record_times, Mapping)
        else np.asarray(record_times, dtype=float)
    )
    m = recording.measurements
    inside = (m.t >= t0 - TIME_TOL) & (m.t <= t1 + TIME_TOL)
    m = m.select(inside)
    if ticks is None:
        odo_times = [od.t[(od.t > t0) & (od.t < t1)] for od in recording.odometry]
        times = merge_times(np.array([t0, t1]), all_record, m.t, *odo_times)
        times = times[(times >= t0 - TIME_TOL) & (times <= t1 + TIME_TOL)]
    else:
        times = ticks
    # the velocity in force up to each event: the one held at the previous event (none before t0)
    before = np.concatenate([times[:1], times[:-1]]) + TIME_TOL
    held = np.stack([od.held_at(before) for od in recording.odometry], axis=1)
    stamps = np.stack([od.stamp_at(before) for od in recording.odometry], axis=1)
    recorder = Recorder(name or "+".join(sorted({e.name for e in estimators})))
    outside = int(inside.size - inside.sum())
    if outside:
        recorder.count({"rows_outside_window": outside})
    run_events(estimators, times, held, stamps, m, record_times, recorder)
    return recorder.results()


def _clock_ticks(clock: Array) -> Array:
    """The ``clock`` argument of :func:`replay` as a validated, strictly increasing array."""
    ticks = np.asarray(clock, dtype=float)
    if ticks.ndim != 1 or ticks.size == 0 or not np.isfinite(ticks).all():
        raise ConfigError("replay: clock must be a non-empty 1-D array of finite times")
    if ticks.size > 1 and not np.all(np.diff(ticks) > TIME_TOL):
        raise ConfigError("replay: clock ticks must be strictly increasing")
    return ticks
