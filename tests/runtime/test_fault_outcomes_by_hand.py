"""What each injected fault did (``fault_outcomes``), on hand-made beliefs, errors and track
events whose RMSEs and track counts are worked out by hand."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from relloc.core.contract import TrackEvent
from relloc.runtime.faults import FaultSettings, Partition, RobotEvent
from relloc.runtime.outcomes import fault_outcomes, figure_agreement

FRAME = "relative_pose4"  # x, y, z, φ: position (0, 1, 2), yaw 3


def _eval(owner: str, subject: str, t: list[float], error: list[list[float]]) -> SimpleNamespace:
    return SimpleNamespace(
        owner=owner, subject=subject, frame=FRAME, t=np.array(t), error=np.array(error)
    )


def _belief(owner: str, subject: str, t: list[float]) -> SimpleNamespace:
    return SimpleNamespace(owner=owner, subject=subject, t=np.array(t))


def _run(faults, evaluations, beliefs, events, t_end=10.0):
    result = SimpleNamespace(evaluations=tuple(evaluations))
    estimates = SimpleNamespace(
        beliefs=tuple(beliefs),
        events=tuple(TrackEvent(t=t, owner=o, subject=s, kind=k) for t, o, s, k in events),
    )
    recording = SimpleNamespace(span=(0.0, t_end))
    return fault_outcomes(faults, result, estimates, recording)


# A and B are cut off from C during [2, 4): the pairs across are A->C, C->A, C->B, B->C.
PARTITION = FaultSettings(partitions=(Partition(side=("A", "B"), start_s=2.0, end_s=4.0),))
ERRORS_AC = _eval(
    "A",
    "C",
    [1.0, 2.0, 3.0, 4.0, 5.0],
    [
        [3.0, 4.0, 0.0, 0.1],  # before: 25 m²
        [0.0, 0.0, 1.0, 0.2],  # during: 1 m²
        [0.0, 0.0, 3.0, -0.2],  # during: 9 m²
        [1.0, 0.0, 0.0, 0.3],  # after: 1 m²
        [0.0, 0.0, 0.0, -0.3],  # after: 0 m²
    ],
)
ERRORS_AB = _eval("A", "B", [1.0, 3.0, 5.0], [[100.0, 0.0, 0.0, 3.0]] * 3)  # same side


def test_a_partitions_rmse_before_during_and_after_cover_only_the_pairs_across():
    (out,) = _run(PARTITION, [ERRORS_AC, ERRORS_AB], [_belief("A", "C", [1.0, 5.0])], [])
    assert out["fault"] == "partition A,B@2-4"
    assert out["window_s"] == [2.0, 4.0]
    assert out["affected_pairs"] == ["A->C"]
    assert out["position_rmse_before_m"] == pytest.approx(5.0)
    assert out["position_rmse_during_m"] == pytest.approx(math.sqrt(5.0))
    assert out["position_rmse_after_m"] == pytest.approx(math.sqrt(0.5))
    assert out["yaw_rmse_before_rad"] == pytest.approx(0.1)
    assert out["yaw_rmse_during_rad"] == pytest.approx(0.2)
    assert out["yaw_rmse_after_rad"] == pytest.approx(0.3)


def test_a_partitions_track_counts():
    beliefs = [
        _belief("A", "C", [1.0, 5.0]),  # live at 2, deleted at 6 = end + keep window (2 s)
        _belief("C", "B", [0.0, 1.0, 5.0]),  # live at 2, kept
        _belief("C", "A", [2.0, 3.0]),  # starts at the partition: not live before it
        _belief("B", "C", [0.0, 1.0]),  # ended before the partition
        _belief("A", "B", [0.0, 9.0]),  # same side
    ]
    events = [
        (3.0, "A", "B", "deleted"),  # same side: not counted
        (6.0, "A", "C", "deleted"),
        (6.5, "C", "B", "deleted"),  # after the keep window: not counted
        (2.0, "C", "A", "created"),  # at the start: not re-found
        (5.0, "C", "A", "recreated"),
        (7.0, "A", "C", "created"),
    ]
    (out,) = _run(PARTITION, [], beliefs, events)
    assert out["affected_pairs"] == ["A->C", "B->C", "C->A", "C->B"]
    assert out["tracks_kept"] == 1
    assert out["tracks_deleted"] == 1
    assert out["tracks_lost_with_process"] == 0
    assert out["tracks_refound"] == 2
    assert out["position_rmse_before_m"] is None


def test_a_killed_robots_window_runs_to_its_first_restart_after_the_kill():
    faults = FaultSettings(
        kills=(RobotEvent(robot="C", at_s=2.0), RobotEvent(robot="C", at_s=5.0)),
        restarts=(RobotEvent(robot="C", at_s=4.0), RobotEvent(robot="C", at_s=6.0)),
    )
    beliefs = [_belief("A", "C", [0.0, 9.0]), _belief("C", "A", [0.0, 9.0])]
    first, second = _run(faults, [], beliefs, [])
    assert (first["fault"], first["window_s"], first["restarted"]) == (
        "kill C@2, restart @4",
        [2.0, 4.0],
        True,
    )
    assert (second["fault"], second["window_s"]) == ("kill C@5, restart @6", [5.0, 6.0])


def test_a_robot_killed_for_good_is_down_to_the_end_and_its_own_tracks_die_with_it():
    faults = FaultSettings(kills=(RobotEvent(robot="C", at_s=2.0),))
    beliefs = [
        _belief("A", "C", [0.0, 9.0]),  # of the dead robot, by a live one: kept
        _belief("C", "A", [0.0, 9.0]),  # the dead robot's own: lost with its process
        _belief("C", "B", [0.0, 9.0]),  # likewise, but deleted first
        _belief("A", "B", [0.0, 9.0]),  # not concerned
    ]
    events = [(3.0, "C", "B", "deleted")]
    (out,) = _run(faults, [], beliefs, events, t_end=8.0)
    assert out["fault"] == "kill C@2"
    assert out["window_s"] == [2.0, 8.0]
    assert out["restarted"] is False
    assert out["affected_pairs"] == ["A->C", "C->A", "C->B"]
    assert out["tracks_kept"] == 1
    assert out["tracks_lost_with_process"] == 1
    assert out["tracks_deleted"] == 1


def test_jitter_alone_is_reported_once_for_the_whole_run():
    events = [
        (1.0, "A", "B", "created"),
        (2.0, "A", "B", "deleted"),
        (3.0, "A", "B", "recreated"),
        (4.0, "B", "A", "created"),
    ]
    errors = _eval("A", "B", [1.0, 2.0], [[3.0, 4.0, 0.0, 0.0], [0.0, 0.0, 0.0, 0.0]])
    (out,) = _run(FaultSettings(jitter_ms=5.0), [errors], [], events)
    assert out["fault"] == "network drop=0 delay=0ms jitter=5ms duplicate=0 reorder=0"
    assert out["window_s"] == [0.0, 10.0]
    assert out["position_rmse_during_m"] == pytest.approx(math.sqrt(12.5))
    assert (out["tracks_created"], out["tracks_deleted"], out["tracks_refound"]) == (2, 1, 1)
    assert _run(FaultSettings(), [errors], [], events) == []


def test_a_figure_below_the_in_process_one_by_more_than_the_tolerance_disagrees():
    verdict = figure_agreement(
        0.0, True, {"pos_rmse_m": -0.01}, belief_tolerance=1e-6, figure_tolerance=1e-3
    )
    assert verdict["agreement"]["within_tolerance"] is False


def test_beliefs_exactly_at_the_tolerance_agree():
    verdict = figure_agreement(
        1e-6, True, {"pos_rmse_m": 1e-3}, belief_tolerance=1e-6, figure_tolerance=1e-3
    )
    assert verdict["agreement"]["within_tolerance"] is True
