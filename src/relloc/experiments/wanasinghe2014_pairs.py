"""``relloc reproduce wanasinghe2014-pairs``: seed 000's real-trajectory Tables 3–4 on many
pairs of one MRCLAM-layout run, each with its own model bound.

Which pair of a recording the replay takes decides much of what Tables 3–4 say: on MRCLAM run 6
the calibrated PLKF's yaw RMSE ranges over 0.05–0.75 rad across pairs in one Table-2 case
(:mod:`relloc.experiments.wanasinghe2014_mrclam`). This experiment runs, for each pair
``observer → observed``, exactly the replay of ``relloc reproduce wanasinghe2014 --pair A,B``
with the same settings and seeds (:func:`relloc.experiments.wanasinghe2014.run_replays`,
:func:`~relloc.experiments.wanasinghe2014.replay_results`): the odometry calibrated on the
pair's calibration window and scored on its disjoint scored window, raw and truth-velocity
odometry beside it, 5 sensor-noise draws (``Wanasinghe2014Config.replay_runs``), and the
√PCRLB of φ of each model (:func:`relloc.experiments.wanasinghe2014_mrclam.replay_pcrlb`). A
pair's row therefore equals the ``replay_targets``, ``table3`` and ``table4`` of that one-pair
reproduction at the same seed.

Pairs: ``--pair A,B`` (repeatable), or by default every robot observing the next two of the
dataset's robots in ascending order, cyclically (``r_k → r_{k+1}`` and ``r_k → r_{k+2}``;
with two or three robots, every ordered pair): run 6's ten pairs 1 → 2, 1 → 3, …, 5 → 1, 5 → 2.
A pair naming a robot the dataset lacks is a ConfigError before anything runs; a pair whose
replay the data cannot give (a DataError: too short a shared span, no ground truth) is skipped,
counted and reported with its reason, and the others still run.

On run 6 (seed 2026, 5 draws, 33 min on 2 cores) the ten default pairs reproduce the tables
of :mod:`relloc.experiments.wanasinghe2014_mrclam` to every printed digit: the targets hold in
10 of the 40 pair-cases and in no pair's four cases, the calibrated model's bound is above
0.10 rad in every cell (0.102–0.611), and no pair meets case 2 (40.7–51.8 % NEES beyond). On
run 6's second half written as a run of its own (``relloc mrclam cut … --start 450``; 24 min)
the targets hold in 6 of the 40 pair-cases (cases 1 and 3 of 1 → 2, 4 → 1 and 5 → 2) and in no
pair's four cases; the bound is 0.100–0.604 rad and case 2 is 31.1–78.3 % beyond.

Seeds: the replay draws ``S + 1`` and the noise-inflation fit ``S + 6`` for every pair, as in
the one-pair reproduction with its default sweep (``S`` = ``--seed``). ``--runs N`` sets the
draws to ``min(N, 5)``.

summary.json keys
-----------------
``experiment``, ``seed``, ``runs`` (sensor-noise draws per pair), ``seeds`` (``replay``,
``replay_noise_inflation``), ``dataset``,
``targets`` (yaw RMSE ≤ 0.10 rad, ``yaw_rmse_rad``, and % NEES beyond χ²(4, 0.95) ≤ 10 %,
``nees_percent_beyond``, per Table-2 case; ``position``: position RMSE no worse than the raw
replay's), ``paper[case]`` (seed 000's Table-3 φ RMSE, ``yaw_rmse_rad``, and Table-4 % NEES
beyond, ``nees_percent_beyond``);
``pairs``: one record per replayed pair with ``observer``, ``observed``, ``windows``
(``calibration`` and ``scored``, disjoint: ``start_s``, ``end_s``, ``source``),
``steady_state_range_m`` (mean horizontal range in the steady state, m),
``relative_yaw_random_walk_rad`` (below) and ``cases[case]``:
``calibrated`` and ``raw`` (PLKF ``yaw_rmse_rad``, ``yaw_rmse_per_draw``,
``nees_percent_beyond`` with ``nees_beyond_interval``, its 95 % interval by cluster means over
the draws and over time and the verdict — ``over-confident``, ``conservative``, ``consistent``
or ``inconclusive``, :func:`relloc.metrics.consistency.share_verdict` —,
``position_rmse_m``: the mean of the x, y and z RMSE),
``yaw_bound_rad`` (√PCRLB of φ, calibrated model), ``truth_velocity_yaw_bound_rad``, ``yaw_ok``,
``nees_ok``, ``position_ok`` (the calibrated figures against the targets) and ``met`` (all
three); a pair's ``relative_yaw_random_walk_rad``: ``calibration`` and ``scored`` → the
calibrated commands' relative-yaw random walk over the scored window's steady-state span, on
the calibration and on the scored window
(:mod:`relloc.calibration.turn_rate`; a scored window with a smaller walk than its calibration
window is kinder than the noise fitted there); ``skipped``: ``{observer, observed, reason}`` of
each pair not replayed; ``loader``: the dataset's rows the loader skipped (``n_skipped``,
``skipped_by_reason``, reason → count; null when no pair was replayed); ``tally``: ``cells``
(pair × case) replayed and
``cells_meeting_yaw_and_nees`` (both the yaw and the NEES target), ``pairs`` replayed and
``pairs_meeting_every_case``, and ``per_case`` (case → the pairs meeting both).
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from relloc.datasets.mrclam import load_mrclam
from relloc.errors import ConfigError, DataError
from relloc.experiments.registry import ReproduceArgs
from relloc.experiments.wanasinghe2014 import (
    Wanasinghe2014Config,
    inflation_seed,
    replay_results,
    run_replays,
)
from relloc.experiments.wanasinghe2014_mrclam import TABLE2, prepare_replays
from relloc.experiments.wanasinghe2014_paper import (
    PAPER_TABLE3,
    PAPER_TABLE4,
    TARGET_NEES_PERCENT,
    TARGET_YAW_RMSE_RAD,
)
from relloc.pipeline.output import (
    figure_md,
    markdown_table,
    prepare_out_dir,
    save_figure,
    skipped_rows_line,
    write_report,
    write_summary,
)

Pair = tuple[int, int]


def reproduce(args: ReproduceArgs) -> dict[str, Any]:
    """Entry point of ``relloc reproduce wanasinghe2014-pairs`` (see module docstring)."""
    config = Wanasinghe2014Config.from_args(dataclasses.replace(args, pairs=None))
    return run_pairs(
        config,
        args.pairs,
        args.out_dir,
        seed=args.master_seed,
        executor=args.executor,
        quiet=args.quiet,
    )


def default_pairs(robots: Sequence[int]) -> tuple[Pair, ...]:
    """Every robot observing the next two of ``robots`` (ascending, cyclic), each pair once."""
    ordered = sorted(robots)
    n = len(ordered)
    pairs: list[Pair] = []
    for k, observer in enumerate(ordered):
        for step in (1, 2):
            pair = (observer, ordered[(k + step) % n])
            if pair[0] != pair[1] and pair not in pairs:
                pairs.append(pair)
    return tuple(pairs)


def chosen_pairs(dataset: Path, pairs: Sequence[Pair] | None) -> tuple[Pair, ...]:
    """``pairs``, or :func:`default_pairs` of the dataset's robots; ConfigError naming a robot
    the dataset does not have."""
    robots = load_mrclam(dataset).robot_ids
    if pairs is None:
        if len(robots) < 2:
            raise ConfigError(f"--dataset: {dataset} has {len(robots)} robot(s); pairs need two")
        return default_pairs(robots)
    for pair in pairs:
        missing = [r for r in pair if r not in robots]
        if missing:
            raise ConfigError(
                f"--pair {pair[0]},{pair[1]}: robot(s) {missing} not in {dataset} "
                f"(robots {list(robots)})"
            )
    return tuple(pairs)


def run_pairs(
    config: Wanasinghe2014Config,
    pairs: Sequence[Pair] | None,
    out_dir: Path,
    *,
    seed: int,
    executor: str | None = None,
    quiet: bool = False,
) -> dict[str, Any]:
    """Replay every pair, write summary.json, report.md and the figure; return the summary."""
    started = time.perf_counter()
    dataset = config.replay.dataset
    replayed = chosen_pairs(dataset, pairs)  # refuse a bad --pair before writing anything
    out = prepare_out_dir(out_dir)
    rows: list[dict[str, Any]] = []
    skipped: list[dict[str, Any]] = []
    loader: dict[str, Any] | None = None  # the same dataset's for every pair
    for observer, observed in replayed:
        pair_config = dataclasses.replace(
            config,
            replay=dataclasses.replace(config.replay, observer=observer, observed=observed),
        )
        try:
            data = prepare_replays(
                pair_config.replay,
                steady_state_s=config.replay_steady_state_s,
                seed=inflation_seed(seed, config),
                executor=executor,
                quiet=quiet,
            )
        except DataError as err:
            skipped.append({"observer": observer, "observed": observed, "reason": str(err)})
            continue
        report = data["calibrated"].load_report  # one load of the dataset for every odometry
        loader = {k: report[k] for k in ("n_skipped", "skipped_by_reason")}
        replay = run_replays(pair_config, data, seed, executor=executor, quiet=quiet)
        part, _ = replay_results(pair_config, data, replay)
        rows.append(pair_row(observer, observed, part))
    summary: dict[str, Any] = {
        "experiment": "wanasinghe2014-pairs",
        "seed": seed,
        "runs": config.replay_runs,
        "seeds": {"replay": seed + 1, "replay_noise_inflation": inflation_seed(seed, config)},
        "dataset": str(dataset),
        "targets": {
            "yaw_rmse_rad": TARGET_YAW_RMSE_RAD,
            "nees_percent_beyond": TARGET_NEES_PERCENT,
            "position": "calibrated RMSE no worse than raw",
        },
        "paper": {
            case: {
                "yaw_rmse_rad": PAPER_TABLE3[case]["phi"][0],
                "nees_percent_beyond": PAPER_TABLE4[case],
            }
            for case in TABLE2
        },
        "pairs": rows,
        "skipped": skipped,
        "loader": loader,
        "tally": tally(rows),
    }
    figures = {"targets": plot_pairs(out, summary)} if rows else {}
    write_summary(out, summary)
    write_report(out, build_report(summary, figures, elapsed_s=time.perf_counter() - started))
    if not rows:  # every pair skipped: an empty table is no result (the report says why)
        raise DataError(
            f"no pair of {dataset} could be replayed; "
            + "; ".join(f"{s['observer']} → {s['observed']}: {s['reason']}" for s in skipped)
        )
    return summary


def _filter_cell(part: dict[str, Any], kind: str, case: str) -> dict[str, Any]:
    """The PLKF's yaw RMSE (with each draw's), % NEES beyond (with its interval) and position
    RMSE (x, y, z mean, as :func:`~relloc.experiments.wanasinghe2014.replay_targets` gives it)."""
    phi = part["table3"][kind][case]["phi"]
    target = part["replay_targets"][case]
    return {
        "yaw_rmse_rad": phi["rmse_mean"],
        "yaw_rmse_per_draw": phi["rmse_per_draw"],
        "nees_percent_beyond": part["table4"][kind][case]["nees_percent_beyond"],
        "nees_beyond_interval": part["table4"][kind][case]["nees_beyond_interval"],
        "position_rmse_m": target["raw_position_rmse_m" if kind == "raw" else "position_rmse_m"],
    }


def pair_row(observer: int, observed: int, part: dict[str, Any]) -> dict[str, Any]:
    """One pair's record (module docstring) from :func:`replay_results`' summary keys."""
    cases = {}
    for case, target in part["replay_targets"].items():
        ok = {key: target[key] for key in ("yaw_ok", "nees_ok", "position_ok")}
        cases[case] = {
            "calibrated": _filter_cell(part, "calibrated", case),
            "raw": _filter_cell(part, "raw", case),
            "yaw_bound_rad": target["yaw_bound_rad"],
            "truth_velocity_yaw_bound_rad": part["replay_pcrlb"]["truth_velocity"][case]["phi"],
            **ok,
            "met": all(ok.values()),
        }
    walk = part["turn_rate_residual"]["residual"]["relative"]
    return {
        "observer": observer,
        "observed": observed,
        "windows": part["table3"]["windows"],
        "steady_state_range_m": part["replay"]["steady_state_range_m"]["mean"],
        "relative_yaw_random_walk_rad": {
            window: walk[window]["calibrated"]["yaw_random_walk_rad"] for window in walk
        },
        "cases": cases,
    }


def _both(cell: dict[str, Any]) -> bool:
    """The yaw and NEES targets of one case of one pair."""
    return bool(cell["yaw_ok"] and cell["nees_ok"])


def tally(rows: list[dict[str, Any]]) -> dict[str, Any]:
    """Cells meeting the yaw and NEES targets, pairs meeting them in every case, per case."""
    cells = [_both(row["cases"][case]) for row in rows for case in TABLE2]
    return {
        "cells": len(cells),
        "cells_meeting_yaw_and_nees": int(sum(cells)),
        "pairs": len(rows),
        "pairs_meeting_every_case": int(
            sum(all(_both(row["cases"][case]) for case in TABLE2) for row in rows)
        ),
        "per_case": {case: int(sum(_both(row["cases"][case]) for row in rows)) for case in TABLE2},
    }


def _name(row: dict[str, Any]) -> str:
    return f"{row['observer']} → {row['observed']}"


def plot_pairs(out: Path, summary: dict[str, Any]) -> str:
    """Each pair and case: the calibrated PLKF's yaw RMSE against its model's √PCRLB, and its %
    NEES beyond, with the targets."""
    from relloc.plotting.setup import pyplot
    from relloc.plotting.wanasinghe import plot_pair_targets

    plt = pyplot()
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.5), layout="constrained")
    plot_pair_targets(
        axes,
        summary["pairs"],
        list(TABLE2),
        yaw_target=TARGET_YAW_RMSE_RAD,
        nees_target=TARGET_NEES_PERCENT,
    )
    fig.suptitle(
        f"{len(summary['pairs'])} pairs of {Path(summary['dataset']).name}, calibrated odometry "
        f"(seed {summary['seed']}, draws per pair: {summary['runs']})"
    )
    return save_figure(fig, out, "pairs_yaw_vs_bound")


def build_report(summary: dict[str, Any], figures: dict[str, str], *, elapsed_s: float) -> str:
    """report.md: the paper beside the pairs, the per-pair tables, windows, skips, figure."""
    rows = summary["pairs"]
    t = summary["tally"]
    seeds = summary["seeds"]
    lines = [
        "# Seed 000 Tables 3–4 on every pair of a run (`wanasinghe2014-pairs`)",
        "",
        f"Dataset `{summary['dataset']}`, seed {summary['seed']} (replay draws "
        f"{seeds['replay']}, noise inflation {seeds['replay_noise_inflation']}), "
        f"{summary['runs']} sensor-noise draws per pair, run time {elapsed_s:.0f} s. "
        "Each pair is the replay of `relloc reproduce wanasinghe2014 --pair A,B`: odometry "
        "calibrated on the pair's calibration window, scored on its disjoint scored window "
        "(table below).",
        "",
        *(
            [skipped_rows_line(loader["n_skipped"], loader["skipped_by_reason"]), ""]
            if (loader := summary["loader"])
            else []
        ),
        f"Targets: calibrated PLKF yaw RMSE ≤ {TARGET_YAW_RMSE_RAD} rad and % NEES beyond "
        f"χ²(4, 0.95) ≤ {TARGET_NEES_PERCENT:g} % in every Table-2 case. Met in "
        f"**{t['cells_meeting_yaw_and_nees']} of {t['cells']}** pair-cases; "
        f"**{t['pairs_meeting_every_case']} of {t['pairs']}** pairs meet them in every case.",
        "",
        "## The paper beside the pairs",
        "",
        "The paper replays one pair of its own recording; ours is every pair here (median and "
        "range over the pairs, calibrated PLKF).",
        "",
    ]
    paper_rows = []
    for case in TABLE2:
        yaw = [row["cases"][case]["calibrated"]["yaw_rmse_rad"] for row in rows]
        nees = [row["cases"][case]["calibrated"]["nees_percent_beyond"] for row in rows]
        paper = summary["paper"][case]
        paper_rows.append(
            [
                case,
                _median_range(yaw, 3),
                paper["yaw_rmse_rad"],
                _median_range(nees, 1),
                paper["nees_percent_beyond"],
                f"{t['per_case'][case]} of {t['pairs']}",
            ]
        )
    lines += [
        markdown_table(
            [
                "case",
                "φ RMSE (rad), ours",
                "paper",
                "% NEES beyond, ours",
                "paper",
                "pairs meeting both",
            ],
            paper_rows,
        ),
        "",
        "## Per pair: calibrated PLKF yaw RMSE (rad) / % NEES beyond",
        "",
        "↑: the NEES share's 95 % interval (cluster means two ways, over the draws and over "
        "time, widened on blocks shorter than ten correlation times) lies wholly above the "
        "5 % of a consistent filter (over-confident); ↓: wholly below (conservative); ?: it "
        "holds 5 % but reaches above 10 %, twice it (inconclusive: not rejected, not shown "
        "consistent either); unmarked: it holds 5 % and reaches no higher than 10 % "
        "(consistent); ✓: the yaw and NEES targets both met.",
        "",
    ]
    lines += _pair_table(rows, "calibrated")
    lines += ["", "## Per pair: raw odometry (the same draws)", ""]
    lines += _pair_table(rows, "raw")
    lines += [
        "",
        "## Per pair: the model's bound",
        "",
        "√PCRLB of φ of the calibrated model per case, of the truth-velocity model (its range "
        "over the cases), and the calibrated yaw RMSE divided by the calibrated bound. A bound "
        f"above {TARGET_YAW_RMSE_RAD} rad means the calibrated model itself does not allow the "
        "yaw target on that pair.",
        "",
    ]
    bound_rows = []
    for row in rows:
        c = row["cases"]
        bound_rows.append(
            [
                _name(row),
                " / ".join(f"{c[case]['yaw_bound_rad']:.3f}" for case in TABLE2),
                _span([c[case]["truth_velocity_yaw_bound_rad"] for case in TABLE2]),
                " / ".join(
                    f"{c[case]['calibrated']['yaw_rmse_rad'] / c[case]['yaw_bound_rad']:.2f}"
                    for case in TABLE2
                ),
            ]
        )
    lines += [
        markdown_table(
            ["pair", "calibrated bound, cases 1–4", "truth velocity", "RMSE ÷ bound, cases 1–4"],
            bound_rows,
        ),
        "",
        "## Windows",
        "",
        "Each pair's windows, and the calibrated commands' relative-yaw random walk over the "
        "steady state on each (the noise the commands leave: a scored window with a smaller "
        "walk than its calibration window is kinder than the filters' noise says).",
        "",
        markdown_table(
            [
                "pair",
                "calibration window (s)",
                "scored window (s)",
                "yaw walk, calibration / scored (rad)",
            ],
            [
                [
                    _name(row),
                    _window(row["windows"]["calibration"]),
                    _window(row["windows"]["scored"]),
                    "{calibration:.3f} / {scored:.3f}".format(
                        **row["relative_yaw_random_walk_rad"]
                    ),
                ]
                for row in rows
            ],
        ),
        "",
    ]
    if summary["skipped"]:
        lines += ["## Skipped pairs", ""]
        lines += [f"- {s['observer']} → {s['observed']}: {s['reason']}" for s in summary["skipped"]]
        lines.append("")
    if "targets" in figures:
        lines.append(
            figure_md(
                figures["targets"],
                "Left: calibrated yaw RMSE against the model's √PCRLB (the diagonal: RMSE = "
                "bound; dashed: the 0.10 rad target). Right: % NEES beyond χ²(4, 0.95) per pair "
                "(dashed: 10 %).",
            )
        )
    return "\n".join(lines)


#: Report marks of the NEES share's verdict (:func:`relloc.metrics.percent_beyond_interval`).
VERDICT_MARKS = {"over-confident": "↑", "conservative": "↓", "inconclusive": "?"}


def _pair_table(rows: list[dict[str, Any]], kind: str) -> list[str]:
    """Pair, mean range, and per case ``yaw / % NEES`` of ``kind`` odometry, the share's
    verdict marked (:data:`VERDICT_MARKS`; ✓: both targets met)."""
    body = []
    for row in rows:
        cells = []
        for case in TABLE2:
            c = row["cases"][case]
            verdict = VERDICT_MARKS.get(c[kind]["nees_beyond_interval"]["verdict"], "")
            mark = " ✓" if kind == "calibrated" and _both(c) else ""
            cells.append(
                f"{c[kind]['yaw_rmse_rad']:.3f} / "
                f"{c[kind]['nees_percent_beyond']:.1f}{verdict}{mark}"
            )
        body.append([_name(row), f"{row['steady_state_range_m']:.1f} m", *cells])
    return [markdown_table(["pair", "range", *TABLE2], body)]


def _median_range(values: list[float], digits: int) -> str:
    if not values:
        return "—"
    return f"{np.median(values):.{digits}f} ({min(values):.{digits}f}–{max(values):.{digits}f})"


def _span(values: list[float]) -> str:
    return f"{min(values):.3f}–{max(values):.3f}"


def _window(w: dict[str, Any]) -> str:
    return f"{w['start_s']:.2f}–{w['end_s']:.2f}"
