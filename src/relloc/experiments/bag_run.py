"""``relloc run BAG --map MAP.toml``: the main job of ``relloc run`` on a recorded ROS 2 bag.

The bag is read through its mapping (:mod:`relloc.datasets.rosbag`) into a
:class:`~relloc.core.recording.Recording`, whose readings are UWB ``range`` rows, and replayed once
(a recording is one run): every pair of robots
that both report odometry and are linked by UWB ``range`` rows gets seed 000's range-only relative
filter (:class:`~relloc.estimators.uwb_range.RangePairBank`, owner the first robot of the pair in
the mapping) from an unknown start; a pair linked by ranges of which one robot reports no odometry
(fewer than two samples) gets none, and is named with its count of ranges
(``range_pairs_without_odometry``, and a note in report.md and on stderr). No track manager runs
(they take ``range_bearing_elevation`` rows, which no bag mapping yields), so the summary states
no track-manager settings and draws nothing at random (no seed). The run is scored against
the bag's motion capture and written like a scenario's (:mod:`relloc.pipeline.team_report`:
summary.json, report.md, figures), with the loader's report (time offsets, unknown topics, skipped
messages, the UWB readings kept at radio level only: ``uwb_readings_not_in_recording``, also
noted in report.md) under ``loader``. Range rows to a static radio of known position (a landmark)
are used by no filter of this run: they are counted (``range_rows_to_static_radios_not_used``,
and a note in report.md). Ranges are used as recorded (σ from the mapping's ``uwb.sigma`` or
:data:`DEFAULT_RANGE_SIGMA`) and between the robots' origins: the mapping's antenna offsets are not
modelled (a range names only the observer's radio), so where a carried radio has one the largest is
reported (``antenna_offset_not_modelled_m``, and a note in report.md and on stderr); the calibrated
comparison, which uses them, is ``relloc reproduce tiers-uwb``.

Its settings in ``summary.json``: ``experiment`` (``run``), the ``bag`` path, the ``mapping``'s
source, the ``filter`` (``range_pair``) and its ``range_sigma_m``, beside the team report's
``runs`` (1), ``settle_s`` and ``record_rate_hz``.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from relloc.core.checks import number, positive
from relloc.core.recording import Recording, kind_code
from relloc.datasets.bag_mapping import BagMapping
from relloc.datasets.rosbag import load_bag
from relloc.errors import DataError
from relloc.estimators.uwb_range import RangePairBank, RangePairSettings
from relloc.models.motion import VelocityNoise
from relloc.pipeline.export import ExportRequest, export_estimates
from relloc.pipeline.output import bag_rows_source, skipped_rows_line
from relloc.pipeline.replay import replay
from relloc.pipeline.team_report import (
    RECORD_RATE_HZ,
    SETTLE_S,
    score_run,
    summarise,
    write_team_report,
)

#: σ (m) of a UWB range when the mapping states none.
DEFAULT_RANGE_SIGMA = 0.1
_RANGE = kind_code("range")


def range_pairs(recording: Recording, sigma: float) -> tuple[list[RangePairBank], dict[str, int]]:
    """A range-only relative filter per pair with odometry on both robots and a range row,
    and the pairs linked by ranges that get none because a robot has fewer than two odometry
    samples (``"a-b"``
    → their range rows, which nothing uses: the summary says so)."""
    m = recording.measurements
    rows = m.kind == _RANGE
    out, without_odometry = [], {}
    for i in range(recording.n_robots):
        for j in range(i + 1, recording.n_robots):
            linked = rows & (
                ((m.observer == i) & (m.target == j)) | ((m.observer == j) & (m.target == i))
            )
            if not linked.any():
                continue
            if recording.odometry[i].t.size < 2 or recording.odometry[j].t.size < 2:
                pair = f"{recording.robots[i]}-{recording.robots[j]}"
                without_odometry[pair] = int(linked.sum())
                continue
            noise = VelocityNoise.of(recording.odometry[i].sigma, recording.odometry[j].sigma)
            out.append(
                RangePairBank(i, j, recording.robots, noise, RangePairSettings(sigma_range=sigma))
            )
    return out, without_odometry


def landmark_range_rows(recording: Recording) -> int:
    """The ``range`` rows to a static radio of known position (a landmark), which no filter of
    ``relloc run`` uses (the range-only filter is a robot pair's)."""
    m = recording.measurements
    assert m.landmark is not None  # filled in by Measurements
    return int(np.count_nonzero((m.kind == _RANGE) & (m.landmark >= 0)))


def antenna_offset_m(mapping: BagMapping) -> float:
    """The largest distance (m) of a carried radio from its robot's origin (0 without UWB)."""
    if mapping.uwb is None:
        return 0.0
    return max((math.hypot(*n.offset) for n in mapping.uwb.nodes), default=0.0)


def run_bag(
    path: Path,
    mapping: BagMapping,
    out_dir: Path | None = None,
    *,
    settle_s: float = SETTLE_S,
    record_rate_hz: float = RECORD_RATE_HZ,
    export: ExportRequest | None = None,
    plots: bool = True,
) -> tuple[dict[str, Any], list[Path]]:
    """Read, track, score and (with ``out_dir``) write one bag (module docstring), its figures
    unless ``plots`` is false; ``settle_s`` and ``record_rate_hz`` as for a scenario
    (:class:`~relloc.experiments.team_run.TeamRunSettings`); write its estimates as MCAP/TUM
    files if ``export`` asks (:func:`relloc.pipeline.export.export_estimates`). Returns the
    summary and the files written (none without ``out_dir``)."""
    settle_s = number(settle_s, "settle_s", low=0.0)
    record_rate_hz = positive(record_rate_hz, "record_rate_hz")
    bag = load_bag(path, mapping)
    rec = bag.recording
    rec.require_truth(f"relloc run on {path} (scoring against motion capture)")
    sigma = (
        DEFAULT_RANGE_SIGMA
        if mapping.uwb is None or mapping.uwb.sigma is None
        else mapping.uwb.sigma
    )
    estimators, without_odometry = range_pairs(rec, sigma)
    if not estimators:
        raise DataError(
            f"{path}: nothing to track: no two robots with odometry are linked by UWB ranges "
            "(see `relloc bag inspect` and the mapping)"
        )
    offset = antenna_offset_m(mapping)
    notes = []
    if offset > 0:
        notes.append(
            f"The mapping places a radio up to {offset:.3g} m from its robot's origin; this "
            "range filter takes every range between the robots' origins (offsets not modelled)."
        )
    if without_odometry:
        pairs = ", ".join(f"{p} ({n} ranges)" for p, n in without_odometry.items())
        notes.append(
            "Not tracked: robots linked by UWB ranges of which one reports no odometry (fewer "
            f"than two samples): {pairs} "
            "(the range-only filter needs both robots' motion)."
        )
    to_landmarks = landmark_range_rows(rec)
    if to_landmarks:
        notes.append(
            f"Not used: {to_landmarks} UWB ranges to static radios of known position (this run "
            "tracks robot pairs; no filter of it takes a range to a fixed radio)."
        )
    radio_only = bag.radio_only
    if radio_only:
        counts = ", ".join(f"{n} {why}" for why, n in sorted(radio_only.items()))
        notes.append(
            f"Not in the recording: {sum(radio_only.values())} of the bag's "
            f"{bag.ranges.t.size} UWB readings ({counts}), which no filter can use."
        )
    skips = bag.recording.skips
    notes.append(
        skipped_rows_line(skips.n_skipped, skips.skipped_by_reason(), bag_rows_source(radio_only))
    )
    estimates = replay(rec, estimators, record_rate_hz=record_rate_hz)
    result = score_run(estimates, rec, keep_paths=True)
    summary = summarise(
        [result],
        settle_s=settle_s,
        record_rate_hz=record_rate_hz,
        meta={
            "experiment": "run",
            "bag": str(path),
            "mapping": mapping.source,
            "filter": RangePairBank.name,
            "range_sigma_m": sigma,
            "antenna_offset_not_modelled_m": offset,
            "range_pairs_without_odometry": without_odometry,
            "range_rows_to_static_radios_not_used": to_landmarks,
            "loader": bag.to_dict(),
        },
    )
    if export is not None and export.wanted:
        summary["export"] = export_estimates(
            export, estimates, rec, run=f"the bag {path.name}", settle_s=settle_s
        )
    if out_dir is None:
        return summary, []
    files = write_team_report(
        Path(out_dir),
        summary,
        [result],
        title=f"relloc run — {path.name}",
        notes=notes,
        plots=plots,
    )
    return summary, files
