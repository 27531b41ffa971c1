"""Turn what the launcher collected into the run's results.

:func:`assemble_estimates` rebuilds an :class:`~relloc.core.estimates.Estimates` — the
very record the in-process run produces — from the robots' ``est``/``evt`` streams, so the
distributed run is scored by the same functions as ``relloc run``. :func:`robot_messages` and
:func:`team_message_totals` add what only a distributed run has: per-robot message counts
(sent, received, rejected), estimate counts, windows filtered overdue, latencies;
:func:`clock_report` reads what the clock process observed (acks it stopped waiting for);
:func:`agreement` compares the distributed beliefs with the in-process ones.
"""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from relloc.core.contract import TrackEvent
from relloc.core.estimates import Estimates
from relloc.errors import ConfigError
from relloc.runtime.launcher import Collected
from relloc.runtime.messages import estimates_from_bodies

DATA_KINDS = ("odom", "meas", "rows", "eqm", "mail")


def assemble_estimates(collected: Collected, roster: Sequence[str], estimator: str) -> Estimates:
    """Every robot's shipped estimates as one record (series sorted by time: a restarted
    observer's second life follows its first); events sorted by time, then roster order."""
    order = {r: i for i, r in enumerate(roster)}
    estimates = latest_of_each_time(estimates_from_bodies(estimator, collected.estimates))
    events = sorted(collected.events, key=lambda e: (e[0], order[e[1]], order[e[2]]))
    return Estimates(
        estimator=estimator,
        beliefs=estimates.beliefs,
        updates=estimates.updates,
        events=tuple(TrackEvent(t=t, owner=o, subject=d, kind=k) for t, o, d, k in events),  # type: ignore[arg-type]
    )


def latest_of_each_time(estimates: Estimates) -> Estimates:
    """Each series with one belief per record time: the last one shipped (a node that
    re-filtered late readings ships the beliefs of those times again; series are sorted by
    time, stable, so the last of equal times is the latest)."""
    beliefs = []
    for s in estimates.beliefs:
        if s.t.size < 2 or np.all(np.diff(s.t) > 0):
            beliefs.append(s)
            continue
        last = np.append(np.diff(s.t) > 0, True)
        beliefs.append(
            dataclasses.replace(
                s,
                t=s.t[last],
                mean=s.mean[last],
                cov=s.cov[last],
                age=s.age[last],
                info={k: v[last] for k, v in s.info.items()},
            )
        )
    return dataclasses.replace(estimates, beliefs=tuple(beliefs))


def sum_counters(incarnations: Sequence[Mapping[str, int]]) -> dict[str, int]:
    """A robot's counters over every process incarnation it had (a restart starts them at 0),
    summed key by key; the latency histograms' bins are left out."""
    total: dict[str, int] = {}
    for counters in incarnations:
        for key, value in counters.items():
            if key.startswith(("latency_us.", "latency_ms.")):
                continue
            total[key] = total.get(key, 0) + int(value)
    return total


def robot_messages(collected: Collected, roster: Sequence[str]) -> dict[str, dict[str, Any]]:
    """Per robot: messages sent / received (on the wire, delivered after faults) / rejected,
    those of a teammate not present (held until it appeared, or never delivered), odometry
    samples late or at a time stamp already filed (a second sample of one time is dropped),
    windows filtered overdue (``overdue_windows``: a teammate's inputs missing;
    ``overdue_windows_waiting_for_mail``: a talking teammate's progress missing), acks held for
    a window that would have been overdue at the next tick (and of those, held until the
    wall-time bound ran out: :meth:`RobotNode._send_due_acks` in :mod:`relloc.runtime.node`),
    estimates, track events, latency percentiles (of its last incarnation)."""
    out: dict[str, dict[str, Any]] = {}
    for robot in roster:
        lives = collected.stats.get(robot, [])
        c = sum_counters(lives)
        last = lives[-1] if lives else {}
        rejected = {k.split(".", 1)[1]: v for k, v in c.items() if k.startswith("rejected.")}
        out[robot] = {
            "processes": len(lives),
            "final_report": bool(last.get("final", 0)),
            "estimates": c.get("estimates", 0),
            "sent": {k: c.get(f"sent.{k}", 0) for k in (*DATA_KINDS, "est", "evt", "stats", "ack")},
            "received_wire": {k: c.get(f"wire.{k}", 0) for k in DATA_KINDS},
            "received_delivered": {k: c.get(f"delivered.{k}", 0) for k in DATA_KINDS},
            "rejected": c.get("rejected", 0),
            "rejected_by_reason": rejected,
            "duplicates_dropped": c.get("duplicates", 0),
            "late_odometry_samples": c.get("late_samples", 0),
            "duplicate_odometry_samples": c.get("duplicate_samples", 0),
            "from_absent_teammate": sum(v for k, v in c.items() if k.startswith("from_absent.")),
            "held_until_appearance": sum(
                v for k, v in c.items() if k.startswith("held_from_absent.")
            ),
            "faults": {k.split(".", 1)[1]: v for k, v in c.items() if k.startswith("fault.")},
            "tracks": {k.split(".", 1)[1]: v for k, v in c.items() if k.startswith("tracks.")},
            "ticks": c.get("ticks", 0),
            "overdue_windows": c.get("overdue_windows", 0),
            "overdue_windows_waiting_for_mail": c.get("overdue_windows.waiting_for_mail", 0),
            "acks_held": c.get("acks_held", 0),
            "acks_held_expired": c.get("acks_held_expired", 0),
            "listens": bool(last.get("listens", 1)),
            "cpu_s": c.get("cpu_ms", 0) / 1000.0,
            "teammate_departures_seen": c.get("teammate.departures", 0),
            "teammate_joins_seen": c.get("teammate.joins", 0),
            "latency_us": {
                "p50": last.get("latency_us.p50"),
                "p99": last.get("latency_us.p99"),
                "samples": last.get("latency_us.samples", 0),
            },
            "estimate_latency_ms": {
                "p50": last.get("latency_ms.p50"),
                "p99": last.get("latency_ms.p99"),
                "samples": last.get("latency_ms.samples", 0),
            },
            "deadlines": {
                "windows": c.get("deadline.windows", 0),
                "missed": c.get("deadline.missed", 0),
            },
        }
    return out


def team_message_totals(
    per_robot: Mapping[str, Mapping[str, Any]], *, killed: bool = False
) -> dict[str, Any]:
    """Team totals and the transport loss rate ``1 − received / expected`` of the data streams,
    where each data message is expected once at every other robot that listens to its
    teammates (all of them, unless robots subscribe only to what they use; emulated faults act
    after reception, so this is what the transport itself lost). With a killed robot the
    expectation is undefined (a dead robot receives nothing) and the rate is None."""
    listeners = {r for r, m in per_robot.items() if m.get("listens", True)}
    sent = sum(sum(r["sent"][k] for k in DATA_KINDS) for r in per_robot.values())
    wire = sum(sum(r["received_wire"].values()) for r in per_robot.values())
    delivered = sum(sum(r["received_delivered"].values()) for r in per_robot.values())
    expected = sum(
        sum(m["sent"][k] for k in DATA_KINDS) * len(listeners - {r}) for r, m in per_robot.items()
    )
    return {
        "data_messages_sent": sent,
        "data_messages_expected": expected,
        "data_messages_received_wire": wire,
        "data_messages_delivered": delivered,
        "transport_loss_rate": None if killed or not expected else 1.0 - wire / expected,
        "rejected": sum(r["rejected"] for r in per_robot.values()),
        "estimates": sum(r["estimates"] for r in per_robot.values()),
    }


def clock_report(run_dir: Path) -> dict[str, Any]:
    """What the clock process observed in a run (``<run_dir>/clock.json``: ticks, wall time,
    ``ack_timeouts`` per robot, arrivals and departures); empty if it wrote nothing."""
    path = run_dir / "clock.json"
    return dict(json.loads(path.read_text())) if path.is_file() else {}


def agreement(distributed: Estimates, in_process: Estimates) -> dict[str, Any]:
    """How far the distributed estimates are from the in-process ones at the same times.

    Per series: the number of common recording times, the largest absolute difference of any
    state and of any covariance entry there, and the records only one run has.
    """
    per_pair: dict[str, Any] = {}
    worst_mean = worst_cov = 0.0
    for ref in in_process.beliefs:
        try:
            got = distributed.series(*ref.key)
        except ConfigError:  # a series the distributed run never recorded
            per_pair[ref.label] = {"common": 0, "only_in_process": int(ref.t.size)}
            continue
        common, i_ref, i_got = np.intersect1d(
            np.round(ref.t, 6), np.round(got.t, 6), return_indices=True
        )
        d_mean = float(np.abs(ref.mean[i_ref] - got.mean[i_got]).max(initial=0.0))
        d_cov = float(np.abs(ref.cov[i_ref] - got.cov[i_got]).max(initial=0.0))
        worst_mean, worst_cov = max(worst_mean, d_mean), max(worst_cov, d_cov)
        per_pair[ref.label] = {
            "common": int(common.size),
            "only_in_process": int(ref.t.size - common.size),
            "only_distributed": int(got.t.size - common.size),
            "max_abs_mean_diff": d_mean,
            "max_abs_cov_diff": d_cov,
        }
    return {"max_abs_mean_diff": worst_mean, "max_abs_cov_diff": worst_cov, "pairs": per_pair}
