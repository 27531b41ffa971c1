"""Run a team scenario end to end: simulate → track every observed robot → score → report.

This is the library behind ``relloc run``. One Monte-Carlo run (:func:`team_task`) simulates
the scenario with its own random stream, tracks every robot each observing robot sees
(:func:`relloc.pipeline.team_report.track_team`: one
:class:`~relloc.estimators.track_manager.TrackManager` per observer, through
:func:`relloc.pipeline.replay.replay`) and scores the run
(:func:`relloc.pipeline.team_report.score_run`). :func:`run_scenario` pools the runs into
``summary.json`` and writes ``report.md`` with figures (keys: :mod:`relloc.pipeline.team_report`);
with ``--mcap``/``--tum`` it also writes run 0's estimates for ROS tools and evo
(:func:`export_run0`; the summary's ``export`` section: :mod:`relloc.pipeline.export`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from relloc.core.checks import number, positive
from relloc.core.estimates import Estimates
from relloc.core.recording import Recording
from relloc.errors import ConfigError
from relloc.estimators.track_manager import TrackManagerSettings, default_tracker
from relloc.pipeline.export import ExportRequest, export_estimates
from relloc.pipeline.montecarlo import MAX_RUNS, run_monte_carlo, spawn_seeds
from relloc.pipeline.team_report import (
    RECORD_RATE_HZ,
    SETTLE_S,
    RunResult,
    scenario_meta,
    score_run,
    summarise,
    track_team,
    write_team_report,
)
from relloc.sim.scenario import Scenario
from relloc.sim.simulate import simulate


@dataclass(frozen=True, kw_only=True)
class TeamRunSettings:
    """How ``relloc run`` runs a scenario.

    ``runs`` Monte-Carlo runs from master ``seed``; ``tracker`` the filter, initialisation,
    yaw bank and keep window (:func:`default_tracker`; the CLI's defaults are these);
    ``settle_s`` the track age after which samples count as steady state;
    ``record_rate_hz`` how often beliefs are recorded; ``executor`` as in
    :func:`relloc.pipeline.montecarlo.run_monte_carlo`.
    """

    runs: int = 10
    seed: int = 2026
    tracker: TrackManagerSettings = field(default_factory=default_tracker)
    settle_s: float = SETTLE_S
    record_rate_hz: float = RECORD_RATE_HZ
    executor: str | None = None
    quiet: bool = False

    def __post_init__(self) -> None:
        if (
            isinstance(self.runs, bool)
            or not isinstance(self.runs, int)
            or not 1 <= self.runs <= MAX_RUNS
        ):
            raise ConfigError(f"--runs: must be an integer in 1…{MAX_RUNS}, got {self.runs!r}")
        if isinstance(self.seed, bool) or not isinstance(self.seed, int) or self.seed < 0:
            raise ConfigError(f"--seed: must be an integer ≥ 0, got {self.seed!r}")
        number(self.settle_s, "settle_s", low=0.0)
        positive(self.record_rate_hz, "record_rate_hz")


def simulate_and_track(
    seed_sequence: np.random.SeedSequence,
    scenario: Scenario,
    tracker: TrackManagerSettings,
    record_rate_hz: float,
) -> tuple[Estimates, Recording]:
    """One run's recording and every observer's tracks of it (streams from ``seed_sequence``)."""
    sim_seed, init_seed = seed_sequence.spawn(2)
    recording = simulate(scenario, np.random.default_rng(sim_seed))
    estimates = track_team(
        recording, tracker, record_rate_hz=record_rate_hz, rng=np.random.default_rng(init_seed)
    )
    return estimates, recording


def team_task(
    seed_sequence: np.random.SeedSequence,
    run_index: int,
    scenario: Scenario,
    tracker: TrackManagerSettings,
    record_rate_hz: float,
) -> RunResult:
    """One Monte-Carlo run (top-level, picklable): simulate, track, score."""
    estimates, recording = simulate_and_track(seed_sequence, scenario, tracker, record_rate_hz)
    return score_run(estimates, recording, keep_paths=run_index == 0)


def export_run0(
    scenario: Scenario, settings: TeamRunSettings, request: ExportRequest
) -> dict[str, Any]:
    """``--mcap``/``--tum``: run 0 again in this process (a run depends only on the master seed
    and its index, so it is the very run 0 the summary pools) and write its estimates; returns
    the summary's ``export`` section (:func:`relloc.pipeline.export.export_estimates`)."""
    run0 = spawn_seeds(settings.seed, settings.runs)[0]
    estimates, recording = simulate_and_track(
        run0, scenario, settings.tracker, settings.record_rate_hz
    )
    return export_estimates(
        request,
        estimates,
        recording,
        run=f"run 0 of {settings.runs} (seed {settings.seed})",
        settle_s=settings.settle_s,
    )


def run_scenario(
    scenario: Scenario,
    settings: TeamRunSettings,
    out_dir: Path | None = None,
    *,
    export: ExportRequest | None = None,
) -> tuple[dict[str, Any], list[RunResult]]:
    """Monte-Carlo runs of a scenario; writes summary, report and figures if ``out_dir``, and
    run 0's estimates as MCAP/TUM files if ``export`` asks (:func:`export_run0`)."""
    results = run_monte_carlo(
        team_task,
        settings.runs,
        settings.seed,
        executor=settings.executor,
        task_args=(scenario, settings.tracker, settings.record_rate_hz),
        description=f"relloc run ({scenario.name})",
        quiet=settings.quiet,
    )
    summary = summarise(
        results,
        settle_s=settings.settle_s,
        record_rate_hz=settings.record_rate_hz,
        meta=scenario_meta(scenario, seed=settings.seed, tracker=settings.tracker),
    )
    summary["pairs_never_read"] = pairs_never_read(scenario, summary)
    if export is not None and export.wanted:
        summary["export"] = export_run0(scenario, settings, export)
    if out_dir is not None:
        write_run_report(scenario, summary, results, Path(out_dir))
    return summary, results


def write_run_report(
    scenario: Scenario,
    summary: dict[str, Any],
    results: list[RunResult],
    out_dir: Path,
    *,
    plots: bool = True,
) -> list[Path]:
    """Write ``summary.json``, ``report.md`` and (if ``plots``) the figures of a scenario's
    runs; returns the files written."""
    return write_team_report(
        out_dir,
        summary,
        results,
        title=f"relloc run — {scenario.name}",
        arena=(scenario.arena.x, scenario.arena.y),
        notes=[
            *([scenario.description] if scenario.description else ()),
            *never_read_note(summary.get("pairs_never_read", [])),
        ],
        plots=plots,
        views=sensor_views(scenario),
    )


def pairs_never_read(scenario: Scenario, summary: dict[str, Any]) -> list[str]:
    """``"observer->observed"`` for every robot with a sensor and every robot it observes
    (its ``observes`` list, or every other robot) that no run ever tracked (never inside the
    sensor's field of view and range): such a pair has no row in the tables, and without this
    list it would vanish from them unexplained."""
    tracked = {(p["observer"], p["observed"]) for p in summary["pairs"].values()}
    return [
        f"{r.name}->{o.name}"
        for r in scenario.robots
        if r.sensor is not None
        for o in scenario.robots
        if o.name != r.name
        and (r.observes is None or o.name in r.observes)
        and (r.name, o.name) not in tracked
    ]


def never_read_note(pairs: list[str]) -> list[str]:
    """report.md's line for :func:`pairs_never_read` (none when every pair was read)."""
    if not pairs:
        return []
    return [
        "Never read in any run, so not in the tables (the observed robot stayed outside the "
        f"observer's field of view or range): {', '.join(pairs)}."
    ]


def sensor_views(scenario: Scenario) -> dict[str, tuple[float, float]]:
    """Observer → (field of view in degrees, range in m) for the trajectory figure; an
    unlimited range is drawn to the arena's diagonal."""
    a = scenario.arena
    diagonal = float(np.hypot(a.x[1] - a.x[0], a.y[1] - a.y[0]))
    return {
        r.name: (r.sensor.fov_deg, min(r.sensor.max_range, diagonal))
        for r in scenario.robots
        if r.sensor is not None
    }
