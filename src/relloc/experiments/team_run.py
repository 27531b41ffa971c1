"""Run a team scenario end to end: simulate → track every pair → score → summary and report.

This is the library behind ``relloc run``. One Monte-Carlo run (:func:`team_task`) simulates
the scenario with its own random stream, runs the :class:`~relloc.estimators.track_manager.
TrackManager` over the log and scores each pair's recorded beliefs against the ground truth
(:func:`evaluate`). :func:`summarise` pools the runs into the numbers of ``summary.json``;
:func:`write_team_report` writes ``report.md`` with figures. :func:`build_summary` does the
scoring and pooling for estimates collected elsewhere (e.g. from robot processes).

Summary keys (``summary.json``), per pair under ``pairs["observer->observed"]``, computed
over all runs on the *steady-state* samples (track age ≥ ``settle_s``):

- ``position_rmse_m``, ``yaw_rmse_rad``, ``rmse`` per state ``x, y, z, phi``;
- ``within_3sigma_percent`` per state: share of samples with ``|e_i| ≤ 3σ_i``;
- ``anees`` (ideal 1) and ``nees_percent_beyond`` the single-run bound ``χ²(4, 0.95)``
  (seed 000 Table 4; about 5 % for a consistent filter);
- ``nees_run_average_in_band_percent``: share of recording times at which the NEES averaged
  over the ``N`` runs lies in the two-sided 95 % band of such an average (``band``; needs
  ``N ≥ 2``; about 95 % for a consistent filter);
- ``anis`` (NIS/3, ideal 1) and ``nis_percent_beyond`` ``χ²(3, 0.95)``;
- ``max_condition_log10`` of ``P``, ``R`` and ``S`` (seed 000 §7.3; > 6 is ill-conditioned);
- ``track_events``: created / deleted / re-created counts over all runs.

``team`` holds the same accuracy and consistency numbers pooled over every pair.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from relloc.errors import ConfigError, require
from relloc.estimators.track_manager import (
    PairEstimates,
    TeamEstimates,
    TrackEvent,
    TrackManagerSettings,
    track_log,
)
from relloc.experiments.montecarlo import run_monte_carlo
from relloc.experiments.output import (
    figure_md,
    markdown_table,
    prepare_out_dir,
    save_figure,
    write_report,
    write_summary,
)
from relloc.metrics.conditioning import ILL_CONDITIONED_LOG10, condition_log10_batch
from relloc.metrics.consistency import anees, chi2_upper, mean_chi2_band, nees, percent_beyond
from relloc.metrics.errors import state_errors
from relloc.sim.log import Log
from relloc.sim.scenario import Scenario
from relloc.sim.simulate import simulate

Array = NDArray[np.float64]

STATES = ("x", "y", "z", "phi")
NEES_DOF = 4
NIS_DOF = 3


@dataclass(frozen=True, kw_only=True)
class TeamRunSettings:
    """How ``relloc run`` runs a scenario.

    ``runs`` Monte-Carlo runs from master ``seed``; ``tracker`` the filter, initialisation and
    keep window; ``settle_s`` the track age after which samples count as steady state;
    ``record_rate_hz`` how often beliefs are recorded; ``executor`` as in
    :func:`relloc.experiments.montecarlo.run_monte_carlo`.
    """

    runs: int = 10
    seed: int = 2026
    tracker: TrackManagerSettings = field(default_factory=TrackManagerSettings)
    settle_s: float = 5.0
    record_rate_hz: float = 10.0
    executor: str | None = None
    quiet: bool = False

    def __post_init__(self) -> None:
        if isinstance(self.runs, bool) or not isinstance(self.runs, int) or self.runs < 1:
            raise ConfigError(f"--runs: must be an integer ≥ 1, got {self.runs!r}")
        if isinstance(self.seed, bool) or not isinstance(self.seed, int) or self.seed < 0:
            raise ConfigError(f"--seed: must be an integer ≥ 0, got {self.seed!r}")
        if not (np.isfinite(self.settle_s) and self.settle_s >= 0):
            raise ConfigError(f"settle_s: must be ≥ 0, got {self.settle_s!r}")
        if not (np.isfinite(self.record_rate_hz) and self.record_rate_hz > 0):
            raise ConfigError(f"record_rate_hz: must be > 0, got {self.record_rate_hz!r}")


@dataclass(frozen=True, kw_only=True)
class PairEvaluation:
    """One pair's scored series in one run.

    ``t (K,)``, ``error (K, 4)`` = estimate − truth (φ wrapped), ``sigma (K, 4)`` the filter's
    standard deviations, ``nees (K,)``, ``age (K,)``, ``cond_p (K,)``; ``update_t``,
    ``update_age``, ``nis``, ``cond_r``, ``cond_s`` per update.
    """

    observer: str
    observed: str
    observed_kind: str
    t: Array
    error: Array
    sigma: Array
    nees: Array
    age: Array
    cond_p: Array
    update_t: Array
    update_age: Array
    nis: Array
    cond_r: Array
    cond_s: Array

    @property
    def label(self) -> str:
        return f"{self.observer}->{self.observed}"


@dataclass(frozen=True, kw_only=True)
class RunResult:
    """What one Monte-Carlo run returns: scored pairs, track events, and (run 0 only) the
    true planar paths ``name -> (K, 4)`` for the trajectory figure."""

    pairs: tuple[PairEvaluation, ...]
    events: tuple[TrackEvent, ...]
    paths: dict[str, Array] | None = None


def evaluate_pair(est: PairEstimates, log: Log) -> PairEvaluation:
    """Score one pair's recorded beliefs against the log's ground truth."""
    truth = log.relative_truth(est.observer, est.observed, est.t)
    err = state_errors(est.mean, truth)
    return PairEvaluation(
        observer=est.observer,
        observed=est.observed,
        observed_kind=log.kinds[log.index(est.observed)],
        t=est.t,
        error=err,
        sigma=np.sqrt(np.diagonal(est.cov, axis1=1, axis2=2)),
        nees=nees(err, est.cov) if est.t.size else np.zeros(0),
        age=est.age,
        cond_p=condition_log10_batch(est.cov) if est.t.size else np.zeros(0),
        update_t=est.update_t,
        update_age=est.update_age,
        nis=est.nis,
        cond_r=est.cond_r,
        cond_s=est.cond_s,
    )


def evaluate(estimates: TeamEstimates, log: Log, *, keep_paths: bool = False) -> RunResult:
    """Score every pair of one run; ``keep_paths`` adds the true paths (10 Hz) for figures."""
    paths = None
    if keep_paths:
        t0, t1 = log.span
        grid = np.linspace(t0, t1, max(2, int((t1 - t0) * 10) + 1))
        paths = {name: log.truth[i].at(grid) for i, name in enumerate(log.robots)}
    return RunResult(
        pairs=tuple(evaluate_pair(p, log) for p in estimates.pairs),
        events=estimates.events,
        paths=paths,
    )


def team_task(
    seed_sequence: np.random.SeedSequence,
    run_index: int,
    scenario: Scenario,
    tracker: TrackManagerSettings,
    record_rate_hz: float,
) -> RunResult:
    """One Monte-Carlo run (top-level, picklable): simulate, track, score."""
    sim_seed, init_seed = seed_sequence.spawn(2)
    log = simulate(scenario, np.random.default_rng(sim_seed))
    estimates = track_log(
        log, tracker, record_rate_hz=record_rate_hz, rng=np.random.default_rng(init_seed)
    )
    return evaluate(estimates, log, keep_paths=run_index == 0)


# --------------------------------------------------------------------------- pooling


def _grid_index(t: Array, t0: float, rate: float) -> NDArray[np.int64]:
    return np.rint((t - t0) * rate).astype(np.int64)


def run_averaged_nees(
    runs: Sequence[PairEvaluation], *, rate_hz: float, settle_s: float
) -> tuple[Array, Array, int]:
    """Times and NEES averaged over runs at the recording times where every run has a
    steady-state sample; returns ``(t, mean_nees, n_runs)``."""
    t0 = min((float(r.t[0]) for r in runs if r.t.size), default=0.0)
    idx = [_grid_index(r.t, t0, rate_hz) for r in runs]
    n = max((int(i.max()) + 1 for i in idx if i.size), default=0)
    table = np.full((len(runs), n), np.nan)
    for k, (r, i) in enumerate(zip(runs, idx, strict=True)):
        steady = r.age >= settle_s
        table[k, i[steady]] = r.nees[steady]
    full = np.all(np.isfinite(table), axis=0)
    t = t0 + np.arange(n) / rate_hz
    return t[full], table[:, full].mean(axis=0), len(runs)


def _accuracy_and_consistency(runs: Sequence[PairEvaluation], *, settle_s: float) -> dict[str, Any]:
    steady = [r.age >= settle_s for r in runs]
    err = np.concatenate([r.error[s] for r, s in zip(runs, steady, strict=True)]).reshape(-1, 4)
    sig = np.concatenate([r.sigma[s] for r, s in zip(runs, steady, strict=True)]).reshape(-1, 4)
    ne = np.concatenate([r.nees[s] for r, s in zip(runs, steady, strict=True)])
    ni = np.concatenate([r.nis[r.update_age >= settle_s] for r in runs])
    nan = float("nan")
    out: dict[str, Any] = {
        "samples": int(err.shape[0]),
        "position_rmse_m": float(np.sqrt(np.mean(np.sum(err[:, :3] ** 2, axis=1))))
        if err.size
        else nan,
        "yaw_rmse_rad": float(np.sqrt(np.mean(err[:, 3] ** 2))) if err.size else nan,
        "rmse": {
            s: float(np.sqrt(np.mean(err[:, i] ** 2))) if err.size else nan
            for i, s in enumerate(STATES)
        },
        "within_3sigma_percent": {
            s: float(100.0 * np.mean(np.abs(err[:, i]) <= 3.0 * sig[:, i])) if err.size else nan
            for i, s in enumerate(STATES)
        },
        "anees": anees(ne, NEES_DOF),
        "nees_bound": chi2_upper(NEES_DOF, 0.95),
        "nees_percent_beyond": percent_beyond(ne, chi2_upper(NEES_DOF, 0.95)),
        "anis": anees(ni, NIS_DOF),
        "nis_bound": chi2_upper(NIS_DOF, 0.95),
        "nis_percent_beyond": percent_beyond(ni, chi2_upper(NIS_DOF, 0.95)),
    }
    return out


def _pair_summary(
    runs: Sequence[PairEvaluation], events: Sequence[TrackEvent], *, settle_s: float, rate: float
) -> dict[str, Any]:
    first = runs[0]
    out = {
        "observer": first.observer,
        "observed": first.observed,
        "observed_kind": first.observed_kind,
        **_accuracy_and_consistency(runs, settle_s=settle_s),
    }
    if len(runs) >= 2:
        _, avg, n = run_averaged_nees(runs, rate_hz=rate, settle_s=settle_s)
        lo, hi = mean_chi2_band(NEES_DOF, n, 0.95)
        inside = float(100.0 * np.mean((avg >= lo) & (avg <= hi))) if avg.size else float("nan")
        out["nees_run_average_in_band_percent"] = inside
        out["nees_run_average_band"] = [lo, hi]
    out["max_condition_log10"] = {
        "P": max((float(np.max(r.cond_p)) for r in runs if r.cond_p.size), default=float("nan")),
        "R": max((float(np.max(r.cond_r)) for r in runs if r.cond_r.size), default=float("nan")),
        "S": max((float(np.max(r.cond_s)) for r in runs if r.cond_s.size), default=float("nan")),
    }
    kinds = [e.kind for e in events if (e.observer, e.observed) == (first.observer, first.observed)]
    out["track_events"] = {k: kinds.count(k) for k in ("created", "deleted", "recreated")}
    return out


def summarise(
    results: Sequence[RunResult],
    *,
    settle_s: float,
    record_rate_hz: float,
    meta: Mapping[str, Any] | None = None,
) -> dict[str, Any]:
    """Pool Monte-Carlo runs into the ``summary.json`` dictionary (keys: module docstring)."""
    if not results:
        raise ConfigError("summarise: no runs to summarise")
    if not any(r.pairs for r in results):
        raise ConfigError(
            "no results: no observing robot measured another robot in any run, so nothing was "
            "tracked (is the run shorter than one sensor period, 1/rate_hz, or is no target "
            "ever in view?)"
        )
    labels = sorted({p.label for r in results for p in r.pairs})
    by_pair = {lab: [p for r in results for p in r.pairs if p.label == lab] for lab in labels}
    events = [e for r in results for e in r.events]
    pairs = {
        lab: _pair_summary(runs, events, settle_s=settle_s, rate=record_rate_hz)
        for lab, runs in by_pair.items()
    }
    everything = [p for r in results for p in r.pairs]
    team = _accuracy_and_consistency(everything, settle_s=settle_s)
    return {
        **(dict(meta) if meta else {}),
        "runs": len(results),
        "settle_s": settle_s,
        "record_rate_hz": record_rate_hz,
        "pairs": pairs,
        "team": team,
        "events_run0": [
            {"t": e.t, "observer": e.observer, "observed": e.observed, "kind": e.kind}
            for e in results[0].events
        ],
    }


def build_summary(
    estimates: Sequence[TeamEstimates],
    logs: Sequence[Log],
    *,
    settle_s: float = 5.0,
    record_rate_hz: float = 10.0,
    meta: Mapping[str, Any] | None = None,
) -> tuple[dict[str, Any], list[RunResult]]:
    """Score estimates collected elsewhere (one :class:`TeamEstimates` per run, with the log
    holding that run's ground truth) and pool them; returns ``(summary, results)`` so the
    results can also be passed to :func:`write_team_report`."""
    if len(estimates) != len(logs):
        raise ConfigError(f"build_summary: {len(estimates)} estimate sets but {len(logs)} logs")
    results = [
        evaluate(e, lg, keep_paths=i == 0)
        for i, (e, lg) in enumerate(zip(estimates, logs, strict=True))
    ]
    summary = summarise(results, settle_s=settle_s, record_rate_hz=record_rate_hz, meta=meta)
    return summary, results


# --------------------------------------------------------------------------- report


def summary_rows(summary: Mapping[str, Any]) -> tuple[list[str], list[list[Any]]]:
    """Headers and rows of the per-robot accuracy/consistency table (report and terminal)."""
    headers = [
        "pair",
        "kind",
        "pos RMSE m",
        "yaw RMSE rad",
        "min in ±3σ %",
        "ANEES",
        "NEES>χ²₉₅ %",
        "avg NEES in band %",
        "ANIS",
        "NIS>χ²₉₅ %",
    ]
    rows = []
    items = [*summary["pairs"].items(), ("team (all pairs)", summary["team"])]
    for label, s in items:
        within = s.get("within_3sigma_percent", {})
        rows.append(
            [
                label,
                s.get("observed_kind", ""),
                s["position_rmse_m"],
                s["yaw_rmse_rad"],
                min(within.values()) if within else None,
                s["anees"],
                s["nees_percent_beyond"],
                s.get("nees_run_average_in_band_percent"),
                s["anis"],
                s["nis_percent_beyond"],
            ]
        )
    return headers, rows


def _pyplot() -> Any:
    matplotlib = require("matplotlib", "plot")
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def write_figures(
    out_dir: Path,
    results: Sequence[RunResult],
    *,
    settle_s: float,
    record_rate_hz: float,
    arena: tuple[tuple[float, float], tuple[float, float]] | None = None,
) -> list[tuple[str, str]]:
    """Write the figures of a team run; returns ``(file, caption)`` pairs in report order."""
    from relloc.metrics.errors import rmse
    from relloc.plotting.consistency import plot_chi2_series, plot_conditioning
    from relloc.plotting.errors import (
        plot_pose_errors_with_bounds,
        plot_robot_errors,
        plot_trajectories,
    )

    plt = _pyplot()
    figures: list[tuple[str, str]] = []
    run0 = results[0]
    n_runs = len(results)
    for p in run0.pairs:
        fig, axes = plt.subplots(4, 1, figsize=(7, 7), sharex=True)
        plot_pose_errors_with_bounds(axes, p.t, p.error, p.sigma)
        steady = p.age >= settle_s
        if steady.any():  # scale to the steady state; the start-up transient is clipped
            for i, ax in enumerate(axes):
                half = 1.3 * float(
                    np.max(np.maximum(3 * p.sigma[steady, i], np.abs(p.error[steady, i])))
                )
                ax.set_ylim(-half, half)
        axes[0].set_title(f"{p.label} ({p.observed_kind}): error and ±3σ, run 0")
        name = save_figure(fig, out_dir, f"error_bounds_{p.observed}")
        figures.append(
            (
                name,
                f"Error of {p.label} with the filter's ±3σ bounds (run 0); axes scaled to the "
                "steady state, so the start-up transient is clipped.",
            )
        )

    series = {}
    labels = [p.label for p in run0.pairs]
    for lab in labels:
        runs = [q for r in results for q in r.pairs if q.label == lab]
        t0 = min(float(r.t[0]) for r in runs if r.t.size)
        n = max(int(_grid_index(r.t, t0, record_rate_hz).max()) + 1 for r in runs if r.t.size)
        table = np.full((len(runs), n, 4), np.nan)
        for k, r in enumerate(runs):
            table[k, _grid_index(r.t, t0, record_rate_hz)] = r.error
        series[lab.split("->")[1]] = (t0 + np.arange(n) / record_rate_hz, rmse(table, axis=0))
    fig, axes = plt.subplots(4, 1, figsize=(7, 7), sharex=True)
    plot_robot_errors(axes, series)
    axes[0].set_title(f"RMSE over {n_runs} run(s), every observed robot")
    figures.append(
        (
            save_figure(fig, out_dir, "errors_all"),
            f"RMSE over {n_runs} Monte-Carlo run(s) of every observed robot.",
        )
    )

    fig, axes = plt.subplots(2, 1, figsize=(7, 6), sharex=True)
    for i, lab in enumerate(labels):
        runs = [q for r in results for q in r.pairs if q.label == lab]
        if n_runs >= 2:
            t, avg, n = run_averaged_nees(runs, rate_hz=record_rate_hz, settle_s=settle_s)
        else:
            keep = runs[0].age >= settle_s
            t, avg, n = runs[0].t[keep], runs[0].nees[keep], 1
        plot_chi2_series(
            axes[0], t, avg, NEES_DOF, n_runs=n, label=lab.split("->")[1], show_bound=i == 0
        )
    p0 = run0.pairs[0]
    plot_chi2_series(axes[1], p0.update_t, p0.nis, NIS_DOF, label=f"NIS {p0.observed}")
    axes[0].set_ylabel("NEES" + (" (run average)" if n_runs >= 2 else ""))
    axes[1].set_ylabel("NIS (run 0)")
    axes[1].set_xlabel("time (s)")
    figures.append(
        (
            save_figure(fig, out_dir, "nees_nis"),
            "NEES (steady state) with its 95 % χ² region, and the NIS of one pair with "
            "χ²(3, 0.95).",
        )
    )

    fig, ax = plt.subplots(figsize=(7, 3.5))
    plot_conditioning(
        ax,
        {
            f"P {p0.observed}": (p0.t, p0.cond_p),
            f"R {p0.observed}": (p0.update_t, p0.cond_r),
            f"S {p0.observed}": (p0.update_t, p0.cond_s),
        },
        threshold=ILL_CONDITIONED_LOG10,
    )
    figures.append(
        (
            save_figure(fig, out_dir, "conditioning"),
            f"Conditioning log10(λmax/λmin) of P, R and S for {p0.label} (run 0).",
        )
    )

    if run0.paths:
        fig, ax = plt.subplots(figsize=(5, 8))
        plot_trajectories(ax, run0.paths, arena=arena)
        ax.set_title("true paths (run 0)")
        figures.append((save_figure(fig, out_dir, "trajectories"), "True paths of the team."))
    return figures


def report_markdown(
    summary: Mapping[str, Any],
    figures: Sequence[tuple[str, str]],
    *,
    title: str,
    notes: Sequence[str] = (),
) -> str:
    """``report.md``: settings, the per-robot table, track events, notes and figures."""
    headers, rows = summary_rows(summary)
    lines = [f"# {title}", ""]
    for key in (
        "scenario",
        "seed",
        "runs",
        "filter",
        "init",
        "yaw_bank_components",
        "keep_window_s",
        "settle_s",
    ):
        if key in summary:
            lines.append(f"- **{key}**: {summary[key]}")
    if "odometry_sigma" in summary:
        lines.append("- **odometry noise σ (v_x, v_y, v_z, ω_z)** per robot:")
        for name, sig in summary["odometry_sigma"].items():
            lines.append(f"  - {name}: {sig}")
    if "sensor_sigma" in summary:
        lines.append(f"- **sensor σ (r, θ, α)**: {summary['sensor_sigma']}")
    lines += [
        "",
        "## Accuracy and consistency (steady state, all runs)",
        "",
        markdown_table(headers, rows),
        "",
        f"Steady state = samples at least {summary.get('settle_s')} s after a track was "
        "(re)created. A consistent filter has ANEES ≈ 1 and ANIS ≈ 1, about 5 % of NEES "
        "(NIS) values above χ²(4, 0.95) = 9.49 (χ²(3, 0.95) = 7.81), and its run-averaged "
        "NEES inside the 95 % band about 95 % of the time. Samples of one run are correlated "
        "in time, so these shares fluctuate more than independent draws would.",
        "",
        "## Track events (run 0)",
        "",
    ]
    ev = summary.get("events_run0", [])
    if ev:
        lines.append(
            markdown_table(
                ["t (s)", "observer", "observed", "event"],
                [[e["t"], e["observer"], e["observed"], e["kind"]] for e in ev],
            )
        )
    else:
        lines.append("No track events.")
    if notes:
        lines += ["", "## Notes", ""] + [f"- {n}" for n in notes]
    lines += ["", "## Figures", ""]
    for name, caption in figures:
        lines.append(figure_md(name, caption))
    return "\n".join(lines)


def write_team_report(
    out_dir: Path,
    summary: Mapping[str, Any],
    results: Sequence[RunResult],
    *,
    title: str = "relloc run",
    arena: tuple[tuple[float, float], tuple[float, float]] | None = None,
    notes: Sequence[str] = (),
) -> None:
    """Write ``summary.json``, the figures and ``report.md`` into ``out_dir``."""
    out = prepare_out_dir(out_dir)
    write_summary(out, summary)
    figures = write_figures(
        out,
        results,
        settle_s=float(summary["settle_s"]),
        record_rate_hz=float(summary["record_rate_hz"]),
        arena=arena,
    )
    write_report(out, report_markdown(summary, figures, title=title, notes=notes))


# --------------------------------------------------------------------------- entry point


def scenario_meta(scenario: Scenario, settings: TeamRunSettings) -> dict[str, Any]:
    """The settings part of ``summary.json``."""
    observers = [r for r in scenario.robots if r.sensor is not None]
    return {
        "experiment": "run",
        "scenario": scenario.name,
        "seed": settings.seed,
        "filter": settings.tracker.filter,
        "init": settings.tracker.init.name,
        "keep_window_s": settings.tracker.keep_window_s,
        "yaw_bank_components": settings.tracker.yaw_bank.n_components
        if settings.tracker.yaw_bank
        else 0,
        "pseudo_linear_covariance": settings.tracker.pseudo_linear_covariance,
        "duration_s": scenario.duration_s,
        "propagation_rate_hz": scenario.propagation_rate_hz,
        "odometry_sigma": {r.name: list(r.odometry.sigma_for(r.kind)) for r in scenario.robots},
        "sensor_sigma": {r.name: list(r.sensor.sigma) for r in observers if r.sensor},
        "sensor_rate_hz": {r.name: r.sensor.rate_hz for r in observers if r.sensor},
    }


def run_team(
    scenario: Scenario, settings: TeamRunSettings, out_dir: Path | None = None
) -> tuple[dict[str, Any], list[RunResult]]:
    """Monte-Carlo runs of a scenario; writes summary, report and figures if ``out_dir``."""
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
        meta=scenario_meta(scenario, settings),
    )
    if out_dir is not None:
        arena = (scenario.arena.x, scenario.arena.y)
        write_team_report(
            Path(out_dir),
            summary,
            results,
            title=f"relloc run — {scenario.name}",
            arena=arena,
            notes=[scenario.description] if scenario.description else (),
        )
    return summary, results
