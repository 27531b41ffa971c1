"""The team part of ``relloc reproduce tiers-uwb``: range-only cooperative localization of every
robot (:class:`~relloc.estimators.uwb_range.RangeTeamFilter`, constant-velocity prior) and raw
multilateration, scored aligned (best rigid motion onto motion capture, reflections allowed) or
anchored (standing robots fixed at their motion-capture position; leave-one-out when every
robot stands; with exactly two anchors, the mirror image in their line is the ambiguity ranges
leave, and the image closer to motion capture is scored).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from relloc.core.kalman import chi2_threshold
from relloc.core.recording import Recording
from relloc.datasets.bag_mapping import BagMapping
from relloc.errors import DataError
from relloc.estimators.uwb_range import RangeTeamFilter, RangeTeamSettings
from relloc.geometry.multilateration import classical_mds, multilaterate, rigid_alignment
from relloc.metrics.consistency import percent_beyond_interval
from relloc.pipeline.replay import record_grid, replay

Array = NDArray[np.float64]

#: Seconds of ranges whose per-link medians give the team's start (classical MDS).
INIT_S = 1.0
#: A robot whose motion capture stays within this distance (m) of its start is standing.
STANDING_M = 0.1
#: Multilateration uses the latest raw range per link not older than this (s).
LATEST_S = 1.0
#: Position error (m) below which the team counts as converged.
CONVERGED_M = 0.3
#: Beliefs are recorded (and scored) at this rate.
RECORD_HZ = 10.0


def standing_robots(rec: Recording, mapping: BagMapping) -> list[int]:
    """The declared anchors, or the robots whose motion capture stays within ``STANDING_M``."""
    if mapping.anchors is not None:
        return [rec.index(a) for a in mapping.anchors]
    truth = rec.require_truth("anchors from motion capture")
    return [
        i
        for i, g in enumerate(truth)
        if float(np.max(np.linalg.norm(g.pose[:, :2] - g.pose[0, :2], axis=1))) < STANDING_M
    ]


def latest_ranges(rec: Recording, t: float, window: float) -> dict[tuple[int, int], float]:
    """Per robot pair (or robot–landmark, the landmark as ``n + l``), the latest range in
    ``[t − window, t]``."""
    m = rec.measurements
    assert m.landmark is not None
    lo, hi = np.searchsorted(m.t, [t - window, t + 1e-9])
    n = rec.n_robots
    out: dict[tuple[int, int], float] = {}
    for q in range(int(lo), int(hi)):
        j = int(m.target[q]) if m.target[q] >= 0 else n + int(m.landmark[q])
        out[(min(int(m.observer[q]), j), max(int(m.observer[q]), j))] = float(m.value[q, 0])
    return out


def median_distances(rec: Recording, t0: float, t1: float) -> Array:
    """Per robot pair the median range in ``[t0, t1]`` (NaN where none)."""
    m = rec.measurements
    n = rec.n_robots
    sel = (m.t >= t0) & (m.t <= t1) & (m.target >= 0)
    D = np.full((n, n), np.nan)
    np.fill_diagonal(D, 0.0)
    for i in range(n):
        for j in range(i + 1, n):
            pick = sel & (
                ((m.observer == i) & (m.target == j)) | ((m.observer == j) & (m.target == i))
            )
            if pick.any():
                D[i, j] = D[j, i] = float(np.median(m.value[pick, 0]))
    return D


def _anchor_positions(rec: Recording, anchors: list[int], t: float) -> Array:
    truth = rec.require_truth("anchor positions")
    return np.array([truth[i].at(t)[0, :2] for i in anchors]).reshape(-1, 2)


def team_start(rec: Recording, t0: float, anchors: list[int]) -> Array:
    """Start positions of every robot: classical MDS of the first ``INIT_S`` s of ranges, moved
    onto the anchors (their motion-capture positions at ``t0``) when there are two or more — by
    the best rotation *or reflection*, since the MDS configuration's handedness is arbitrary
    (with exactly two anchors the mirror image fits as well: ranges cannot decide)."""
    X = classical_mds(median_distances(rec, t0, t0 + INIT_S))
    if len(anchors) >= 2:
        R, tr = rigid_alignment(X[anchors], _anchor_positions(rec, anchors, t0), reflection=True)
        X = X @ R.T + tr
        X[anchors] = _anchor_positions(rec, anchors, t0)
    return X


def truth_xy(rec: Recording, t: Array) -> Array:
    """``(K, n, 2)`` true positions of every robot."""
    truth = rec.require_truth("scoring")
    return np.stack([g.at(t)[:, :2] for g in truth], axis=1)


@dataclass(frozen=True)
class TeamTrack:
    """Estimated positions ``(K, n, 2)`` of the scored robots (NaN for others) and covariances."""

    t: Array
    mean: Array
    cov: Array


def run_team(
    rec: Recording, t0: float, t1: float, anchors: list[int], settings: RangeTeamSettings
) -> TeamTrack:
    """The range-only team filter on ``[t0, t1]``; with anchors, only the free robots' beliefs."""
    start = team_start(rec, t0, anchors)
    est = RangeTeamFilter(
        rec.robots, start, settings, anchors=anchors, landmarks=rec.landmarks, start=t0
    )
    grid = record_grid(t0, t1, RECORD_HZ)
    estimates = replay(rec, [est], record_times=grid, start=t0, end=t1)
    n = rec.n_robots
    mean = np.full((grid.size, n, 2), np.nan)
    cov = np.full((grid.size, n, 2, 2), np.nan)
    for s in estimates.beliefs:
        k = np.searchsorted(grid, s.t)
        i = rec.index(s.subject)
        mean[k, i], cov[k, i] = s.mean, s.cov
    return TeamTrack(grid, mean, cov)


def leave_one_out(
    rec: Recording, t0: float, t1: float, anchors: list[int], settings: RangeTeamSettings
) -> TeamTrack:
    """Each robot estimated with every other robot as an anchor, the tracks put together."""
    tracks = [run_team(rec, t0, t1, [a for a in anchors if a != i], settings) for i in anchors]
    out = tracks[0]
    mean, cov = np.array(out.mean), np.array(out.cov)
    for i, tr in zip(anchors, tracks, strict=True):
        mean[:, i], cov[:, i] = tr.mean[:, i], tr.cov[:, i]
    return TeamTrack(out.t, mean, cov)


def _latest_start(
    rec: Recording, ranges: dict[tuple[int, int], float], t: float, fixed_ids: list[int]
) -> Array:
    """Classical MDS of the latest robot–robot ranges, moved onto ``fixed_ids`` (≥ 2)."""
    n = rec.n_robots
    D = np.full((n, n), np.nan)
    np.fill_diagonal(D, 0.0)
    for (a, b), d in ranges.items():
        if b < n:
            D[a, b] = D[b, a] = d
    X = classical_mds(D)
    if len(fixed_ids) >= 2:
        R, tr = rigid_alignment(X[fixed_ids], _anchor_positions(rec, fixed_ids, t), reflection=True)
        X = X @ R.T + tr
    return X


def _multilaterate_at(
    rec: Recording,
    ranges: dict[tuple[int, int], float],
    t: float,
    free: list[int],
    fixed_ids: list[int],
    previous: Array,
) -> Array:
    """Least-squares positions ``(len(free), 2)`` of ``free`` at ``t`` (NaN if unlinked)."""
    n, n_landmarks = rec.n_robots, rec.landmarks.shape[0]
    fixed = np.vstack([_anchor_positions(rec, fixed_ids, t), rec.landmarks[:, :2]])
    index = {r: c for c, r in enumerate(free)}
    index |= {r: len(free) + c for c, r in enumerate(fixed_ids)}
    index |= {n + k: len(free) + len(fixed_ids) + k for k in range(n_landmarks)}
    used = [
        (index[a], index[b], d)
        for (a, b), d in ranges.items()
        if a in index and b in index and (a in free or b in free)
    ]
    if not used:
        return np.full((len(free), 2), np.nan)
    x0 = previous[free]
    if not np.isfinite(x0).all():
        try:
            x0 = _latest_start(rec, ranges, t, fixed_ids)[free]
        except DataError:  # the latest ranges leave a robot unlinked: no solution now
            return np.full((len(free), 2), np.nan)
    pairs = [(a, b) for a, b, _ in used]
    return multilaterate(x0, fixed, pairs, np.array([d for _, _, d in used]))


def multilateration(rec: Recording, grid: Array, anchors: list[int]) -> Array:
    """Raw multilateration at each grid time, from the latest range per link within
    ``LATEST_S`` and no memory beyond the previous solution as the starting guess: the free
    robots given the anchors (each robot given the others when every robot is an anchor; all
    robots up to a rigid motion without anchors). ``(K, n, 2)``."""
    n = rec.n_robots
    if len(anchors) == n:
        groups = [([i], [a for a in anchors if a != i]) for i in range(n)]
    else:
        groups = [([i for i in range(n) if i not in anchors], list(anchors))]
    out = np.full((grid.size, n, 2), np.nan)
    previous = np.full((n, 2), np.nan)
    for k, t in enumerate(grid):
        ranges = latest_ranges(rec, float(t), LATEST_S)
        for free, fixed_ids in groups:
            out[k, free] = _multilaterate_at(rec, ranges, float(t), free, fixed_ids, previous)
        previous = out[k]
    return out


def score_positions(
    grid: Array, est: Array, cov: Array | None, truth: Array, robots: list[int], *, align: bool
) -> dict[str, Any]:
    """Position RMSE (all, per robot), NEES share beyond χ²₂(0.95) with its interval by batch
    means over the grid (:func:`relloc.metrics.consistency.percent_beyond_interval`), convergence
    time; with
    ``align`` after the per-time best rigid alignment of the robots' estimates onto truth."""
    err = np.full((grid.size, len(robots), 2), np.nan)
    nees = np.full((grid.size, len(robots)), np.nan)
    for k in range(grid.size):
        e, g = est[k, robots], truth[k, robots]
        if not np.isfinite(e).all():
            continue
        R = np.eye(2)
        if align:
            R, tr = rigid_alignment(e, g, reflection=True)
            e = e @ R.T + tr
        err[k] = e - g
        if cov is not None:
            for c, r in enumerate(robots):
                P = R @ cov[k, r] @ R.T
                if np.isfinite(P).all():
                    nees[k, c] = float(err[k, c] @ np.linalg.solve(P, err[k, c]))
    norm = np.linalg.norm(err, axis=2)
    ok = np.isfinite(norm).all(axis=1)
    if not ok.any():
        return {"pos_rmse_m": None, "records": 0}
    out: dict[str, Any] = {
        "pos_rmse_m": float(np.sqrt(np.nanmean(norm[ok] ** 2))),
        "records": int(ok.sum()),
    }
    if cov is not None:
        times = np.broadcast_to(grid[:, None], nees.shape)
        share = percent_beyond_interval(nees, times, chi2_threshold(2, 0.95))
        out["nees_pct_beyond"] = share.percent if share.samples else None
        out["nees_beyond_interval"] = share.to_dict()
        above = np.flatnonzero(ok & ~np.all(norm < CONVERGED_M, axis=1))
        records = np.flatnonzero(ok)
        settled = records[records > above[-1]] if above.size else records
        out["converged_after_s"] = (
            float(grid[settled[0]] - grid[records[0]]) if settled.size else None
        )
    return out


def mirrored(track: Array, line: Array) -> Array:
    """Positions ``(K, n, 2)`` reflected across the line through the two points ``line (2, 2)``."""
    p, q = line
    d = (q - p) / np.linalg.norm(q - p)
    rel = track - p
    along = rel @ d
    return np.asarray(p + 2 * along[..., None] * d - rel)


def _best_mirror(
    rec: Recording, track: TeamTrack, anchors: list[int], scored: list[int], t0: float
) -> tuple[TeamTrack, bool]:
    """With exactly two anchors ranges fix the free robots only up to the mirror image in the
    anchors' line: the image closer to motion capture is scored (as the aligned case allows a
    reflection); returns the track and whether the mirror image was taken."""
    if len(anchors) != 2:
        return track, False
    line = _anchor_positions(rec, anchors, t0)
    flip = mirrored(track.mean, line)
    truth = truth_xy(rec, track.t)

    def sq(m: Array) -> float:
        return float(np.nanmean(np.sum((m[:, scored] - truth[:, scored]) ** 2, axis=-1)))

    if sq(flip) >= sq(track.mean):
        return track, False
    d = (line[1] - line[0]) / np.linalg.norm(line[1] - line[0])
    M = 2 * np.outer(d, d) - np.eye(2)
    return TeamTrack(track.t, flip, M @ track.cov @ M.T), True


def _best_mirrors(
    rec: Recording, track: TeamTrack, anchors: list[int], scored: list[int], t0: float
) -> tuple[TeamTrack, bool]:
    """:func:`_best_mirror`; when every robot is an anchor (leave-one-out), each robot's track
    against the line of the others, which is a line when they are two."""
    if len(anchors) != rec.n_robots:
        return _best_mirror(rec, track, anchors, scored, t0)
    mean, cov, flipped = np.array(track.mean), np.array(track.cov), False
    for i in anchors:
        one, taken = _best_mirror(rec, track, [a for a in anchors if a != i], [i], t0)
        mean[:, i], cov[:, i] = one.mean[:, i], one.cov[:, i]
        flipped = flipped or taken
    return TeamTrack(track.t, mean, cov), flipped


def team_case(
    rec: Recording,
    raw: Recording,
    t0: float,
    t1: float,
    anchors: list[int],
    settings: RangeTeamSettings,
    *,
    anchored: bool,
) -> dict[str, Any]:
    """One team case (aligned or anchored): filter on calibrated and raw ranges, and raw
    multilateration, scored alike."""
    n = rec.n_robots
    use = anchors if anchored else []
    if anchored and len(anchors) < 2:
        return {"skipped": f"needs ≥ 2 anchors, the bag has {len(anchors)}"}
    every_anchor = anchored and len(anchors) == n
    runner = leave_one_out if every_anchor else run_team
    scored = (
        list(range(n))
        if every_anchor or not anchored
        else [i for i in range(n) if i not in anchors]
    )
    track, flipped = _best_mirrors(rec, runner(rec, t0, t1, use, settings), use, scored, t0)
    truth = truth_xy(rec, track.t)
    out = score_positions(track.t, track.mean, track.cov, truth, scored, align=not anchored)
    out["per_robot"] = {
        rec.robots[i]: score_positions(track.t, track.mean, track.cov, truth, [i], align=False)[
            "pos_rmse_m"
        ]
        if anchored
        else None
        for i in scored
    }
    if not anchored:
        out.pop("per_robot")
    uncal, _ = _best_mirrors(rec, runner(raw, t0, t1, use, settings), use, scored, t0)
    every = max(1, int(RECORD_HZ // 2))
    lat_t = track.t[::every]
    no_cov = np.full((lat_t.size, n, 2, 2), np.nan)
    lat_track = TeamTrack(lat_t, multilateration(raw, lat_t, use), no_cov)
    lat = _best_mirrors(rec, lat_track, use, scored, t0)[0].mean
    out["baselines"] = {
        "uncalibrated": {
            "pos_rmse_m": score_positions(
                uncal.t, uncal.mean, None, truth, scored, align=not anchored
            )["pos_rmse_m"]
        },
        "multilateration": {
            "pos_rmse_m": score_positions(
                track.t[::every],
                lat,
                None,
                truth[::every],
                scored,
                align=not anchored,
            )["pos_rmse_m"]
        },
    }
    out["anchors"] = [rec.robots[i] for i in use]
    out["mirror_ambiguous"] = len(use) == 2 or (every_anchor and n == 3)
    out["mirror_image_scored"] = flipped
    out["mode"] = "leave-one-out" if every_anchor else ("anchors" if anchored else "aligned")
    return out
