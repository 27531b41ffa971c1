"""``relloc team up desilva2015``'s small figures and sentences: the share of the last
second's scans in which the other sensing robots track a robot (``tracked_at_end``, window
edge included, each run weighted alike), the report's sentence on who runs a fuser
(``_who_senses``), and the summary's process counts, agreement and message table."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from relloc.experiments.desilva2015 import LeaderRunScores
from relloc.experiments.desilva2015_team import (
    DeSilvaTeamSettings,
    _summary,
    _who_senses,
    report_markdown,
    tracked_at_end,
)
from relloc.runtime.faults import FaultSettings, RobotEvent

TIMES = np.array([0.0, 0.5, 1.0, 1.5, 2.0])


def _scores(tracked_p2: list[list[bool]], times: np.ndarray = TIMES) -> LeaderRunScores:
    """Leaders L1, L2 (robots 0, 1); ``tracked_p2[leader][scan]`` for pod P2 (robot 3) at the
    scan ``times``."""
    tracked = np.zeros((2, times.size, 5), dtype=bool)
    tracked[:, :, 3] = tracked_p2
    zeros = np.zeros((2, times.size, 5))
    counts = np.zeros((2, 5), dtype=np.int64)
    return LeaderRunScores(
        observers=(0, 1),
        times=times,
        pos_err=zeros,
        yaw_err=zeros,
        components=np.ones((2, times.size, 5), dtype=np.int64),
        confirmed=tracked,
        tracked=tracked,
        wrong=counts,
        used=counts,
        joint_wrong=counts,
        joint_used=counts,
        nees=zeros,
        estimate_xy=np.zeros((2, times.size, 5, 2)),
        truth_xy=np.zeros((2, times.size, 5, 2)),
        world_xy=np.zeros((times.size, 5, 2)),
    )


def test_tracked_in_the_last_second_counts_its_first_scan_and_weights_runs_alike() -> None:
    # the last second is t ≥ 1.0: scans 2, 3, 4. L1 tracks P2 in 2 of them, L2 in 2: 2/3
    run = _scores([[False, False, True, False, True], [False, False, False, True, True]])
    assert tracked_at_end([run], 3) == 2.0 / 3.0
    # a second run never tracking it: the mean of the runs' shares, (2/3 + 0)/2
    lost = _scores([[False] * 5, [False] * 5])
    assert tracked_at_end([run, lost], 3) == 1.0 / 3.0


def test_each_run_is_cut_at_its_own_last_scan() -> None:
    """A distributed run whose scans end at 1.0 s: its last second is its scans 0, 0.5 and
    1.0 s, where L1 tracks P2 in all three and L2 in none (1/2), beside the full run's 2/3."""
    full = _scores([[False, False, True, False, True], [False, False, False, True, True]])
    short = _scores([[True, True, True], [False, False, False]], TIMES[:3])
    assert tracked_at_end([short], 3) == 0.5
    assert tracked_at_end([full, short], 3) == (2.0 / 3.0 + 0.5) / 2


def test_who_senses_names_the_paper_leaders_or_the_chosen_robots() -> None:
    paper = {"sensing": ["L1", "L2"], "paper_sensing": ["L1", "L2"]}
    assert _who_senses(paper) == (
        "Leaders L1, L2 run their Gaussian-sum fusers in their own processes, pods P1–P3 "
        "share their odometry"
    )
    chosen = {"sensing": ["L1", "P2"], "paper_sensing": ["L1", "L2"]}
    assert _who_senses(chosen) == (
        "Sensing robots L1, P2 (`--sensing`; an extension: the paper's sensing robots are "
        "L1, L2, so the figures are of a different team) run their Gaussian-sum fusers in "
        "their own processes, L2, P1, P3 only share their odometry"
    )
    everyone = {"sensing": ["L1", "L2", "P1", "P2", "P3"], "paper_sensing": ["L1", "L2"]}
    assert _who_senses(everyone).endswith("run their Gaussian-sum fusers in their own processes")


def _per_run() -> list[dict]:
    leader = {"sent": {"odom": 5, "mail": 2}, "received_delivered": {"odom": 8, "mail": 1}}
    leader |= {"rejected": 0, "overdue_windows": 1, "overdue_windows_waiting_for_mail": 2}
    leader |= {"acks_held": 4, "acks_held_expired": 1, "estimates": 10}
    return [
        {
            "run": 0,
            "agreement": {"max_abs_mean_diff": 0.0, "max_abs_cov_diff": 0.0},
            "messages": {"L1": leader},
            "clock_ack_timeouts": {"L1": 3},
        }
    ]


def test_summary_counts_the_fusers_the_pairs_and_a_kill_as_a_fault() -> None:
    """L1 tracks P2 in every scan, nothing else is tracked: 1 of the 8 pairs succeeds."""
    run = _scores([[True] * 5, [False] * 5])
    everyone = DeSilvaTeamSettings(name="desilva2015", out_dir=Path("unused"), sensing=(0, 1, 2))
    s = _summary(everyone, 2.0, [run], [run], _per_run())
    assert s["processes_per_run"] == {"leaders": 2, "pods": 3, "clock": 1, "fusers": 3}
    assert s["sensing"] == ["L1", "L2", "P1"] and s["paper_sensing"] == ["L1", "L2"]
    assert s["distributed"]["success_rate"] == 0.125
    per_pair = s["distributed"]["success_rate_per_pair"]
    assert len(per_pair) == 8 and per_pair["L1->P2"] == 1.0
    assert sum(per_pair.values()) == 1.0
    assert s["agreement"] == {
        "max_abs_diff": 0.0,
        "perfect_network": True,
        "within_tolerance": True,
    }
    killed = DeSilvaTeamSettings(
        name="desilva2015",
        out_dir=Path("unused"),
        faults=FaultSettings(kills=(RobotEvent(robot="P1", at_s=1.0),)),
    )
    assert _summary(killed, 2.0, [run], [run], _per_run())["agreement"]["perfect_network"] is False


def test_message_table_sums_both_kinds_of_overdue_windows() -> None:
    run = _scores([[True] * 5, [False] * 5])
    settings = DeSilvaTeamSettings(name="desilva2015", out_dir=Path("unused"))
    md = report_markdown(_summary(settings, 2.0, [run], [run], _per_run()))
    # overdue 1 + 2 waiting for mail; 4 acks held, 1 ran out; 3 acks the clock stopped awaiting
    assert "| 0 | L1 | 5 | 2 | 9 | 0 | 3 | 4 (1) | 3 | 10 |" in md
