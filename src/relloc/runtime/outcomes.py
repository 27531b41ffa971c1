"""What each injected fault did: accuracy before / during / after it, and the tracks it touched.

For a fault with a time window — a partition ``[T1, T2)``, or a robot killed at ``T1`` and
restarted at ``T2`` (end of run if never) — the *affected pairs* are those whose observer and
observed robot are on different sides of the partition, or that involve the killed robot.
Over those pairs:

- position RMSE (m) and yaw RMSE (rad) (the states of each belief's frame) of all recorded
  beliefs before ``T1``, in ``[T1, T2)`` and from ``T2`` on (no steady-state filter: the point
  is what the fault does to a running team);
- ``tracks_kept``: affected pairs with a live track at ``T1`` that were not deleted before
  ``T2 + keep window`` and did not die with a killed observer's process
  (``tracks_lost_with_process``); ``tracks_deleted``: deletions of affected pairs in that interval;
  ``tracks_refound``: tracks of affected pairs (re-)created after a deletion or a restart
  in ``(T1, end]`` (none can be re-found at the instant the fault starts).

Network faults without a window (loss, delay, jitter, duplicates, reordering) are reported once
for the whole run against the fault-free in-process run on the same seed.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from relloc.core.estimates import Estimates
from relloc.core.recording import Recording
from relloc.pipeline.frames import FRAMES
from relloc.pipeline.output import fmt
from relloc.pipeline.team_report import RunResult
from relloc.runtime.faults import FaultSettings

Errors = Sequence[tuple[np.ndarray, str]]
"""Per series, its ``(K, d)`` errors (angles wrapped) and the name of its frame."""


def _rmse(errors: Errors) -> float | None:
    """Position RMSE (m) over the series (each frame's position states); None without
    samples."""
    sq = [np.sum(e[:, list(FRAMES[f].position)] ** 2, axis=1) for e, f in errors]
    e = np.concatenate(sq) if sq else np.zeros(0)
    return float(np.sqrt(np.mean(e))) if e.size else None


def _yaw_rmse(errors: Errors) -> float | None:
    """Yaw RMSE (rad) over the series whose frame has a yaw; None without samples."""
    parts = [e[:, FRAMES[f].yaw] for e, f in errors if FRAMES[f].yaw is not None]
    e = np.concatenate(parts) if parts else np.zeros(0)
    return float(np.sqrt(np.mean(e**2))) if e.size else None


def _window_outcome(
    name: str,
    t1: float,
    t2: float,
    affected: set[tuple[str, str]],
    result: RunResult,
    estimates: Estimates,
    keep_window_s: float,
    dead_observers: frozenset[str] = frozenset(),
) -> dict[str, Any]:
    pairs = [p for p in result.evaluations if (p.owner, p.subject) in affected]
    phases = {
        "before": [(p.error[p.t < t1], p.frame) for p in pairs],
        "during": [(p.error[(p.t >= t1) & (p.t < t2)], p.frame) for p in pairs],
        "after": [(p.error[p.t >= t2], p.frame) for p in pairs],
    }
    events = [e for e in estimates.events if (e.owner, e.subject) in affected]
    horizon = t2 + keep_window_s
    deleted = [e for e in events if e.kind == "deleted" and t1 <= e.t <= horizon]
    refound = [e for e in events if e.kind in ("created", "recreated") and e.t > t1]
    live_at_start = {
        (s.owner, s.subject)
        for s in estimates.beliefs
        if (s.owner, s.subject) in affected and s.t.size and s.t[0] < t1 <= s.t[-1]
    }
    deleted_pairs = {(e.owner, e.subject) for e in deleted}
    lost = {pair for pair in live_at_start - deleted_pairs if pair[0] in dead_observers}
    return {
        "fault": name,
        "window_s": [t1, t2],
        "affected_pairs": sorted(f"{a}->{b}" for a, b in affected),
        "position_rmse_before_m": _rmse(phases["before"]),
        "position_rmse_during_m": _rmse(phases["during"]),
        "position_rmse_after_m": _rmse(phases["after"]),
        "yaw_rmse_before_rad": _yaw_rmse(phases["before"]),
        "yaw_rmse_during_rad": _yaw_rmse(phases["during"]),
        "yaw_rmse_after_rad": _yaw_rmse(phases["after"]),
        "tracks_kept": len(live_at_start - deleted_pairs - lost),
        "tracks_deleted": len(deleted),
        "tracks_lost_with_process": len(lost),
        "tracks_refound": len(refound),
    }


def fault_outcomes(
    faults: FaultSettings,
    result: RunResult,
    estimates: Estimates,
    recording: Recording,
    *,
    keep_window_s: float = 2.0,
) -> list[dict[str, Any]]:
    """One entry per fault (see module docstring)."""
    t_end = recording.span[1]
    all_pairs = {(s.owner, s.subject) for s in estimates.beliefs}
    out: list[dict[str, Any]] = []
    for p in faults.partitions:
        affected = {(a, b) for a, b in all_pairs if (a in p.side) != (b in p.side)}
        name = f"partition {','.join(p.side)}@{p.start_s:g}-{p.end_s:g}"
        out.append(
            _window_outcome(name, p.start_s, p.end_s, affected, result, estimates, keep_window_s)
        )
    for kill in faults.kills:
        back = [r.at_s for r in faults.restarts if r.robot == kill.robot and r.at_s > kill.at_s]
        t2 = min(back) if back else t_end
        affected = {(a, b) for a, b in all_pairs if kill.robot in (a, b)}
        name = f"kill {kill.robot}@{kill.at_s:g}" + (f", restart @{t2:g}" if back else "")
        entry = _window_outcome(
            name,
            kill.at_s,
            t2,
            affected,
            result,
            estimates,
            keep_window_s,
            frozenset({kill.robot}),
        )
        entry["restarted"] = bool(back)
        out.append(entry)
    if faults.drop or faults.delay_ms or faults.jitter_ms or faults.duplicate or faults.reorder:
        counts = {k: sum(e.kind == k for e in estimates.events) for k in ("created", "deleted")}
        counts["recreated"] = sum(e.kind == "recreated" for e in estimates.events)
        out.append(
            {
                "fault": (
                    f"network drop={faults.drop:g} delay={faults.delay_ms:g}ms "
                    f"jitter={faults.jitter_ms:g}ms duplicate={faults.duplicate:g} "
                    f"reorder={faults.reorder:g}"
                ),
                "window_s": [recording.span[0], t_end],
                "position_rmse_during_m": _rmse([(p.error, p.frame) for p in result.evaluations]),
                "yaw_rmse_during_rad": _yaw_rmse([(p.error, p.frame) for p in result.evaluations]),
                "tracks_created": counts["created"],
                "tracks_deleted": counts["deleted"],
                "tracks_refound": counts["recreated"],
                "note": "whole run; compare with the in-process (fault-free) accuracy above",
            }
        )
    return out


def outcomes_of(
    faults: FaultSettings, estimates: Estimates, recording: Recording
) -> list[dict[str, Any]]:
    """:func:`fault_outcomes` of a team's collected estimates, scored against the recording."""
    from relloc.pipeline.evaluation import evaluate

    result = RunResult(evaluations=evaluate(estimates, recording), events=estimates.events)
    return fault_outcomes(faults, result, estimates, recording)


def figure_difference(a: float | None, b: float | None) -> float | None:
    """A figure of the distributed team minus the in-process run's; None when there is nothing
    to compare: a figure missing, or undefined (NaN) in both — a run shorter than the
    steady-state start has no RMSE. NaN in one only stays NaN, a disagreement."""
    if a is None or b is None or (math.isnan(a) and math.isnan(b)):
        return None
    return float(a) - float(b)


def difference_cell(difference: float | None) -> float | str | None:
    """A difference as a report's table shows it: a number, None (nothing to compare, shown as
    ``—``), or ``"differs"`` where it is not finite — a figure undefined on one side only
    (:func:`figure_difference`'s NaN) or of another shape or text (∞)."""
    if difference is None or math.isfinite(difference):
        return difference
    return "differs"


def figure_agreement(
    worst: float,
    perfect: bool,
    differences: Mapping[str, float | None],
    *,
    belief_tolerance: float,
    figure_tolerance: float,
) -> dict[str, Any]:
    """The ``tolerance`` and ``agreement`` blocks of a reproduction's team: the tolerances on a
    belief entry and on a headline figure, the largest belief-entry difference ``worst`` from
    the in-process run, whether the network was perfect, and whether both the beliefs and every
    headline figure (``|difference|``; None: nothing to compare) are within their tolerance."""
    figures_ok = all(d is None or abs(d) <= figure_tolerance for d in differences.values())
    return {
        "tolerance": {"belief_entry": belief_tolerance, "figure": figure_tolerance},
        "agreement": {
            "max_abs_diff": worst,
            "perfect_network": perfect,
            "within_tolerance": bool(worst <= belief_tolerance and figures_ok),
        },
    }


def agreement_text(summary: Mapping[str, Any]) -> str:
    """The console's agreement with the in-process run, from :func:`figure_agreement`'s
    blocks: the largest belief-entry difference against its tolerance, met or not."""
    agree, tolerance = summary["agreement"], summary["tolerance"]["belief_entry"]
    verdict = "within tolerance" if agree["within_tolerance"] else "NOT within tolerance"
    return (
        f"largest |Δ| of a belief entry {fmt(agree['max_abs_diff'])} "
        f"(tolerance {tolerance:g}; {verdict})"
    )
