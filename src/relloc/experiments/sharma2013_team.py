"""``relloc team up sharma2013 --out DIR``: seed 001's cooperative localization, decentralised
over robot processes, beside the in-process team EIF on the same seeds.

Every run ``i`` of ``--runs N`` launches robots 1–5 as processes
(:mod:`relloc.experiments.team_sources`): each shares its odometry (``odom``) and its readings
(``rows``: bearings of robots and landmarks, robot 1's GPS fixes) every tick, and runs the team
EIF of one case (``--case``, default ``two_landmarks``) on everything it received. The
in-process reference is that case's filter of ``relloc reproduce sharma2013`` replayed over the
same recording (:func:`relloc.pipeline.replay.replay`, poses recorded every 0.5 s).

Tolerance. On a perfect network each agent filters the same events with the same readings as
the in-process EIF; the readings of one instant reach it in robot order rather than in the
recording's order, so its information sums are added in another order: each agent's beliefs
must match the in-process ones within :data:`AGREEMENT_TOLERANCE` (any mean or covariance
entry). With loss or delay (``--drop``, ``--delay``, ``--jitter``, ...) a window is filtered once a
later ``rows`` of every teammate has arrived or it is overdue; a reading that arrives after its
window was filtered is still fused at its own time stamp: the agent goes back to the state it
checkpointed before that window and filters every window since again with it
(:meth:`relloc.runtime.estimation.WindowDriver.refilter`, 5 s of checkpoints). Lost readings stay
lost: ``cost_of_loss`` reports each agent's accuracy against the perfect-network (in-process)
run.

``summary.json``: ``in_process`` (position and heading RMSE over the robots and the record
times), ``agents.<robot>`` (the same of that agent's estimates, its ``max_abs_mean_diff`` /
``max_abs_cov_diff`` against the in-process EIF, its late readings — re-filtered from a
checkpoint or lost — and overdue windows), ``agreement``
(worst over agents, ``within_tolerance``), ``cost_of_loss`` (per agent, RMSE − in-process
RMSE), ``secure`` (mutual TLS and access control: ``--secure``), ``messages`` per run and
robot and what the collector rejected (``collector_rejected_by_reason``), per run
``fault_outcomes`` (accuracy before / during / after each fault: :mod:`relloc.runtime.outcomes`),
``fault_phases`` (per kill or partition, every agent's and the in-process EIF's position RMSE
before / during / after it) and ``rejoined`` (per restart: the restarted agent's ``sync``
counters and its largest difference from every agent that stayed up).

Faults. A restarted agent does not start from the t = 0 prior: it asks a teammate for the
team belief and continues from it (:mod:`relloc.runtime.handoff`). While a teammate's process
is gone its robot is *lost* to the others — still, with the variance of a robot driving at up
to the scenario's speed (:attr:`relloc.estimators.cooperative.OdometryModel.lost_speed`) —
and the others' readings of it are still fused (its own stopped with its process). Late
odometry is re-filtered from the checkpoints like late readings.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from relloc.core.checks import count, positive
from relloc.core.estimates import Estimates
from relloc.core.recording import Recording
from relloc.experiments.sharma2013 import OUTPUT_EVERY_S
from relloc.experiments.team_sources import check_sharma_case, sharma_estimator, sharma_sim
from relloc.pipeline.evaluation import evaluate
from relloc.pipeline.output import fmt, markdown_table, prepare_out_dir, write_report, write_summary
from relloc.pipeline.replay import replay
from relloc.runtime.faults import FaultSettings
from relloc.runtime.launcher import Collected, ProcessTeam, TeamLauncher
from relloc.runtime.outcomes import figure_difference, outcomes_of
from relloc.runtime.summary import (
    agreement,
    assemble_estimates,
    robot_messages,
    sum_counters,
)

AGREEMENT_TOLERANCE = 1e-9
"""Largest |difference| of an agent's belief entry from the in-process EIF's at a common record
time on a perfect network (summation order only; see the module docstring)."""


@dataclass(frozen=True, kw_only=True)
class SharmaTeamSettings(ProcessTeam):
    """One ``team up sharma2013`` invocation."""

    out_dir: Path
    seed: int = 0
    runs: int = 1
    duration_s: float | None = None
    case: str = "two_landmarks"

    def __post_init__(self) -> None:
        super().__post_init__()
        count(self.runs, "--runs")
        count(self.seed, "--seed", low=0)
        if self.duration_s is not None:
            positive(self.duration_s, "--duration")
        check_sharma_case(self.case)  # before any process starts


def in_process(recording: Recording, sim: Any, scenario: Any, case: str) -> Estimates:
    """The case's team EIF replayed over the recording, as in ``relloc reproduce sharma2013``."""
    t = recording.require_truth("sharma2013")[0].t
    out_t = t[:: round(OUTPUT_EVERY_S / scenario.dt)]
    estimator = sharma_estimator(sim, scenario, case)
    return replay(recording, [estimator], record_times=out_t, start=0.0, end=float(out_t[-1]))


def accuracy(estimates: Estimates, recording: Recording) -> dict[str, float | None]:
    """Position RMSE (m) and heading RMSE (rad) over every robot and record time."""
    errors = [e.error for e in evaluate(estimates, recording)]
    if not errors:
        return {"pos_rmse_m": None, "heading_rmse_rad": None, "records": 0}
    e = np.concatenate(errors)
    return {
        "pos_rmse_m": float(np.sqrt(np.mean(e[:, 0] ** 2 + e[:, 1] ** 2))),
        "heading_rmse_rad": float(np.sqrt(np.mean(e[:, 2] ** 2))),
        "records": int(e.shape[0]),
    }


def _of_owner(estimates: Estimates, owner: str, as_owner: str | None = None) -> Estimates:
    """The series of one owner (renamed ``as_owner``)."""
    beliefs = tuple(
        dataclasses.replace(s, owner=as_owner or owner)
        for s in estimates.beliefs
        if s.owner == owner
    )
    return Estimates(estimator=estimates.estimator, beliefs=beliefs)


def compare_agents(
    got: Estimates, ref: Estimates, recording: Recording, collected: Collected
) -> dict[str, Any]:
    """Per agent: its accuracy, its largest difference from the in-process team filter
    (``ref``, owner ``"team"``), the records it lacks and its late readings."""
    agents: dict[str, Any] = {}
    for robot in recording.robots:
        mine = _of_owner(got, robot)
        agree = agreement(mine, _of_owner(ref, "team", robot))
        agents[robot] = accuracy(mine, recording) | {
            "max_abs_mean_diff": agree["max_abs_mean_diff"],
            "max_abs_cov_diff": agree["max_abs_cov_diff"],
            "records_missing": sum(p.get("only_in_process", 0) for p in agree["pairs"].values()),
            **_late_counts(sum_counters(collected.stats.get(robot, []))),
        }
    return agents


def run_sharma_team(s: SharmaTeamSettings) -> dict[str, Any]:
    """Run every run's team, compare every agent with the in-process EIF, write the outputs."""
    out = prepare_out_dir(s.out_dir)
    start = time.monotonic()
    runs: list[dict[str, Any]] = []
    for i in range(s.runs):
        scenario, sim = sharma_sim(s.seed, i, s.duration_s)
        recording = sim.recording
        settings = s.launch(
            scenario="sharma2013",
            out_dir=out / f"run{i}",
            seed=s.seed,
            preload=("relloc.experiments.team_sources", "relloc.experiments.sharma2013"),
            node_args=("--run", str(i), "--duration", repr(scenario.duration), "--case", s.case),
        )
        span = recording.span[1] - recording.span[0]
        collected = TeamLauncher(settings, recording.robots, span).run()
        got = assemble_estimates(collected, recording.robots, "eif")
        ref = in_process(recording, sim, scenario, s.case)
        agents = compare_agents(got, ref, recording, collected)
        messages = robot_messages(collected, recording.robots)
        runs.append(
            {
                "run": i,
                "fault_outcomes": outcomes_of(s.faults, got, recording),
                "fault_phases": fault_phases(s.faults, got, ref, recording),
                "rejoined": rejoined(s.faults, got, collected, recording),
                "wall_s": collected.wall_s,
                "in_process": accuracy(ref, recording),
                "agents": agents,
                "messages": messages,
                "collector_rejected_by_reason": dict(collected.rejected_by_reason),
                "exit_codes": collected.exit_codes,
            }
        )
    summary = _summary(s, runs)
    summary["wall_s"] = time.monotonic() - start
    write_summary(out, summary)
    write_report(out, report_markdown(summary))
    return summary


def _phase_rmse(estimates: Estimates, recording: Recording, t1: float, t2: float) -> dict[str, Any]:
    """Position RMSE (m) over every robot of the records before ``t1``, in ``[t1, t2)``
    and from ``t2`` on."""
    evals = evaluate(estimates, recording)
    out: dict[str, Any] = {}
    for phase, pick in (
        ("before", lambda t: t < t1),
        ("during", lambda t: (t >= t1) & (t < t2)),
        ("after", lambda t: t >= t2),
    ):
        e = [p.error[pick(p.t)] for p in evals]
        sq = np.concatenate([x[:, 0] ** 2 + x[:, 1] ** 2 for x in e]) if e else np.zeros(0)
        out[f"pos_rmse_{phase}_m"] = float(np.sqrt(np.mean(sq))) if sq.size else None
    return out


def fault_phases(
    faults: FaultSettings, got: Estimates, ref: Estimates, recording: Recording
) -> list[dict[str, Any]]:
    """Per kill (restarted or not) and partition: every agent's position RMSE over the whole
    team before, during and after it, beside the in-process EIF's (the fault-free run on the
    same seed) over the same records."""
    windows = [(f"partition {','.join(p.side)}", p.start_s, p.end_s) for p in faults.partitions]
    for kill in faults.kills:
        back = [r.at_s for r in faults.restarts if r.robot == kill.robot and r.at_s > kill.at_s]
        windows.append((f"kill {kill.robot}", kill.at_s, min(back, default=recording.span[1])))
    return [
        {
            "fault": name,
            "window_s": [t1, t2],
            "in_process": _phase_rmse(ref, recording, t1, t2),
            "agents": {
                robot: _phase_rmse(_of_owner(got, robot), recording, t1, t2)
                for robot in recording.robots
            },
        }
        for name, t1, t2 in windows
    ]


def rejoined(
    faults: FaultSettings, got: Estimates, collected: Collected, recording: Recording
) -> list[dict[str, Any]]:
    """Per restart: how the restarted agent rejoined the team's estimate (its ``sync``
    counters, :mod:`relloc.runtime.handoff`) and its largest difference from every agent that
    stayed up, over their common record times (before the kill they agree to the
    perfect-network tolerance; after the restart they filter the same events)."""
    out = []
    for restart in faults.restarts:
        robot = restart.robot
        mine = _of_owner(got, robot)
        diffs = {}
        for other in recording.robots:
            if other == robot or any(k.robot == other for k in faults.kills):
                continue
            agree = agreement(mine, _of_owner(got, other, robot))
            diffs[other] = max(agree["max_abs_mean_diff"], agree["max_abs_cov_diff"])
        last = collected.stats.get(robot, [{}])[-1]
        out.append(
            {
                "robot": robot,
                "restart_s": restart.at_s,
                "sync": {k.split(".", 1)[1]: v for k, v in last.items() if k.startswith("sync.")},
                "first_record_s": min(
                    (float(b.t[0]) for b in mine.beliefs if b.t.size), default=None
                ),
                "max_abs_diff_from_agents": diffs,
            }
        )
    return out


def _late_counts(counters: Mapping[str, int]) -> dict[str, int]:
    """An agent's late readings: arrived after their window was filtered, re-filtered from a
    checkpoint, or lost (older than every checkpoint); windows filtered overdue."""
    return {
        "readings_late": counters.get("rows_late", 0),
        "readings_refiltered": counters.get("tracks.rows_refiltered", 0),
        "readings_late_lost": counters.get("tracks.rows_late_lost", 0),
        "odometry_late": counters.get("late_samples", 0),
        "odometry_refiltered": counters.get("tracks.odometry_refiltered", 0),
        "odometry_late_lost": counters.get("tracks.odometry_late_lost", 0),
        "overdue_windows": counters.get("overdue_windows", 0),
    }


def _summary(s: SharmaTeamSettings, runs: list[dict[str, Any]]) -> dict[str, Any]:
    return agents_summary(runs, s.faults) | {
        "experiment": "sharma2013",
        "secure": s.secure,
        "case": s.case,
        "seed": s.seed,
        "runs": s.runs,
    }


def agents_summary(runs: list[dict[str, Any]], faults: FaultSettings) -> dict[str, Any]:
    """The agreement of every agent of every run, and the cost of what was lost."""
    worst = max(
        max(a["max_abs_mean_diff"], a["max_abs_cov_diff"])
        for r in runs
        for a in r["agents"].values()
    )
    missing = sum(a["records_missing"] for r in runs for a in r["agents"].values())
    perfect = not faults.network_faulty and not faults.kills
    cost = {
        f"run{r['run']}:{robot}": figure_difference(a["pos_rmse_m"], r["in_process"]["pos_rmse_m"])
        for r in runs
        for robot, a in r["agents"].items()
    }
    return {
        "faults": faults.to_dict(),
        "tolerance": AGREEMENT_TOLERANCE,
        "agreement": {
            "max_abs_diff": worst,
            "records_missing": missing,
            "perfect_network": perfect,
            "within_tolerance": bool(worst <= AGREEMENT_TOLERANCE and missing == 0),
        },
        "cost_of_loss": {"pos_rmse_minus_in_process_m": cost},
        "per_run": runs,
    }


def _largest(values: Mapping[str, float]) -> float | None:
    return max(values.values(), default=None)


def report_markdown(summary: Mapping[str, Any]) -> str:
    """``report.md``: every agent's accuracy and agreement beside the in-process EIF."""
    rows = []
    for r in summary["per_run"]:
        ref = r["in_process"]
        rows.append(
            [r["run"], "in-process EIF", ref["pos_rmse_m"], ref["heading_rmse_rad"], "", ""]
        )
        for robot, a in r["agents"].items():
            rows.append(
                [
                    r["run"],
                    f"agent {robot}",
                    a["pos_rmse_m"],
                    a["heading_rmse_rad"],
                    max(a["max_abs_mean_diff"], a["max_abs_cov_diff"]),
                    f"{a['readings_late']} ({a['readings_refiltered']} re-filtered)",
                ]
            )
    agree = summary["agreement"]
    rejoins = [
        f"Run {r['run']}: agent {j['robot']} restarted at {j['restart_s']:g} s, rejoined "
        f"({', '.join(f'{k} {v}' for k, v in sorted(j['sync'].items()))}); largest |Δ| from "
        f"the agents that stayed up: {fmt(_largest(j['max_abs_diff_from_agents']))}."
        for r in summary["per_run"]
        for j in r["rejoined"]
    ]
    return "\n".join(
        [
            f"# relloc team up — {summary['experiment']}, case {summary['case']} "
            f"({summary['runs']} run(s), seed {summary['seed']})",
            "",
            "Every robot shares its odometry and readings and runs the team EIF on what it "
            "received.",
            "",
            markdown_table(
                [
                    "run",
                    "",
                    "pos. RMSE (m)",
                    "heading RMSE (rad)",
                    "max \\|Δ\\| of a mean or covariance entry vs in-process",
                    "late readings",
                ],
                rows,
            ),
            "",
            f"Largest |Δ| of a belief entry: {fmt(agree['max_abs_diff'])} (tolerance "
            f"{summary['tolerance']:g}), records missing: {agree['records_missing']}: "
            f"{'met' if agree['within_tolerance'] else 'not met'}"
            f"{'' if agree['perfect_network'] else ' — faults were injected, so not expected'}.",
            *(["", *rejoins] if rejoins else []),
        ]
    )
