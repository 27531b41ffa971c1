"""The one event loop (:func:`run_events`) over estimators that implement the contract of
:mod:`relloc.core.contract`.

At each event time ``t_k`` every estimator is advanced with the velocities in force since
``t_{k−1}`` (:class:`~relloc.core.contract.HeldOdometry`), then given the readings stamped up to
``t_k`` that were not given yet, then the messages in its outbox are delivered to every other
estimator; at record times the beliefs are recorded into a
:class:`~relloc.core.estimates.Recorder`. :func:`relloc.pipeline.replay.replay` builds the
events of a whole :class:`~relloc.core.recording.Recording`; a robot node builds them window by
window from what it received; the closed-loop air-ground simulator runs one event per tick. It
lives in core so that estimators, simulators and the runtime all share it.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Mapping, Sequence
from typing import overload

import numpy as np
from numpy.typing import NDArray

from relloc.core.checks import MAX_TIME_STEP_S, floats
from relloc.core.contract import Estimator, HeldOdometry
from relloc.core.estimates import Recorder
from relloc.core.recording import Measurements
from relloc.errors import ConfigError, DataError

Array = NDArray[np.float64]
TIME_TOL = 1e-9
"""Event times closer than this are one event."""


@overload
def elapsed(previous: None, t: object, where: str) -> None: ...
@overload
def elapsed(previous: float, t: object, where: str) -> float: ...
def elapsed(previous: float | None, t: object, where: str) -> float | None:
    """``t − previous`` (s) for an estimator advanced to ``t``; ``None`` at its first event
    (``previous`` None). ``t`` must be a finite number no earlier than ``previous − TIME_TOL``
    (one event that rounding split) and no later than ``previous +``
    :data:`~relloc.core.checks.MAX_TIME_STEP_S`: otherwise a DataError naming ``where`` — an
    estimator advanced back in time would predict over one interval twice, or keep a clock that
    went back, and one advanced by more would overflow its prediction."""
    # float first: the numbers.Real check costs about 0.3 µs
    if not (
        isinstance(t, float) or (isinstance(t, numbers.Real) and not isinstance(t, bool))
    ) or not math.isfinite(t):
        raise DataError(f"{where}: time {t!r:.40} is not a finite number")
    if previous is None:
        return None
    dt = float(t) - previous
    if dt < -TIME_TOL:
        raise DataError(f"{where}: time went back from {previous!r} to {t!r}")
    if dt > MAX_TIME_STEP_S:
        raise DataError(
            f"{where}: time jumped {dt:g} s from {previous!r} to {t!r}, more than the "
            f"{MAX_TIME_STEP_S:g} s an estimator predicts over"
        )
    return dt


def run_events(
    estimators: Sequence[Estimator],
    times: Array,
    held: Array,
    stamps: Array,
    measurements: Measurements,
    record_times: Array | Mapping[str, Array],
    recorder: Recorder,
) -> None:
    """The loop (module docstring) over event times ``times (K,)`` (increasing).

    ``held (K, n, 4)`` and ``stamps (K, n)``: the velocities (and their time stamps) in force
    from the previous event up to ``times[k]``; ``measurements`` sorted by time, each fed at the
    first event at or after its stamp; ``record_times`` — for every estimator, or per owner —
    must be among the event times.

    Event times that are not a finite, non-decreasing 1-D array (an estimator would be advanced
    back in time) and ``held`` or ``stamps`` of another length than ``times`` are a
    :class:`~relloc.errors.DataError`; no estimators, or ``measurements`` that are not a
    :class:`~relloc.core.recording.Measurements` table or a ``recorder`` that is not a
    :class:`~relloc.core.estimates.Recorder`, a :class:`ConfigError`.
    """
    times = _event_times(times, held, stamps)
    if not estimators:
        raise ConfigError("run_events: no estimators to run")
    if not isinstance(recorder, Recorder):
        raise ConfigError(f"run_events: recorder must be a Recorder, got {type(recorder).__name__}")
    if not isinstance(measurements, Measurements):
        raise ConfigError(
            f"run_events: measurements must be a Measurements table, got "
            f"{type(measurements).__name__}"
        )
    marks = _record_marks(estimators, times, record_times)
    ends = np.searchsorted(measurements.t, times + TIME_TOL, side="right")
    done = 0
    previous = -math.inf
    for k, t in enumerate(times):
        t = float(t)
        if not (math.isfinite(t) and t >= previous):  # (a NaN fails both)
            raise DataError(
                f"run_events: event {k} at t={t!r} after t={previous!r}; event times must be "
                "finite and non-decreasing"
            )
        previous = t
        odometry = HeldOdometry(velocity=held[k], stamp=stamps[k])
        for est in estimators:
            est.advance(t, odometry)
        end = int(ends[k])
        if end > done:
            batch = measurements.select(slice(done, end))
            for est in estimators:
                est.measure(batch)
            done = end
        if len(estimators) > 1:
            outgoing = [(est, m) for est in estimators for m in est.outbox()]
            if outgoing:
                for est in estimators:
                    est.receive([m for sender, m in outgoing if sender is not est])
        else:
            estimators[0].outbox()  # a lone estimator's messages reach no one
        for est, is_record in zip(estimators, marks, strict=True):
            if is_record[k]:
                recorder.record(t, est.owner, est.beliefs())
    for est in estimators:
        recorder.add_updates(est.owner, est.take_updates())
        recorder.add_events(est.take_events())
        take_counts = getattr(est, "take_counts", None)  # optional (see the contract)
        if take_counts is not None:
            recorder.count(take_counts())


def _event_times(times: Array, held: Array, stamps: Array) -> Array:
    """``times`` as a 1-D float array of one entry per ``held`` and ``stamps`` row (the order
    and finiteness are checked event by event, in the loop: a robot node runs a few events per
    call, where a numpy reduction would cost microseconds)."""
    t = floats(times, "run_events: event times")
    if t.ndim != 1:
        raise DataError(f"run_events: event times must be 1-D, got shape {t.shape}")
    try:
        fits = len(held) == t.size and len(stamps) == t.size
    except TypeError:  # None, a number
        fits = False
    if not fits:
        raise DataError(
            f"run_events: held velocities {np.shape(held)} and stamps {np.shape(stamps)} need "
            f"one row per event, {t.size}"
        )
    return t


def _record_marks(
    estimators: Sequence[Estimator], times: Array, record_times: Array | Mapping[str, Array]
) -> list[NDArray[np.bool_]]:
    def marks(rt: Array) -> NDArray[np.bool_]:
        rt = floats(rt, "run_events: record times", ConfigError).reshape(-1)
        idx = np.searchsorted(times, rt - TIME_TOL)
        if rt.size and (
            np.any(idx >= times.size)
            or np.any(np.abs(times[np.minimum(idx, times.size - 1)] - rt) > TIME_TOL)
        ):
            raise ConfigError("run_events: every record time must be an event time")
        out = np.zeros(times.size, dtype=bool)
        out[idx] = True
        return out

    if isinstance(record_times, Mapping):
        unknown = sorted(set(record_times) - {est.owner for est in estimators})
        if unknown:  # a misspelt owner would record nothing
            raise ConfigError(f"run_events: record_times of {unknown}, who own no estimator")
        return [marks(record_times.get(est.owner, np.zeros(0))) for est in estimators]
    shared = marks(np.asarray(record_times))
    return [shared for _ in estimators]
