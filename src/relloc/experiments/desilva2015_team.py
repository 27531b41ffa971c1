"""``relloc team up desilva2015 | desilva2015-kidnapped --out DIR [--sharing-policy NAME]
[--sensing all|L1,P2,...]``: seed 002's team as robot processes, scored beside the in-process
reproduction on the same seeds.

Every run ``i`` of ``--runs N`` launches the whole team — leaders L1, L2 each running its
Gaussian-sum fuser in its own process, pods P1–P3 sharing their odometry — over Zenoh
(:class:`relloc.runtime.launcher.TeamLauncher`, :mod:`relloc.experiments.team_sources`);
the leaders' equivalent measurements (Eq. 8) travel once a second as ``mail``. With
``--sensing`` the named robots (``all``: every robot) sense and run the fusers instead of the
leaders, and the in-process reference uses the same sensing robots. The collected
estimates are scored by the reproduction's own functions
(:func:`relloc.experiments.desilva2015.score_run`, :func:`~relloc.experiments.desilva2015.metrics`),
and the same runs are replayed in-process
(:func:`~relloc.experiments.desilva2015.leader_estimates`) for the side-by-side figures.

``summary.json``: ``distributed`` and ``in_process`` (``success_rate``, ``pos_rmse_m``,
``yaw_rmse_rad``, ``anees``, ``hypotheses``, ``time_to_first_confirmed_s``, per pair success),
``difference`` (distributed − in-process of each figure) and ``tolerance``;
``agreement`` (largest |Δ| of any belief mean / covariance entry at common record times, per
run); for the kidnapped team ``kidnapped`` (``refound_rate``, ``time_to_refind_s`` and
``tracked_last_second``, distributed and in-process);
``sharing_policy`` (the leaders', ``--sharing-policy``: ``all``, seed 002's, or
``mutual-confirmed``, :data:`relloc.estimators.gaussian_sum.SHARING_POLICIES`); ``sensing``
(the sensing robots' names, ``--sensing all|L1,P2,...``, parsed by
:func:`relloc.experiments.desilva2015.sensing_robots` as for ``relloc reproduce desilva2015``;
every robot process simulates the same sensing robots and each of them runs a fuser, so the
figures and the agreement are those of every sensing robot's filters) and ``paper_sensing``
(the paper's, L1, L2); ``secure``
(mutual TLS and access control: ``--secure``); ``messages`` per robot and per run
(sent, received, rejected by reason, windows filtered overdue for a teammate's inputs or a
leader's progress, acks held for a waiting
window and how many of those ran out of time) and what the collector
rejected (``collector_rejected_by_reason``); per run the acks the clock stopped waiting for
(``clock_ack_timeouts``); per run ``fault_outcomes`` (accuracy before / during /
after each fault, tracks kept, deleted and re-found: :mod:`relloc.runtime.outcomes`);
``wall_s``.

Tolerance. On a perfect network every leader processes the in-process event sequence and fuses
each equivalent measurement at the event the in-process loop does (see
:mod:`relloc.runtime.estimation`), so the beliefs agree to floating-point round-off;
:data:`AGREEMENT_TOLERANCE` bounds any belief entry, and the headline figures must then be
equal within :data:`FIGURE_TOLERANCE`. That holds when a link stops for a moment and then
delivers (``--stall``, still a perfect network): a leader whose window waits holds its ack, so
the clock never forces the window through without what it waits for
(:meth:`relloc.runtime.node.RobotNode._send_due_acks`). With faults (``--drop`` ...) what was
lost is the point: the differences are reported, not held to the tolerance.
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from relloc.experiments.desilva2015 import (
    LeaderRunScores,
    RunConfig,
    kidnap_metrics,
    leader_estimates,
    metrics,
    score_run,
    sensing_robots,
    tracked_by_others,
)
from relloc.experiments.team_sources import desilva_recording, desilva_scenario
from relloc.pipeline.output import fmt, markdown_table, prepare_out_dir, write_report, write_summary
from relloc.runtime.launcher import ProcessTeam, TeamLauncher
from relloc.runtime.node import ACK_HOLD_S
from relloc.runtime.outcomes import (
    difference_cell,
    figure_agreement,
    figure_difference,
    outcomes_of,
)
from relloc.runtime.summary import (
    agreement,
    assemble_estimates,
    clock_report,
    robot_messages,
)
from relloc.sim.multihypothesis import ROBOT_NAMES

AGREEMENT_TOLERANCE = 1e-6
"""Largest |difference| of a belief entry (mean or covariance) at a common record time that
counts as agreement on a perfect network."""
FIGURE_TOLERANCE = 1e-6
"""Largest |difference| of a headline figure (success rate, RMSE, ANEES) on a perfect network."""
HEADLINE = ("success_rate", "pos_rmse_m", "yaw_rmse_rad", "anees", "time_to_first_confirmed_s")


@dataclass(frozen=True, kw_only=True)
class DeSilvaTeamSettings(ProcessTeam):
    """One ``team up desilva2015`` invocation."""

    name: str
    out_dir: Path
    seed: int = 0
    runs: int = 1
    duration_s: float | None = None
    sharing_policy: str = "all"
    sensing: tuple[int, ...] = sensing_robots(None)
    """The sensing robots' indices (``--sensing``; default the paper's leaders L1, L2)."""


def run_desilva_team(s: DeSilvaTeamSettings) -> dict[str, Any]:
    """Run every run's team, score it beside the in-process run, write the outputs."""
    scenario = desilva_scenario(s.name, s.duration_s, s.sensing)
    config = RunConfig(scenario=scenario, sharing_policy=s.sharing_policy)
    out = prepare_out_dir(s.out_dir)
    distributed: list[LeaderRunScores] = []
    in_process: list[LeaderRunScores] = []
    runs: list[dict[str, Any]] = []
    start = time.monotonic()
    for i in range(s.runs):
        recording = desilva_recording(s.name, s.seed, i, s.duration_s, scenario.sensing)
        settings = s.launch(
            scenario=s.name,
            out_dir=out / f"run{i}",
            seed=s.seed,
            preload=("relloc.experiments.team_sources",),
            node_args=(
                "--run",
                str(i),
                "--duration",
                repr(scenario.duration),
                "--sharing-policy",
                s.sharing_policy,
                "--sensing",
                ",".join(_names(scenario.sensing)),
            ),
        )
        span = recording.span[1] - recording.span[0]
        collected = TeamLauncher(settings, recording.robots, span).run()
        got = assemble_estimates(collected, recording.robots, "gaussian_sum")
        ref = leader_estimates(recording, config)
        distributed.append(score_run(got, recording, config))
        in_process.append(score_run(ref, recording, config))
        agree = agreement(got, ref)
        runs.append(
            {
                "run": i,
                "fault_outcomes": outcomes_of(s.faults, got, recording),
                "wall_s": collected.wall_s,
                "agreement": {k: agree[k] for k in ("max_abs_mean_diff", "max_abs_cov_diff")},
                "messages": robot_messages(collected, recording.robots),
                "clock_ack_timeouts": clock_report(settings.out_dir).get("ack_timeouts", {}),
                "collector_rejected_by_reason": dict(collected.rejected_by_reason),
                "exit_codes": collected.exit_codes,
            }
        )
    summary = _summary(s, scenario.duration, distributed, in_process, runs)
    summary["wall_s"] = time.monotonic() - start
    if scenario.kidnap is not None:
        summary["kidnapped"] = {
            name: kidnap_metrics(results, scenario.kidnap)
            | {"tracked_last_second": tracked_at_end(results, int(scenario.kidnap[0]))}
            for name, results in (("distributed", distributed), ("in_process", in_process))
        }
    write_summary(out, summary)
    write_report(out, report_markdown(summary))
    return summary


def _names(sensing: tuple[int, ...]) -> list[str]:
    """The sensing robots' names (:data:`~relloc.sim.multihypothesis.ROBOT_NAMES`)."""
    return [ROBOT_NAMES[i] for i in sensing]


def tracked_at_end(results: list[LeaderRunScores], robot: int, window_s: float = 1.0) -> float:
    """Fraction of the scans of the last ``window_s`` in which the leaders track ``robot``
    (over leaders and runs): a short run's view of "re-found and tracked to the end". Each run
    is cut at its own last scan (a distributed run's scans need not be the in-process run's)."""
    return float(
        np.mean(
            [
                tracked_by_others(r, robot)[:, r.times >= r.times[-1] - window_s].mean()
                for r in results
            ]
        )
    )


def _headline(m: Mapping[str, Any]) -> dict[str, Any]:
    return {
        **{k: m[k] for k in HEADLINE},
        "hypotheses": m["hypotheses"],
        "success_rate_per_pair": {k: v["success_rate"] for k, v in m["per_pair"].items()},
    }


def _summary(
    s: DeSilvaTeamSettings,
    duration_s: float,
    distributed: list[LeaderRunScores],
    in_process: list[LeaderRunScores],
    runs: list[dict[str, Any]],
) -> dict[str, Any]:
    ours, ref = _headline(metrics(distributed)), _headline(metrics(in_process))
    diff = {k: figure_difference(ours[k], ref[k]) for k in HEADLINE}
    worst = max(max(r["agreement"].values()) for r in runs)
    perfect = not s.faults.network_faulty and not s.faults.kills
    return {
        "experiment": s.name,
        "seed": s.seed,
        "runs": s.runs,
        "duration_s": duration_s,
        "processes_per_run": {"leaders": 2, "pods": 3, "clock": 1, "fusers": len(s.sensing)},
        "sharing_policy": s.sharing_policy,
        "sensing": _names(s.sensing),
        "paper_sensing": _names(sensing_robots(None)),
        "faults": s.faults.to_dict(),
        "secure": s.secure,
        "distributed": ours,
        "in_process": ref,
        "difference": diff,
        **figure_agreement(
            worst,
            perfect,
            diff,
            belief_tolerance=AGREEMENT_TOLERANCE,
            figure_tolerance=FIGURE_TOLERANCE,
        ),
        "per_run": runs,
    }


def _who_senses(summary: Mapping[str, Any]) -> str:
    """The report's sentence on which robots run fusers (``--sensing``)."""
    sensing, paper = summary["sensing"], summary["paper_sensing"]
    if sensing == paper:
        return (
            "Leaders L1, L2 run their Gaussian-sum fusers in their own processes, pods P1–P3 "
            "share their odometry"
        )
    others = [r for r in ROBOT_NAMES if r not in sensing]
    return (
        f"Sensing robots {', '.join(sensing)} (`--sensing`; an extension: the paper's sensing "
        f"robots are {', '.join(paper)}, so the figures are of a different team) run their "
        "Gaussian-sum fusers in their own processes"
        + (f", {', '.join(others)} only share their odometry" if others else "")
    )


def report_markdown(summary: Mapping[str, Any]) -> str:
    """``report.md``: the figures side by side, the agreement, the messages."""
    d, r = summary["distributed"], summary["in_process"]
    rows = [[k, d[k], r[k], difference_cell(summary["difference"][k])] for k in HEADLINE]
    agree = summary["agreement"]
    lines = [
        f"# relloc team up — {summary['experiment']} ({summary['runs']} run(s), seed "
        f"{summary['seed']}, {fmt(summary['duration_s'])} s each)",
        "",
        f"{_who_senses(summary)}; equivalent measurements travel once a second over Zenoh; "
        f"sharing policy `{summary['sharing_policy']}`.",
        "",
        markdown_table(["figure", "distributed", "in-process", "difference"], rows),
        "",
        f"Largest |Δ| of a belief entry at a common record time: {fmt(agree['max_abs_diff'])} "
        f"(tolerance {summary['tolerance']['belief_entry']:g}; figures "
        f"{summary['tolerance']['figure']:g}): "
        f"{'met' if agree['within_tolerance'] else 'not met'}"
        f"{'' if agree['perfect_network'] else ' — faults were injected, so not expected'}.",
    ]
    if "kidnapped" in summary:
        k = summary["kidnapped"]
        lines += [
            "",
            "## Kidnapped robot",
            "",
            markdown_table(
                ["", "re-found rate", "time to re-find (s)", "tracked in the last second"],
                [
                    [
                        name,
                        k[name]["refound_rate"],
                        k[name]["time_to_refind_s"],
                        k[name]["tracked_last_second"],
                    ]
                    for name in ("distributed", "in_process")
                ],
            ),
        ]
    lines += ["", "## Messages (per run)", ""]
    msg_rows = []
    for run in summary["per_run"]:
        for robot, m in run["messages"].items():
            msg_rows.append(
                [
                    run["run"],
                    robot,
                    m["sent"].get("odom", 0),
                    m["sent"].get("mail", 0),
                    sum(m["received_delivered"].values()),
                    m["rejected"],
                    m["overdue_windows"] + m["overdue_windows_waiting_for_mail"],
                    f"{m['acks_held']} ({m['acks_held_expired']})",
                    run["clock_ack_timeouts"].get(robot, 0),
                    m["estimates"],
                ]
            )
    lines.append(
        markdown_table(
            [
                "run",
                "robot",
                "odom sent",
                "mail sent",
                "delivered",
                "rejected",
                "windows overdue",
                "acks held (ran out)",
                "acks timed out",
                "estimates",
            ],
            msg_rows,
        )
    )
    lines += [
        "",
        "A window filtered overdue (held velocities, without the other leader's progress) or "
        "an ack the clock stopped waiting for is where a run on a perfect network can part "
        "from the in-process one. On a network without emulated faults a robot holds its ack "
        "while a window of its would be overdue at the next tick, until what it waits for "
        f"arrives or {ACK_HOLD_S:g} s have passed (ran out); with emulated faults it never "
        "holds.",
    ]
    return "\n".join(lines)
