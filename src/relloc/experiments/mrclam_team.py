"""``relloc team up MRCLAM_DIR --estimator cooperative --out DIR``: seed 001's cooperative
localization of a recorded team (any MRCLAM-layout folder), every robot its own process.

The team is that of ``relloc reproduce mrclam-cl``
(:mod:`relloc.experiments.mrclam_cl`): the odometry and camera error models are fitted on the
first half of the run (the launcher fits them once and hands every robot the fitted values in
``<out>/fit.json``: fitting is deterministic, so this only saves each robot the fit), the
recording is calibrated with them and robot 1 gets its GPS-like fixes (seed ``--seed``). Every
robot shares its odometry and its readings and runs the team EIF of one case
(``--case MODE/ANCHORS``, default ``range_bearing/2_landmarks``; ``--fit FILE`` reuses the
``fit.json`` of an earlier run instead of fitting again) from the first common
ground-truth time for ``--duration`` seconds, recording every robot's pose every 0.5 s; the
in-process reference is that case's filter replayed over the same window. Scoring and tolerance
as :mod:`relloc.experiments.sharma2013_team` (each agent against the in-process EIF; the cost of
what a faulty network lost). ``load_report`` (summary.json, and a line in report.md) counts the rows
the loader and the conversion to a recording skipped, by reason, as mrclam-cl's does.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from relloc.calibration.window import leading_fraction
from relloc.core.estimates import Estimates
from relloc.errors import ConfigError
from relloc.estimators.cooperative import CooperativeEstimator, CooperativeSettings
from relloc.experiments.fit_file import check_fit_for, load_fit, save_fit
from relloc.experiments.mrclam_cl import (
    ANCHORS,
    MODES,
    OUTPUT_DT_S,
    FittedModels,
    Prepared,
    build_recording,
    case_settings,
    fit_models,
    load_report_line,
)
from relloc.experiments.sharma2013_team import (
    accuracy,
    agents_summary,
    compare_agents,
    fault_phases,
    rejoined,
    report_markdown,
)
from relloc.pipeline.output import prepare_out_dir, write_report, write_summary
from relloc.pipeline.replay import replay
from relloc.runtime.estimation import WindowDriver, grid_record_times
from relloc.runtime.launcher import ProcessTeam, TeamLauncher
from relloc.runtime.node import NodeParts
from relloc.runtime.outcomes import outcomes_of
from relloc.runtime.sources import RecordingSource
from relloc.runtime.summary import assemble_estimates, robot_messages

FIT_FILE = "fit.json"
DEFAULT_CASE = "range_bearing/2_landmarks"
CHECKPOINT_WINDOWS = 50


def fit_dataset(folder: Path) -> tuple[Any, FittedModels]:
    """The dataset and the models fitted on the first half of its run (as mrclam-cl)."""
    from relloc.datasets.mrclam import load_mrclam

    ds = load_mrclam(folder)
    t0 = ds.truth_span[0]
    window = leading_fraction(t0, ds.truth_end, 0.5, str(folder))
    return ds, fit_models(ds, window)


def checked_fit(path: Path, ds: Any) -> FittedModels:
    """The models of the fit file ``path``, checked to be of the team of the dataset ``ds``."""
    fit = load_fit(path)
    check_fit_for(fit, len(ds.robot_ids), (ds.truth_span[0], ds.truth_end), f"{path}: ")
    return fit


def parse_case(case: str) -> tuple[str, str]:
    """``MODE/ANCHORS`` of :data:`relloc.experiments.mrclam_cl.MODES` and ``ANCHORS``."""
    mode, _, anchors = case.partition("/") if isinstance(case, str) else ("", "", "")
    if mode not in MODES or anchors not in ANCHORS:
        raise ConfigError(
            f"--case: {case!r} is not MODE/ANCHORS with MODE in {MODES}, ANCHORS in {ANCHORS}"
        )
    return mode, anchors


def prepared_team(
    ds: Any, fit: FittedModels, seed: int, case: str
) -> tuple[Prepared, CooperativeSettings]:
    """The calibrated recording and the case's filter settings."""
    prepared = build_recording(ds, fit, np.random.default_rng(seed))
    mode, anchors = parse_case(case)
    n_lm = prepared.recording.landmarks.shape[0]
    return prepared, case_settings(mode, anchors, fit, prepared.two_landmarks, n_lm)


def load_report(prepared: Prepared) -> dict[str, Any]:
    """The rows of the dataset's files that the loader and the conversion skipped (as
    mrclam-cl's ``load_report``)."""
    skips = prepared.recording.skips
    return {"n_skipped": skips.n_skipped, "by_reason": skips.skipped_by_reason()}


def window_end(prepared: Prepared, duration_s: float | None) -> float:
    """The last record time of the run: ``duration_s`` after the start (default: all)."""
    out_t = prepared.out_t
    if duration_s is not None:
        out_t = out_t[out_t <= prepared.t_start + duration_s + 1e-9]
    if out_t.size < 2:
        raise ConfigError(f"--duration: {duration_s} s holds no record time after the start")
    return float(out_t[-1])


def cooperative_node_parts(
    folder: str, robot: str, seed: int, fit_path: Path, duration_s: float | None, case: str
) -> NodeParts:
    """Agent ``robot`` of the recorded team (module docstring)."""
    from relloc.datasets.mrclam import load_mrclam

    ds = load_mrclam(folder)
    prepared, settings = prepared_team(ds, checked_fit(fit_path, ds), seed, case)
    rec = prepared.recording
    if robot not in rec.robots:
        raise ConfigError(f"--robot: {robot!r} is not in {folder} {rec.robots}")
    estimator = CooperativeEstimator(rec.robots, prepared.prior, settings, rec.landmarks)
    driver = WindowDriver(
        estimator,
        rec.robots,
        robot,
        record_times=grid_record_times(1.0 / OUTPUT_DT_S, prepared.t_start),
        checkpoint_windows=CHECKPOINT_WINDOWS,
        start=prepared.t_start,
    )
    del duration_s  # the clock ends the run
    source = RecordingSource(rec, robot, all_readings=True)
    return NodeParts(rec.robots, source, driver, share_rows=True, recording=rec)


def in_process(prepared: Prepared, settings: CooperativeSettings, end: float) -> Estimates:
    """The case's team EIF over ``[t_start, end]`` (as mrclam-cl's ``run_filter``)."""
    rec = prepared.recording
    out_t = prepared.out_t[prepared.out_t <= end + 1e-9]
    estimator = CooperativeEstimator(rec.robots, prepared.prior, settings, rec.landmarks)
    return replay(rec, [estimator], record_times=out_t, start=prepared.t_start, end=end)


@dataclass(frozen=True, kw_only=True)
class MrclamTeamSettings(ProcessTeam):
    """One ``team up MRCLAM_DIR --estimator cooperative`` invocation."""

    folder: Path
    out_dir: Path
    seed: int = 0
    duration_s: float | None = None
    case: str = DEFAULT_CASE
    wall_timeout_s: float = 600.0
    fit_path: Path | None = None
    """Models fitted before (a ``fit.json`` of an earlier run): used instead of fitting."""


def run_mrclam_team(s: MrclamTeamSettings) -> dict[str, Any]:
    """Fit, run the team, compare every agent with the in-process EIF, write the outputs."""
    out = prepare_out_dir(s.out_dir)
    parse_case(s.case)
    start = time.monotonic()
    if s.fit_path is None:
        ds, fit = fit_dataset(s.folder)
    else:
        from relloc.datasets.mrclam import load_mrclam

        ds = load_mrclam(s.folder)
        fit = checked_fit(s.fit_path, ds)
    save_fit(fit, out / FIT_FILE)
    prepared, settings = prepared_team(ds, fit, s.seed, s.case)
    rec = prepared.recording
    end = window_end(prepared, s.duration_s)
    team = s.launch(
        scenario=str(s.folder),
        out_dir=out / "run0",
        seed=s.seed,
        preload=("relloc.experiments.mrclam_team", "relloc.estimators.cooperative"),
        node_args=("--estimator", "cooperative", "--fit", str(out / FIT_FILE), "--case", s.case),
    )
    # the clock's last tick at or after the last record time (nodes filter whole ticks)
    ticks = int(np.ceil(end / s.tick_s - 1e-9))
    collected = TeamLauncher(team, rec.robots, ticks * s.tick_s).run()
    got = assemble_estimates(collected, rec.robots, "eif")
    ref = in_process(prepared, settings, end)
    run = {
        "run": 0,
        "fault_outcomes": outcomes_of(s.faults, got, rec),
        "fault_phases": fault_phases(s.faults, got, ref, rec),
        "rejoined": rejoined(s.faults, got, collected, rec),
        "wall_s": collected.wall_s,
        "window_s": [prepared.t_start, end],
        "in_process": accuracy(ref, rec),
        "agents": compare_agents(got, ref, rec, collected),
        "messages": robot_messages(collected, rec.robots),
        "collector_rejected_by_reason": dict(collected.rejected_by_reason),
        "exit_codes": collected.exit_codes,
    }
    summary = agents_summary([run], s.faults) | {
        "experiment": f"cooperative on {s.folder}",
        "secure": s.secure,
        "case": s.case,
        "seed": s.seed,
        "runs": 1,
        "fit": fit.to_dict(),
        "load_report": load_report(prepared),
        "per_run": [run],
        "wall_s": time.monotonic() - start,
    }
    write_summary(out, summary)
    write_report(
        out, report_markdown(summary) + "\n\n" + load_report_line(summary["load_report"]) + "\n"
    )
    return summary
