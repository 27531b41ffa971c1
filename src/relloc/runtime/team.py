"""``run_team``: launch a team, collect, score and write ``summary.json`` + ``report.md``.

The distributed estimates are rebuilt into an :class:`~relloc.core.estimates.Estimates`
and scored by the very functions of the in-process ``relloc run``
(:func:`relloc.pipeline.team_report.build_summary` and
:func:`~relloc.pipeline.team_report.write_team_report`) on the same seeded recording (run 0 of
``relloc run --seed SEED``), so ``summary.json`` and ``report.md`` have the same layout
(``experiment`` is ``team_up``; a dataset team states its ``source`` instead of a scenario's
rates, :func:`team_meta`). Added keys:

- ``processes``: robot processes, the clock process, kills and restarts (with ``exit_codes``);
  ``presence``: each liveliness event seen (``member``, ``token``, ``event``, ``wall_s``);
  ``wall_s`` and ``simulated_s``: how long the team ran on the wall clock and in the recording;
- ``faults``: the injected network faults as given (:class:`~relloc.runtime.faults.FaultSettings`);
- ``messages.per_robot[robot]``: ``sent`` / ``received_wire`` / ``received_delivered`` per
  stream, ``rejected`` (by reason), duplicates dropped, late odometry samples, fault tallies,
  ``estimates``, track counts, ``latency_us`` p50/p99; ``messages.team``: totals and the
  transport's own loss rate;
- ``in_process``: the in-process run's team accuracy on the same seed, and ``agreement``: the
  largest difference between distributed and in-process beliefs at common times;
- ``fault_outcomes``: per fault, accuracy before/during/after and tracks kept/deleted/re-found
  (:mod:`relloc.runtime.outcomes`);
- ``clock``: ticks, wall time, barrier timeouts, arrivals and departures;
- ``rejected_by_reason``: every message refused anywhere in the team, by receiver (robots
  together, the collector, the clock) and reason (:mod:`relloc.runtime.messages`,
  :mod:`relloc.runtime.admission`), with the total; ``secure``: whether the run used mutual TLS
  and access control (``--secure``).
"""

from __future__ import annotations

import dataclasses
import json
from collections import Counter
from collections.abc import Mapping
from typing import Any

import numpy as np

from relloc.core.estimates import Estimates
from relloc.estimators.relative import FRAME
from relloc.estimators.track_manager import TrackManagerSettings, default_tracker
from relloc.pipeline.export import ExportRequest, export_estimates
from relloc.pipeline.output import fmt, markdown_table, prepare_out_dir, write_report
from relloc.pipeline.team_report import (
    RECORD_RATE_HZ,
    SETTLE_S,
    build_summary,
    scenario_meta,
    track_team,
    tracker_meta,
    write_team_report,
)
from relloc.runtime.launcher import Collected, TeamLauncher, TeamSettings
from relloc.runtime.outcomes import fault_outcomes
from relloc.runtime.scenario import Team, load_team, run_seeds
from relloc.runtime.summary import (
    agreement,
    assemble_estimates,
    clock_report,
    robot_messages,
    team_message_totals,
)

AGREEMENT_TOLERANCE = 1e-6
"""Largest |difference| of any state or covariance entry between the distributed and the
in-process beliefs at common times that counts as agreement on a perfect network."""


def run_team(settings: TeamSettings, *, export: ExportRequest | None = None) -> dict[str, Any]:
    """Run the team of ``settings`` and write its outputs; returns the summary. ``export``
    (``--mcap``/``--tum``) also writes the distributed estimates for ROS tools and evo
    (the summary's ``export`` section, :mod:`relloc.pipeline.export`)."""
    out = prepare_out_dir(settings.out_dir)
    team = load_team(settings.scenario, settings.seed)
    recording = team.recording
    t0, t1 = recording.span
    tracker = dataclasses.replace(
        default_tracker(), filter=settings.filter_kind, gate_probability=settings.gate_probability
    )
    launcher = TeamLauncher(settings, recording.robots, t1 - t0, est_frame=FRAME)
    # the in-process reference runs in a process of its own while the team runs; leaving the
    # block terminates it, also when the launcher is stopped (Ctrl-C, SIGTERM) mid-run
    with launcher.context.Pool(1) as pool:
        reference_run = pool.apply_async(
            in_process_estimates, (settings.scenario, settings.seed, tracker)
        )
        collected = launcher.run()
        in_process = reference_run.get()
    distributed = assemble_estimates(collected, recording.robots, settings.filter_kind)
    meta = team_meta(team, settings, tracker)
    summary, results = build_summary(
        [distributed], [recording], settle_s=SETTLE_S, record_rate_hz=RECORD_RATE_HZ, meta=meta
    )
    reference, _ = build_summary(
        [in_process], [recording], settle_s=SETTLE_S, record_rate_hz=RECORD_RATE_HZ
    )
    per_robot = robot_messages(collected, recording.robots)
    clock = clock_report(out)
    agree = agreement(distributed, in_process)
    agree["tolerance"] = AGREEMENT_TOLERANCE
    agree["within_tolerance"] = bool(
        max(agree["max_abs_mean_diff"], agree["max_abs_cov_diff"]) <= AGREEMENT_TOLERANCE
    )
    summary |= {
        "processes": {
            "robots": len(recording.robots),
            "clock": 1,
            "kills": len(collected.kills),
            "restarts": len(collected.restarts),
            "exit_codes": collected.exit_codes,
        },
        "presence": collected.presence,
        "wall_s": collected.wall_s,
        "simulated_s": t1 - t0,
        "messages": {
            "per_robot": per_robot,
            "team": team_message_totals(per_robot, killed=bool(collected.kills)),
        },
        "in_process": {"team": reference["team"], "pairs": reference["pairs"]},
        "agreement": agree,
        "rejected_by_reason": rejected_by_reason(per_robot, collected, clock),
        "secure": settings.secure,
        "faults": settings.faults.to_dict(),
        "fault_outcomes": fault_outcomes(settings.faults, results[0], distributed, recording),
        "clock": clock,
    }
    if export is not None:
        summary["export"] = export_estimates(
            export,
            distributed,
            recording,
            run=f"the distributed run (seed {settings.seed}): every robot's shipped estimates",
            settle_s=SETTLE_S,
        )
    write_team_report(
        out,
        summary,
        results,
        title=f"relloc team up — {team.name} ({len(recording.robots)} robot processes)",
        arena=(team.scenario.arena.x, team.scenario.arena.y) if team.scenario else None,
        notes=[team.description] if team.description else (),
    )
    report = (out / "report.md").read_text()
    write_report(out, report.rstrip() + "\n\n" + runtime_markdown(summary))
    return summary


def rejected_by_reason(
    per_robot: dict[str, dict[str, Any]], collected: Collected, clock: dict[str, Any]
) -> dict[str, Any]:
    """Rejections by receiver and reason (see the module docstring)."""
    robots: Counter[str] = Counter()
    for m in per_robot.values():
        robots.update(m["rejected_by_reason"])
    by_receiver = {
        "robots": dict(sorted(robots.items())),
        "collector": dict(sorted(collected.rejected_by_reason.items())),
        "clock": dict(sorted(clock.get("rejected_by_reason", {}).items())),
    }
    total = sum(sum(v.values()) for v in by_receiver.values())
    return by_receiver | {"total": total}


def team_meta(team: Team, settings: TeamSettings, tracker: TrackManagerSettings) -> dict[str, Any]:
    """The settings part of ``summary.json`` (that of ``relloc run`` for a scenario)."""
    if team.scenario is not None:
        return scenario_meta(team.scenario, seed=settings.seed, tracker=tracker) | {
            "experiment": "team_up"
        }
    rec = team.recording
    m = rec.measurements
    return {
        "experiment": "team_up",
        "scenario": team.name,
        "source": team.description,
        "seed": settings.seed,
        **tracker_meta(tracker),
        "odometry_sigma": {r: rec.odometry[i].sigma.tolist() for i, r in enumerate(rec.robots)},
        "sensor_sigma": {rec.robots[int(m.observer[0])]: m.sigma[0].tolist()} if m.size else {},
    }


def in_process_estimates(scenario: str, seed: int, tracker: TrackManagerSettings) -> Estimates:
    """The in-process run's estimates on the same recording (run 0 of ``relloc run --seed
    SEED``)."""
    recording = load_team(scenario, seed).recording
    rng = np.random.default_rng(run_seeds(seed)[1])
    return track_team(recording, tracker, record_rate_hz=RECORD_RATE_HZ, rng=rng)


def runtime_markdown(summary: dict[str, Any]) -> str:
    """The report's runtime section: processes, messages, agreement and faults."""
    msgs = summary["messages"]
    rows = []
    for robot, m in msgs["per_robot"].items():
        rows.append(
            [
                robot,
                m["processes"],
                m["estimates"],
                sum(m["sent"][k] for k in ("odom", "meas", "eqm")),
                sum(m["received_wire"].values()),
                sum(m["received_delivered"].values()),
                m["rejected"],
                m["duplicates_dropped"],
                m["late_odometry_samples"],
                m["latency_us"]["p50"],
                m["latency_us"]["p99"],
            ]
        )
    team = msgs["team"]
    agree = summary["agreement"]
    ref = summary["in_process"]["team"]
    ours = summary["team"]
    lines = [
        "## Runtime: every robot its own process over Zenoh",
        "",
        f"{summary['processes']['robots']} robot processes and 1 clock process on loopback; "
        f"{fmt(summary['simulated_s'])} s simulated in {fmt(summary['wall_s'])} s of wall time "
        f"(kills: {summary['processes']['kills']}, restarts: {summary['processes']['restarts']}).",
        "",
        markdown_table(
            [
                "robot",
                "processes",
                "estimates",
                "data sent",
                "received (wire)",
                "delivered",
                "rejected",
                "duplicates",
                "late samples",
                "latency p50 (µs)",
                "latency p99 (µs)",
            ],
            rows,
        ),
        "",
        f"Transport loss (data messages that never arrived, faults excluded): "
        f"{fmt(team['transport_loss_rate'])} (not defined when a robot was killed).",
        "",
        f"Network: {'mutual TLS + access control' if summary['secure'] else 'plain TCP'}; "
        f"rejected messages: {json.dumps(summary['rejected_by_reason'])}.",
        "",
        "### Distributed vs in-process (same seed)",
        "",
        markdown_table(
            ["", "position RMSE (m)", "yaw RMSE (rad)", "ANEES"],
            [
                [
                    "distributed",
                    ours.get("position_rmse_m"),
                    ours.get("yaw_rmse_rad"),
                    ours.get("anees"),
                ],
                [
                    "in-process",
                    ref.get("position_rmse_m"),
                    ref.get("yaw_rmse_rad"),
                    ref.get("anees"),
                ],
            ],
        ),
        "",
        f"Largest difference of a belief at a common time: mean {fmt(agree['max_abs_mean_diff'])}, "
        f"covariance {fmt(agree['max_abs_cov_diff'])} (tolerance {agree['tolerance']:g}: "
        f"{'met' if agree['within_tolerance'] else 'not met'}). The node filters exactly the "
        "in-process event sequence when every teammate's odometry arrives before the window that "
        "needs it; message timing can change that — a sample that arrives after its window was "
        "filtered (counted as late) or a window filtered after waiting the maximum lag holds the "
        "teammate's previous velocity instead — and faults change it on purpose.",
        "",
    ]
    outcomes = summary["fault_outcomes"]
    if outcomes:
        lines += ["### Faults", ""]
        frows = [
            [
                o["fault"],
                _window_text(o),
                o.get("position_rmse_before_m"),
                o.get("position_rmse_during_m"),
                o.get("position_rmse_after_m"),
                o.get("yaw_rmse_before_rad"),
                o.get("yaw_rmse_during_rad"),
                o.get("yaw_rmse_after_rad"),
                o.get("tracks_kept"),
                o.get("tracks_deleted"),
                o.get("tracks_lost_with_process"),
                o.get("tracks_refound"),
            ]
            for o in outcomes
        ]
        lines.append(
            markdown_table(
                [
                    "fault",
                    "window (s)",
                    "pos. RMSE before (m)",
                    "during",
                    "after",
                    "yaw RMSE before (rad)",
                    "during",
                    "after",
                    "tracks kept",
                    "deleted",
                    "lost with process",
                    "re-found",
                ],
                frows,
            )
        )
        for o in outcomes:
            if o.get("note"):
                lines.append(f"- {o['fault']}: {o['note']}")
    return "\n".join(lines)


def _window_text(outcome: Mapping[str, Any]) -> str:
    """A fault's window ``T1–T2`` (s)."""
    t1, t2 = outcome["window_s"]
    return f"{fmt(t1)}–{fmt(t2)}"


def fault_outcome_text(outcome: Mapping[str, Any]) -> str:
    """One console line of a fault's outcome (:mod:`relloc.runtime.outcomes`): its window,
    the RMSEs of the affected pairs before → during → after it (only during, for a network
    fault, which spans the run) and its track counts."""

    def phases(stem: str, unit: str) -> str:
        keys = [f"{stem}_{phase}_{unit}" for phase in ("before", "during", "after")]
        if keys[0] in outcome:
            return " → ".join(fmt(outcome.get(k)) for k in keys) + f" {unit}"
        return f"{fmt(outcome.get(keys[1]))} {unit}"

    tracks = ", ".join(
        f"{label} {outcome[key]}"
        for key, label in (
            ("tracks_created", "created"),
            ("tracks_kept", "kept"),
            ("tracks_deleted", "deleted"),
            ("tracks_lost_with_process", "lost with process"),
            ("tracks_refound", "re-found"),
        )
        if key in outcome
    )
    order = " (before → during → after)" if "position_rmse_before_m" in outcome else ""
    line = (
        f"fault {outcome['fault']} ({_window_text(outcome)} s): position RMSE "
        f"{phases('position_rmse', 'm')}, yaw RMSE {phases('yaw_rmse', 'rad')}{order}; "
        f"tracks {tracks}"
    )
    return line + (f"; {outcome['note']}" if outcome.get("note") else "")


def print_summary(summary: dict[str, Any]) -> None:
    """A short terminal summary of a team run."""
    from rich.console import Console
    from rich.table import Table

    table = Table(title=f"team up — {summary['scenario']} (seed {summary['seed']})")
    for col in ("robot", "procs", "estimates", "sent", "received", "rejected", "p50 µs", "p99 µs"):
        table.add_column(col)
    for robot, m in summary["messages"]["per_robot"].items():
        table.add_row(
            robot,
            str(m["processes"]),
            str(m["estimates"]),
            str(sum(m["sent"][k] for k in ("odom", "meas", "eqm"))),
            str(sum(m["received_delivered"].values())),
            str(m["rejected"]),
            str(m["latency_us"]["p50"]),
            str(m["latency_us"]["p99"]),
        )
    console = Console()
    console.print(table)
    team, ref, agree = summary["team"], summary["in_process"]["team"], summary["agreement"]
    verdict = "within tolerance" if agree["within_tolerance"] else "NOT within tolerance"
    if summary["fault_outcomes"] and not agree["within_tolerance"]:
        verdict += ", as faults change the beliefs on purpose"
    console.print(
        f"position RMSE {fmt(team.get('position_rmse_m'))} m (in-process "
        f"{fmt(ref.get('position_rmse_m'))} m); largest |Δ| of a belief mean entry "
        f"{fmt(agree['max_abs_mean_diff'])} (tolerance {agree['tolerance']:g}; {verdict}); "
        f"wall {fmt(summary['wall_s'])} s"
    )
    for o in summary["fault_outcomes"]:
        console.print(fault_outcome_text(o))
