"""``relloc team up sharma2013``'s per-agent late readings (``compare_agents``): a restarted
agent's counters start again at zero in its new process, so its late readings are those of
every incarnation summed, as the same run's ``messages`` block sums them."""

from __future__ import annotations

from relloc.core.estimates import Estimates
from relloc.experiments.sharma2013_team import compare_agents
from relloc.experiments.team_sources import sharma_sim
from relloc.runtime.launcher import Collected
from relloc.runtime.summary import robot_messages


def test_a_restarted_agent_counts_the_late_readings_of_both_its_processes() -> None:
    _, sim = sharma_sim(0, 0, 0.5)
    first = {"rows_late": 3, "tracks.rows_refiltered": 3, "late_samples": 4, "overdue_windows": 1}
    second = {"rows_late": 2, "tracks.rows_refiltered": 1, "tracks.rows_late_lost": 1}
    second |= {"late_samples": 1, "tracks.odometry_refiltered": 1}
    collected = Collected(stats={"1": [first, second], "2": [{"rows_late": 7}]})
    empty = Estimates(estimator="eif")
    agents = compare_agents(empty, empty, sim.recording, collected)
    assert {
        k: v for k, v in agents["1"].items() if "late" in k or "refilt" in k or "overdue" in k
    } == {
        "readings_late": 5,
        "readings_refiltered": 4,
        "readings_late_lost": 1,
        "odometry_late": 5,
        "odometry_refiltered": 1,
        "odometry_late_lost": 0,
        "overdue_windows": 1,
    }
    assert agents["2"]["readings_late"] == 7 and agents["3"]["readings_late"] == 0
    messages = robot_messages(collected, sim.recording.robots)
    assert agents["1"]["odometry_late"] == messages["1"]["late_odometry_samples"] == 5


def test_an_agent_that_ran_once_reports_its_counters_under_their_names() -> None:
    _, sim = sharma_sim(0, 0, 0.5)
    counters = {"rows_late": 6, "tracks.rows_refiltered": 4, "tracks.rows_late_lost": 2}
    counters |= {"late_samples": 5, "tracks.odometry_refiltered": 3}
    counters |= {"tracks.odometry_late_lost": 1, "overdue_windows": 7}
    empty = Estimates(estimator="eif")
    agents = compare_agents(empty, empty, sim.recording, Collected(stats={"1": [counters]}))
    assert {
        k: v for k, v in agents["1"].items() if k not in ("pos_rmse_m", "heading_rmse_rad")
    } == {
        "records": 0,
        "max_abs_mean_diff": 0.0,
        "max_abs_cov_diff": 0.0,
        "records_missing": 0,
        "readings_late": 6,
        "readings_refiltered": 4,
        "readings_late_lost": 2,
        "odometry_late": 5,
        "odometry_refiltered": 3,
        "odometry_late_lost": 1,
        "overdue_windows": 7,
    }
