"""UWB localization of a TurtleBot team on real ROS 2 bags (TIERS layouts).

``relloc reproduce tiers-uwb --out DIR [--bag BAG --map MAP] [--calibrate-on BAG]``

Without ``--bag`` both bags of ``../shared/data/tiers`` run with their shipped mappings
(``relloc/datasets/mappings``); with ``--bag`` only that bag, read through ``--map``. Nothing
about a bag is assumed beyond its mapping: robots, radios, anchors, pairs and windows all follow
from the mapping and the data.

What runs on each bag (:func:`analyse_bag`):

(c) **Calibration.** The UWB error model (:func:`relloc.calibration.uwb.fit_uwb_noise`: bias per
    link, spread, outliers, correlation) is fitted on readings whose two radios have known
    positions (motion capture ⊕ antenna offset, or surveyed): on the first
    ``CALIBRATION_FRACTION`` of the bag, or on the whole ``--calibrate-on`` bag (links matched by
    radio names; a link it lacks takes the fitted team bias). Everything below is scored on the
    rest of the bag (the whole bag with ``--calibrate-on``), where the held-out range error
    before and after the correction is reported too.
(b) **Team, ranges only** (:class:`~relloc.estimators.uwb_range.RangeTeamFilter`, constant
    velocity prior): every robot with ground truth, started from the classical-MDS positions of
    the first ``INIT_S`` seconds of ranges, scored (1) *aligned*: at each record time after the
    best rigid alignment of all estimated positions onto motion capture (rotation + translation,
    no scale; reflections allowed, since ranges cannot tell a mirror image), and (2) *anchored*:
    the mapping's ``anchors`` (default: the robots whose motion capture moves less than
    ``STANDING_M`` from where they start) are fixed at their motion-capture start and the others
    estimated in the world frame; when every robot stands, each in turn is estimated with the
    others as anchors (leave-one-out).
(a) **Pairs, range + odometry** (:class:`~relloc.estimators.uwb_range.RangePairBank`): every pair
    of robots that both have odometry, are linked by a range and of which at least one moves by
    its odometry (path length > ``MOVING_M``), from an unknown start; the observability verdict
    per pair comes from relloc's own tool (rank of the observability matrix of the range-only
    seed-000 model along the recorded relative states and inputs,
    :class:`~relloc.observability.analysis.InputRankEvaluator`; and the generic input conditions
    of :func:`~relloc.observability.analysis.analyse`).
(d) **Baselines** side by side: raw multilateration (latest raw range per link within
    ``LATEST_S``, least squares, no memory), uncalibrated ranges (the same filters without the
    bias correction) and, for pairs, odometry alone (both odometries integrated from the true
    relative pose at the start of the scored stretch).

summary.json: ``bags.<name>``: ``loader`` (offsets header → bag time, unknown topics, skips),
``calibration`` (``window`` or ``bag``, the fit, ``heldout`` range errors raw and corrected),
``scored_window_s``, ``team.aligned`` and ``team.anchored`` (``pos_rmse_m``,
``nees_pct_beyond``: share of record times whose 2-DOF NEES exceeds χ²₂(0.95) — one run, so a
description, not a test —, ``converged_after_s``, ``per_robot``, ``baselines``), ``pairs.<a->b>``
(the same keys in the owner's body frame, ``observability``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from relloc.calibration.inflation import gauss_markov_inflation
from relloc.calibration.uwb import UwbNoiseFit, fit_uwb_noise, link_masks
from relloc.calibration.window import CalibrationWindow, leading_fraction, spanning
from relloc.core.kalman import chi2_threshold
from relloc.core.recording import FileSkips, Measurements, Recording
from relloc.datasets.bag_mapping import BagMapping, load_mapping
from relloc.datasets.paths import shared_data_dir
from relloc.datasets.rosbag import BagRecording, load_bag
from relloc.datasets.uwb import UwbRecording
from relloc.errors import ConfigError, DataError
from relloc.estimators.uwb_range import (
    RangePairBank,
    RangePairSettings,
    RangeTeamFilter,
    RangeTeamSettings,
    RelativeDeadReckoning,
)
from relloc.experiments.registry import ReproduceArgs
from relloc.geometry.multilateration import classical_mds, multilaterate, rigid_alignment
from relloc.models.motion import VelocityNoise
from relloc.models.symbolic import relative_nonlinear
from relloc.observability.analysis import InputRankEvaluator, analyse
from relloc.pipeline.evaluation import SeriesEvaluation, convergence_time, evaluate
from relloc.pipeline.output import markdown_table, prepare_out_dir, write_report, write_summary
from relloc.pipeline.replay import record_grid, replay

Array = NDArray[np.float64]

#: Share of a bag, from its start, the UWB error model is fitted on (when not --calibrate-on).
CALIBRATION_FRACTION = 0.3
#: Seconds of ranges whose per-link medians give the team's start (classical MDS).
INIT_S = 1.0
#: A robot whose motion capture stays within this distance (m) of its start is standing.
STANDING_M = 0.1
#: A robot whose odometry path is longer than this (m) moves.
MOVING_M = 0.2
#: Multilateration uses the latest raw range per link not older than this (s).
LATEST_S = 1.0
#: Position error (m) (and relative-yaw error, rad) below which an estimate counts as converged.
CONVERGED_M = 0.3
CONVERGED_YAW = 0.5
#: Beliefs are recorded (and scored) at this rate.
RECORD_HZ = 10.0
#: Observability is checked at this many instants of the scored stretch.
OBSERVABILITY_SAMPLES = 40
SHIPPED = (
    ("cooperative_shortbag", "tiers_cooperative"),
    ("relative_case4_test1", "tiers_relative"),
)


# ----------------------------------------------------------------------------------------------
# Calibration (c)
# ----------------------------------------------------------------------------------------------


def as_uwb_recording(bag: BagRecording) -> UwbRecording:
    """The readings whose two radios have known positions, with the true distance beside each
    (motion capture ⊕ offsets, 3-D), as the calibration's :class:`UwbRecording` (radio indices
    as node ids)."""
    r = bag.ranges
    true = np.full(r.t.size, np.nan)
    for a, b in r.links():
        m = r.link_mask(a, b)
        pa, pb = bag.node_truth(a, r.t[m]), bag.node_truth(b, r.t[m])
        true[m] = np.linalg.norm(pa - pb, axis=1)
    ok = np.isfinite(true) & (true > 0)
    if not ok.any():
        raise DataError(f"{bag.path}: no UWB reading between radios of known position to calibrate")
    return UwbRecording(
        path=bag.path,
        t=r.t[ok],
        node1=r.node_a[ok],
        node2=r.node_b[ok],
        uwb_range=r.value[ok],
        mocap_range=true[ok],
        data_rows=int(r.t.size),
        skipped=FileSkips(file=str(bag.path), rows_read=int(r.t.size), rows_kept=int(ok.sum())),
    )


def _names(bag: BagRecording, a: int, b: int) -> tuple[str, str]:
    assert bag.mapping.uwb is not None
    na, nb = bag.mapping.uwb.nodes[a].name, bag.mapping.uwb.nodes[b].name
    return (na, nb) if na <= nb else (nb, na)


@dataclass(frozen=True)
class Calibration:
    """The fit, the bag it came from, the bias per radio-name link, how much a link's bias
    moves within the window (``bias_drift``, m) and the σ the filters give one range."""

    fit: UwbNoiseFit
    source: str
    link_bias: dict[tuple[str, str], float]
    bias_drift: float
    range_sigma: float

    def bias(self, link: tuple[str, str]) -> float:
        return self.link_bias.get(link, self.fit.model.bias)


def bias_drift(rec: UwbRecording, window: CalibrationWindow) -> float:
    """How far a link's bias moves within ``window``: the RMS over the fitted links of the
    difference between the median errors of the window's two halves, divided by √2 (the σ of
    one half's median about the bias, if both halves are alike)."""
    mid = 0.5 * (window.start_s + window.end_s)
    diffs = []
    for mask in link_masks(rec, window).values():
        first, second = mask & (rec.t <= mid), mask & (rec.t > mid)
        if first.any() and second.any():
            diffs.append(float(np.median(rec.error[first]) - np.median(rec.error[second])))
    return float(np.sqrt(np.mean(np.square(diffs)) / 2.0)) if diffs else 0.0


def calibrate(bag: BagRecording, window: CalibrationWindow) -> Calibration:
    """Fit the UWB error model on ``bag`` inside ``window``, and the σ of one corrected range
    for the filters: ``σ² = f·spread² + drift²`` with ``f`` the Gauss–Markov variance
    inflation of the fitted correlation time at the fitted sampling period
    (:func:`~relloc.calibration.inflation.gauss_markov_inflation`: consecutive errors are far
    from independent) and ``drift`` the bias drift within the window (:func:`bias_drift`)."""
    rec = as_uwb_recording(bag)
    fit = fit_uwb_noise(rec, window)
    links: dict[tuple[str, str], float] = {}
    for key, value in fit.link_biases.items():
        a, b = (int(v) for v in key.split("-"))
        links[_names(bag, a, b)] = value
    m = fit.model
    inflation = (
        gauss_markov_inflation(fit.sample_period, m.correlation_time)
        if fit.sample_period > 0
        else 1.0
    )
    drift = bias_drift(rec, window)
    sigma = max(math.sqrt(inflation * m.spread**2 + drift**2), 1e-3)
    return Calibration(
        fit=fit, source=str(bag.path), link_bias=links, bias_drift=drift, range_sigma=sigma
    )


def heldout_errors(bag: BagRecording, cal: Calibration, t0: float, t1: float) -> dict[str, Any]:
    """Range error (reading − true distance) on ``[t0, t1]`` before and after the correction."""
    rec = as_uwb_recording(bag)
    inside = (rec.t >= t0) & (rec.t <= t1)
    if not inside.any():
        return {"rows": 0}
    bias = np.array(
        [
            cal.bias(_names(bag, int(a), int(b)))
            for a, b in zip(rec.node1[inside], rec.node2[inside], strict=True)
        ]
    )
    raw = rec.error[inside]
    fixed = raw - bias

    def stats(e: Array) -> dict[str, float]:
        return {
            "mean_m": float(np.mean(e)),
            "std_m": float(np.std(e)),
            "rmse_m": float(np.sqrt(np.mean(e**2))),
        }

    return {"rows": int(inside.sum()), "raw": stats(raw), "calibrated": stats(fixed)}


def row_links(bag: BagRecording) -> list[tuple[str, str] | None]:
    """The radio-name link of each ``range`` row of the recording (``None`` if the target
    robot carries several radios, so the row does not say which)."""
    m, mapping = bag.recording.measurements, bag.mapping
    assert mapping.uwb is not None and m.sensor is not None and m.landmark is not None
    nodes = mapping.uwb.nodes
    on_robot: dict[int, list[int]] = {}
    for k, n in enumerate(nodes):
        if n.robot is not None:
            on_robot.setdefault(mapping.robot_index(n.robot), []).append(k)
    static = [k for k, n in enumerate(nodes) if n.robot is None and n.position is not None]
    out: list[tuple[str, str] | None] = []
    for q in range(m.size):
        a = on_robot[int(m.observer[q])][int(m.sensor[q])]
        if m.target[q] >= 0:
            targets = on_robot[int(m.target[q])]
            if len(targets) != 1:
                out.append(None)
                continue
            b = targets[0]
        else:
            b = static[int(m.landmark[q])]
        out.append(_names(bag, a, b))
    return out


def corrected(bag: BagRecording, cal: Calibration | None, sigma: float) -> Recording:
    """The recording with every range corrected by its link's bias (none if ``cal`` is None)
    and the stated σ set to ``sigma``."""
    m = bag.recording.measurements
    value = np.array(m.value, copy=True)
    if cal is not None:
        bias = np.array([cal.bias(k) if k else cal.fit.model.bias for k in row_links(bag)])
        value[:, 0] = np.maximum(value[:, 0] - bias, 0.01)
    s = np.array(m.sigma, copy=True)
    s[:, 0] = sigma
    rows = Measurements(
        t=m.t,
        kind=m.kind,
        observer=m.observer,
        target=m.target,
        value=value,
        sigma=s,
        landmark=m.landmark,
        origin=m.origin,
        sensor=m.sensor,
    )
    return replace(bag.recording, measurements=rows)


# ----------------------------------------------------------------------------------------------
# Team (b) and multilateration (d)
# ----------------------------------------------------------------------------------------------


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
    """Position RMSE (all, per robot), NEES share beyond χ²₂(0.95), convergence time; with
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
        finite = np.isfinite(nees)
        out["nees_pct_beyond"] = (
            float(100 * np.mean(nees[finite] > chi2_threshold(2, 0.95))) if finite.any() else None
        )
        above = np.flatnonzero(ok & ~np.all(norm < CONVERGED_M, axis=1))
        last = int(above[-1]) if above.size else -1
        out["converged_after_s"] = (
            None if last == grid.size - 1 else float(grid[last + 1] - grid[0]) if last >= 0 else 0.0
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
    track, flipped = _best_mirror(rec, runner(rec, t0, t1, use, settings), use, scored, t0)
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
    uncal, _ = _best_mirror(rec, runner(raw, t0, t1, use, settings), use, scored, t0)
    every = max(1, int(RECORD_HZ // 2))
    lat_t = track.t[::every]
    no_cov = np.full((lat_t.size, n, 2, 2), np.nan)
    lat_track = TeamTrack(lat_t, multilateration(raw, lat_t, use), no_cov)
    lat = _best_mirror(rec, lat_track, use, scored, t0)[0].mean
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
    out["mirror_ambiguous"] = len(use) == 2
    out["mirror_image_scored"] = flipped
    out["mode"] = "leave-one-out" if every_anchor else ("anchors" if anchored else "aligned")
    return out


# ----------------------------------------------------------------------------------------------
# Pairs (a) with observability
# ----------------------------------------------------------------------------------------------


def moving_pairs(rec: Recording) -> list[tuple[int, int]]:
    """Pairs with odometry on both robots, a range between them, and one moving by odometry."""
    m = rec.measurements
    has_odo = [od.t.size >= 2 for od in rec.odometry]
    path = [
        float(np.sum(np.linalg.norm(od.velocity[:-1, :3], axis=1) * np.diff(od.t)))
        if od.t.size >= 2
        else 0.0
        for od in rec.odometry
    ]
    out = []
    for i in range(rec.n_robots):
        for j in range(i + 1, rec.n_robots):
            linked = bool(
                (
                    ((m.observer == i) & (m.target == j)) | ((m.observer == j) & (m.target == i))
                ).any()
            )
            if has_odo[i] and has_odo[j] and linked and max(path[i], path[j]) > MOVING_M:
                out.append((i, j))
    return out


def observability(rec: Recording, i: int, j: int, t0: float, t1: float) -> dict[str, Any]:
    """Rank of the range-only seed-000 model along the recorded relative states and inputs."""
    evaluator = _range_pair_rank()
    model = evaluator.model
    t = np.linspace(t0, t1, OBSERVABILITY_SAMPLES)
    states = rec.relative_truth(i, j, t)
    u = np.hstack([rec.odometry[i].held_at(t), rec.odometry[j].held_at(t)])
    ranks = np.array([evaluator.rank(states[k], u[k]) for k in range(t.size)])
    full = float(np.mean(ranks == model.n))
    generic = _generic_conditions()
    if full == 1.0:
        verdict = "observable along the whole stretch"
    elif full > 0.0:
        verdict = f"observable at {100 * full:.0f} % of the sampled instants"
    else:
        verdict = f"unobservable along this stretch (rank ≤ {int(ranks.max())} of {model.n})"
    return {
        "verdict": verdict,
        "full_rank_share": full,
        "max_rank": int(ranks.max()),
        "state_dim": model.n,
        "samples": int(t.size),
        "generic_conditions": generic,
    }


@lru_cache(maxsize=1)
def _range_pair_rank() -> InputRankEvaluator:
    """The rank evaluator of the range-only seed-000 pair (built once per process)."""
    return InputRankEvaluator.build(relative_nonlinear(("range",)))


@lru_cache(maxsize=1)
def _generic_conditions() -> str:
    """The generic rank and input conditions of the range-only pair (once per process)."""
    result = analyse(relative_nonlinear(("range",)), order=3, samples=3, directions="none")
    return f"generic rank {result.rank} of {result.state_dim}; {result.conditions_text()}"


def _pair_score(ev: SeriesEvaluation) -> dict[str, Any]:
    pos = np.linalg.norm(ev.error[:, :3], axis=1)
    finite = np.isfinite(ev.nees)
    return {
        "pos_rmse_m": float(np.sqrt(np.mean(pos**2))) if pos.size else None,
        "nees_pct_beyond": float(100 * np.mean(ev.nees[finite] > chi2_threshold(4, 0.95)))
        if finite.any()
        else None,
        "converged_after_s": convergence_time(ev, [CONVERGED_M] * 3 + [CONVERGED_YAW]),
        "records": int(ev.t.size),
    }


def pair_case(
    rec: Recording, raw: Recording, i: int, j: int, t0: float, t1: float, sigma: float
) -> dict[str, Any]:
    """Range + odometry pair from an unknown start, with its baselines and observability."""
    sig = [tuple(rec.odometry[k].sigma.tolist()) for k in (i, j)]
    noise = VelocityNoise(observer=sig[0], observed=sig[1])  # type: ignore[arg-type]
    settings = RangePairSettings(sigma_range=sigma)
    grid = record_grid(t0, t1, RECORD_HZ)

    def score(recording: Recording, est: Any) -> dict[str, Any]:
        estimates = replay(recording, [est], record_times=grid, start=t0, end=t1)
        evs = evaluate(estimates, recording)
        return _pair_score(evs[0]) if evs else {"pos_rmse_m": None, "records": 0}

    out = score(rec, RangePairBank(i, j, rec.robots, noise, settings))
    truth0 = rec.relative_truth(i, j, t0)[0]
    dead = RelativeDeadReckoning(i, j, rec.robots, noise, (t0, truth0, np.eye(4) * 1e-4))
    out["baselines"] = {
        "uncalibrated": {
            "pos_rmse_m": score(raw, RangePairBank(i, j, rec.robots, noise, settings))["pos_rmse_m"]
        },
        "odometry_alone": {"pos_rmse_m": score(rec, dead)["pos_rmse_m"]},
    }
    out["observability"] = observability(rec, i, j, t0, t1)
    return out


# ----------------------------------------------------------------------------------------------
# One bag, the experiment
# ----------------------------------------------------------------------------------------------


def analyse_bag(bag: BagRecording, calibration_bag: BagRecording | None) -> dict[str, Any]:
    """Everything of the module docstring on one bag."""
    rec = bag.recording
    span0, span1 = rec.span
    if calibration_bag is None:
        window = leading_fraction(span0, span1, CALIBRATION_FRACTION, str(bag.path))
        cal = calibrate(bag, window)
        t0 = window.end_s
        cal_info: dict[str, Any] = {"source": "window", "window": window.to_dict()}
    else:
        window = spanning(calibration_bag.ranges.t, str(calibration_bag.path))
        cal = calibrate(calibration_bag, window)
        t0 = span0
        cal_info = {"source": "bag", "bag": str(calibration_bag.path), "window": window.to_dict()}
    cal_info["fit"] = cal.fit.to_dict()
    cal_info["link_bias_m"] = {f"{a}-{b}": v for (a, b), v in sorted(cal.link_bias.items())}
    cal_info["heldout"] = heldout_errors(bag, cal, t0, span1)
    cal_info["bias_drift_m"] = cal.bias_drift
    cal_info["range_sigma_m"] = cal.range_sigma
    sigma = cal.range_sigma
    fixed = corrected(bag, cal, sigma)
    raw = corrected(bag, None, sigma)
    team_settings = RangeTeamSettings(sigma_range=sigma)
    anchors = standing_robots(rec, bag.mapping)
    team = {
        "aligned": team_case(fixed, raw, t0, span1, anchors, team_settings, anchored=False),
        "anchored": team_case(fixed, raw, t0, span1, anchors, team_settings, anchored=True),
    }
    pairs = {
        f"{rec.robots[i]}->{rec.robots[j]}": pair_case(fixed, raw, i, j, t0, span1, sigma)
        for i, j in moving_pairs(rec)
    }
    return {
        "loader": bag.to_dict(),
        "calibration": cal_info,
        "scored_window_s": [t0, span1],
        "team": team,
        "pairs": pairs,
    }


def _bags(args: ReproduceArgs) -> list[tuple[Path, BagMapping]]:
    if args.bag is not None:
        if args.map is None:
            raise ConfigError("--bag needs --map (the bag's topic mapping TOML)")
        return [(args.bag, load_mapping(args.map))]
    if args.map is not None:
        raise ConfigError("--map needs --bag")
    folder = shared_data_dir() / "tiers"
    if not folder.is_dir():
        raise DataError(
            f"{folder}: the TIERS bags are not there; pass --bag BAG --map MAP or point "
            "RELLOC_SHARED_DATA at the shared data folder"
        )
    return [(folder / name, load_mapping(mapping)) for name, mapping in SHIPPED]


def reproduce(args: ReproduceArgs) -> dict[str, Any]:
    out_dir = prepare_out_dir(args.out_dir)
    summary: dict[str, Any] = {"experiment": "tiers-uwb", "seed": None, "runs": 1, "bags": {}}
    bags = _bags(args)
    for path, mapping in bags:
        calibration_bag = None
        if args.calibrate_on is not None:
            if args.calibrate_on.resolve() == path.resolve():
                raise ConfigError(
                    f"--calibrate-on {args.calibrate_on}: that is the bag being scored; a fit "
                    "must be scored on data it was not fitted on (leave --calibrate-on out to "
                    f"fit on the first {CALIBRATION_FRACTION:.0%} of the bag)"
                )
            calibration_bag = load_bag(args.calibrate_on, mapping)
        summary["bags"][path.name] = analyse_bag(load_bag(path, mapping), calibration_bag)
    write_summary(out_dir, summary)
    write_report(out_dir, report(summary))
    return summary


def _f(x: Any) -> Any:
    return "—" if x is None or (isinstance(x, float) and not math.isfinite(x)) else x


def report(summary: dict[str, Any]) -> str:
    """report.md: per bag the calibration, the team table and the pair table."""
    lines = ["# tiers-uwb: UWB localization on real ROS 2 bags", ""]
    for name, b in summary["bags"].items():
        cal = b["calibration"]
        fit = cal["fit"]
        w = cal["window"]
        lines += [
            f"## {name}",
            "",
            f"Calibrated on {cal['source']} `{w['source']}` "
            f"[{w['start_s']:.1f}, {w['end_s']:.1f}] s: bias {fit['bias_m']:.3f} m, "
            f"spread {fit['spread_m']:.3f} m, link-bias std "
            f"{fit['link_bias_std_m']:.3f} m, outliers {100 * fit['outlier_rate']:.1f} %, "
            f"correlation time {fit['correlation_time_s']:.2f} s, bias drift "
            f"{cal['bias_drift_m']:.3f} m → σ of one range in the filters "
            f"{cal['range_sigma_m']:.3f} m. "
            f"Scored on [{b['scored_window_s'][0]:.1f}, {b['scored_window_s'][1]:.1f}] s.",
            "",
        ]
        h = cal["heldout"]
        if h.get("rows"):
            lines += [
                f"Held-out range error ({h['rows']} readings): raw mean {h['raw']['mean_m']:.3f} m "
                f"/ RMSE {h['raw']['rmse_m']:.3f} m → calibrated mean "
                f"{h['calibrated']['mean_m']:.3f} m / RMSE {h['calibrated']['rmse_m']:.3f} m.",
                "",
            ]
        rows = []
        for case, t in b["team"].items():
            if "skipped" in t:
                rows.append([f"team {case}", "—", "—", "—", "—", "—", t["skipped"]])
                continue
            bl = t["baselines"]
            rows.append(
                [
                    f"team {case} ({t['mode']})",
                    _f(t["pos_rmse_m"]),
                    _f(t.get("nees_pct_beyond")),
                    _f(t.get("converged_after_s")),
                    _f(bl["uncalibrated"]["pos_rmse_m"]),
                    _f(bl["multilateration"]["pos_rmse_m"]),
                    ", ".join(t["anchors"]) or "—",
                ]
            )
        lines += [
            markdown_table(
                [
                    "case",
                    "pos RMSE (m)",
                    "NEES % > χ²₂(.95)",
                    "converged after (s)",
                    "uncalibrated RMSE (m)",
                    "multilateration RMSE (m)",
                    "anchors",
                ],
                rows,
                3,
            ),
            "",
        ]
        if b["pairs"]:
            prow = []
            for label, p in b["pairs"].items():
                prow.append(
                    [
                        label,
                        _f(p["pos_rmse_m"]),
                        _f(p["nees_pct_beyond"]),
                        _f(p["converged_after_s"]),
                        _f(p["baselines"]["uncalibrated"]["pos_rmse_m"]),
                        _f(p["baselines"]["odometry_alone"]["pos_rmse_m"]),
                        p["observability"]["verdict"],
                    ]
                )
            lines += [
                markdown_table(
                    [
                        "pair (owner frame)",
                        "pos RMSE (m)",
                        "NEES % > χ²₄(.95)",
                        "converged after (s)",
                        "uncalibrated RMSE (m)",
                        "odometry alone RMSE (m)",
                        "observability",
                    ],
                    prow,
                    3,
                ),
                "",
            ]
        else:
            lines += ["No pair with odometry on both robots and one of them moving.", ""]
        skipped = b["loader"]["skips"]["by_reason"]
        lines += [
            f"Loader: header → bag time offset {b['loader']['stamp_offset_s']['bag']:.3f} s; "
            f"unknown topics: {len(b['loader']['unknown_topics'])}; skipped/folded messages by "
            f"reason: {skipped or 'none'}.",
            "",
        ]
    lines += [
        "RMSE over every record of the scored stretch (10 Hz), start transient included. NEES "
        "shares pool the records of one run, which are correlated in time: a description of "
        "consistency, not a statistical test.",
    ]
    return "\n".join(lines) + "\n"
