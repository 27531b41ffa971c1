"""``relloc reproduce wanasinghe2014``: seed 000 (Wanasinghe, Mann & Gosine, J. Intell. Robot.
Syst. 2014, "Relative localization approach for combined aerial and ground robotic system").

What is run (run counts: the paper's where it gives one)
--------------------------------------------------------
* ``runs`` (default 20, the paper's §5 count) Monte-Carlo draws of the built-in default team
  (:func:`relloc.sim.scenario.default_scenario`), each running every simulation filter at once
  (:mod:`relloc.experiments.wanasinghe2014_sim`): the accuracy PLKF of the four observed robots
  and Table 1 (13 initial guesses per case — the paper's count — for PLKF, TEKF and relloc's
  yaw bank) for the aerial robot 2 m above the observer;
* the odometry-noise sweep: ``sweep_runs`` (4) draws per noise scale (×1, ×2, ×4, ×8 of the
  scenario's σ) on a 30 s version of the team — the sweep is ours, not the paper's;
* ``replay_runs`` (5) sensor-noise draws of the MRCLAM replay of Tables 3–4
  (:mod:`relloc.experiments.wanasinghe2014_mrclam`). The paper reports one recorded run; one
  draw of sensor noise is a noisy statistic, five are a compromise with the run time.

Each draw runs all its filters of the observing robot in one
:class:`~relloc.estimators.relative_batch.RelativeFilterBatch` through
:func:`relloc.pipeline.replay.replay` and scores each at its own updates with
:func:`relloc.pipeline.evaluation.evaluate` (:mod:`relloc.experiments.wanasinghe2014_filters`);
the pooled RMSE, ±3σ containment, ANEES and % NEES/NIS beyond their bounds are
:func:`relloc.pipeline.evaluation.accuracy_and_consistency`; Table 1 (updates to converge of
the RMSE over draws), Table 3 (RMSE over draws per instant), the radial bias and the PCRLB
ratios are built here on those evaluations. The paper's numbers and the issue's targets are in
:mod:`relloc.experiments.wanasinghe2014_paper`; the figures and report.md, written from the
summary, in :mod:`relloc.experiments.wanasinghe2014_report`.

``--runs N`` sets the team draws to N and the sweep and replay draws to ``min(N, 4)`` and
``min(N, 5)``; ``--dataset D`` replays another MRCLAM-layout folder and ``--pair A,B``
robot ``A`` observing robot ``B`` of it (default ``1,3``; many pairs of one run, each with its
bound: :mod:`relloc.experiments.wanasinghe2014_pairs`). Every Monte-Carlo loop goes
through :func:`relloc.pipeline.montecarlo.run_monte_carlo` with ``--executor``; seeds: team
``S``, replay ``S + 1``, sweep level ``i`` ``S + 2 + i``, the replay's noise-inflation fit on
the calibration window the next one (``S`` = ``--seed``).

summary.json keys
-----------------
``experiment``, ``seed``, ``runs``, ``replay_runs``, ``sweep_runs``, ``seeds`` (``team``,
``replay``, ``sweep``: one per scale, ``replay_noise_inflation``; as above);
``accuracy[robot]`` (``aerial1``, ``aerial2``, ``ground1``, ``ground2``): steady-state (t ≥ 10
s) position RMSE (3-D, m), yaw RMSE (rad), RMSE per state ``x, y, z, phi`` (``position_rmse_m``,
``yaw_rmse_rad``, ``rmse``); over every update, the fraction of
updates with the error inside ±3σ per state (``inside_3sigma``, 0–1), ANEES (``anees``), the NEES
averaged over the independent draws at each update against the 95 % band of such a mean
(``run_averaged_nees``: :func:`relloc.metrics.run_average_band`'s keys, ``in_band_percent``
the % of instants inside, ``band``, ``runs`` the draws; null with one draw), % NEES beyond
χ²(4, 0.95) and % NIS beyond χ²(3, 0.95) (``nees_percent_beyond``, ``nis_percent_beyond``);
``updates`` (of one draw) and ``paper`` (``position_rmse_m`` [0.05, 0.1] m, ``yaw_rmse_rad``
[0.075, 0.1] rad);
``odometry_noise``: the σ used by the team (``team``: robot → ``sigma_v``, ``sigma_vz`` (m/s),
``sigma_w`` (rad/s), per 100 Hz step as ``team_note`` says), the sweep (``sweep``: one entry per
scale, ``scale``, the observer's scaled ``sigma_v`` and ``sigma_w``, and ``position_rmse_m`` /
``yaw_rmse_rad`` robot → RMSE after min(10 s, a third of the run) of the
``sweep_duration_s`` (s) runs), the σ fitted for the replay (``replay_fit[odometry]`` with
``observer`` and ``observed``, each a :class:`relloc.calibration.odometry.OdometryNoiseFit`:
``sigma_v``, ``sigma_lateral``, ``sigma_w``, ``bias_v``, ``bias_w``, ``rate_hz``, ``window_s``,
``n_windows`` and its ``calibration_window``; before the noise inflation, which multiplies the
calibrated and truth-velocity σ by ``noise_inflation.k``) and the calibration of the
calibrated replay (``replay_calibration``: ``calibration_window``, ``latency_s``,
``time_constant_s``, ``scale_v`` and ``scale_w`` (robot of the pair → scale), and
``noise_inflation``, the factor on σ fitted on the calibration window with what was tried:
``k``, ``met``, ``target_percent``, ``tried`` (``k`` and ``yaw_percent_beyond`` per factor),
``samples_per_factor``, the replayed ``stretches`` of ``stretches_in_window``,
``draws_per_stretch``, ``seed``) and of the truth-velocity replay
(``replay_truth_velocity``: its ``calibration_window`` and ``noise_inflation``);
``table1[case][filter][rule][state] = {mean, median, worst}`` (updates to converge over the
guesses) for case2–4, PLKF/TEKF, rules
``paper_rule`` (Eq. 32) and ``fixed`` (0.05 m, 0.1 rad), plus ``table1[case][filter]["paper"]``
(state → the paper's count);
a guess that never converges counts as (updates + 1) and is counted in
``table1_not_converged[case][filter][rule][state]``; ``table1_thresholds[filter][rule][state]``
(m, rad); ``table1_best[case][rule][state]`` (the yaw bank; case 3 has a known yaw, where the
bank is the PLKF; ``method`` says which, ``not_converged`` counts as in
``table1_not_converged``, absent in case 3),
``table1_best[case]["speedup_vs_plkf"][rule][state]`` (the PLKF's mean over the bank's) and
``table1_best["acceptance"]`` (``case4_fixed_phi_worst`` with ``case4_fixed_phi_worst_le_12``,
``case4_paper_rule_phi_mean``, ``case4_plkf_paper_rule_phi_mean``, ``case4_paper_rule_ok``:
the bank's mean ≤ 12 or ≤ a third of the PLKF's);
``table1_readings``: ``readings`` (reading → what it counts) and, per filter (``PLKF``,
``TEKF``), case 4, φ, the count under each reading of the paper's set-up
(:data:`~relloc.experiments.wanasinghe2014_paper.TABLE1_READINGS`: ``stays_below``,
``first_below``, ``pooled_guesses``, ``yaw_within_half_pi``) with ``guesses_within_half_pi``
of the ``guesses``, beside the paper's (``paper``);
``table3[odometry][case][state] = {rmse_mean, rmse_std, rmse_per_draw, paper_rmse, paper_std}``
(PLKF, MRCLAM replay, steady state t ≥ 40 s of the window; ``rmse_mean`` and ``rmse_std``: the
mean and std over the steady-state updates of the RMSE over draws; ``rmse_per_draw``: each
draw's RMSE over its steady state; ``odometry`` ``calibrated``, ``raw`` or
``truth_velocity`` — the last a diagnostic driven by the ground truth's own velocities, which no
robot has, described in ``odometry_kinds``: odometry → text) and
``table3_best`` (the same for the yaw bank started from the same pose);
``replay_pcrlb[odometry][case][state]``: √PCRLB of the replay's own model, RMS over the steady
state (:func:`relloc.experiments.wanasinghe2014_mrclam.replay_pcrlb`; ``replay_targets`` carries
the calibrated φ bound as ``yaw_bound_rad``);
``table4[odometry][case]``, steady state: % NEES beyond χ²(4, 0.95) with the paper's value
(``nees_percent_beyond``, ``paper_nees_percent_beyond``; ``nees_beyond_interval`` its 95 %
interval by cluster means over the draws and over time, with the verdict: over-confident,
conservative, consistent or inconclusive, :func:`relloc.metrics.consistency.share_verdict`), %
NIS beyond
χ²(3, 0.95) (``nis_percent_beyond``), ANEES (``anees``), the run-averaged NEES against its band
(``run_averaged_nees``, null with one draw), max log10 conditioning of P, R, S over every
update (``max_conditioning``: ``P``, ``R``, ``S``; the paper's bound
``paper_max_conditioning_below``), the NEES ``samples``, and the same for the yaw bank under
``["yaw_bank"]`` (without the paper's values); ``table3``,
``table3_best`` and ``table4`` also carry ``windows`` (``calibration``: where the calibrated
odometry was fitted, ``scored``: the replayed window, disjoint; ``start_s``, ``end_s``,
``source``); ``replay_targets[case]``: the
issue's targets and whether each is met: calibrated yaw RMSE ≤ 0.10 rad (``yaw_rmse_rad``,
``yaw_ok``), NEES beyond ≤ 10 % (``nees_percent_beyond``, ``nees_ok``), position no worse than
raw (``position_rmse_m`` and ``raw_position_rmse_m``, the mean of the x, y, z ``rmse_mean``;
``position_ok``), with the calibrated √PCRLB of φ (``yaw_bound_rad``) and
whether it is within the yaw target (``yaw_bound_ok``);
``turn_rate_residual``: the calibrated commands' turn-rate residual against the ground truth
(:mod:`relloc.calibration.turn_rate`, rad/s) per robot of the pair (by id: ``"1"`` and ``"3"``
for the default pair) and for the relative yaw (``relative``; the top-level ``relative`` says
which difference)
(``residual[who][window][model]``, windows ``calibration`` and ``scored`` (``windows``), models
``calibrated`` — the headline's response — and ``fir`` — the best linear filter of the commands
fitted on the calibration window, summarised per robot under ``fir``: ``turn_rate_taps``,
``turn_rate_lags_s`` (first and last), ``speed_taps``, ``dc_gain``, ``centroid_lag_s``,
``speed_gain_rad_per_m``, ``constant_rad_s``, ``samples``, ``calibration_window``): ``mean``,
``std``, ``block_std`` the std of its ``block_s`` means (over ``blocks`` full blocks of
``samples``) and the yaw random walk ``σ_B √(B L)`` (``yaw_random_walk_rad``, the
``yaw_random_walk_formula``) over the steady-state span ``yaw_random_walk_span_s``;
``bias_comparison[case][filter]``: steady-state radial bias (``radial_bias_m``),
``position_rmse_m``, ``yaw_rmse_rad`` and % NEES beyond χ²(4, 0.95) (``nees_percent_beyond``)
of PLKF, BC-PLKF (noisy cases 2 and 4), TEKF and the yaw bank on the calibrated replay;
``replay``: ``source``, ``dataset``, ``observer``, ``observed``, ``observed_height_m``,
``window_s`` (the scored window's ends, s), ``steady_state_after_s``, the pair's horizontal range
in the steady state (``steady_state_range_m``: ``mean``, ``max``), skipped epochs
(``epochs_skipped_in_groundtruth_gaps``: case → count), loader report (``loader``:
``n_skipped``, ``skipped_by_reason``); ``pcrlb_ratio[robot][state]``:
RMSE / √PCRLB (steady state) from :mod:`relloc.observability.pcrlb`. The run time is in
report.md only (the summary is the same whatever the executor).
"""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from relloc.core.checks import count, number, positive
from relloc.datasets.paths import default_mrclam_dataset
from relloc.errors import ConfigError
from relloc.estimators.initialisation import known_pose
from relloc.experiments.registry import ReproduceArgs
from relloc.experiments.wanasinghe2014_mrclam import (
    TABLE2,
    ReplayData,
    ReplaySettings,
    ReplayTrack,
    prepare_replays,
    replay_filters,
    replay_pcrlb,
    replay_task,
)
from relloc.experiments.wanasinghe2014_paper import (
    PAPER_ACCURACY,
    PAPER_RUNS,
    PAPER_TABLE1,
    PAPER_TABLE3,
    PAPER_TABLE4,
    RULES,
    STATES,
    TABLE1_READINGS,
    TARGET_NEES_PERCENT,
    TARGET_YAW_RMSE_RAD,
)
from relloc.experiments.wanasinghe2014_report import build_report, make_figures
from relloc.experiments.wanasinghe2014_sim import (
    SimSettings,
    accuracy_run,
    sweep_task,
    team_task,
    true_pair_inputs,
)
from relloc.metrics.convergence import FIXED_THRESHOLDS, paper_thresholds, updates_to_converge
from relloc.metrics.errors import rmse
from relloc.models.motion import VelocityNoise
from relloc.observability.pcrlb import pcrlb_ratio, relative_pair_pcrlb
from relloc.pipeline.evaluation import (
    SeriesEvaluation,
    accuracy_and_consistency,
    nees_band_check,
)
from relloc.pipeline.export import ExportRequest, export_estimates
from relloc.pipeline.montecarlo import run_monte_carlo, spawn_seeds
from relloc.pipeline.output import (
    prepare_out_dir,
    write_report,
    write_summary,
)

Array = NDArray[np.float64]


#: What ``--mcap``/``--tum`` write (:func:`relloc.experiments.registry.exported_run`).
EXPORTED_RUN = (
    "the accuracy PLKF of every observed robot by the observer, beliefs at its measurement "
    "times (the MRCLAM replay and Table-1 filters are not exported)"
)


@dataclass(frozen=True, kw_only=True)
class Wanasinghe2014Config:
    """Run counts and settings of the reproduction (module docstring gives the defaults' why)."""

    runs: int = PAPER_RUNS
    replay_runs: int = 5
    sweep_runs: int = 4
    sweep_scales: tuple[float, ...] = (1.0, 2.0, 4.0, 8.0)
    sweep_duration_s: float = 30.0
    steady_state_s: float = 10.0
    replay_steady_state_s: float = 40.0
    sim: SimSettings = field(default_factory=SimSettings)
    replay: ReplaySettings = field(
        default_factory=lambda: ReplaySettings(dataset=default_mrclam_dataset())
    )

    def __post_init__(self) -> None:
        for name in ("runs", "replay_runs", "sweep_runs"):
            count(getattr(self, name), name)
        if not self.sweep_scales:
            raise ConfigError("sweep_scales: at least one scale")
        for scale in self.sweep_scales:
            positive(scale, "sweep_scales")
        duration = self.sim.scenario.duration_s
        number(self.steady_state_s, "steady_state_s", low=0.0, high=duration, open_high=True)
        positive(self.sweep_duration_s, "sweep_duration_s")
        number(
            self.replay_steady_state_s,
            "replay_steady_state_s",
            low=0.0,
            high=self.replay.duration_s,
            open_high=True,
        )

    @classmethod
    def from_args(cls, args: ReproduceArgs) -> Wanasinghe2014Config:
        """Defaults, with ``--runs``, ``--dataset`` and ``--pair`` applied."""
        base = cls()
        changes: dict[str, Any] = {}
        if args.runs is not None:
            changes.update(
                runs=args.runs,
                replay_runs=min(args.runs, base.replay_runs),
                sweep_runs=min(args.runs, base.sweep_runs),
            )
        replay: dict[str, Any] = {}
        if args.dataset is not None:
            replay["dataset"] = Path(args.dataset)
        if args.pairs is not None:
            if len(args.pairs) != 1:
                raise ConfigError(
                    f"--pair: wanasinghe2014 replays one pair, got {len(args.pairs)}; "
                    "relloc reproduce wanasinghe2014-pairs replays several"
                )
            replay["observer"], replay["observed"] = args.pairs[0]
        if replay:
            changes["replay"] = dataclasses.replace(base.replay, **replay)
        return dataclasses.replace(base, **changes)


def reproduce(args: ReproduceArgs) -> dict[str, Any]:
    """Entry point of ``relloc reproduce wanasinghe2014`` (see module docstring)."""
    return run_reproduction(
        Wanasinghe2014Config.from_args(args),
        args.out_dir,
        seed=args.master_seed,
        executor=args.executor,
        quiet=args.quiet,
        export=args.export,
    )


# ---------------------------------------------------------------------------------------------
# Running
# ---------------------------------------------------------------------------------------------


def inflation_seed(seed: int, config: Wanasinghe2014Config) -> int:
    """Seed of the noise-inflation draws on the calibration window: the next after the
    sweep's (team ``S``, replay ``S + 1``, sweep ``S + 2 …``)."""
    return seed + 2 + len(config.sweep_scales)


def run_reproduction(
    config: Wanasinghe2014Config,
    out_dir: Path,
    *,
    seed: int,
    executor: str | None = None,
    quiet: bool = False,
    export: ExportRequest | None = None,
) -> dict[str, Any]:
    """Run everything, write summary.json, report.md and figures; return the summary (and,
    with ``export``, the :data:`EXPORTED_RUN` as MCAP/TUM files)."""
    started = time.perf_counter()
    out = prepare_out_dir(out_dir)
    data = prepare_replays(  # fail early on a bad --dataset
        config.replay,
        steady_state_s=config.replay_steady_state_s,
        seed=inflation_seed(seed, config),
        executor=executor,
        quiet=quiet,
    )
    team = run_monte_carlo(
        team_task,
        config.runs,
        seed,
        executor=executor,
        task_args=(config.sim,),
        description="seed 000: team (accuracy, Table 1)",
        quiet=quiet,
    )
    replay = run_replays(config, data, seed, executor=executor, quiet=quiet)
    sweep = []
    for i, scale in enumerate(config.sweep_scales):
        settings = dataclasses.replace(
            config.sim,
            scenario=dataclasses.replace(config.sim.scenario, duration_s=config.sweep_duration_s),
            odometry_scale=scale,
            table1=False,
        )
        sweep.append(
            run_monte_carlo(
                sweep_task,
                config.sweep_runs,
                seed + 2 + i,
                executor=executor,
                task_args=(settings,),
                description=f"seed 000: odometry-noise sweep x{scale:g}",
                quiet=quiet,
            )
        )

    summary: dict[str, Any] = {
        "experiment": "wanasinghe2014",
        "seed": seed,
        "runs": config.runs,
        "replay_runs": config.replay_runs,
        "sweep_runs": config.sweep_runs,
        "seeds": {
            "team": seed,
            "replay": seed + 1,
            "sweep": [seed + 2 + i for i in range(len(config.sweep_scales))],
            "replay_noise_inflation": inflation_seed(seed, config),
        },
    }
    accuracy, acc_series = accuracy_summary(team, config)
    summary["accuracy"] = accuracy
    summary["odometry_noise"] = odometry_noise_summary(config, sweep, data)
    table1, not_converged, thresholds, rmse_curves = table1_summary(team)
    summary["table1"] = table1
    summary["table1_not_converged"] = not_converged
    summary["table1_thresholds"] = thresholds
    summary["table1_best"] = table1_best_summary(team, table1, thresholds)
    summary["table1_readings"] = table1_readings(team, thresholds)
    replay_part, replay_series = replay_results(config, data, replay)
    summary.update(replay_part)
    ratios, bounds = pcrlb_summary(config, acc_series)
    summary["pcrlb_ratio"] = ratios
    if export is not None:
        estimates, recording = accuracy_run(spawn_seeds(seed, config.runs)[0], config.sim)
        summary["export"] = export_estimates(
            export,
            estimates,
            recording,
            run=f"team draw 0 of {config.runs} (seed {seed}): {EXPORTED_RUN}",
            settle_s=config.steady_state_s,
        )
    figures = make_figures(
        out, config, team, acc_series, rmse_curves, thresholds, replay_series, bounds, summary
    )
    write_summary(out, summary)
    write_report(out, build_report(summary, figures, elapsed_s=time.perf_counter() - started))
    return summary


# ---------------------------------------------------------------------------------------------
# Accuracy (§5, Figs. 3–4) and the odometry-noise sweep
# ---------------------------------------------------------------------------------------------


#: The per-update series of a filter stacked over draws (figures, PCRLB): name →
#: :class:`~relloc.pipeline.evaluation.SeriesEvaluation` field.
SERIES_FIELDS: dict[str, str] = {
    "errors": "error",
    "sigma": "sigma",
    "nees": "nees",
    "nis": "nis",
    "cond_p": "cond_p",
    "cond_r": "cond_r",
    "cond_s": "cond_s",
}


def stacked_series(runs: list[SeriesEvaluation], t: Array) -> dict[str, Array]:
    """``{"t": t, name: (draws, updates, ...)}`` of one filter over its draws."""
    out = {"t": t}
    for name, attr in SERIES_FIELDS.items():
        out[name] = np.stack([getattr(r, attr) for r in runs])
    return out


def accuracy_summary(
    team: list[dict[str, Any]], config: Wanasinghe2014Config
) -> tuple[dict[str, Any], dict[str, dict[str, Array]]]:
    """Per observed robot: steady-state RMSE; ±3σ containment, ANEES, NEES and NIS beyond
    their bounds over every update; and the series stacked over draws."""
    out: dict[str, Any] = {}
    series: dict[str, dict[str, Array]] = {}
    for robot in config.sim.targets:
        runs = [run["accuracy"][robot] for run in team]
        steady = accuracy_and_consistency(runs, settle_s=config.steady_state_s)
        every = accuracy_and_consistency(runs, settle_s=0.0)
        out[robot] = {
            "position_rmse_m": steady["position_rmse_m"],
            "yaw_rmse_rad": steady["yaw_rmse_rad"],
            "rmse": steady["rmse"],
            "inside_3sigma": {k: v / 100.0 for k, v in every["within_3sigma_percent"].items()},
            "anees": every["anees"],
            "run_averaged_nees": run_averaged_band(runs, 0.0),
            "nees_percent_beyond": every["nees_percent_beyond"],
            "nis_percent_beyond": every["nis_percent_beyond"],
            "updates": int(runs[0].t.size),
            "paper": {k: list(v) for k, v in PAPER_ACCURACY.items()},
        }
        series[robot] = stacked_series(runs, runs[0].t)
    return out, series


def odometry_noise_summary(
    config: Wanasinghe2014Config,
    sweep: list[list[dict[str, SeriesEvaluation]]],
    data: dict[str, ReplayData],
) -> dict[str, Any]:
    """The σ the team uses, the sweep's RMSE per scale, and the σ fitted for the replay."""
    scenario = config.sim.scenario
    used = {
        r.name: {
            "sigma_v": r.odometry.sigma_v,
            "sigma_vz": r.odometry.sigma_vz,
            "sigma_w": r.odometry.sigma_w,
        }
        for r in scenario.robots
    }
    steady = min(config.steady_state_s, config.sweep_duration_s / 3.0)
    observer = used[config.sim.observer]
    rows = []
    for scale, runs in zip(config.sweep_scales, sweep, strict=True):
        row: dict[str, Any] = {
            "scale": scale,
            "sigma_v": observer["sigma_v"] * scale,
            "sigma_w": observer["sigma_w"] * scale,
            "position_rmse_m": {},
            "yaw_rmse_rad": {},
        }
        for robot in config.sim.targets:
            pooled = accuracy_and_consistency([run[robot] for run in runs], settle_s=steady)
            row["position_rmse_m"][robot] = pooled["position_rmse_m"]
            row["yaw_rmse_rad"][robot] = pooled["yaw_rmse_rad"]
        rows.append(row)
    return {
        "team": used,
        "team_note": "white noise per 100 Hz propagation step on each reported body velocity",
        "sweep": rows,
        "sweep_duration_s": config.sweep_duration_s,
        "replay_fit": {
            kind: {label: fit.to_dict() for label, fit in d.fits.items()}
            for kind, d in data.items()
        },
        "replay_calibration": _calibration_dict(data["calibrated"]),
        "replay_truth_velocity": _truth_velocity_dict(data["truth_velocity"]),
    }


# ---------------------------------------------------------------------------------------------
# Table 1 (§5.1) and the yaw bank
# ---------------------------------------------------------------------------------------------


def _rmse_curves(team: list[dict[str, Any]], case: str, filt: str) -> Array:
    """RMSE over runs per guess and update: ``(guesses, updates, 4)``."""
    E = np.stack([run["table1"][case][filt] for run in team])  # (runs, guesses, updates, 4)
    return rmse(E, axis=0)


def _convergence_stats(curves: Array, thresholds: Array) -> tuple[dict[str, Any], dict[str, int]]:
    """Updates to converge per guess and state → mean / median / worst (censored at M + 1)."""
    n_upd = curves.shape[1]
    stats: dict[str, Any] = {}
    censored: dict[str, int] = {}
    for i, state in enumerate(STATES):
        counts = []
        missed = 0
        for g in range(curves.shape[0]):
            k = updates_to_converge(curves[g, :, i], float(thresholds[i]))
            if k is None:
                missed += 1
                k = n_upd + 1
            counts.append(k)
        c = np.asarray(counts, dtype=float)
        stats[state] = {
            "mean": float(c.mean()),
            "median": float(np.median(c)),
            "worst": int(c.max()),
        }
        censored[state] = missed
    return stats, censored


def table1_summary(
    team: list[dict[str, Any]],
) -> tuple[dict[str, Any], dict[str, Any], dict[str, Any], dict[str, dict[str, Array]]]:
    """Table 1 for PLKF and TEKF, both rules; thresholds; RMSE curves (for figures)."""
    thresholds: dict[str, Any] = {}
    curves: dict[str, dict[str, Array]] = {}
    for filt in ("PLKF", "TEKF"):
        known = _rmse_curves(team, "case1", filt)[0]
        thresholds[filt] = {
            "paper_rule": dict(zip(STATES, paper_thresholds(known).tolist(), strict=True)),
            "fixed": dict(zip(STATES, FIXED_THRESHOLDS, strict=True)),
        }
    table: dict[str, Any] = {}
    missed: dict[str, Any] = {}
    for case in ("case2", "case3", "case4"):
        table[case], missed[case] = {}, {}
        curves[case] = {}
        for filt in ("PLKF", "TEKF"):
            c = _rmse_curves(team, case, filt)
            curves[case][filt] = c
            table[case][filt], missed[case][filt] = {}, {}
            for rule in RULES:
                th = np.array([thresholds[filt][rule][s] for s in STATES])
                table[case][filt][rule], missed[case][filt][rule] = _convergence_stats(c, th)
            table[case][filt]["paper"] = PAPER_TABLE1[case][filt]
        if "bank" in team[0]["table1"][case]:
            curves[case]["bank"] = _rmse_curves(team, case, "bank")
    return table, missed, thresholds, curves


def table1_best_summary(
    team: list[dict[str, Any]], table1: dict[str, Any], thresholds: dict[str, Any]
) -> dict[str, Any]:
    """The yaw bank on the same draws and guesses (its thresholds are the PLKF's: it is one)."""
    best: dict[str, Any] = {}
    for case in ("case2", "case3", "case4"):
        if "bank" in team[0]["table1"][case]:
            c = _rmse_curves(team, case, "bank")
            entry: dict[str, Any] = {}
            not_conv: dict[str, Any] = {}
            for rule in RULES:
                th = np.array([thresholds["PLKF"][rule][s] for s in STATES])
                entry[rule], not_conv[rule] = _convergence_stats(c, th)
            entry["not_converged"] = not_conv
            entry["method"] = "yaw bank (Gaussian sum over relative yaw, PLKF components)"
        else:
            entry = {rule: table1[case]["PLKF"][rule] for rule in RULES}
            entry["method"] = "PLKF (yaw known: the bank is a single PLKF)"
        entry["speedup_vs_plkf"] = {
            rule: {
                s: table1[case]["PLKF"][rule][s]["mean"] / entry[rule][s]["mean"] for s in STATES
            }
            for rule in RULES
        }
        best[case] = entry
    c4 = best["case4"]
    plkf_mean = table1["case4"]["PLKF"]["paper_rule"]["phi"]["mean"]
    best["acceptance"] = {
        "case4_fixed_phi_worst": c4["fixed"]["phi"]["worst"],
        "case4_fixed_phi_worst_le_12": c4["fixed"]["phi"]["worst"] <= 12,
        "case4_paper_rule_phi_mean": c4["paper_rule"]["phi"]["mean"],
        "case4_plkf_paper_rule_phi_mean": plkf_mean,
        "case4_paper_rule_ok": c4["paper_rule"]["phi"]["mean"] <= 12
        or c4["paper_rule"]["phi"]["mean"] <= plkf_mean / 3.0,
    }
    return best


def _first_below(series: Array, threshold: float) -> int | None:
    """Updates until ``|series|`` first dips below ``threshold`` (``None``: never)."""
    below = np.flatnonzero(np.abs(series) < threshold)
    return int(below[0]) + 1 if below.size else None


def table1_readings(team: list[dict[str, Any]], thresholds: dict[str, Any]) -> dict[str, Any]:
    """Case 4, φ, plain PLKF and TEKF: the count under each reading of the paper's set-up
    (:data:`~relloc.experiments.wanasinghe2014_paper.TABLE1_READINGS`) beside the paper's, all
    from the same draws and guesses (no noise changed). A count that never settles is
    (updates + 1), as in Table 1."""
    out: dict[str, Any] = {"readings": TABLE1_READINGS}
    for filt in ("PLKF", "TEKF"):
        E = np.stack([run["table1"]["case4"][filt] for run in team])[..., 3]  # (runs, g, K)
        n = E.shape[-1]
        th = float(thresholds[filt]["paper_rule"]["phi"])
        curves = rmse(E, axis=0)  # (guesses, updates)

        def count(k: int | None, never: int = n + 1) -> int:
            return never if k is None else k

        stays = np.array([count(updates_to_converge(c, th)) for c in curves], dtype=float)
        first = np.array([count(_first_below(c, th)) for c in curves], dtype=float)
        near = np.mean(np.abs(E[:, :, 0]), axis=0) < math.pi / 2
        pooled = rmse(E.reshape(-1, n), axis=0)
        out[filt] = {
            "stays_below": float(stays.mean()),
            "first_below": float(first.mean()),
            "pooled_guesses": float(count(updates_to_converge(pooled, th))),
            "yaw_within_half_pi": float(stays[near].mean()) if near.any() else float("nan"),
            "guesses_within_half_pi": int(near.sum()),
            "guesses": int(near.size),
            "paper": PAPER_TABLE1["case4"][filt]["phi"],
        }
    return out


# ---------------------------------------------------------------------------------------------
# Tables 3–4 on the MRCLAM replay, bias comparison
# ---------------------------------------------------------------------------------------------


def _table3_entry(E: Array, ss: NDArray[np.bool_], case: str) -> dict[str, Any]:
    """Mean and std over the steady-state updates of the RMSE over draws, per state, and each
    draw's RMSE over its steady-state updates (``rmse_per_draw``: whether one draw dominates)."""
    curve = rmse(E, axis=0)[ss]
    per_draw = rmse(E[:, ss], axis=1)
    return {
        st: {
            "rmse_mean": float(np.nanmean(curve[:, i])),
            "rmse_std": float(np.nanstd(curve[:, i])),
            "rmse_per_draw": [float(v) for v in per_draw[:, i]],
            "paper_rmse": PAPER_TABLE3[case][st][0],
            "paper_std": PAPER_TABLE3[case][st][1],
        }
        for i, st in enumerate(STATES)
    }


def _consistency_entry(runs: list[SeriesEvaluation], settle_s: float) -> dict[str, Any]:
    """Steady-state % NEES beyond χ²(4, 0.95), % NIS beyond χ²(3, 0.95) and ANEES; max
    conditioning of P, R and S over every update."""
    pooled = accuracy_and_consistency(
        runs, settle_s=settle_s, runs=range(len(runs)), shared_recording=True
    )
    return {
        "nees_percent_beyond": pooled["nees_percent_beyond"],
        "nees_beyond_interval": pooled["nees_beyond_interval"],
        "nis_percent_beyond": pooled["nis_percent_beyond"],
        "anees": pooled["anees"],
        "max_conditioning": {
            "P": float(max(np.max(r.cond_p) for r in runs)),
            "R": float(max(np.max(r.cond_r) for r in runs)),
            "S": float(max(np.max(r.cond_s) for r in runs)),
        },
        "samples": pooled["samples"],
        "run_averaged_nees": run_averaged_band(runs, settle_s),
    }


def run_averaged_band(runs: list[SeriesEvaluation], settle_s: float) -> dict[str, Any] | None:
    """The NEES averaged over the draws at each update time (t ≥ ``settle_s``) against the
    95 % band of a mean of that many independent χ²(4) values
    (:func:`relloc.pipeline.evaluation.nees_band_check`): the share of instants inside it is
    about 95 % for a consistent filter. ``None`` with fewer than two draws. The updates are on
    one grid; its rate is read from the first draw's update times."""
    if len(runs) < 2 or runs[0].t.size < 2:
        return None
    rate_hz = 1.0 / float(np.median(np.diff(runs[0].t)))
    return nees_band_check(runs, rate_hz=rate_hz, settle_s=settle_s)


def run_replays(
    config: Wanasinghe2014Config,
    data: dict[str, ReplayData],
    seed: int,
    *,
    executor: str | None = None,
    quiet: bool = False,
) -> dict[str, list[dict[str, dict[str, ReplayTrack]]]]:
    """``config.replay_runs`` draws of the replay per odometry kind of ``data``, all with seed
    ``seed + 1``: the same sensor-noise draws and initial poses for every odometry."""
    r = config.replay
    return {
        kind: run_monte_carlo(
            replay_task,
            config.replay_runs,
            seed + 1,
            executor=executor,
            task_args=(replay_data, r),
            description=f"seed 000: MRCLAM replay {r.observer} → {r.observed}, {kind} odometry",
            quiet=quiet,
        )
        for kind, replay_data in data.items()
    }


def replay_results(
    config: Wanasinghe2014Config,
    data: dict[str, ReplayData],
    replay: dict[str, list[dict[str, dict[str, ReplayTrack]]]],
) -> tuple[dict[str, Any], dict[str, dict[str, dict[str, Array]]]]:
    """The summary's replay keys (module docstring: ``table3``, ``table3_best``, ``table4``
    with their ``windows``, ``bias_comparison``, ``replay_pcrlb``, ``replay_targets``,
    ``turn_rate_residual``, ``replay``, ``odometry_kinds``) of :func:`run_replays`' draws, and
    the calibrated replay's series for the figures."""
    windows = replay_windows(data["calibrated"])
    part: dict[str, Any] = {
        key: {"windows": windows} for key in ("table3", "table3_best", "table4")
    }
    replay_series: dict[str, dict[str, dict[str, Array]]] = {}
    for kind, runs in replay.items():
        table3, table3_best, table4, bias, series = replay_summary(runs, config, kind)
        part["table3"][kind] = table3
        part["table3_best"][kind] = table3_best
        part["table4"][kind] = table4
        if kind == "calibrated":
            part["bias_comparison"] = bias
            replay_series = series
    part["replay_pcrlb"] = {
        kind: replay_pcrlb(replay_data, config.replay, config.replay_steady_state_s)
        for kind, replay_data in data.items()
    }
    part["replay_targets"] = replay_targets(part)
    part["turn_rate_residual"] = turn_rate_summary(config, data["calibrated"])
    part["replay"] = replay_info(config, data["calibrated"])
    part["odometry_kinds"] = {kind: ODOMETRY_KIND_NOTES[kind] for kind in data}
    return part, replay_series


def replay_summary(
    replay: list[dict[str, dict[str, ReplayTrack]]],
    config: Wanasinghe2014Config,
    odometry_kind: str,
) -> tuple[dict[str, Any], ...]:
    """Table 3 (PLKF; yaw bank in ``table3_best``), Table 4, bias comparison, series (time
    from the start of the window) of the replay with ``odometry_kind`` odometry."""
    table3: dict[str, Any] = {}
    table3_best: dict[str, Any] = {}
    table4: dict[str, Any] = {}
    bias: dict[str, Any] = {}
    series: dict[str, dict[str, dict[str, Array]]] = {}
    settle = config.replay_steady_state_s
    for case in TABLE2:
        bias[case] = {}
        series[case] = {}
        for filt in replay_filters(case, odometry_kind):
            runs = [run[case][filt].evaluation for run in replay]
            t = runs[0].age
            ss = t >= settle
            stacked = stacked_series(runs, t)
            radial = np.stack([run[case][filt].radial for run in replay])
            series[case][filt] = {**stacked, "radial": radial}
            pooled = accuracy_and_consistency(runs, settle_s=settle)
            bias[case][filt] = {
                "radial_bias_m": float(np.nanmean(radial[:, ss])),
                "position_rmse_m": pooled["position_rmse_m"],
                "yaw_rmse_rad": pooled["yaw_rmse_rad"],
                "nees_percent_beyond": pooled["nees_percent_beyond"],
            }
            if filt == "PLKF":
                table3[case] = _table3_entry(stacked["errors"], ss, case)
                table4[case] = {
                    **_consistency_entry(runs, settle),
                    "paper_nees_percent_beyond": PAPER_TABLE4[case],
                    "paper_max_conditioning_below": 6.0,
                }
            elif filt == "yaw bank":
                table3_best[case] = _table3_entry(stacked["errors"], ss, case)
                table4[case]["yaw_bank"] = _consistency_entry(runs, settle)
    return table3, table3_best, table4, bias, series


def replay_windows(data: ReplayData) -> dict[str, Any]:
    """The calibrated odometry's calibration window and the scored window (disjoint)."""
    assert data.calibration is not None
    return {
        "calibration": data.calibration.calibration_window.to_dict(),
        "scored": data.scored_window.to_dict(),
    }


def _calibration_dict(data: ReplayData) -> dict[str, Any]:
    """The team fit behind the calibrated odometry: window, latency, the pair's scales."""
    fit = data.calibration
    assert fit is not None
    assert data.inflation is not None
    return {
        "calibration_window": fit.calibration_window.to_dict(),
        "noise_inflation": data.inflation.to_dict(),
        "latency_s": fit.latency_s,
        "time_constant_s": fit.time_constant_s,
        "scale_v": {r: sc[0] for r, sc in zip(data.robots, data.pair_scales, strict=True)},
        "scale_w": {r: sc[1] for r, sc in zip(data.robots, data.pair_scales, strict=True)},
    }


#: What each odometry version of the replay is (summary.json ``odometry_kinds``).
ODOMETRY_KIND_NOTES: dict[str, str] = {
    "calibrated": "headline: the recorded commands with latency, lag and scales fitted on the "
    "calibration window",
    "raw": "the recorded commands as they are",
    "truth_velocity": "diagnostic, not a result: the ground truth's own velocities (Vicon "
    "central differences), which no robot has; the floor the filters reach when the odometry "
    "is as good as the ground truth",
}


def _truth_velocity_dict(data: ReplayData) -> dict[str, Any]:
    """Where the truth-velocity noise was fitted and its inflation."""
    assert data.response is not None and data.inflation is not None
    return {
        "calibration_window": data.response.window.to_dict(),
        "noise_inflation": data.inflation.to_dict(),
    }


def turn_rate_summary(config: Wanasinghe2014Config, data: ReplayData) -> dict[str, Any]:
    """The calibrated commands' turn-rate residual (:mod:`relloc.calibration.turn_rate`), its
    yaw random walk over the scored window's steady state ``L = duration − settle``."""
    assert data.turn_rate is not None
    span = data.scored_window.duration_s - config.replay_steady_state_s
    return data.turn_rate.to_dict(span)


def replay_targets(summary: dict[str, Any]) -> dict[str, Any]:
    """Per Table-2 case: the calibrated PLKF's yaw RMSE ≤ 0.10 rad, % NEES beyond χ²(4, 0.95)
    ≤ 10 % and position RMSE (x, y, z mean) no worse than the raw replay's; beside them the
    yaw's √PCRLB of the calibrated model (``yaw_bound_rad``, :func:`replay_pcrlb`) and whether
    it leaves the yaw target reachable (``yaw_bound_ok``)."""
    out: dict[str, Any] = {}
    for case in summary["table3"]["calibrated"]:
        cal, raw = summary["table3"]["calibrated"][case], summary["table3"]["raw"][case]
        yaw = cal["phi"]["rmse_mean"]
        nees = summary["table4"]["calibrated"][case]["nees_percent_beyond"]
        pos = [float(np.mean([t3[st]["rmse_mean"] for st in STATES[:3]])) for t3 in (cal, raw)]
        bound = summary["replay_pcrlb"]["calibrated"][case]["phi"]
        out[case] = {
            "yaw_rmse_rad": yaw,
            "yaw_ok": yaw <= TARGET_YAW_RMSE_RAD,
            "nees_percent_beyond": nees,
            "nees_ok": nees <= TARGET_NEES_PERCENT,
            "position_rmse_m": pos[0],
            "raw_position_rmse_m": pos[1],
            "position_ok": pos[0] <= pos[1],
            "yaw_bound_rad": bound,
            "yaw_bound_ok": bound <= TARGET_YAW_RMSE_RAD,
        }
    return out


def replay_info(config: Wanasinghe2014Config, data: ReplayData) -> dict[str, Any]:
    """Where the replay came from, the pair's horizontal range in the steady state of the
    scored window (mean and largest, from the ground truth at the valid epochs: the lever an
    error of the observer's turn rate acts through) and what the loader skipped."""
    r = config.replay
    steady = data.valid & (data.t >= data.t[0] + config.replay_steady_state_s)
    relative = data.relative_truth(data.t[steady])
    horizontal = np.hypot(relative[:, 0], relative[:, 1])
    return {
        "source": data.source,
        "dataset": str(r.dataset),
        "observer": r.observer,
        "observed": r.observed,
        "observed_height_m": r.height,
        "window_s": [float(data.t[0]), float(data.t[-1])],
        "steady_state_after_s": config.replay_steady_state_s,
        "steady_state_range_m": {
            "mean": float(np.mean(horizontal)),
            "max": float(np.max(horizontal)),
        },
        "epochs_skipped_in_groundtruth_gaps": data.skipped_epochs,
        "loader": {
            "n_skipped": data.load_report["n_skipped"],
            "skipped_by_reason": data.load_report["skipped_by_reason"],
        },
    }


# ---------------------------------------------------------------------------------------------
# PCRLB
# ---------------------------------------------------------------------------------------------


def pcrlb_summary(
    config: Wanasinghe2014Config, acc_series: dict[str, dict[str, Array]]
) -> tuple[dict[str, Any], dict[str, Array]]:
    """RMSE / √PCRLB per observed robot and state, and √diag(PCRLB) at the updates."""
    sim = config.sim
    scenario = sim.scenario
    specs = {r.name: r for r in scenario.robots}
    obs_spec = specs[sim.observer]
    sensor = sim.sensor
    ratios: dict[str, Any] = {}
    bounds: dict[str, Array] = {}
    for robot in sim.targets:
        t, truth, u_l, u_c = true_pair_inputs(sim, robot)
        dt = float(t[1] - t[0])
        series = acc_series[robot]
        steps = np.rint(series["t"] / dt).astype(np.int64)
        mask = np.zeros(t.size, dtype=bool)
        mask[steps] = True
        tgt_spec = specs[robot]
        noise = VelocityNoise(
            observer=obs_spec.odometry.sigma_for(obs_spec.kind),
            observed=tgt_spec.odometry.sigma_for(tgt_spec.kind),
        )
        B = relative_pair_pcrlb(
            truth,
            u_l,
            u_c,
            dt,
            mask,
            sigma_r=sensor.sigma_range,
            sigma_theta=sensor.sigma_azimuth,
            sigma_alpha=sensor.sigma_elevation,
            velocity_noise=noise,
            P0=np.asarray(known_pose(truth[0]).cov),
        )[steps]
        start = int(np.searchsorted(series["t"], config.steady_state_s))
        ratio = pcrlb_ratio(series["errors"], B, start=start)
        ratios[robot] = dict(zip(STATES, np.asarray(ratio).tolist(), strict=True))
        bounds[robot] = np.sqrt(np.diagonal(B, axis1=-2, axis2=-1))
    return ratios, bounds
