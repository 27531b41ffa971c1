"""How well can any filter associate the bearings of a recording? A truth-placed bound.

``association_accuracy`` of :mod:`relloc.experiments.mrclam_association` scores, at every
record, the bearing the dominant track of a filter ``GSF^(i,j)`` was last updated with: the
per-scan maximum of the formation weights (seed 002 §II-D.3) among the false-alarm branch
``w (1 − P_D P_G)`` and the detected branches ``w P_D N(z_b; ẑ, S) / κ_b``. Even a filter
that knows where every teammate is cannot make that choice without error: in a scan where
its teammate is in view but not detected (probability ``1 − P_D``), a false bearing close
enough to the predicted azimuth makes a detected branch heavier than the false-alarm one.

:func:`association_bound` measures this on the recording itself. For every scan of every
observer it places, in a :class:`~relloc.estimators.gaussian_sum.GaussianSumFuser` with the
experiment's settings, one track per teammate at its true relative pose (ground truth, a
covariance of ``TRUTH_VARIANCE``, so the innovation covariance is the bearing noise alone),
runs the fuser's own bearing step (:meth:`GaussianSumFuser.update_bearings`: the same gate,
``P_D`` with the field of view, clutter and other-teammate density ``κ``) and reads which
bearing the heaviest component of each filter took. The share of those bearings that came
from the teammate (``origin``, scoring only) is the accuracy a filter with perfect tracks
would score under the same definition: an upper bound of ``association_accuracy`` on that
recording (a real filter's wider innovation captures more false bearings).

:func:`sighting_reset_reference` does the same for ``tracked_fraction``, which counts the
records whose dominant track is within a position and a yaw tolerance of the truth. Between two
sightings of teammate ``j`` a filter of observer ``i`` that fuses only its own readings (direct
fusion) learns nothing new about ``j``: it can only dead-reckon both robots with their
odometry. The reference gives it the most a sighting could give — the exact relative pose,
yaw included, which one range and bearing never fix — and dead-reckons from there: at a record
time ``t`` with ``s`` the last sighting (a bearing of ``j`` in ``i``'s readings, by ``origin``)
at or before it, robot ``k ∈ {i, j}`` is put at

    x̂_k(t) = T_k(s) ⊕ (⊖O_k(s) ⊕ O_k(t)),

``T_k`` its ground truth and ``O_k`` the pose integrated from its recorded (held) odometry
(:func:`relloc.sim.trajectories.integrate_body_velocities` on a ``dt`` grid, read at the nearest
grid time), and the record counts as tracked when ``⊖x̂_i ⊕ x̂_j`` is within the tolerances of
the true relative pose. The share over the records after the teammate's first sighting is what
such a filter scores; a real filter, which must find the yaw from the motion during its
sightings, scores less. :class:`TrackedByAge` splits a tracked share by the record's age
``t − s`` (bins :data:`AGE_EDGES_S`), for the reference and for a filter alike
(:func:`last_sightings`): how fast a track is lost once its teammate is out of sight.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from relloc.association.nscan import new_history
from relloc.core.angles import wrap_angle
from relloc.core.recording import Recording, compose_pose, relative_pose
from relloc.estimators.gaussian_sum import GaussianSumFuser, GaussianSumSettings, Tracks
from relloc.fusion.gaussian_sum_estimator import bearing_kind, bearing_rows
from relloc.sim.trajectories import integrate_body_velocities

Array = NDArray[np.float64]

#: variance of the truth-placed tracks (m², rad²): the innovation is the bearing noise alone
TRUTH_VARIANCE = 1e-10
#: edges (s) of the bins of a record's age, the time since the last sighting (the last is ∞)
AGE_EDGES_S = (0.0, 1.0, 5.0, 15.0, 45.0, np.inf)


@dataclass(frozen=True)
class AssociationBound:
    """Bearings the truth-placed filters took (``used``), how many came from their teammate
    (``correct``) and the share, ``None`` when none was taken."""

    used: int
    correct: int

    @property
    def accuracy(self) -> float | None:
        return self.correct / self.used if self.used else None

    def to_dict(self) -> dict[str, float | int | None]:
        return {"accuracy": self.accuracy, "used": self.used, "correct": self.correct}


def association_bound(rec: Recording, settings: GaussianSumSettings) -> AssociationBound:
    """The truth-placed bound of every observer's scans (module docstring)."""
    m = rec.measurements
    assert m.origin is not None
    truth = rec.require_truth("association_bound")
    kind = bearing_kind(settings)
    nb = len(settings.bearing_rows)
    used = correct = 0
    for i in range(rec.n_robots):
        team = [j for j in range(rec.n_robots) if j != i]
        rows = bearing_rows(m, i, kind)
        if rows.size == 0:
            continue
        stamps, first = np.unique(m.t[rows], return_index=True)
        valid = np.logical_and.reduce([truth[j].valid_at(stamps) for j in (i, *team)])
        poses = np.stack([rec.relative_truth(i, j, stamps) for j in team], axis=1)
        fuser = GaussianSumFuser(i, team, settings)
        nan = np.full(len(team), np.nan)
        bounds = np.append(first, rows.size)
        for s in np.flatnonzero(valid):
            scan = rows[bounds[s] : bounds[s + 1]]
            fuser.tracks = _truth_tracks(poses[s], settings.nscan_depth)
            fuser.update_bearings(m.value[scan, :nb], nan, nan)
            t = fuser.tracks
            for local, j in enumerate(team):
                sel = np.flatnonzero(t.groups == local)
                best = sel[int(np.argmax(t.weights[sel]))]
                if t.assoc[best] >= 0:
                    used += 1
                    correct += int(m.origin[scan[t.assoc[best]]] == j)
    return AssociationBound(used=used, correct=correct)


def _truth_tracks(poses: np.ndarray, depth: int) -> Tracks:
    """One track per teammate at its true relative pose, weight 1."""
    n = poses.shape[0]
    covs = np.broadcast_to(TRUTH_VARIANCE * np.eye(4), (n, 4, 4)).copy()
    return Tracks(
        groups=np.arange(n, dtype=np.int64),
        means=poses.copy(),
        covs=covs,
        prior_means=poses.copy(),
        prior_covs=covs.copy(),
        weights=np.ones(n),
        history=new_history(np.arange(n, dtype=np.int64), depth),
        assoc=np.full(n, -1, dtype=np.int64),
    )


def last_sightings(rec: Recording, observer: int, target: int, t: Array, kind: str) -> Array:
    """The time ``s`` of ``observer``'s last sighting of ``target`` (a bearing row of kind
    ``kind`` whose ``origin`` is ``target``: the truth, for scoring only) at or before each
    of ``t``; NaN before the first."""
    m = rec.measurements
    assert m.origin is not None
    rows = bearing_rows(m, observer, kind)
    sightings = np.unique(m.t[rows[m.origin[rows] == target]])
    if sightings.size == 0:
        return np.full(np.shape(t), np.nan)
    last = np.searchsorted(sightings, t, side="right") - 1
    return np.where(last >= 0, sightings[np.maximum(last, 0)], np.nan)


@dataclass(frozen=True)
class TrackedByAge:
    """Records and tracked records in each bin ``[AGE_EDGES_S[k], AGE_EDGES_S[k + 1])`` of
    the time since the last sighting."""

    records: tuple[int, ...]
    tracked: tuple[int, ...]

    @classmethod
    def count(cls, age: Array, tracked: NDArray[np.bool_]) -> TrackedByAge:
        """Bin the records of ages ``age`` (s, finite, ≥ 0) and their ``tracked`` flags."""
        k = np.searchsorted(AGE_EDGES_S, np.asarray(age, dtype=float), side="right") - 1
        n = len(AGE_EDGES_S) - 1
        flags = np.asarray(tracked, dtype=bool)
        return cls(
            tuple(int(v) for v in np.bincount(k, minlength=n)),
            tuple(int(v) for v in np.bincount(k[flags], minlength=n)),
        )

    def to_list(self) -> list[dict[str, float | int | None]]:
        """One entry per bin: ``from_s``, ``to_s`` (None: no end), ``records`` and
        ``tracked_fraction`` (None: no record)."""
        return [
            {
                "from_s": AGE_EDGES_S[k],
                "to_s": AGE_EDGES_S[k + 1] if np.isfinite(AGE_EDGES_S[k + 1]) else None,
                "records": n,
                "tracked_fraction": self.tracked[k] / n if n else None,
            }
            for k, n in enumerate(self.records)
        ]


@dataclass(frozen=True)
class TrackingReference:
    """Of ``records`` (observer records × teammates after the teammate's first sighting, truth
    valid at the record and the sighting), how many the sighting-reset dead reckoning keeps
    within the tolerances (``tracked``); ``truth_missing`` records left out for a ground-truth
    gap; ``median_age_s`` the median time since the last sighting, ``by_age`` the records by
    that time."""

    records: int
    tracked: int
    truth_missing: int
    median_age_s: float | None
    by_age: TrackedByAge

    @property
    def fraction(self) -> float | None:
        return self.tracked / self.records if self.records else None

    def to_dict(self) -> dict[str, Any]:
        return {
            "tracked_fraction": self.fraction,
            "records": self.records,
            "tracked": self.tracked,
            "truth_missing": self.truth_missing,
            "median_age_s": self.median_age_s,
            "by_age": self.by_age.to_list(),
        }


def sighting_reset_reference(
    rec: Recording,
    settings: GaussianSumSettings,
    record_times: Mapping[str, Array],
    *,
    pos_tol: float,
    yaw_tol: float,
    dt: float = 0.01,
) -> TrackingReference:
    """The tracked fraction of dead reckoning reset to the true relative pose at every
    sighting (module docstring), at each observer's ``record_times`` (robot name → times);
    the planar position error is tested against ``pos_tol`` (m), the yaw's against ``yaw_tol``
    (rad)."""
    m = rec.measurements
    assert m.origin is not None
    truth = rec.require_truth("sighting_reset_reference")
    kind = bearing_kind(settings)
    times = {name: np.asarray(t, dtype=float) for name, t in record_times.items()}
    stamps = [t for t in times.values() if t.size]
    if not stamps:
        empty = TrackedByAge.count(np.empty(0), np.empty(0, dtype=bool))
        return TrackingReference(0, 0, 0, None, empty)
    start = min(float(m.t.min()) if m.t.size else np.inf, min(float(t[0]) for t in stamps))
    grid = np.arange(start, max(float(t[-1]) for t in stamps) + dt, dt)
    odometry = [
        integrate_body_velocities(np.zeros(4), rec.odometry[k].held_at(grid[:-1]), dt)
        for k in range(rec.n_robots)
    ]

    def reset(k: int, s: Array, t: Array) -> Array:
        """``x̂_k(t)`` from the truth at ``s`` (module docstring)."""
        at_s, at_t = (
            odometry[k][np.clip(np.rint((u - start) / dt).astype(np.int64), 0, grid.size - 1)]
            for u in (s, t)
        )
        return compose_pose(truth[k].at(s), relative_pose(at_s, at_t))

    missing = 0
    ages, flags = [], []
    for i in range(rec.n_robots):
        t_all = times.get(rec.robots[i], np.empty(0))
        for j in range(rec.n_robots):
            if j == i or t_all.size == 0:
                continue
            s_all = last_sightings(rec, i, j, t_all, kind)
            seen = np.isfinite(s_all)
            t, s = t_all[seen], s_all[seen]
            ok = np.logical_and.reduce([truth[k].valid_at(u) for k in (i, j) for u in (s, t)])
            missing += int(t.size - ok.sum())
            t, s = t[ok], s[ok]
            if t.size == 0:
                continue
            estimate = relative_pose(reset(i, s, t), reset(j, s, t))
            true = rec.relative_truth(i, j, t)
            position = np.hypot(*(estimate[:, :2] - true[:, :2]).T)
            yaw = np.abs(wrap_angle(estimate[:, 3] - true[:, 3]))
            flags.append((position <= pos_tol) & (yaw <= yaw_tol))
            ages.append(t - s)
    age = np.concatenate(ages) if ages else np.empty(0)
    hit = np.concatenate(flags) if flags else np.empty(0, dtype=bool)
    return TrackingReference(
        records=int(age.size),
        tracked=int(np.count_nonzero(hit)),
        truth_missing=missing,
        median_age_s=float(np.median(age)) if age.size else None,
        by_age=TrackedByAge.count(age, hit),
    )
