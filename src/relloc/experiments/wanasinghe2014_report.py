"""Figures and report.md of ``relloc reproduce wanasinghe2014``
(:mod:`relloc.experiments.wanasinghe2014`): the paper's figures and tables with ours beside,
and the "differences explained" text, written from the numbers of the run (the summary) so that
every sentence states what this run measured.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from relloc.calibration.inflation import search_text
from relloc.experiments.wanasinghe2014_mrclam import TABLE2
from relloc.experiments.wanasinghe2014_paper import (
    PAPER_ACCURACY,
    RULES,
    STATES,
    TABLE1_READINGS,
)
from relloc.metrics.errors import rmse
from relloc.pipeline.output import (
    figure_md,
    fmt,
    interval_text,
    markdown_table,
    save_figure,
    skipped_rows_line,
)

if TYPE_CHECKING:
    from relloc.experiments.wanasinghe2014 import Wanasinghe2014Config

Array = NDArray[np.float64]


def make_figures(
    out: Path,
    config: Wanasinghe2014Config,
    team: list[dict[str, Any]],
    acc: dict[str, dict[str, Array]],
    curves: dict[str, dict[str, Array]],
    thresholds: dict[str, Any],
    replay: dict[str, dict[str, dict[str, Array]]],
    bounds: dict[str, Array],
    summary: dict[str, Any],
) -> dict[str, str]:
    """Draw every figure; returns ``{key: file name}``."""
    from relloc.plotting.consistency import plot_chi2_series, plot_conditioning
    from relloc.plotting.errors import plot_pose_errors_with_bounds, plot_robot_errors
    from relloc.plotting.setup import pyplot
    from relloc.plotting.wanasinghe import (
        plot_bias_comparison,
        plot_convergence_curves,
        plot_noise_sweep,
        plot_rmse_vs_bound,
    )

    plt = pyplot()

    files: dict[str, str] = {}
    targets = config.sim.targets
    aerial = config.sim.table1_target

    # Fig. 3: one aerial robot, error of draw 0 with its ±3σ bounds
    fig, axes = plt.subplots(4, 1, figsize=(8, 8), sharex=True, layout="constrained")
    a = acc[aerial]
    plot_pose_errors_with_bounds(axes, a["t"], a["errors"][0], a["sigma"][0])
    axes[0].set_title(f"{aerial}: PLKF error and ±3σ (draw 0, seed {summary['seed']})")
    files["aerial_error"] = save_figure(fig, out, "fig3_aerial_error_3sigma")

    # Fig. 4: all four robots (draw 0)
    fig, axes = plt.subplots(4, 1, figsize=(8, 8), sharex=True, layout="constrained")
    plot_robot_errors(axes, {r: (acc[r]["t"], acc[r]["errors"][0]) for r in targets})
    axes[0].set_title("PLKF errors of the four observed robots (draw 0)")
    files["all_errors"] = save_figure(fig, out, "fig4_all_robot_errors")

    # Fig. 6: PLKF vs TEKF vs yaw bank from the case-4 guess with the largest initial yaw error
    c4 = team[0]["table1"]["case4"]
    g = int(np.argmax(np.abs(c4["PLKF"][:, 0, 3])))
    t = acc[aerial]["t"]
    fig, axes = plt.subplots(4, 1, figsize=(8, 8), sharex=True, layout="constrained")
    plot_robot_errors(axes, {f: (t, c4[f][g]) for f in ("PLKF", "TEKF", "bank")})
    axes[0].set_title(f"case 4, guess {g}: arbitrary initialisation (draw 0)")
    files["arbitrary_init"] = save_figure(fig, out, "fig6_plkf_vs_tekf_arbitrary_init")

    # Table 1 convergence curves of the yaw
    fig, axes = plt.subplots(1, 2, figsize=(11, 4), sharey=True, layout="constrained")
    for ax, case in zip(axes, ("case2", "case4"), strict=True):
        th = thresholds["PLKF"]["fixed"]["phi"]
        for filt, color in (("TEKF", "tab:red"), ("PLKF", "tab:blue"), ("bank", "tab:green")):
            plot_convergence_curves(
                ax, curves[case][filt][..., 3], threshold=th, label=filt, color=color
            )
        ax.set_title(f"{case}: yaw RMSE per initial guess ({config.runs} draws)")
        ax.legend(fontsize="small")
    axes[0].set_ylabel("φ RMSE (rad)")
    files["convergence"] = save_figure(fig, out, "table1_yaw_convergence")

    # NEES / NIS with χ² bounds: team average over draws, and the replay's case (1) single draw
    fig, axes = plt.subplots(2, 2, figsize=(11, 7), layout="constrained")
    n = config.runs
    plot_chi2_series(axes[0, 0], t, np.nanmean(acc[aerial]["nees"], 0), 4, n_runs=n, label="NEES")
    plot_chi2_series(axes[1, 0], t, np.nanmean(acc[aerial]["nis"], 0), 3, n_runs=n, label="NIS")
    axes[0, 0].set_title(f"{aerial}, simulation, mean of {n} draws")
    r1 = replay["case1"]["PLKF"]
    plot_chi2_series(axes[0, 1], r1["t"], r1["nees"][0], 4, label="NEES")
    plot_chi2_series(axes[1, 1], r1["t"], r1["nis"][0], 3, label="NIS")
    axes[0, 1].set_title("MRCLAM replay, Table-2 case (1), draw 0")
    for ax in axes[1]:
        ax.set_xlabel("time (s)")
    files["nees_nis"] = save_figure(fig, out, "fig10_11_nees_nis")

    # Fig. 12: conditioning of P, R, S on the replay, four Table-2 cases (draw 0)
    fig, axes = plt.subplots(2, 2, figsize=(11, 7), sharey=True, layout="constrained")
    for ax, case in zip(axes.ravel(), TABLE2, strict=True):
        rc = replay[case]["PLKF"]
        plot_conditioning(ax, {m: (rc["t"], rc[f"cond_{m.lower()}"][0]) for m in ("P", "R", "S")})
        ax.set_title(f"Table-2 {case}")
    files["conditioning"] = save_figure(fig, out, "fig12_conditioning")

    # RMSE vs PCRLB
    fig, axes = plt.subplots(4, 1, figsize=(8, 8), sharex=True, layout="constrained")
    plot_rmse_vs_bound(axes, t, rmse(acc[aerial]["errors"], axis=0), bounds[aerial], label=aerial)
    axes[0].set_title(f"{aerial}: PLKF RMSE over {n} draws vs √PCRLB")
    files["pcrlb"] = save_figure(fig, out, "rmse_vs_pcrlb")

    # odometry-noise sweep
    sweep = summary["odometry_noise"]["sweep"]
    fig, ax = plt.subplots(figsize=(7, 4.5), layout="constrained")
    plot_noise_sweep(
        ax,
        [row["sigma_v"] for row in sweep],
        {r: [row["position_rmse_m"][r] for row in sweep] for r in targets},
        paper_band=PAPER_ACCURACY["position_rmse_m"],
    )
    ax.set_title("Position RMSE against the odometry noise σ_v")
    files["sweep"] = save_figure(fig, out, "odometry_noise_sweep")

    # radial bias of PLKF / BC-PLKF / TEKF on the replay
    fig, ax = plt.subplots(figsize=(7, 4), layout="constrained")
    plot_bias_comparison(
        ax,
        {
            c: {f: v["radial_bias_m"] for f, v in d.items()}
            for c, d in summary["bias_comparison"].items()
        },
        ylabel="radial bias (m)",
    )
    ax.set_title("Radial bias of PLKF, BC-PLKF and TEKF on the replay")
    files["bias"] = save_figure(fig, out, "radial_bias")
    return files


def _table3_cells(t3: dict[str, Any]) -> list[str]:
    """Ours and the paper's "RMSE (std)" per state, in the paper's column order φ, x, y, z."""
    cells = []
    for st in ("phi", "x", "y", "z"):
        cells.append(f"{t3[st]['rmse_mean']:.4f} ({t3[st]['rmse_std']:.4f})")
        cells.append(f"{t3[st]['paper_rmse']:.4f} ({t3[st]['paper_std']:.4f})")
    return cells


def _band_cell(band: dict[str, Any] | None) -> str:
    """``in-band % [lo, hi], n draws`` of :func:`run_averaged_band` (— with one draw)."""
    if band is None:
        return "— (one draw)"
    lo, hi = band["band"]
    return f"{band['in_band_percent']:.1f} % [{lo:.2f}, {hi:.2f}], {band['runs']} draws"


def _t1_cell(entry: dict[str, Any]) -> str:
    return f"{fmt(entry['mean'], 3)} / {fmt(entry['median'], 3)} / {entry['worst']}"


def build_report(summary: dict[str, Any], figures: dict[str, str], *, elapsed_s: float) -> str:
    """report.md: tables ours | paper, figures inline, differences explained.

    The run time is reported here and not in summary.json, so that the summary is identical
    whatever the executor.
    """
    s = summary
    lines = [
        "# Seed 000 — Wanasinghe, Mann & Gosine (2014), reproduced",
        "",
        f"Seed {s['seed']}; {s['runs']} team draws (the paper's 20), {s['replay_runs']} "
        f"MRCLAM replay draws, {s['sweep_runs']} draws per sweep level; "
        f"run time {elapsed_s:.0f} s.",
        "",
        "## Accuracy of the four observed robots (PLKF, known initial pose, t ≥ 10 s)",
        "",
        markdown_table(
            [
                "robot",
                "position RMSE (m)",
                "yaw RMSE (rad)",
                "inside ±3σ (x/y/z/φ)",
                "ANEES (pooled)",
                "run-averaged NEES in its 95 % band (% of instants; band, draws)",
                "NIS % > χ²(3)",
                "paper",
            ],
            [
                [
                    r,
                    a["position_rmse_m"],
                    a["yaw_rmse_rad"],
                    " / ".join(f"{v:.3f}" for v in a["inside_3sigma"].values()),
                    a["anees"],
                    _band_cell(a["run_averaged_nees"]),
                    a["nis_percent_beyond"],
                    "0.05–0.10 m, 0.075–0.1 rad",
                ]
                for r, a in s["accuracy"].items()
            ],
        ),
        "",
        figure_md(
            figures["aerial_error"], "Error and ±3σ bounds of the aerial robot (paper Fig. 3)"
        ),
        figure_md(figures["all_errors"], "Errors of the four observed robots (paper Fig. 4)"),
        "### Odometry noise and the paper's 5–10 cm",
        "",
        "The team's odometry noise (white, per 100 Hz step, on every reported body velocity): "
        + ", ".join(
            f"{r}: σ_v {v['sigma_v']:g} m/s, σ_vz {v['sigma_vz']:g} m/s, σ_ω {v['sigma_w']:g} rad/s"
            for r, v in s["odometry_noise"]["team"].items()
        )
        + ". With the Table-2 precise sensor the position error is centimetre-level; the sweep "
        "below reruns the team with every σ scaled (simulated and assumed alike). It is shown, "
        "not used to pick the noise.",
        "",
        markdown_table(
            ["σ_v (m/s)", "σ_ω (rad/s)"] + [f"{r} pos / yaw RMSE" for r in s["accuracy"]],
            [
                [row["sigma_v"], row["sigma_w"]]
                + [
                    f"{row['position_rmse_m'][r]:.4f} / {row['yaw_rmse_rad'][r]:.4f}"
                    for r in s["accuracy"]
                ]
                for row in s["odometry_noise"]["sweep"]
            ],
        ),
        "",
        figure_md(figures["sweep"], "Steady-state position RMSE against odometry noise"),
        "## Table 1 — measurement updates to converge (mean / median / worst of 13 guesses)",
        "",
        "Rule `paper_rule` is Eq. 32 (1.05 × the maximum case-1 RMSE of the same filter); "
        "`fixed` is 0.05 m / 0.1 rad. The RMSE of each guess is taken over the draws. A guess "
        "that never converges counts as (updates + 1). Thresholds: "
        + "; ".join(
            f"{f} Eq. 32: " + ", ".join(f"{k} {v:.4g}" for k, v in th["paper_rule"].items())
            for f, th in s["table1_thresholds"].items()
        )
        + ".",
        "",
    ]
    rows = []
    for case in ("case2", "case3", "case4"):
        for filt in ("PLKF", "TEKF"):
            entry = s["table1"][case][filt]
            for rule in RULES:
                rows.append(
                    [case, filt, rule]
                    + [_t1_cell(entry[rule][st]) for st in STATES]
                    + [" / ".join(str(entry["paper"][st]) for st in STATES)]
                )
        best = s["table1_best"][case]
        for rule in RULES:
            rows.append(
                [case, "yaw bank" if "bank" in best["method"] else "best (PLKF)", rule]
                + [_t1_cell(best[rule][st]) for st in STATES]
                + ["—"]
            )
    lines += [
        markdown_table(["case", "filter", "rule", "x", "y", "z", "φ", "paper x/y/z/φ"], rows),
        "",
        "Not converged within the run (guesses, per state x/y/z/φ): "
        + "; ".join(
            f"{case} {filt} {rule}: "
            + "/".join(str(v) for v in s["table1_not_converged"][case][filt][rule].values())
            for case in ("case2", "case3", "case4")
            for filt in ("PLKF", "TEKF")
            for rule in RULES
        )
        + ".",
        "",
        f"Acceptance (yaw bank, case 4): fixed-rule worst φ = "
        f"{s['table1_best']['acceptance']['case4_fixed_phi_worst']} (≤ 12: "
        f"{fmt(s['table1_best']['acceptance']['case4_fixed_phi_worst_le_12'])}); Eq.-32 mean φ = "
        f"{fmt(s['table1_best']['acceptance']['case4_paper_rule_phi_mean'], 3)} vs plain PLKF "
        f"{fmt(s['table1_best']['acceptance']['case4_plkf_paper_rule_phi_mean'], 3)} (≤ 12 or "
        f"≤ 1/3 of the PLKF: {fmt(s['table1_best']['acceptance']['case4_paper_rule_ok'])}).",
        "",
        *readings_section(s),
        figure_md(figures["convergence"], "Yaw RMSE per initial guess: TEKF, PLKF, yaw bank"),
        figure_md(
            figures["arbitrary_init"],
            "PLKF vs TEKF vs yaw bank from an arbitrary pose (paper Fig. 6)",
        ),
        *replay_section(s),
        "### Radial bias: PLKF vs bias-compensated PLKF vs TEKF (replay, steady state)",
        "",
        markdown_table(
            [
                "case",
                "filter",
                "radial bias (m)",
                "position RMSE (m)",
                "yaw RMSE (rad)",
                "NEES beyond χ²(4, 0.95) (%)",
            ],
            [
                [
                    case,
                    filt,
                    v["radial_bias_m"],
                    v["position_rmse_m"],
                    v["yaw_rmse_rad"],
                    v["nees_percent_beyond"],
                ]
                for case, d in s["bias_comparison"].items()
                for filt, v in d.items()
            ],
        ),
        "",
        figure_md(figures["bias"], "Radial bias of the three filters per Table-2 case"),
        figure_md(figures["nees_nis"], "NEES and NIS with χ² bounds (paper Figs. 10–11)"),
        figure_md(figures["conditioning"], "Conditioning of P, R, S (paper Fig. 12)"),
        "## RMSE against the PCRLB (simulation, steady state)",
        "",
        markdown_table(
            ["robot", "x", "y", "z", "φ"],
            [[r] + [v[st] for st in STATES] for r, v in s["pcrlb_ratio"].items()],
        ),
        "",
        figure_md(figures["pcrlb"], "RMSE and √PCRLB of the aerial robot"),
        "## Differences from the paper, explained",
        "",
        *differences(s),
    ]
    return "\n".join(lines)


def readings_section(s: dict[str, Any]) -> list[str]:
    """Table 1, case 4, φ: which reading of the paper's set-up gives its count."""
    r = s["table1_readings"]
    closest = min(TABLE1_READINGS, key=lambda k: abs(r["PLKF"][k] - r["PLKF"]["paper"]))
    return [
        "### Case 4, φ: which reading of the paper's set-up gives its 12 updates",
        "",
        markdown_table(
            ["reading", "PLKF", "TEKF"],
            [[text, r["PLKF"][k], r["TEKF"][k]] for k, text in TABLE1_READINGS.items()]
            + [["paper (Table 1)", r["PLKF"]["paper"], r["TEKF"]["paper"]]],
        ),
        "",
        f"Same draws, guesses and noise for every reading ({r['PLKF']['guesses_within_half_pi']} "
        f"of {r['PLKF']['guesses']} guesses start within π/2 of the true yaw). Closest to the "
        f"paper's PLKF count: {TABLE1_READINGS[closest].split(':')[-1].strip()} "
        f"({r['PLKF'][closest]:.1f} updates)"
        + (
            "; none comes within a factor of two of it, so neither the counting rule nor the "
            "yaw spread explains the gap: the plain PLKF's slow φ comes from the guesses whose "
            "yaw correction stalls (the worst column above). "
            if r["PLKF"][closest] > 2 * r["PLKF"]["paper"]
            else ". "
        )
        + "Our guesses sit at ⅓ and ⅔ of the sensor's range "
        "across its field of view with yaws evenly on the circle "
        "(`relloc.estimators.initialisation.poses_spread_in_fov`); the paper says only that its "
        "13 poses are spread within the field of view.",
        "",
    ]


def replay_section(s: dict[str, Any]) -> list[str]:
    """Tables 3–4: the windows, the calibration, the targets, then calibrated and raw."""
    w = s["table3"]["windows"]
    rng = s["replay"]["steady_state_range_m"]
    cal = s["odometry_noise"]["replay_calibration"]
    fits = s["odometry_noise"]["replay_fit"]

    def noise(kind: str) -> str:
        return "; ".join(
            f"{k}: σ_v {v['sigma_v']:.3f} m/s, σ_lateral {v['sigma_lateral']:.3f} m/s, "
            f"σ_ω {v['sigma_w']:.3f} rad/s over {v['window_s']:g} s windows of "
            f"[{v['calibration_window']['start_s']:.1f}, {v['calibration_window']['end_s']:.1f}] s"
            for k, v in fits[kind].items()
        )

    lines = [
        "## Tables 3–4 — real MRCLAM trajectories",
        "",
        f"{s['replay']['source']} (another pair: `--pair OBSERVER,OBSERVED`; every pair of the "
        "run: `relloc reproduce wanasinghe2014-pairs`); observed plane "
        f"raised {s['replay']['observed_height_m']:g} m; "
        f"scored window [{w['scored']['start_s']:.1f}, {w['scored']['end_s']:.1f}] s of the "
        f"recording, steady state after {s['replay']['steady_state_after_s']:g} s, in which "
        f"the pair is {rng['mean']:.2f} m apart on average (at most {rng['max']:.2f} m, "
        "horizontally); "
        "measurements synthesised from the ground truth; the same draws (sensor noise, initial "
        "pose) for every odometry.",
        "",
        skipped_rows_line(
            s["replay"]["loader"]["n_skipped"], s["replay"]["loader"]["skipped_by_reason"]
        ),
        "",
        "The reading of seed 000 §6 followed: the observer's range, azimuth and elevation of "
        "the observed robot only (no observation of the observer by the observed robot, no "
        "heading sensor), synthesised from the ground truth at the Table-2 settings, and each "
        "robot's own odometry as the velocity input. The paper's odometry is the robots' "
        "measured wheel odometry; MRCLAM records the commanded velocities, which the calibration "
        "below maps to the motion (latency, lag, scales) but whose remaining error — turns the "
        "robot makes that no command asked for — is what the relative yaw drifts with: the "
        "relative yaw is read only from the direction of the observed robot's apparent motion "
        "(a few cm/s here), which an error of the observer's turn rate times the range swamps.",
        "",
        f"- **Calibrated odometry** (the headline): fitted on [{w['calibration']['start_s']:.1f}, "
        f"{w['calibration']['end_s']:.1f}] s (the rest of the recording after the scored window, "
        f"disjoint from it): latency {cal['latency_s']:.2f} s, speed scales "
        + ", ".join(f"robot {r} {v:.3f}" for r, v in cal["scale_v"].items())
        + ", turn-rate scales "
        + ", ".join(f"robot {r} {v:.3f}" for r, v in cal["scale_w"].items())
        + f"; time constant {cal['time_constant_s']:.2f} s"
        + f"; noise left after the calibration: {noise('calibrated')}; "
        + inflation_text(cal["noise_inflation"]),
        "- **Raw odometry** (the recorded commands as they are, kept beside): noise "
        f"{noise('raw')} (each robot's whole recording, the scored window included).",
        "- **Truth-velocity odometry** (a diagnostic, not a result: no robot has it): the same "
        "filters, draws and seed driven by the ground truth's own velocities (Vicon central "
        "differences), with the equivalent white noise fitted the same way on the calibration "
        f"window: {noise('truth_velocity')}; "
        + inflation_text(s["odometry_noise"]["replay_truth_velocity"]["noise_inflation"])
        + " It measures the odometry floor: what the same filters reach when the velocities are "
        "as good as the ground truth.",
        "",
        "Targets (calibrated, PLKF): yaw RMSE ≤ 0.10 rad, NEES beyond χ²(4, 0.95) ≤ 10 %, "
        "position RMSE (mean of x, y, z) no worse than raw.",
        "",
        markdown_table(
            ["case", "yaw RMSE", "≤ 0.10", "% NEES > χ²", "≤ 10", "pos RMSE", "raw", "≤ raw"],
            [
                [
                    case,
                    v["yaw_rmse_rad"],
                    v["yaw_ok"],
                    v["nees_percent_beyond"],
                    v["nees_ok"],
                    v["position_rmse_m"],
                    v["raw_position_rmse_m"],
                    v["position_ok"],
                ]
                for case, v in s["replay_targets"].items()
            ],
        ),
        "",
    ]
    titles = {
        "calibrated": "Calibrated odometry",
        "raw": "Raw odometry",
        "truth_velocity": "Truth-velocity odometry (diagnostic: the ground truth's velocities)",
    }
    for kind, title in titles.items():
        lines += [f"### {title}", "", *_replay_tables(s, kind), ""]
    return lines + turn_rate_section(s)


def turn_rate_section(s: dict[str, Any]) -> list[str]:
    """The calibrated commands' turn-rate residual per robot, window and model."""
    tr = s["turn_rate_residual"]
    B, L = tr["block_s"], tr["yaw_random_walk_span_s"]
    firs = "; ".join(
        f"robot {r}: {f['turn_rate_taps']} turn-rate taps over [{f['turn_rate_lags_s'][0]:g}, "
        f"{f['turn_rate_lags_s'][1]:g}] s and {f['speed_taps']} speed taps, DC gain "
        f"{f['dc_gain']:.3f}, mean delay {f['centroid_lag_s']:.2f} s"
        for r, f in tr["fir"].items()
    )
    windows = ", ".join(
        f"{k} [{w['start_s']:.1f}, {w['end_s']:.1f}] s" for k, w in tr["windows"].items()
    )
    rows = [
        [
            f"robot {who}" if who != "relative" else f"relative ({tr['relative']})",
            win,
            {"calibrated": "calibrated command", "fir": "best FIR"}[model],
            st["mean"],
            st["std"],
            st["block_std"],
            st["blocks"],
            st["yaw_random_walk_rad"],
        ]
        for who, by_window in tr["residual"].items()
        for win, by_model in by_window.items()
        for model, st in by_model.items()
    ]
    return [
        "### What the commands cannot explain: the turn-rate residual",
        "",
        "Residual = true turn rate (Vicon central differences) − modelled turn rate, on a "
        f"0.02 s grid of each window ({windows}); models: the calibrated command response "
        "(the headline's) and the best linear filter (FIR) of the turn-rate and speed commands "
        f"plus a constant, least squares on the calibration window only ({firs}). Blocks: "
        f"non-overlapping {B:g} s means; the yaw random walk they imply over the steady-state "
        f"span L = {L:g} s is σ_B √(B L) (`relloc.calibration.turn_rate`).",
        "",
        markdown_table(
            [
                "who",
                "window",
                "model",
                "mean (rad/s)",
                "std (rad/s)",
                f"std of {B:g} s means",
                "blocks",
                f"yaw random walk over {L:g} s (rad)",
            ],
            rows,
        ),
        "",
    ]


def _stretch_count(fit: dict[str, Any]) -> str:
    """The prefix naming how many of the window's stretches the inflation fit replayed, when
    it replayed only some (:func:`relloc.experiments.wanasinghe2014_mrclam.spread_stretches`);
    empty when it replayed all."""
    used, held = len(fit["stretches"]), fit["stretches_in_window"]
    return "" if used == held else f"{used} of the window's {held} stretches: "


def inflation_text(fit: dict[str, Any]) -> str:
    """How the calibrated noise inflation was chosen (:func:`fit_noise_inflation`)."""
    search = search_text([(t["k"], t["yaw_percent_beyond"]) for t in fit["tried"]], fit["met"])
    spans = ", ".join(f"[{w['start_s']:.1f}, {w['end_s']:.1f}]" for w in fit["stretches"])
    lead, keeps = (
        ("the smallest factor at which", "keeps")
        if fit["met"]
        else ("the largest tried; at none does", "keep")
    )
    return (
        f"that σ multiplied by **×{fit['k']:g}**, {lead} the PLKF replayed "
        f"on the calibration window ({_stretch_count(fit)}{spans} s, "
        f"{fit['draws_per_stretch']} draws each, seed "
        f"{fit['seed']}) {keeps} its relative-yaw NEES beyond χ²(1, 0.95) at most "
        f"{fit['target_percent']:g} % of the steady-state updates ({search})."
    )


def _replay_tables(s: dict[str, Any], kind: str) -> list[str]:
    """Table 3 (PLKF and yaw bank) and Table 4 of the replay with ``kind`` odometry."""
    t4s = s["table4"][kind]
    return [
        markdown_table(
            [
                "case",
                "filter",
                "φ RMSE (std)",
                "paper",
                "x RMSE (std)",
                "paper",
                "y RMSE (std)",
                "paper",
                "z RMSE (std)",
                "paper",
                "φ RMSE of each draw",
                "φ √PCRLB",
            ],
            [
                [
                    case,
                    filt,
                    *_table3_cells(s[key][kind][case]),
                    " / ".join(f"{v:.3f}" for v in s[key][kind][case]["phi"]["rmse_per_draw"]),
                    s["replay_pcrlb"][kind][case]["phi"],
                ]
                for case in s["table3"][kind]
                for key, filt in (("table3", "PLKF"), ("table3_best", "yaw bank"))
            ],
        ),
        "",
        markdown_table(
            [
                "case",
                "% NEES > χ²(4, .95)",
                "its 95 % interval",
                "paper",
                "% NIS > χ²(3, .95)",
                "ANEES (pooled)",
                "run-averaged NEES in its 95 % band",
                "max cond P / R / S",
                "paper: all < 6",
                "yaw bank: % NEES / % NIS",
            ],
            [
                [
                    case,
                    t4["nees_percent_beyond"],
                    interval_text(t4["nees_beyond_interval"]),
                    t4["paper_nees_percent_beyond"],
                    t4["nis_percent_beyond"],
                    t4["anees"],
                    _band_cell(t4["run_averaged_nees"]),
                    " / ".join(f"{v:.2f}" for v in t4["max_conditioning"].values()),
                    "yes" if max(t4["max_conditioning"].values()) < 6 else "no",
                    f"{t4['yaw_bank']['nees_percent_beyond']:.2f} / "
                    f"{t4['yaw_bank']['nis_percent_beyond']:.2f}",
                ]
                for case, t4 in t4s.items()
            ],
        ),
        "",
        "% NEES beyond the bound is the paper's single-run share over the steady state. The "
        "run-averaged NEES averages the draws at each update time; the draws differ in sensor "
        "noise and initial pose but share the one recorded odometry, so its band tests the "
        "consistency towards the sensor noise, not towards the odometry error. The share's "
        "95 % interval is by cluster means two ways, over the draws and over time (the "
        "steady state cut into 10 blocks), so it counts the errors the draws share at one "
        "time and those that persist through a draw, and widened, when a block lasts less "
        "than ten correlation times of the NEES, to Clopper–Pearson's interval for the "
        "effective sample size that time leaves; its verdict says whether it lies wholly "
        "above the 5 % of a consistent filter (over-confident), wholly below (conservative), "
        "holds 5 % and reaches no higher than 10 %, twice it, the share seed 000 calls "
        "acceptable (consistent), or holds 5 % but reaches above 10 % (inconclusive: not "
        "rejected, not shown consistent either).",
    ]


def conditioning_text(s: dict[str, Any]) -> str:
    """Covariance conditioning on the replay against the paper's bound of 6 (its Fig. 12),
    naming each matrix that reaches it."""
    cases = s["table4"]["calibrated"]
    worst = {c: max(t4["max_conditioning"].values()) for c, t4 in cases.items()}
    text = (
        "- **Conditioning (paper: all below 6).** Max log10 condition numbers of P, R, S on "
        "the replay: " + ", ".join(f"{c} {v:.2f}" for c, v in worst.items()) + ". "
    )
    reached = {
        m: [c for c, t4 in cases.items() if t4["max_conditioning"][m] >= 6.0]
        for m in ("P", "R", "S")
    }
    if not any(reached.values()):
        return text + "All stay below 6, as in the paper."
    why = {
        "P": ": the observed robot's height is constant (a ground robot on a raised plane, no "
        "vertical velocity noise), so with the precise elevation measurement the z variance "
        "keeps shrinking while the yaw variance stays large"
    }
    parts = [f"in {', '.join(cs)} {m} reaches 6{why.get(m, '')}" for m, cs in reached.items() if cs]
    calm = [m for m, cs in reached.items() if not cs]
    if calm:
        parts.append(
            f"{' and '.join(calm)} {'stay' if len(calm) > 1 else 'stays'} well conditioned"
        )
    sentence = "; ".join(parts)
    return text + sentence[0].upper() + sentence[1:] + "."


def _replay_yaw_cause(s: dict[str, Any]) -> str:
    """Whether the replay's yaw error comes from the initial guess or from the odometry."""
    plkf = s["table3"]["calibrated"]["case1"]["phi"]["rmse_mean"]
    bank = s["table3_best"]["calibrated"]["case1"]["phi"]["rmse_mean"]
    if bank < 0.7 * plkf:
        return (
            f"Part of it is the initial guess: the yaw bank from the same pose reaches {bank:.3f} "
            "rad in case 1; the rest is odometry drift the slow motion cannot correct."
        )
    return (
        f"The yaw bank from the same pose gives {bank:.3f} rad in case 1, so the initial guess "
        "is not the cause: at these speeds the motion corrects the odometry's yaw drift slowly."
    )


def _span(values: list[float], unit: str = "") -> str:
    """``min–max`` of ``values`` to three decimals (one value when they agree)."""
    lo, hi = f"{min(values):.3f}", f"{max(values):.3f}"
    return f"{lo}{unit}" if lo == hi else f"{lo}–{hi}{unit}"


def replay_text(s: dict[str, Any]) -> str:
    """Tables 3–4 against the paper: what the calibration changes and what it cannot."""
    cal, raw = s["table3"]["calibrated"], s["table3"]["raw"]
    t4c, t4r = s["table4"]["calibrated"], s["table4"]["raw"]
    targets = s["replay_targets"]
    yaw = [v["yaw_rmse_rad"] for v in targets.values()]
    missed = [c for c, v in targets.items() if not (v["yaw_ok"] and v["nees_ok"])]

    fits = s["odometry_noise"]["replay_fit"]["calibrated"]
    drift = {
        k: (
            v["sigma_v"] * math.sqrt(1.0 / (v["rate_hz"] * v["window_s"])),
            v["sigma_w"] * math.sqrt(1.0 / (v["rate_hz"] * v["window_s"])),
            v["window_s"],
        )
        for k, v in fits.items()
    }
    drift_text = "; ".join(
        f"{k}: {dv * 100:.2f} cm/s and {dw:.4f} rad/s rms over {w:g} s"
        for k, (dv, dw, w) in drift.items()
    )
    yaw_missed = [c for c, v in targets.items() if not v["yaw_ok"]]
    nees_missed = [c for c, v in targets.items() if not v["nees_ok"]]
    verdict = "Every case meets the yaw and NEES targets." if not missed else ""
    if yaw_missed:
        verdict += (
            f"The yaw target (≤ 0.10 rad) is missed in {', '.join(yaw_missed)}: the calibrated "
            f"yaw RMSE is {_span(yaw, ' rad')}. "
        ) + _yaw_bound_text(targets, yaw_missed)
    if nees_missed:
        verdict += (
            f"The NEES target (≤ 10 %) is missed in {', '.join(nees_missed)} ("
            + ", ".join(f"{c} {targets[c]['nees_percent_beyond']:.1f} %" for c in nees_missed)
            + "). "
            + (
                "The precise-sensor cases run on the same odometry and meet it, so the excess "
                "comes with the noisy sensor, whose readings the filter averages over many "
                "seconds; the PLKF's pseudo-measurement noise is also evaluated at the estimate "
                "with 0.1 rad bearings, and this run does not separate the two. "
                if all(targets[c]["nees_ok"] for c in ("case1", "case3") if c in targets)
                else "The odometry errors left after the calibration are correlated over "
                "seconds to a minute (the fitted turn-rate σ grows with the window length), "
                "which no equivalent white noise describes at every time scale (the inflation "
                "fitted on the calibration window narrows the gap, it does not close it); with "
                "the yaw only weakly observable, the filter's yaw also absorbs the speed errors "
                "it does not model. "
            )
            + _bias_nees_text(s["bias_comparison"], nees_missed)
        )
    return (
        "- **Tables 3–4 (real data).** The paper used two Pioneer robots with laser map-based "
        "localisation as ground truth; we use two iRobot Create robots of MRCLAM with Vicon "
        "truth and their recorded *commanded* odometry. Calibrating it (latency, lag, scales, the "
        "noise left after them and that noise's inflation, all fitted after the scored window) "
        "changes the yaw RMSE from "
        f"{_span([raw[c]['phi']['rmse_mean'] for c in raw], ' rad')} (raw) to "
        f"{_span([cal[c]['phi']['rmse_mean'] for c in cal], ' rad')} and the NEES beyond the bound "
        f"from {_span([t4r[c]['nees_percent_beyond'] for c in t4r], ' %')} to "
        f"{_span([t4c[c]['nees_percent_beyond'] for c in t4c], ' %')} (paper 0.03–0.18 rad, "
        f"0.06–9.25 %). {verdict.strip()} {_replay_yaw_cause(s)} {odometry_floor_text(s)} "
        "What is left after the calibration is "
        "not a lag or a scale but the commands' own error: the commanded speed is quantised and "
        "constant while the real speed wanders, and the mean error of the calibrated commands "
        f"over the noise windows is {drift_text} — several percent of the robots' 5–7 cm/s. "
        "The relative yaw is observable only through the observed robot's motion (seed 000 "
        "Lemma 1), so a speed error of the observer across the observed robot's direction of "
        "motion reads as a yaw error of the same share (a 7 % speed error is about 0.07 rad), "
        "and turn-rate errors add to it between the corrections. We did not shrink the fitted "
        "noise or choose a window by its score on the scored stretch. Positions, measured "
        f"directly, are at {cal['case1']['x']['rmse_mean'] * 100:.1f} / "
        f"{cal['case1']['y']['rmse_mean'] * 100:.1f} cm in case 1 (paper 1.0 / 1.3 cm). "
        f"The replay averages {s['replay_runs']} sensor-noise draws; the paper's table is one run."
    )


def _yaw_bound_text(targets: dict[str, Any], missed: list[str]) -> str:
    """What the calibrated model's √PCRLB of the yaw says of the cases that miss the target."""
    above = [c for c in missed if not targets[c]["yaw_bound_ok"]]
    bounds = ", ".join(f"{c} {targets[c]['yaw_bound_rad']:.3f}" for c in missed)
    ratios = [targets[c]["yaw_rmse_rad"] / targets[c]["yaw_bound_rad"] for c in missed]
    text = (
        "The posterior Cramér–Rao bound of the filters' own model (the pair's true trajectory, "
        "the calibrated commands with their inflated white noise, the case's sensor; √PCRLB of "
        f"φ over the steady state, column φ √PCRLB) is {bounds} rad there, and the PLKF's yaw "
        f"RMSE is {_span(ratios)} times it"
    )
    if not above:
        return text + ": the model allows the target and the filter misses it. "
    return text + (
        f": in {', '.join(above)} the model itself does not allow 0.10 rad — with the noise "
        "the calibration needs to keep the filter consistent, no estimator of data that "
        "followed the model would get below the bound. The recorded commands' errors are not "
        "that white noise, so the bound is the model's, not a limit on what the data allow. "
    )


def _bias_nees_text(bias: dict[str, Any], cases: list[str]) -> str:
    """The NEES beyond the bound of the bias-compensated PLKF beside the PLKF's, on the same
    draws of the calibrated replay, in those of ``cases`` where it runs: how much of a NEES
    miss the pseudo-linear bias accounts for. Empty where it does not run."""
    noisy = [c for c in cases if "BC-PLKF" in bias.get(c, {})]
    if not noisy:
        return ""
    return (
        "On the same draws the bias-compensated PLKF, which removes the pseudo-linear bias, "
        "has "
        + ", ".join(
            f"{c} {bias[c]['BC-PLKF']['nees_percent_beyond']:.1f} % (PLKF "
            f"{bias[c]['PLKF']['nees_percent_beyond']:.1f} %)"
            for c in noisy
        )
        + " beyond the bound; the tables and the target are the paper's filter, the PLKF. "
    )


def odometry_floor_text(s: dict[str, Any]) -> str:
    """The truth-velocity diagnostic and the turn-rate residual: the measured share of the
    odometry in the replay's yaw error."""

    truth, t4 = s["table3"]["truth_velocity"], s["table4"]["truth_velocity"]
    cal = s["table3"]["calibrated"]
    yaw_truth = [truth[c]["phi"]["rmse_mean"] for c in truth]
    yaw_cal = [cal[c]["phi"]["rmse_mean"] for c in cal]
    lead = (
        "The odometry is the gap: driven"
        if max(yaw_truth) < 0.5 * min(yaw_cal)
        else "The odometry is not the whole gap: driven"
    )
    tr = s["turn_rate_residual"]
    rel = tr["residual"]["relative"]
    B, L = tr["block_s"], tr["yaw_random_walk_span_s"]

    def block(model: str) -> str:
        return " and ".join(
            f"{rel[w][model]['block_std']:.4f} rad/s ({w})" for w in ("calibration", "scored")
        )

    return (
        f"{lead} by the ground truth's own velocities (a diagnostic no robot has, its white "
        "noise fitted the same way on the calibration window), the same PLKF on the same draws "
        f"reaches a yaw RMSE of {_span(yaw_truth, ' rad')} (calibrated "
        f"{_span(yaw_cal, ' rad')}) with "
        f"{_span([t4[c]['nees_percent_beyond'] for c in t4], ' %')} of the NEES beyond the bound. "
        "The calibrated commands' turn-rate residual is correlated over seconds: for the "
        f"relative yaw ({tr['relative']}) its std is "
        f"{rel['scored']['calibrated']['std']:.3f} rad/s on the scored window, yet its {B:g} s "
        f"means still spread by {block('calibrated')}; the best linear filter of the commands, "
        f"fitted on the calibration window, leaves {block('fir')} — nothing more in the commands "
        f"explains it. A random walk of that size over the {L:g} s steady state, σ_B √(B L), is "
        f"{rel['scored']['calibrated']['yaw_random_walk_rad']:.2f} rad (best filter "
        f"{rel['scored']['fir']['yaw_random_walk_rad']:.2f} rad) on the scored window: the size "
        "of the calibrated yaw RMSE, and a floor that no noise model of the commands lowers."
    )


def differences(s: dict[str, Any]) -> list[str]:
    """The "differences explained" section, with the numbers of this run."""
    acc = s["accuracy"]
    pos = [a["position_rmse_m"] for a in acc.values()]
    yaw = [a["yaw_rmse_rad"] for a in acc.values()]
    sweep = s["odometry_noise"]["sweep"]
    reaching = [
        row
        for row in sweep
        if min(row["position_rmse_m"].values()) >= PAPER_ACCURACY["position_rmse_m"][0]
    ]
    if reaching:
        row = reaching[0]
        sweep_text = (
            f"in the sweep every robot's position RMSE reaches 5 cm only at σ_v = "
            f"{row['sigma_v']:g} m/s, σ_ω = {row['sigma_w']:g} rad/s (×{row['scale']:g} the "
            "scenario's noise)"
        )
    else:
        top = sweep[-1]
        low, high = min(top["position_rmse_m"].values()), max(top["position_rmse_m"].values())
        sweep_text = (
            f"even at ×{top['scale']:g} the scenario's noise (σ_v = {top['sigma_v']:g} m/s) the "
            f"position RMSE stays at {low:.3f}–{high:.3f} m, "
            + (
                "below the paper's band"
                if high < PAPER_ACCURACY["position_rmse_m"][0]
                else "not every robot reaching the paper's band"
            )
        )
    t1 = s["table1"]["case4"]
    never = s["table1_best"]["case4"]["not_converged"]["fixed"]["phi"]
    c3 = s["table1"]["case3"]
    best = s["table1_best"]["case4"]
    bias = s["bias_comparison"]
    noisy = [c for c in ("case2", "case4") if "BC-PLKF" in bias.get(c, {})]
    bias_text = "; ".join(
        f"{c}: PLKF {bias[c]['PLKF']['radial_bias_m'] * 100:+.1f} cm, BC-PLKF "
        f"{bias[c]['BC-PLKF']['radial_bias_m'] * 100:+.1f} cm, TEKF "
        f"{bias[c]['TEKF']['radial_bias_m'] * 100:+.1f} cm"
        for c in noisy
    )
    return [
        "- **Accuracy (paper: 5–10 cm, 0.075–0.1 rad).** The paper does not state its odometry "
        "noise. With the Table-2 precise sensor and the default scenario's odometry noise our "
        f"steady-state position RMSE is {min(pos):.3f}–{max(pos):.3f} m and the yaw RMSE "
        f"{min(yaw):.3f}–{max(yaw):.3f} rad; {sweep_text}. We keep the scenario's noise instead "
        "of tuning it to the paper.",
        "- **Table 1.** The paper prints one number per cell, the mean over its 13 guesses; we "
        "add the median, the worst guess and a fixed threshold beside Eq. 32. Eq. 32 ties the "
        "threshold to the known-initialisation RMSE of the same filter (PLKF here: "
        + ", ".join(f"{k} {v:.3g}" for k, v in s["table1_thresholds"]["PLKF"]["paper_rule"].items())
        + "), so it moves with the odometry noise; the trajectories "
        "are relloc's default team, not the paper's (unpublished) ones. In case 4 the plain PLKF "
        f"needs {t1['PLKF']['paper_rule']['phi']['mean']:.1f} updates for φ on average by Eq. 32 "
        f"(paper: 12), worst {t1['PLKF']['paper_rule']['phi']['worst']}; the TEKF "
        f"{t1['TEKF']['paper_rule']['phi']['mean']:.1f} (paper: 263), worst "
        f"{t1['TEKF']['paper_rule']['phi']['worst']}. Guesses whose yaw is near the wrong side of "
        "the circle stall both filters (the mean hides it; see the worst column and the "
        "convergence figure). The PLKF's advantage is in the position: in case 3 (yaw "
        f"known) it needs {c3['PLKF']['paper_rule']['x']['mean']:.1f} updates for x where the "
        f"TEKF needs {c3['TEKF']['paper_rule']['x']['mean']:.1f} (paper: 1 and 34). The yaw "
        "is not measured; both filters correct it through the same predicted "
        "cross-covariance, so from a yaw guess near the wrong side both stall alike. "
        "Under the fixed rule the PLKF's x needs "
        f"{t1['PLKF']['fixed']['x']['mean']:.1f} updates on average; under Eq. "
        "32 position waits for the yaw, because a wrong yaw moves the predicted position between "
        "updates by more than these thresholds. The yaw bank brings φ inside 0.1 rad "
        + (
            f"within {best['fixed']['phi']['worst']} updates for every guess"
            if not never
            else f"for all but {never} guess(es), which never stay inside it within the run"
        )
        + f" (Eq. 32 mean {best['paper_rule']['phi']['mean']:.1f}).",
        replay_text(s),
        "- **Bias.** With the noisy Table-2 sensor the measured bearings inside H_pmo correlate "
        "the PLKF's gain with its pseudo-measurement noise, which pushes the range estimate "
        "outwards; the bias-compensated PLKF (`relloc.estimators.relative`, after Nguyen & "
        "Doğançay 2017) subtracts the estimated bias, the TEKF has none of this kind but "
        "linearises the bearing at the estimate. Radial bias on the replay (steady state): "
        f"{bias_text}.",
        conditioning_text(s),
        "- **PCRLB.** The bound uses the true commands and the filters' own noise models; a "
        "ratio near 1 means the PLKF is close to efficient for that state, above 1 how far "
        "from it.",
    ]
