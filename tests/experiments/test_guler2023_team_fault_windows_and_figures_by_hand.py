"""``relloc team up guler2023``'s pure parts on hand-made inputs: the fault windows
(``fault_windows``), the RMSE before / during / after a fault (``_window_rmse``,
``fault_accuracy``; the formation error of tick k belongs to t_{k+1}), the followers' filter
counters summed over process incarnations (``follower_counts``), the seed of run i (run i of
the reproduction's case), the ``--duration`` checks, and the summary's agreement and report
table."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from relloc.core.estimates import BeliefSeries, Estimates
from relloc.core.gaussian import Gaussian
from relloc.core.recording import GroundTruth, Odometry, Recording, empty_measurements
from relloc.errors import ConfigError
from relloc.experiments.guler2023 import build_cases
from relloc.experiments.guler2023_team import (
    GulerTeamSettings,
    _summary,
    _window_rmse,
    fault_accuracy,
    fault_windows,
    follower_counts,
    largest_difference,
    report_markdown,
    run_seed,
    team_case,
)
from relloc.models.uwb_noise import TIERS_ROUNDED
from relloc.runtime.faults import FaultSettings, Partition, RobotEvent
from relloc.runtime.launcher import Collected
from relloc.sim.airground import AirGroundRun


def _event(robot: str, at_s: float) -> RobotEvent:
    return RobotEvent(robot=robot, at_s=at_s)


def test_fault_windows_end_at_the_first_later_restart() -> None:
    """R_2 killed at 0.5 s, restarted at 1 s, killed again at 1 s (a restart comes first at one
    instant), restarted at 2 s; D_1 cut off over [0.5, 1); 20 % of the messages dropped."""
    faults = FaultSettings(
        drop=0.2,
        partitions=(Partition(side=("D_1",), start_s=0.5, end_s=1.0),),
        kills=(_event("R_2", 0.5), _event("R_2", 1.0)),
        restarts=(_event("R_2", 1.0), _event("R_2", 2.0)),
    )
    assert fault_windows(faults, 3.0) == [
        ("partition D_1@0.5-1", 0.5, 1.0),
        ("kill R_2@0.5, back @1", 0.5, 1.0),
        ("kill R_2@1, back @2", 1.0, 2.0),
        ("network drop=0.2 delay=0ms jitter=0ms duplicate=0 reorder=0", 0.0, 3.0),
    ]
    assert fault_windows(FaultSettings(kills=(_event("R_1", 0.5),)), 3.0) == [
        ("kill R_1@0.5, back @3", 0.5, 3.0)
    ]


def _run() -> AirGroundRun:
    """Ticks at 0, 0.05, 0.1, 0.15 s; one follower's formation error (3, 4), 0 and (6, 8) m
    after ticks 0, 1, 2 (so at 0.05, 0.1 and 0.15 s); no estimates."""
    still = Odometry(t=np.zeros(0), velocity=np.zeros((0, 4)), sigma=np.zeros(4))
    t = np.array([0.0, 0.05, 0.1, 0.15])
    rec = Recording(
        robots=("R_0",),
        platforms=("ground",),
        odometry=(still,),
        measurements=empty_measurements(),
        truth=(GroundTruth(t=t, pose=np.zeros((4, 4))),),
    )
    error = np.array([[[3.0, 4.0]], [[0.0, 0.0]], [[6.0, 8.0]]])
    return AirGroundRun(
        recording=rec,
        estimates=Estimates(estimator="switching_ekf"),
        priors={},
        formation_error=error,
    )


def test_window_rmse_takes_the_formation_error_at_the_end_of_its_tick() -> None:
    run = _run()
    assert _window_rmse(run, 0.05, 0.1) == {"estimate_rmse_m": None, "formation_rmse_m": 5.0}
    assert _window_rmse(run, 0.1, 0.2)["formation_rmse_m"] == pytest.approx(math.sqrt(50.0))
    assert _window_rmse(run, 0.0, 0.05)["formation_rmse_m"] is None


def test_window_rmse_of_the_estimates_leaves_out_the_window_end() -> None:
    """Leader 2 m ahead of its follower, both still; the follower's estimate of r is off by
    (0.3, 0.4), (0.3, 0.4), (0.6, 0.8) and 0 at 0.25, 0.5, 0.75 and 1 s: over [0.25, 0.75)
    the squared errors 0.25 and 0.25."""
    still = Odometry(t=np.zeros(0), velocity=np.zeros((0, 4)), sigma=np.zeros(4))
    t = np.array([0.0, 0.25, 0.5, 0.75, 1.0])
    truth = (
        GroundTruth(t=t, pose=np.tile([2.0, 0.0, 0.0, 0.0], (5, 1))),
        GroundTruth(t=t, pose=np.zeros((5, 4))),
    )
    rec = Recording(
        robots=("R_0", "R_1"),
        platforms=("ground", "ground"),
        odometry=(still, still),
        measurements=empty_measurements(),
        truth=truth,
        meta={"common_frame_yaw": 0.0},
    )
    err = np.array([[0.3, 0.4, 0, 0], [0.3, 0.4, 0, 0], [0.6, 0.8, 0, 0], [0.0, 0.0, 0, 0]])
    belief = BeliefSeries(
        owner="R_1",
        subject="R_0",
        frame="airground_follower",
        t=t[1:],
        mean=np.array([2.0, 0.0, 0.0, 0.0]) + err,
        cov=np.stack([np.eye(4)] * 4),
        age=np.zeros(4),
    )
    run = AirGroundRun(
        recording=rec,
        estimates=Estimates(estimator="switching_ekf", beliefs=(belief,)),
        priors={"R_1": Gaussian(mean=np.zeros(4), cov=np.eye(4))},
        formation_error=np.zeros((4, 1, 2)),
    )
    assert _window_rmse(run, 0.25, 0.75) == {
        "estimate_rmse_m": pytest.approx(0.5),
        "formation_rmse_m": 0.0,
    }
    assert _window_rmse(run, 0.75, 1.5)["estimate_rmse_m"] == pytest.approx(math.sqrt(0.5))


def test_a_fault_lasting_to_the_end_keeps_the_last_tick() -> None:
    """Killed at 0.1 s for good: the window runs to just after the last tick (0.15 s)."""
    run = _run()
    (f,) = fault_accuracy(FaultSettings(kills=(_event("R_1", 0.1),)), run, run)
    assert f["fault"] == "kill R_1@0.1, back @0.150001"
    assert f["before"]["distributed"]["formation_rmse_m"] == 5.0
    assert f["during"]["in_process"]["formation_rmse_m"] == pytest.approx(math.sqrt(50.0))
    assert f["after"]["distributed"]["formation_rmse_m"] is None


def test_follower_counts_sum_every_incarnation_of_the_followers_only() -> None:
    collected = Collected(
        stats={
            "R_1": [
                {"ekf.range_applied": 3, "sent.rows": 9},
                {"ekf.range_applied": 2, "ekf.triangle_refusals": 1},
            ],
            "R_2": [{"ekf.range_applied": 4}],
            "D_1": [{"ekf.range_applied": 100}],
        }
    )
    assert follower_counts(collected, ("R_1", "R_2")) == {
        "range_applied": 9,
        "triangle_refusals": 1,
    }


def test_lists_of_different_lengths_differ() -> None:
    assert largest_difference([1.0, 2.0, 3.0], [1.0, 2.0]) == math.inf
    assert largest_difference([1.0, 2.0], [1.0, 2.0, 3.0]) == math.inf


def test_run_i_of_a_case_is_run_i_of_that_cases_monte_carlo() -> None:
    """The reproduction seeds its scenarios with the words of ``SeedSequence(seed)`` in the
    order one_drone, two_drones, formation, and run i with the i-th child of the word."""
    word = int(np.random.SeedSequence(7).generate_state(9)[1])
    child = np.random.SeedSequence(word).spawn(3)[2]
    got = run_seed(7, "two_drones", 2)
    assert list(got.generate_state(4)) == list(child.generate_state(4))


def test_duration_checks_count_every_robot_tick() -> None:
    # one tick (0.05 s) is enough
    assert team_case("one_drone", 0.05).scenario.duration == 0.05
    # 90 000 s: 1.8 million ticks, but 10.8 million robot-ticks for the six robots
    with pytest.raises(ConfigError, match="90000 s is more than 10000000 robot-ticks"):
        team_case("one_drone", 90_000.0)


def _headline(mean: float) -> dict[str, Any]:
    axes = {"R1": {"x": mean, "y": mean}}
    return {
        "rmse_m": axes,
        "rmse_m_max_over_runs": axes,
        "rmse_m_worst": 0.08,
        "rmse_m_mean": mean,
        "heading_rmse_rad": {"R1": 0.01},
        "formation_rmse_m": axes,
        "formation_rmse_m_worst": 0.09,
        "mode_fraction": {"sw1": 0.5, "sw2": 0.25, "sw3": 0.25},
        "anees_position": 1.25,
        "nees_run_average": {"verdict": None, "runs": 1, "reason": "one run"},
        "gate_rejections": {"range": {"rejected": 0, "applied": 5}},
        "triangle_refusals": 0,
    }


def _per_run() -> list[dict[str, Any]]:
    robot = {"sent": {"rows": 4, "cmd": 3}, "received_delivered": {"rows": 6, "odom": 3}}
    robot |= {"rejected": 1, "late_rows": 2}
    world = {"cmd_received": {"R_1": 3, "R_2": 2}, "rejected": 0}
    agreement = {"max_abs_mean_diff": 0.0, "max_abs_cov_diff": 0.0}
    return [
        {"run": 0, "agreement": agreement, "messages": {"robots": {"R_1": robot}, "world": world}}
    ]


def test_summary_agreement_and_report_table() -> None:
    case = build_cases(TIERS_ROUNDED)["two_drones"].with_scenario(duration=1.5)
    perfect = GulerTeamSettings(out_dir=Path("unused"))
    s = _summary(perfect, case, _headline(0.04), _headline(0.04), _per_run())
    assert s["agreement"] == {
        "max_abs_diff": 0.0,
        "perfect_network": True,
        "within_tolerance": True,
    }
    assert s["processes_per_run"] == {"world": 1, "leader": 1, "followers": 4, "drones": 2}
    killed = GulerTeamSettings(
        out_dir=Path("unused"),
        faults=FaultSettings(kills=(_event("R_1", 0.5),), restarts=(_event("R_1", 1.0),)),
    )
    s = _summary(killed, case, _headline(0.05), _headline(0.04), _per_run())
    assert s["agreement"]["perfect_network"] is False
    assert s["difference"]["rmse_m_mean"] == pytest.approx(0.01)
    assert s["difference"]["rmse_m"] == pytest.approx(0.01)
    # the same verdict (none), the same run count, the same reason
    assert s["difference"]["nees_run_average"] == 0.0
    md = report_markdown(s)
    assert "| rmse_m_mean | 0.05 | 0.04 | 0.01 |" in md
    assert "| mode_fraction.sw2 | 0.25 | 0.25 |  |" in md
    assert "| 0 | R_1 | 4 | 0 | 3 | 9 | 1 | 2 |" in md
    assert "| 0 | world |  |  | 5 |  | 0 |  |" in md
    assert ": not met — faults were injected, so not expected." in md


def test_a_figure_undefined_in_the_distributed_run_only_shows_as_differs() -> None:
    """The report's "largest |Δ|" cell of a one-sided NaN says "differs", not the "—" of a
    figure with nothing to compare."""
    case = build_cases(TIERS_ROUNDED)["two_drones"].with_scenario(duration=1.5)
    ours = _headline(0.04) | {"rmse_m_mean": float("nan")}
    s = _summary(GulerTeamSettings(out_dir=Path("unused")), case, ours, _headline(0.04), _per_run())
    assert s["agreement"]["within_tolerance"] is False
    md = report_markdown(s)
    assert "| rmse_m_mean | — | 0.04 | differs |" in md
    assert "| rmse_m_worst | 0.08 | 0.08 | 0 |" in md
