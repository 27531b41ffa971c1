"""``relloc team up sharma2013``'s figures from hand-made beliefs of robots standing still:
an agent's accuracy (``accuracy``), its RMSE before / during / after a fault
(``_phase_rmse``, ``fault_phases``), how a restarted agent rejoined (``rejoined``), the
agreement and cost of loss (``agents_summary``) and report.md's table and sentences."""

from __future__ import annotations

import math

import numpy as np
import pytest

from relloc.core.estimates import BeliefSeries, Estimates
from relloc.core.recording import GroundTruth, Odometry, Recording, empty_measurements
from relloc.experiments.sharma2013_team import (
    _phase_rmse,
    accuracy,
    agents_summary,
    compare_agents,
    fault_phases,
    rejoined,
    report_markdown,
)
from relloc.runtime.faults import FaultSettings, RobotEvent
from relloc.runtime.launcher import Collected

POSES = {"1": [0.0, 0.0, 0.0, 0.0], "2": [10.0, 0.0, 0.0, 1.0], "3": [0.0, 10.0, 0.0, -1.0]}
T = np.array([1.0, 2.0, 3.0, 4.0])


def _recording() -> Recording:
    """Robots 1-3 standing still, truth known from 0 s to 10 s."""
    still = Odometry(t=np.zeros(0), velocity=np.zeros((0, 4)), sigma=np.zeros(4))
    truth = tuple(
        GroundTruth(t=np.array([0.0, 10.0]), pose=np.array([p, p])) for p in POSES.values()
    )
    return Recording(
        robots=tuple(POSES),
        platforms=("ground",) * 3,
        odometry=(still,) * 3,
        measurements=empty_measurements(),
        truth=truth,
    )


def _series(owner: str, subject: str, errors: list[list[float]]) -> BeliefSeries:
    x, y, _, yaw = POSES[subject]
    return BeliefSeries(
        owner=owner,
        subject=subject,
        frame="world_pose2",
        t=T,
        mean=np.array([x, y, yaw]) + np.array(errors),
        cov=np.stack([np.eye(3)] * T.size),
        age=np.zeros(T.size),
    )


def _agent_1() -> Estimates:
    """Agent 1's beliefs: of itself off by (3, 4), (6, 8), 0, (0, 3) m at 1, 2, 3, 4 s; of
    robot 2 in place but 0.1 rad off in heading throughout."""
    own = _series("1", "1", [[3.0, 4.0, 0.0], [6.0, 8.0, 0.0], [0.0, 0.0, 0.0], [0.0, 3.0, 0.0]])
    other = _series("1", "2", [[0.0, 0.0, 0.1]] * 4)
    return Estimates(estimator="eif", beliefs=(own, other))


def test_accuracy_over_every_robot_and_record() -> None:
    # squared planar errors 25, 100, 0, 9 and four zeros: 134/8; headings 0.1 rad in 4 of 8
    assert accuracy(_agent_1(), _recording()) == {
        "pos_rmse_m": pytest.approx(math.sqrt(134 / 8)),
        "heading_rmse_rad": pytest.approx(math.sqrt(0.04 / 8)),
        "records": 8,
    }


def test_each_agent_against_the_in_process_team_filter() -> None:
    """The in-process team filter believes robots 1 and 2 exactly where they stand at 1-4 s;
    agent 1 has both series (largest difference 8 m, the y of its (6, 8) error), agents 2 and
    3 recorded nothing: 8 records missing each."""
    exact = [[0.0, 0.0, 0.0]] * 4
    ref = Estimates(
        estimator="eif", beliefs=(_series("team", "1", exact), _series("team", "2", exact))
    )
    agents = compare_agents(_agent_1(), ref, _recording(), Collected())
    assert agents["1"]["max_abs_mean_diff"] == pytest.approx(8.0)
    assert agents["1"]["max_abs_cov_diff"] == 0.0
    assert [agents[r]["records_missing"] for r in ("1", "2", "3")] == [0, 8, 8]
    assert agents["2"]["records"] == 0 and agents["1"]["records"] == 8


def test_phases_split_the_records_at_the_fault_window() -> None:
    # before 2 s: 25 and 0; in [2, 3): 100 and 0; from 3 s: 0, 9 and two zeros
    assert _phase_rmse(_agent_1(), _recording(), 2.0, 3.0) == pytest.approx(
        {
            "pos_rmse_before_m": math.sqrt(12.5),
            "pos_rmse_during_m": math.sqrt(50.0),
            "pos_rmse_after_m": 1.5,
        }
    )
    # a window after every record: nothing during or after
    assert _phase_rmse(_agent_1(), _recording(), 5.0, 6.0)["pos_rmse_after_m"] is None


def test_fault_windows_end_at_the_next_restart_or_the_end_of_the_truth() -> None:
    """Robot 2 killed at 1 s, restarted at 2 s, killed again at 2 s (a restart comes first
    at one instant) and restarted at 3 s; robot 3 killed at 2.5 s for good."""
    faults = FaultSettings(
        kills=(
            RobotEvent(robot="2", at_s=1.0),
            RobotEvent(robot="2", at_s=2.0),
            RobotEvent(robot="3", at_s=2.5),
        ),
        restarts=(RobotEvent(robot="2", at_s=2.0), RobotEvent(robot="2", at_s=3.0)),
    )
    got = _agent_1()
    phases = fault_phases(faults, got, got, _recording())
    assert [(p["fault"], p["window_s"]) for p in phases] == [
        ("kill 2", [1.0, 2.0]),
        ("kill 2", [2.0, 3.0]),
        ("kill 3", [2.5, 10.0]),
    ]
    assert phases[1]["agents"]["1"]["pos_rmse_during_m"] == pytest.approx(math.sqrt(50.0))
    assert phases[1]["agents"]["2"] == {
        "pos_rmse_before_m": None,
        "pos_rmse_during_m": None,
        "pos_rmse_after_m": None,
    }
    assert phases[1]["in_process"]["pos_rmse_after_m"] == pytest.approx(1.5)


def test_a_restarted_agent_is_compared_with_the_agents_that_stayed_up() -> None:
    faults = FaultSettings(
        kills=(RobotEvent(robot="2", at_s=1.0), RobotEvent(robot="3", at_s=1.5)),
        restarts=(RobotEvent(robot="2", at_s=2.0),),
    )
    collected = Collected(
        stats={"2": [{"sync.requests": 3}, {"sync.requests": 1, "sync.applied": 1, "ticks": 9}]}
    )
    (back,) = rejoined(faults, Estimates(estimator="eif"), collected, _recording())
    assert back == {
        "robot": "2",
        "restart_s": 2.0,
        "sync": {"requests": 1, "applied": 1},
        "first_record_s": None,
        # robot 3 was killed too: only robot 1 stayed up
        "max_abs_diff_from_agents": {"1": 0.0},
    }


def _runs() -> list[dict]:
    def agent(mean_diff: float, cov_diff: float, missing: int, pos: float) -> dict:
        return {
            "max_abs_mean_diff": mean_diff,
            "max_abs_cov_diff": cov_diff,
            "records_missing": missing,
            "pos_rmse_m": pos,
            "heading_rmse_rad": 0.25,
            "readings_late": 3,
            "readings_refiltered": 2,
        }

    return [
        {
            "run": 0,
            "in_process": {"pos_rmse_m": 1.0, "heading_rmse_rad": 0.2},
            "agents": {"1": agent(1e-12, 3e-12, 0, 1.5), "2": agent(4e-12, 2e-12, 1, 2.0)},
            "rejoined": [],
        }
    ]


def test_agreement_needs_every_record_and_a_kill_is_not_a_perfect_network() -> None:
    s = agents_summary(_runs(), FaultSettings())
    assert s["agreement"] == {
        "max_abs_diff": 4e-12,
        "records_missing": 1,
        "perfect_network": True,
        "within_tolerance": False,
    }
    assert s["cost_of_loss"] == {"pos_rmse_minus_in_process_m": {"run0:1": 0.5, "run0:2": 1.0}}
    killed = agents_summary(_runs(), FaultSettings(kills=(RobotEvent(robot="2", at_s=1.0),)))
    assert killed["agreement"]["perfect_network"] is False


def test_report_table_and_rejoin_sentence() -> None:
    runs = _runs()
    runs[0]["rejoined"] = [
        {
            "robot": "2",
            "restart_s": 2.0,
            "sync": {"requests": 1, "applied": 1},
            "max_abs_diff_from_agents": {"1": 0.5, "3": 0.25},
        },
        # no teammate stayed up to compare with
        {"robot": "3", "restart_s": 4.0, "sync": {}, "max_abs_diff_from_agents": {}},
    ]
    s = agents_summary(
        runs,
        FaultSettings(
            kills=(RobotEvent(robot="2", at_s=1.0),), restarts=(RobotEvent(robot="2", at_s=2.0),)
        ),
    )
    s |= {"experiment": "sharma2013", "case": "two_landmarks", "seed": 4, "runs": 1}
    md = report_markdown(s)
    # the larger of the mean and covariance differences
    assert "| 0 | agent 1 | 1.5 | 0.25 | 3e-12 | 3 (2 re-filtered) |" in md
    assert "| 0 | agent 2 | 2 | 0.25 | 4e-12 | 3 (2 re-filtered) |" in md
    assert "| 0 | in-process EIF | 1 | 0.2 |  |  |" in md
    assert (
        "Largest |Δ| of a belief entry: 4e-12 (tolerance 1e-09), records missing: 1: not met "
        "— faults were injected, so not expected." in md
    )
    assert md.endswith(
        "Run 0: agent 2 restarted at 2 s, rejoined (applied 1, requests 1); largest |Δ| from "
        "the agents that stayed up: 0.5.\n"
        "Run 0: agent 3 restarted at 4 s, rejoined (); largest |Δ| from the agents that "
        "stayed up: —."
    )
