"""Seed 002's figures over several runs and sensing robots (``relloc.experiments.desilva2015``:
``metrics``, ``_run_result``) where the by-hand tests of one leader with its counts in one run
cannot tell the runs, the leaders or a mean from a median apart."""

from __future__ import annotations

import numpy as np
import pytest
from test_scoring_desilva_metrics_by_hand import _recording

from relloc.experiments.desilva2015 import LeaderRunScores, _run_result, metrics
from relloc.experiments.multihypothesis_scores import NO_READING, LeaderScores

#: scans at 0, 5, 15 and 20 s: the final window (the last 10 s) is the scans at 15 s and 20 s
T = np.array([0.0, 5.0, 15.0, 20.0])
L1, L2, P1, P3 = 0, 1, 2, 4


def _blank(observers: tuple[int, ...] = (L1, L2)) -> LeaderRunScores:
    """A run in which no filter has a track, counts nothing and tracks nothing."""
    o, s, n = len(observers), T.size, 5
    counts = np.zeros((o, n), dtype=np.int64)
    return LeaderRunScores(
        observers=observers,
        times=T.copy(),
        pos_err=np.full((o, s, n), np.nan),
        yaw_err=np.full((o, s, n), np.nan),
        components=np.zeros((o, s, n), dtype=np.int64),
        confirmed=np.zeros((o, s, n), dtype=bool),
        tracked=np.zeros((o, s, n), dtype=bool),
        wrong=counts.copy(),
        used=counts.copy(),
        joint_wrong=counts.copy(),
        joint_used=counts.copy(),
        nees=np.full((o, s, n), np.nan),
        estimate_xy=np.full((o, s, n, 2), np.nan),
        truth_xy=np.full((o, s, n, 2), np.nan),
        world_xy=np.zeros((s, n, 2)),
    )


def _three_runs() -> list[LeaderRunScores]:
    """L1's filter of P3 tracked at 15 s and 20 s in run A (all of the final window, not the
    5-s scan before it) and confirmed from 5 s; confirmed from 15 s in run B and from 20 s in
    run C. L2's filter of P1 used 3 bearings in run C, 1 of them
    wrong, and the joint decision gave it 2, 1 wrong."""
    a, b, c = _blank(), _blank(), _blank()
    a.tracked[0, 2:, P3] = True
    a.confirmed[0, 1:, P3] = True
    b.confirmed[0, 2:, P3] = True
    c.confirmed[0, 3:, P3] = True
    c.used[1, P1], c.wrong[1, P1] = 3, 1
    c.joint_used[1, P1], c.joint_wrong[1, P1] = 2, 1
    return [a, b, c]


def test_success_is_judged_on_the_last_ten_seconds_only() -> None:
    m = metrics(_three_runs())
    assert m["per_pair"]["L1->P3"]["success_rate"] == pytest.approx(1 / 3)
    assert m["success_rate"] == pytest.approx(1 / 24)  # 1 of 8 pairs × 3 runs


def test_time_to_first_confirmed_is_the_mean_over_the_confirmed_cells() -> None:
    """L1's filter of P3 first confirmed at 5 s, 15 s and 20 s in runs A, B and C: the mean,
    40/3 s (not the median 15 s), for the pair and over every (run, pair) cell that has one;
    a pair never confirmed has none."""
    m = metrics(_three_runs())
    assert m["per_pair"]["L1->P3"]["time_to_first_confirmed_s"] == pytest.approx(40 / 3)
    assert m["per_pair"]["L2->P3"]["time_to_first_confirmed_s"] is None
    assert m["time_to_first_confirmed_s"] == pytest.approx(40 / 3)


def test_bearing_counts_add_up_over_the_runs_of_each_leader() -> None:
    """Run C's counts of L2's filter of P1 (the third run, the second leader): 1 wrong of 3,
    1 wrong of 2 for the joint decision; no other filter used a bearing."""
    m = metrics(_three_runs())
    assert m["per_pair"]["L2->P1"]["wrong_association_rate"] == pytest.approx(1 / 3)
    assert m["per_pair"]["L1->P1"]["wrong_association_rate"] == 0.0
    assert m["wrong_association_rate"] == pytest.approx(1 / 3)
    assert m["joint_wrong_association_rate"] == 0.5


def test_a_single_wrong_bearing_is_a_rate_of_one() -> None:
    run = _blank()
    run.used[0, P3] = run.wrong[0, P3] = 1
    run.joint_used[1, P1] = run.joint_wrong[1, P1] = 1
    run.confirmed[0, :, P3] = True
    m = metrics([run])
    assert m["wrong_association_rate"] == 1.0
    assert m["joint_wrong_association_rate"] == 1.0
    assert m["per_pair"]["L1->P3"]["wrong_association_rate"] == 1.0


def test_a_run_counts_joint_decisions_given_to_another_robot() -> None:
    """Leader A (robot 0) at 0.5 s and 0.8 s; its filter of B (robot 1), confirmed from the
    first scan, was given C's bearing then B's by the joint decision (1 wrong of 2), its
    filter of C never confirmed. The true paths of the three robots: (T, robot, xy)."""
    nan4 = [np.nan] * 4
    sc = LeaderScores(
        observer=0,
        t=np.array([0.5, 0.8]),
        error=np.array([[nan4, [0.0] * 4, [0.0] * 4]] * 2),
        estimate=np.zeros((2, 3, 4)),
        nees=np.ones((2, 3)),
        components=np.ones((2, 3), dtype=np.int64),
        confirmed=np.array([[False, True, False], [False, False, False]]),
        assoc_origin=np.full((2, 3), NO_READING),
        joint_origin=np.array([[NO_READING, 2, 1], [NO_READING, 1, 2]]),
    )
    r = _run_result([sc], _recording())
    assert r.joint_used.tolist() == [[0, 2, 0]]
    assert r.joint_wrong.tolist() == [[0, 1, 0]]
    assert r.used.tolist() == r.wrong.tolist() == [[0, 0, 0]]
    assert r.estimate_xy.shape == (1, 2, 3, 2)
    assert r.world_xy.shape == (2, 3, 2)
    np.testing.assert_array_equal(r.world_xy[1], [[0, 0], [3, 1], [1, 2]])
