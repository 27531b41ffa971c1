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
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from relloc.association.nscan import new_history
from relloc.core.recording import Recording
from relloc.estimators.gaussian_sum import GaussianSumFuser, GaussianSumSettings, Tracks
from relloc.fusion.gaussian_sum_estimator import bearing_kind, bearing_rows

#: variance of the truth-placed tracks (m², rad²): the innovation is the bearing noise alone
TRUTH_VARIANCE = 1e-10


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
