"""Scores of seed 002's Gaussian-sum team on the Estimates record (desilva2015, mrclam-association).

:func:`leader_scores` lays one sensing robot's beliefs (dominant tracks,
:mod:`relloc.fusion.gaussian_sum_estimator`) out as dense arrays indexed ``[record, robot]`` at
its record times, scored by :func:`relloc.pipeline.evaluation.evaluate` (error with the yaw
wrapped, NEES), with the fields of the beliefs' ``info`` and the true *origin* of the bearings
the filter used: a belief names a bearing row of its last scan (``scan_t``, ``bearing_row``,
``decision_row``), which is looked up here in the recording's ``origin`` column — the truth
only scoring reads.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from relloc.core.estimates import Estimates
from relloc.core.recording import Recording
from relloc.errors import DataError
from relloc.fusion.gaussian_sum_estimator import NO_BEARING, bearing_rows
from relloc.pipeline.evaluation import evaluate_series

Array = NDArray[np.float64]
IntArray = NDArray[np.int64]
BoolArray = NDArray[np.bool_]

#: Origin entry of a record whose dominant track used no bearing (or of a missing track); the
#: recording's own codes are robot indices, ``CLUTTER`` (−1) and ``ORIGIN_UNKNOWN`` (−2).
NO_READING = -3


@dataclass(frozen=True)
class LeaderScores:
    """One leader's filters at its record times ``t (S,)``, indexed ``[record, robot]``.

    ``error``/``estimate (S, n, 4)`` and ``nees (S, n)`` are NaN, ``components`` 0,
    ``confirmed`` False and the origins :data:`NO_READING` where the filter has no track (and
    in the leader's own column). ``assoc_origin``: origin of the bearing the dominant track was
    last updated with; ``joint_origin``: of the bearing the joint decision gave the teammate.
    """

    observer: int
    t: Array
    error: Array
    estimate: Array
    nees: Array
    components: IntArray
    confirmed: BoolArray
    assoc_origin: IntArray
    joint_origin: IntArray


def leader_scores(
    estimates: Estimates, recording: Recording, observer: int, times: Array, bearing_kind: str
) -> LeaderScores:
    """Dense scores of ``observer``'s beliefs recorded at ``times`` (module docstring);
    ``bearing_kind`` is the kind of its fuser's bearing rows."""
    n, size = recording.n_robots, np.asarray(times).size
    t = np.asarray(times, dtype=float)
    out = LeaderScores(
        observer=observer,
        t=t,
        error=np.full((size, n, 4), np.nan),
        estimate=np.full((size, n, 4), np.nan),
        nees=np.full((size, n), np.nan),
        components=np.zeros((size, n), dtype=np.int64),
        confirmed=np.zeros((size, n), dtype=bool),
        assoc_origin=np.full((size, n), NO_READING, dtype=np.int64),
        joint_origin=np.full((size, n), NO_READING, dtype=np.int64),
    )
    origin = _BearingOrigins(recording, observer, bearing_kind)
    owner = recording.robots[observer]
    for series in estimates.beliefs:
        if series.owner != owner:
            continue
        k = np.searchsorted(t, series.t)
        if np.any(k >= size) or np.any(t[np.minimum(k, size - 1)] != series.t):
            raise DataError(f"{series.label}: beliefs recorded outside the given record times")
        ev = evaluate_series(series, estimates.updates_of(*series.key), recording)
        j = recording.index(series.subject)
        info = series.info
        out.error[k, j] = ev.error
        out.estimate[k, j] = series.mean
        out.nees[k, j] = ev.nees
        out.components[k, j] = info["components"].astype(np.int64)
        out.confirmed[k, j] = info["confirmed"] > 0.5
        out.assoc_origin[k, j] = origin.of(info["scan_t"], info["bearing_row"], series.label)
        out.joint_origin[k, j] = origin.of(info["scan_t"], info["decision_row"], series.label)
    return out


class _BearingOrigins:
    """The ``origin`` of the ``row``-th bearing row of one observer's scan at ``scan_t``."""

    def __init__(self, recording: Recording, observer: int, kind: str) -> None:
        m = recording.measurements
        assert m.origin is not None
        rows = bearing_rows(m, observer, kind)
        self._t = m.t[rows]
        self._origin = m.origin[rows]

    def of(self, scan_t: Array, row: Array, label: str) -> IntArray:
        out = np.full(row.shape, NO_READING, dtype=np.int64)
        used = row != NO_BEARING
        idx = np.searchsorted(self._t, scan_t[used]) + row[used].astype(np.int64)
        ok = idx < self._t.size
        ok[ok] = self._t[idx[ok]] == scan_t[used][ok]
        if not ok.all():
            bad = int(np.argmin(ok))
            raise DataError(
                f"{label}: bearing row {int(row[used][bad])} of the scan at "
                f"t={float(scan_t[used][bad])!r} is not in the recording"
            )
        out[used] = self._origin[idx]
        return out
