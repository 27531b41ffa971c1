"""The team report of relative localisation: score a team's estimates, pool runs, write it out.

``relloc run`` (:mod:`relloc.experiments.team_run`) and ``relloc team up``
(:mod:`relloc.runtime.team`) both track every robot a team observes with one
:class:`~relloc.estimators.track_manager.TrackManager` per observing robot
(:func:`track_team`, through :func:`relloc.pipeline.replay.replay`), score each run's
:class:`~relloc.core.estimates.Estimates` with :func:`relloc.pipeline.evaluation.evaluate`
(:func:`score_run`), pool the runs into ``summary.json`` (:func:`summarise`,
:func:`build_summary`) and write ``report.md`` with figures (:func:`write_team_report`).

Summary keys (``summary.json``): the settings first — ``experiment`` (``run``), ``runs``,
``settle_s``, ``record_rate_hz``; for a simulated scenario (:func:`scenario_meta`) its
``scenario`` name, ``seed``, ``duration_s``, ``propagation_rate_hz``, per robot
``odometry_sigma`` and, per observing robot, ``sensor_sigma`` (r, θ, α) and ``sensor_rate_hz``,
and the track managers' settings (:func:`tracker_meta`: ``filter``, ``init``,
``keep_window_s``, ``yaw_bank_components``, ``pseudo_linear_covariance``, ``gate_probability``);
a bag states its own (:mod:`relloc.experiments.bag_run`). ``events_run0`` lists run 0's track
events (``t``, ``observer``, ``observed``, ``kind``). Per pair under
``pairs["observer->observed"]`` (``observer``, ``observed``, the ``observed_kind`` of platform),
computed over all runs on the *steady-state* samples (track age ≥ ``settle_s``, their number
``samples``):

- ``position_rmse_m``, ``yaw_rmse_rad``, ``rmse`` per state ``x, y, z, phi``;
- ``within_3sigma_percent`` per state: share of samples with ``|e_i| ≤ 3σ_i``;
- ``anees`` (ideal 1) and ``nees_percent_beyond`` the single-run bound ``χ²(4, 0.95)``
  (``nees_bound``)
  (seed 000 Table 4; about 5 % for a consistent filter), ``nees_beyond_interval`` its 95 %
  interval by cluster means (the independent runs; one run's record times in blocks), with
  the verdict (:func:`relloc.metrics.consistency.percent_beyond_interval`): ``over-confident``
  (interval wholly above 5 %), ``conservative`` (wholly below), ``consistent`` (holds 5 % and
  reaches no higher than 10 %, twice it: :data:`relloc.metrics.consistency.EQUIVALENCE_FACTOR`)
  or ``inconclusive`` (holds 5 % but reaches above 10 %: not rejected, not shown either);
- ``nees_run_average_in_band_percent``: share of recording times at which the NEES averaged
  over the ``N`` runs lies in the two-sided 95 % band of such an average
  (``nees_run_average_band``; needs ``N ≥ 2``; about 95 % for a consistent filter), and
  ``nees_run_average_verdict``, whether the shares below and above the band exceed the 2.5 %
  each side leaves by more than their intervals allow (``conservative``, ``over-confident``),
  else ``consistent`` (a significance test, without the equivalence margin: see
  :func:`relloc.metrics.consistency.run_average_band`) —
  :func:`relloc.pipeline.evaluation.nees_band_check` — with
  ``nees_run_average_blocks_short``, whether those intervals' blocks of times last less than
  ten correlation times (:attr:`relloc.metrics.BeyondShare.blocks_short`; the intervals are
  then widened to the correlation-time interval);
- ``anis`` (NIS per degree of freedom, ideal 1) and ``nis_percent_beyond`` (each NIS against
  ``χ²(d, 0.95)`` of its reading's dimension ``d``; ``nis_dof`` is the most common ``d`` and
  ``nis_bound`` its bound: 3 for range, bearing and elevation, 1 for a UWB range);
- ``max_condition_log10`` of ``P``, ``R`` and ``S`` (seed 000 §7.3; > 6 is ill-conditioned);
- ``track_events``: created / deleted / re-created counts over all runs;
- ``position_rmse_over_runs``, ``yaw_rmse_over_runs``: the spread of the per-run steady-state
  RMSE — ``runs``, ``mean``, ``std`` (ddof 1) and ``interval95`` (the 2.5 and 97.5 percentiles
  of the per-run values, linear interpolation), :func:`rmse_over_runs`;
- ``convergence``: from the track's first record (the unknown start), the time and the number
  of updates until every state's error stays below :data:`CONVERGENCE_THRESHOLDS` for good
  (:func:`relloc.pipeline.evaluation.convergence_time`): ``median_time_s``, ``max_time_s``,
  ``median_updates`` over the runs that converged, ``runs_converged`` of ``runs``.

``team`` holds the same accuracy and consistency numbers pooled over every pair
(:func:`relloc.pipeline.evaluation.accuracy_and_consistency`) and their spread over runs;
``rows_not_used`` (present only when some were) counts the readings the trackers could not
use, by reason (also a note in report.md). ``relloc run`` adds ``pairs_never_read``: every
``"observer->observed"`` of a robot with a sensor that no run tracked
(:func:`relloc.experiments.team_run.pairs_never_read`), also named in report.md's notes.
"""

from __future__ import annotations

import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from relloc.core.checks import positive
from relloc.core.contract import TrackEvent
from relloc.core.estimates import Estimates
from relloc.core.recording import Recording
from relloc.errors import ConfigError
from relloc.estimators.relative import FRAME, MEASUREMENT_DOF
from relloc.estimators.track_manager import TrackManagerSettings, managers_for
from relloc.metrics.conditioning import ILL_CONDITIONED_LOG10
from relloc.metrics.consistency import chi2_upper
from relloc.pipeline.evaluation import (
    SeriesEvaluation,
    accuracy_and_consistency,
    convergence_time,
    evaluate,
    nees_band_check,
    run_averaged_nees,
)
from relloc.pipeline.frames import frame
from relloc.pipeline.output import (
    figure_md,
    fmt,
    interval_text,
    markdown_table,
    prepare_out_dir,
    run_average_verdict_text,
    save_figure,
    write_report,
    write_summary,
)
from relloc.pipeline.replay import replay
from relloc.sim.scenario import Scenario

Array = NDArray[np.float64]

NEES_DOF = frame(FRAME).dim
NIS_DOF = MEASUREMENT_DOF
SETTLE_S = 5.0
"""Default track age (s) after which samples count as steady state."""
RECORD_RATE_HZ = 10.0
"""Default rate (Hz) at which beliefs are recorded."""
CONVERGENCE_THRESHOLDS = (0.1, 0.1, 0.1, 0.1)
"""|error| bounds (x, y, z in m; φ in rad) a track must stay inside to count as converged."""
_UNSAFE_IN_NAME = re.compile(r"[^A-Za-z0-9_-]")


@dataclass(frozen=True, kw_only=True)
class RunResult:
    """One run scored: an evaluation per (observer, observed) series, the track events, the
    rows the trackers did not use (by reason) and — run 0 only — the true paths
    ``name -> (K, 4)`` (x, y, z, ψ) at times ``path_t`` for the trajectory figure."""

    evaluations: tuple[SeriesEvaluation, ...]
    events: tuple[TrackEvent, ...]
    rows_not_used: Mapping[str, int] = field(default_factory=dict)
    paths: dict[str, Array] | None = None
    path_t: Array | None = None


def track_team(
    recording: Recording,
    tracker: TrackManagerSettings,
    *,
    record_rate_hz: float = RECORD_RATE_HZ,
    rng: np.random.Generator | None = None,
) -> Estimates:
    """Every observing robot's tracks over the whole recording (one manager per observer);
    no estimates at all when no robot measured another (:func:`summarise` says so if no run
    of a Monte-Carlo set tracked anything)."""
    managers = managers_for(recording, tracker, rng=rng)
    if not managers:
        return Estimates(estimator=tracker.filter)
    return replay(recording, managers, record_rate_hz=record_rate_hz)


def score_run(estimates: Estimates, recording: Recording, *, keep_paths: bool = False) -> RunResult:
    """Score every series of one run; ``keep_paths`` adds the true paths (10 Hz) for figures."""
    paths, grid = None, None
    if keep_paths:
        truth = recording.require_truth("the trajectory figure")
        t0, t1 = recording.span
        grid = np.linspace(t0, t1, max(2, int((t1 - t0) * 10) + 1))
        paths = {name: truth[i].at(grid) for i, name in enumerate(recording.robots)}
    return RunResult(
        evaluations=evaluate(estimates, recording),
        events=estimates.events,
        rows_not_used=dict(estimates.counts),
        paths=paths,
        path_t=grid,
    )


# --------------------------------------------------------------------------- pooling


def _grid_index(t: Array, t0: float, rate: float) -> NDArray[np.int64]:
    return np.rint((t - t0) * rate).astype(np.int64)


def _runs_of(results: Sequence[RunResult], label: str) -> list[SeriesEvaluation]:
    """The evaluations of one series over every run, in run order."""
    return [e for r in results for e in r.evaluations if e.label == label]


def _pair_summary(
    runs: Sequence[SeriesEvaluation],
    events: Sequence[TrackEvent],
    *,
    settle_s: float,
    rate: float,
) -> dict[str, Any]:
    first = runs[0]
    out = {
        "observer": first.owner,
        "observed": first.subject,
        "observed_kind": first.platform,
        **accuracy_and_consistency(runs, settle_s=settle_s, runs=range(len(runs))),
    }
    if len(runs) >= 2:
        band = nees_band_check(runs, rate_hz=rate, settle_s=settle_s)
        out["nees_run_average_in_band_percent"] = band["in_band_percent"]
        out["nees_run_average_band"] = band["band"]
        out["nees_run_average_verdict"] = band["verdict"]
        out["nees_run_average_blocks_short"] = bool(band.get("blocks_short"))
    out["max_condition_log10"] = {
        "P": max((float(np.max(r.cond_p)) for r in runs if r.cond_p.size), default=float("nan")),
        "R": max((float(np.max(r.cond_r)) for r in runs if r.cond_r.size), default=float("nan")),
        "S": max((float(np.max(r.cond_s)) for r in runs if r.cond_s.size), default=float("nan")),
    }
    kinds = [e.kind for e in events if (e.owner, e.subject) == (first.owner, first.subject)]
    out["track_events"] = {k: kinds.count(k) for k in ("created", "deleted", "recreated")}
    out["position_rmse_over_runs"] = rmse_over_runs(runs, "position_rmse_m", settle_s=settle_s)
    out["yaw_rmse_over_runs"] = rmse_over_runs(runs, "yaw_rmse_rad", settle_s=settle_s)
    out["convergence"] = convergence_summary(runs)
    return out


def rmse_over_runs(
    runs: Sequence[SeriesEvaluation], key: str, *, settle_s: float
) -> dict[str, Any]:
    """Spread of one steady-state RMSE (``position_rmse_m`` or ``yaw_rmse_rad`` of
    :func:`accuracy_and_consistency`) over runs: ``runs`` (with steady-state samples),
    ``mean``, ``std`` (ddof 1, NaN for one run) and ``interval95``, the 2.5–97.5 percentiles
    of the per-run values."""
    return _spread([accuracy_and_consistency([r], settle_s=settle_s)[key] for r in runs])


def _spread(per_run: Sequence[float]) -> dict[str, Any]:
    values = np.asarray(per_run, dtype=float)
    values = values[np.isfinite(values)]
    nan = float("nan")
    if values.size == 0:
        return {"runs": 0, "mean": nan, "std": nan, "interval95": [nan, nan]}
    return {
        "runs": int(values.size),
        "mean": float(np.mean(values)),
        "std": float(np.std(values, ddof=1)) if values.size >= 2 else nan,
        "interval95": [float(v) for v in np.percentile(values, [2.5, 97.5])],
    }


def convergence_summary(
    runs: Sequence[SeriesEvaluation], thresholds: Sequence[float] = CONVERGENCE_THRESHOLDS
) -> dict[str, Any]:
    """Time and updates from each run's first record until the error stays inside
    ``thresholds`` for good, summarised over the runs that converged (module docstring)."""
    times, updates = [], []
    for r in runs:
        ct = convergence_time(r, thresholds)
        if ct is not None:
            times.append(ct)
            updates.append(int(np.sum(r.update_t <= r.t[0] + ct)))
    nan = float("nan")
    return {
        "thresholds": list(thresholds),
        "runs": len(runs),
        "runs_converged": len(times),
        "median_time_s": float(np.median(times)) if times else nan,
        "max_time_s": float(np.max(times)) if times else nan,
        "median_updates": float(np.median(updates)) if updates else nan,
    }


def summarise(
    results: Sequence[RunResult],
    *,
    settle_s: float,
    record_rate_hz: float,
    meta: Mapping[str, Any] | None = None,
) -> dict[str, Any]:
    """Pool runs into the ``summary.json`` dictionary (keys: module docstring).

    ``record_rate_hz`` must be a finite number > 0 (ConfigError) for one run too, where no
    run-averaged NEES reads it: the summary states it."""
    if not results:
        raise ConfigError("summarise: no runs to summarise")
    positive(record_rate_hz, "summarise: record_rate_hz")
    if not any(r.evaluations for r in results):
        raise ConfigError(
            "no results: no observing robot measured another robot in any run, so nothing was "
            "tracked (is the run shorter than one sensor period, 1/rate_hz, or is no target "
            "ever in view?)"
        )
    labels = sorted({e.label for r in results for e in r.evaluations})
    events = [e for r in results for e in r.events]
    pairs = {
        lab: _pair_summary(_runs_of(results, lab), events, settle_s=settle_s, rate=record_rate_hz)
        for lab in labels
    }
    everything = [e for r in results for e in r.evaluations]
    run_of = [k for k, r in enumerate(results) for _ in r.evaluations]
    summary = {
        **(dict(meta) if meta else {}),
        "runs": len(results),
        "settle_s": settle_s,
        "record_rate_hz": record_rate_hz,
        "pairs": pairs,
        "team": {
            **accuracy_and_consistency(everything, settle_s=settle_s, runs=run_of),
            **_team_spread(results, settle_s=settle_s),
        },
        "events_run0": [
            {"t": e.t, "observer": e.owner, "observed": e.subject, "kind": e.kind}
            for e in results[0].events
        ],
    }
    not_used: dict[str, int] = {}
    for r in results:
        for reason, n in r.rows_not_used.items():
            not_used[reason] = not_used.get(reason, 0) + n
    if any(not_used.values()):
        summary["rows_not_used"] = not_used
    return summary


def _team_spread(results: Sequence[RunResult], *, settle_s: float) -> dict[str, Any]:
    """The per-run spread of the team's RMSE (every pair of a run pooled)."""
    tracked = [r.evaluations for r in results if r.evaluations]
    return {
        f"{name}_over_runs": _spread(
            [accuracy_and_consistency(e, settle_s=settle_s)[key] for e in tracked]
        )
        for name, key in (("position_rmse", "position_rmse_m"), ("yaw_rmse", "yaw_rmse_rad"))
    }


def build_summary(
    estimates: Sequence[Estimates],
    recordings: Sequence[Recording],
    *,
    settle_s: float = SETTLE_S,
    record_rate_hz: float = RECORD_RATE_HZ,
    meta: Mapping[str, Any] | None = None,
) -> tuple[dict[str, Any], list[RunResult]]:
    """Score estimates collected elsewhere (one :class:`Estimates` per run, with the recording
    holding that run's ground truth) and pool them; returns ``(summary, results)`` so the
    results can also be passed to :func:`write_team_report`."""
    if len(estimates) != len(recordings):
        raise ConfigError(
            f"build_summary: {len(estimates)} estimate sets but {len(recordings)} recordings"
        )
    results = [
        score_run(e, rec, keep_paths=i == 0)
        for i, (e, rec) in enumerate(zip(estimates, recordings, strict=True))
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
        "its 95 % interval",
        "avg NEES in band %",
        "its verdict",
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
                interval_text(s.get("nees_beyond_interval")),
                s.get("nees_run_average_in_band_percent"),
                run_average_verdict_text(
                    {
                        "verdict": s.get("nees_run_average_verdict"),
                        "blocks_short": s.get("nees_run_average_blocks_short"),
                    }
                ),
                s["anis"],
                s["nis_percent_beyond"],
            ]
        )
    return headers, rows


def spread_rows(summary: Mapping[str, Any]) -> tuple[list[str], list[list[Any]]]:
    """Headers and rows of the report's spread-and-convergence table."""
    headers = [
        "pair",
        "pos RMSE m, mean ± std",
        "95 % of runs",
        "yaw RMSE rad, mean ± std",
        "95 % of runs",
        "converged runs",
        "median (max) time s",
        "median updates",
    ]
    rows = []
    for label, s in [*summary["pairs"].items(), ("team (all pairs)", summary["team"])]:
        row: list[Any] = [label]
        for key in ("position_rmse_over_runs", "yaw_rmse_over_runs"):
            sp = s.get(key, {})
            lo, hi = sp.get("interval95", [None, None])
            row += [
                f"{fmt(sp.get('mean'), 3)} ± {fmt(sp.get('std'), 2)}",
                f"{fmt(lo, 3)}–{fmt(hi, 3)}",
            ]
        conv = s.get("convergence")
        if conv:
            row += [
                f"{conv['runs_converged']}/{conv['runs']}",
                f"{fmt(conv['median_time_s'], 3)} ({fmt(conv['max_time_s'], 3)})",
                conv["median_updates"],
            ]
        else:
            row += ["", "", ""]
        rows.append(row)
    return headers, rows


def write_figures(
    out_dir: Path,
    results: Sequence[RunResult],
    *,
    settle_s: float,
    record_rate_hz: float,
    arena: tuple[tuple[float, float], tuple[float, float]] | None = None,
    views: Mapping[str, tuple[float, float]] | None = None,
) -> list[tuple[str, str]]:
    """Write the figures of a team run; returns ``(file, caption)`` pairs in report order.

    ``views``: observer → ``(fov_deg, max_range_m)`` for the trajectory figure.
    """
    from relloc.plotting.setup import pyplot

    plt = pyplot()
    run0 = results[0]
    return [
        *_error_bound_figures(plt, out_dir, run0, settle_s=settle_s),
        _rmse_figure(plt, out_dir, results, settle_s=settle_s, rate=record_rate_hz),
        _nees_nis_figure(plt, out_dir, results, settle_s=settle_s, rate=record_rate_hz),
        _conditioning_figure(plt, out_dir, run0),
        _convergence_figure(plt, out_dir, results),
        *_trajectory_figure(plt, out_dir, run0, arena=arena, views=views),
    ]


def pair_figure_stems(pairs: Sequence[SeriesEvaluation]) -> list[str]:
    """One file-name stem per series: ``observer_observed`` (``__track`` appended when the
    track has a name), so two observers of one robot get a figure each. Characters outside
    ``[A-Za-z0-9_-]`` become ``_``; a stem another series already has gets ``_2``, ``_3``, …"""
    stems: list[str] = []
    for p in pairs:
        stem = f"{p.owner}_{p.subject}" + (f"__{p.track}" if p.track else "")
        stem = _UNSAFE_IN_NAME.sub("_", stem)
        unique, k = stem, 1
        while unique in stems:
            k += 1
            unique = f"{stem}_{k}"
        stems.append(unique)
    return stems


def _legend_names(pairs: Sequence[SeriesEvaluation]) -> list[str]:
    """A legend name per series: the observed robot, or the series' label (``observer->observed``)
    where more than one series observe that robot — so none hides another."""
    subjects = [p.subject for p in pairs]
    return [p.subject if subjects.count(p.subject) == 1 else p.label for p in pairs]


def _error_bound_figures(
    plt: Any, out_dir: Path, run0: RunResult, *, settle_s: float
) -> list[tuple[str, str]]:
    from relloc.plotting.errors import plot_pose_errors_with_bounds
    from relloc.plotting.style import legend_outside
    from relloc.plotting.team import shade_gaps, track_gaps

    figures = []
    stems = pair_figure_stems(run0.evaluations)
    for p, stem in zip(run0.evaluations, stems, strict=True):
        fig, axes = plt.subplots(4, 1, figsize=(8, 7), sharex=True)
        plot_pose_errors_with_bounds(axes, p.t, p.error, p.sigma)
        gaps = track_gaps(run0.events, p.owner, p.subject, float(p.t[-1]) if p.t.size else 0.0)
        steady = p.age >= settle_s
        for i, ax in enumerate(axes):
            shade_gaps(ax, gaps)
            if steady.any():  # scale to the steady state; the start-up transient is clipped
                half = 1.3 * float(
                    np.max(np.maximum(3 * p.sigma[steady, i], np.abs(p.error[steady, i])))
                )
                ax.set_ylim(-half, half)
        legend_outside(axes[0])
        axes[0].set_title(f"{p.label} ({p.platform}): error and ±3σ, run 0")
        name = save_figure(fig, out_dir, f"error_bounds_{stem}")
        figures.append(
            (
                name,
                f"Error of {p.label} with the filter's ±3σ bounds (run 0); axes scaled to the "
                f"steady state (track age ≥ {settle_s:g} s), so the start-up transient is "
                "clipped; shaded: no track (deleted, not yet re-created).",
            )
        )
    return figures


def _rmse_figure(
    plt: Any, out_dir: Path, results: Sequence[RunResult], *, settle_s: float, rate: float
) -> tuple[str, str]:
    from relloc.metrics.errors import rmse
    from relloc.plotting.errors import plot_robot_errors
    from relloc.plotting.style import legend_outside
    from relloc.plotting.team import steady_limits

    series = {}
    t_first = float("inf")
    pairs = results[0].evaluations
    for p, name in zip(pairs, _legend_names(pairs), strict=True):
        runs = _runs_of(results, p.label)
        t0 = min(float(r.t[0]) for r in runs if r.t.size)
        t_first = min(t_first, t0)
        n = max(int(_grid_index(r.t, t0, rate).max()) + 1 for r in runs if r.t.size)
        table = np.full((len(runs), n, 4), np.nan)
        for k, r in enumerate(runs):
            table[k, _grid_index(r.t, t0, rate)] = r.error
        series[name] = (t0 + np.arange(n) / rate, rmse(table, axis=0))
    fig, axes = plt.subplots(4, 1, figsize=(8, 7), sharex=True)
    plot_robot_errors(axes, series)
    for i, ax in enumerate(axes):
        t_all = np.concatenate([t for t, _ in series.values()])
        v_all = np.concatenate([v[:, i] for _, v in series.values()])
        steady_limits(ax, t_all, v_all, t_first + settle_s)
        ax.set_ylim(bottom=0.0)
    legend_outside(axes[0])
    n_runs = len(results)
    axes[0].set_title(f"RMSE over {n_runs} run(s), every observed robot")
    return (
        save_figure(fig, out_dir, "errors_all"),
        f"RMSE over {n_runs} Monte-Carlo run(s) of every observed robot; y axes scaled to the "
        f"values from {settle_s:g} s after the first track started (the start-up spike is "
        "clipped).",
    )


def _nees_nis_figure(
    plt: Any, out_dir: Path, results: Sequence[RunResult], *, settle_s: float, rate: float
) -> tuple[str, str]:
    from relloc.plotting.consistency import plot_chi2_series
    from relloc.plotting.style import legend_outside, plain_log_ticks

    n_runs = len(results)
    fig, axes = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
    pairs = results[0].evaluations
    for i, (p, name) in enumerate(zip(pairs, _legend_names(pairs), strict=True)):
        runs = _runs_of(results, p.label)
        if n_runs >= 2:
            t, avg, n = run_averaged_nees(runs, rate_hz=rate, settle_s=settle_s)
        else:
            keep = runs[0].age >= settle_s
            t, avg, n = runs[0].t[keep], runs[0].nees[keep], 1
        plot_chi2_series(
            axes[0], t, avg, NEES_DOF, n_runs=n, label=name, show_bound=i == 0, normalise=True
        )
        keep = p.update_age >= settle_s
        plot_chi2_series(
            axes[1],
            p.update_t[keep],
            p.nis[keep],
            NIS_DOF,
            label=name,
            show_bound=i == 0,
            normalise=True,
        )
    axes[0].set_ylabel(f"NEES/{NEES_DOF}" + (f" ({n_runs}-run average)" if n_runs >= 2 else ""))
    axes[1].set_ylabel(f"NIS/{NIS_DOF} (run 0)")
    axes[1].set_xlabel("time (s)")
    axes[0].set_title(f"Normalised NEES and NIS, steady state (track age ≥ {settle_s:g} s)")
    for ax in axes:
        plain_log_ticks(ax)
        legend_outside(ax)
    return (
        save_figure(fig, out_dir, "nees_nis"),
        f"Normalised NEES (NEES/{NEES_DOF}, the table's ANEES, ideal 1) with its 95 % region, "
        f"and every pair's NIS/{NIS_DOF} in run 0 with χ²({NIS_DOF}, 0.95)/{NIS_DOF}; steady "
        "state only.",
    )


def _conditioning_figure(plt: Any, out_dir: Path, run0: RunResult) -> tuple[str, str]:
    from relloc.plotting.consistency import plot_conditioning
    from relloc.plotting.style import legend_outside

    pairs = run0.evaluations
    fig, axes = plt.subplots(len(pairs), 1, figsize=(8, 1.2 + 1.8 * len(pairs)), sharex=True)
    axes = np.atleast_1d(axes)
    for ax, p in zip(axes, pairs, strict=True):
        plot_conditioning(
            ax,
            {"P": (p.t, p.cond_p), "R": (p.update_t, p.cond_r), "S": (p.update_t, p.cond_s)},
            threshold=ILL_CONDITIONED_LOG10,
        )
        ax.set_title(p.label, fontsize="small", loc="left")
        ax.set_ylabel("log10 κ")
        if ax is not axes[-1]:
            ax.set_xlabel("")
        legend_outside(ax)
    fig.suptitle("Conditioning of P, R and S, run 0")
    return (
        save_figure(fig, out_dir, "conditioning"),
        "Conditioning log10(λmax/λmin) of P, R and S for every pair (run 0); dashed: the "
        f"ill-conditioning threshold 10^{ILL_CONDITIONED_LOG10:g}.",
    )


def _convergence_figure(plt: Any, out_dir: Path, results: Sequence[RunResult]) -> tuple[str, str]:
    from relloc.plotting.team import plot_convergence

    times = {
        p.label: [convergence_time(r, CONVERGENCE_THRESHOLDS) for r in _runs_of(results, p.label)]
        for p in results[0].evaluations
    }
    fig, ax = plt.subplots(figsize=(8, 3.5))
    plot_convergence(ax, times)
    th = CONVERGENCE_THRESHOLDS
    ax.set_title(
        f"Convergence from the unknown start: |x|,|y|,|z| < {th[0]:g} m, |φ| < {th[3]:g} rad"
    )
    return (
        save_figure(fig, out_dir, "convergence"),
        "Share of runs whose error has entered, and stays inside, the convergence bounds, by "
        "time since the track first started (per pair, all runs); a track deleted and "
        "re-created starts again from an unknown pose, so its time includes the second start.",
    )


def _trajectory_figure(
    plt: Any,
    out_dir: Path,
    run0: RunResult,
    *,
    arena: tuple[tuple[float, float], tuple[float, float]] | None,
    views: Mapping[str, tuple[float, float]] | None,
) -> list[tuple[str, str]]:
    from relloc.plotting.team import estimated_world_path, plot_team_paths

    if not run0.paths or run0.path_t is None:
        return []
    estimates = {
        p.label: (
            p.t,
            estimated_world_path(
                run0.path_t, run0.paths[p.owner], run0.paths[p.subject], p.t, p.error
            ),
            p.subject,
        )
        for p in run0.evaluations
        if p.owner in run0.paths and p.subject in run0.paths
    }
    fig = plt.figure(figsize=(9, 9))
    grid = fig.add_gridspec(2, 1, height_ratios=(3, 1))
    ax_xy, ax_z = fig.add_subplot(grid[0]), fig.add_subplot(grid[1])
    plot_team_paths(ax_xy, ax_z, run0.path_t, run0.paths, estimates, views=views, arena=arena)
    ax_xy.set_title("Team paths, run 0: true (solid) and estimated by the observer (dashed)")
    ax_z.set_title("Heights", fontsize="small", loc="left")
    return [
        (
            save_figure(fig, out_dir, "trajectories"),
            "True paths (solid, start marked) and each observer's estimates of its teammates "
            "drawn in the world frame (dashed), with the observers' field of view at the start; "
            "below, the heights over time.",
        )
    ]


def report_markdown(
    summary: Mapping[str, Any],
    figures: Sequence[tuple[str, str]],
    *,
    title: str,
    notes: Sequence[str] = (),
) -> str:
    """``report.md``: settings, the per-robot table, track events, notes and figures."""
    headers, rows = summary_rows(summary)
    nis_dof = (summary.get("team") or {}).get("nis_dof")  # 0 or absent: no NIS in the window
    common = (
        f": χ²({nis_dof}, 0.95) = {chi2_upper(nis_dof, 0.95):.2f} for the most common here"
        if nis_dof
        else ""
    )
    lines = [f"# {title}", ""]
    for key in (
        "scenario",
        "seed",
        "runs",
        "filter",
        "init",
        "yaw_bank_components",
        "keep_window_s",
        "gate_probability",
        "settle_s",
    ):
        if key in summary:  # a setting of None is one that is off (no gate)
            lines.append(f"- **{key}**: {'off' if summary[key] is None else summary[key]}")
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
        "(NIS) values above χ²(4, 0.95) = 9.49 (each NIS against χ² of its reading's "
        f"dimension{common}), and its run-averaged "
        "NEES inside the 95 % band about 95 % of the time. Samples of one run are correlated "
        "in time, so these shares fluctuate more than independent draws would: the NEES "
        "share's 95 % interval is by cluster means (each independent run one cluster; one "
        "run's steady-state span cut into 10 blocks, each a cluster), and its verdict says "
        "whether it lies wholly above the 5 % of a consistent filter (over-confident), wholly "
        "below (conservative), holds 5 % and reaches no higher than 10 %, twice it, the share "
        "seed 000 calls acceptable (consistent), or holds 5 % but reaches above 10 % "
        "(inconclusive: too wide to tell a consistent filter from one that leaves more than "
        "10 % beyond; not rejected, not shown consistent either). The run-averaged NEES's "
        "verdict is over-confident (conservative) when the share of times above (below) the "
        "band is more than the 2.5 % a consistent filter leaves there by more than its 95 % "
        "interval allows (batch means over the times), else consistent (not rejected: the "
        "10 % margin is not applied here, since ten blocks of times would leave most "
        "consistent filters inconclusive); it needs two runs or more. "
        "*Blocks short*: the blocks of times last less "
        "than ten correlation times of the values they hold, where batch means alone would "
        "give too narrow an interval; it is then widened to hold Clopper–Pearson's interval "
        "for the effective sample size that correlation time leaves "
        "(`relloc.metrics.consistency`).",
        "",
        "## Spread over runs and convergence from the unknown start",
        "",
        markdown_table(*spread_rows(summary)),
        "",
        "RMSE per run (steady state): mean ± std (ddof 1) over the runs and the interval "
        "holding the middle 95 % of the per-run values (2.5–97.5 percentiles). Convergence: "
        "time and updates from a track's first record until every state's error stays "
        f"inside ({', '.join(f'{v:g}' for v in CONVERGENCE_THRESHOLDS)}) (x, y, z in m, φ in "
        "rad) for good, median and maximum over the runs that converged.",
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
    not_used = summary.get("rows_not_used") or {}
    notes = [*notes, *not_used_note(not_used)]
    if notes:
        lines += ["", "## Notes", ""] + [f"- {n}" for n in notes]
    lines += ["", "## Figures", ""]
    for name, caption in figures:
        lines.append(figure_md(name, caption))
    return "\n".join(lines)


def not_used_note(not_used: Mapping[str, int]) -> list[str]:
    """report.md's line for ``rows_not_used`` (none when every reading was used)."""
    if not any(not_used.values()):
        return []
    reasons = ", ".join(f"{n} {why}" for why, n in sorted(not_used.items()) if n)
    return [f"Readings the trackers did not use, over all runs, by reason: {reasons}."]


def write_team_report(
    out_dir: Path,
    summary: Mapping[str, Any],
    results: Sequence[RunResult],
    *,
    title: str = "relloc run",
    arena: tuple[tuple[float, float], tuple[float, float]] | None = None,
    notes: Sequence[str] = (),
    plots: bool = True,
    views: Mapping[str, tuple[float, float]] | None = None,
) -> list[Path]:
    """Write ``summary.json``, the figures (unless ``plots`` is false) and ``report.md`` into
    ``out_dir``; returns every file written, in that order."""
    out = prepare_out_dir(out_dir)
    written = [write_summary(out, summary)]
    figures = (
        write_figures(
            out,
            results,
            settle_s=float(summary["settle_s"]),
            record_rate_hz=float(summary["record_rate_hz"]),
            arena=arena,
            views=views,
        )
        if plots
        else []
    )
    if not plots:
        notes = [*notes, "Figures were not drawn (--no-plots, or matplotlib is not installed)."]
    written.append(write_report(out, report_markdown(summary, figures, title=title, notes=notes)))
    return [*written, *(out / name for name, _ in figures)]


def tracker_meta(tracker: TrackManagerSettings) -> dict[str, Any]:
    """The track managers' settings, as ``summary.json`` states them."""
    return {
        "filter": tracker.filter,
        "init": tracker.init.name,
        "keep_window_s": tracker.keep_window_s,
        "yaw_bank_components": tracker.yaw_bank.n_components if tracker.yaw_bank else 0,
        "pseudo_linear_covariance": tracker.pseudo_linear_covariance,
        "gate_probability": tracker.gate_probability,
    }


def scenario_meta(
    scenario: Scenario, *, seed: int, tracker: TrackManagerSettings
) -> dict[str, Any]:
    """The settings part of ``summary.json`` for a simulated scenario."""
    observers = [r for r in scenario.robots if r.sensor is not None]
    return {
        "experiment": "run",
        "scenario": scenario.name,
        "seed": seed,
        **tracker_meta(tracker),
        "duration_s": scenario.duration_s,
        "propagation_rate_hz": scenario.propagation_rate_hz,
        "odometry_sigma": {r.name: list(r.odometry.sigma_for(r.kind)) for r in scenario.robots},
        "sensor_sigma": {r.name: list(r.sensor.sigma) for r in observers if r.sensor},
        "sensor_rate_hz": {r.name: r.sensor.rate_hz for r in observers if r.sensor},
    }
