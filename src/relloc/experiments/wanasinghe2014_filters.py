"""The seed-000 reproduction's filters over one recording: one batch, one replay, one scoring.

Every part of the reproduction (the simulated team, Table 1, the odometry-noise sweep, the
MRCLAM replay) runs all its relative filters of one observing robot as one
:class:`~relloc.estimators.relative_batch.RelativeFilterBatch` through
:func:`relloc.pipeline.replay.replay`, recording the beliefs at the observer's measurement
times (after the updates of that time), and scores every filter with
:func:`relloc.pipeline.evaluation.evaluate` at its own updates: for each filter, the error, σ,
NEES and conditioning of ``P`` just after each update it made, aligned with that update's NIS
and the conditioning of ``R`` and ``S``.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from relloc.core.estimates import Estimates
from relloc.core.recording import Recording
from relloc.estimators.relative_batch import RelativeFilterBatch, TrackSpec
from relloc.estimators.yaw_bank import YawBankSettings
from relloc.pipeline.evaluation import SeriesEvaluation, evaluate
from relloc.pipeline.replay import replay


def run_filters(
    recording: Recording,
    specs: Sequence[TrackSpec],
    *,
    observer: str,
    bank: YawBankSettings,
    start: float | None = None,
    end: float | None = None,
) -> dict[tuple[str, str], SeriesEvaluation]:
    """Run ``specs`` of ``observer`` over ``recording`` from ``start`` to ``end`` (default: its
    span); the evaluation of each filter at its updates, keyed by ``(subject, label)``."""
    estimates = filter_estimates(
        recording, specs, observer=observer, bank=bank, start=start, end=end
    )
    return {(e.subject, e.track): e for e in evaluate(estimates, recording, at_updates=True)}


def filter_estimates(
    recording: Recording,
    specs: Sequence[TrackSpec],
    *,
    observer: str,
    bank: YawBankSettings,
    start: float | None = None,
    end: float | None = None,
) -> Estimates:
    """The estimates of :func:`run_filters`: every filter's belief at the observer's
    measurement times, after that time's updates."""
    batch = RelativeFilterBatch(
        specs,
        owner=observer,
        robots=recording.robots,
        odometry_sigma=[od.sigma for od in recording.odometry],
        bank=bank,
    )
    m = recording.measurements
    times = np.unique(m.t[m.observer == recording.index(observer)])
    if start is not None:
        times = times[times >= start]
    if end is not None:
        times = times[times <= end]
    return replay(recording, [batch], record_times=times, start=start, end=end)
