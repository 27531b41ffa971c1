"""The figures of merit of seed 002 (``relloc.experiments.desilva2015``: ``metrics``,
``kidnap_metrics``, ``_run_result``, ``sensing_robots``) on hand-made per-run scores whose
values follow by hand: one leader (L1) over five robots, only its filter of L2 filled in."""

from __future__ import annotations

import re

import numpy as np
import pytest

from relloc.core.recording import CLUTTER, GroundTruth, Measurements, Odometry, Recording
from relloc.errors import ConfigError
from relloc.experiments.desilva2015 import (
    LeaderRunScores,
    _run_result,
    kidnap_metrics,
    metrics,
    sensing_robots,
)
from relloc.experiments.multihypothesis_scores import NO_READING, LeaderScores

#: scans at 0 s, 5 s and 11..20 s: the steady state (t ≥ 5 s) is the last 11 scans, the final
#: window (the last 10 s, t ≥ 10 s) the last 10
T = np.concatenate([[0.0, 5.0], np.arange(11.0, 21.0)])


def _scores(
    tracked_at: list[float], confirmed_from: float | None, first_run: bool
) -> LeaderRunScores:
    """Run scores of leader L1 (robot 0); its filter of L2 (robot 1) only: position errors
    100, 1, 1, 7 m at 0, 5, 11, 12 s (none later), yaw errors 3, 0.3, 0.4 rad at 0, 5, 11 s,
    one component except 5 at 20 s, tracked at ``tracked_at``, confirmed from
    ``confirmed_from``; the first run used 2 bearings (1 wrong), the joint decision 4 (3
    wrong)."""
    s, n = T.size, 5
    pe = np.full((1, s, n), np.nan)
    ye = np.full((1, s, n), np.nan)
    pe[0, :4, 1] = [100.0, 1.0, 1.0, 7.0]
    ye[0, :3, 1] = [3.0, 0.3, 0.4]
    nees = np.where(np.isfinite(pe), 4.0, np.nan)
    nees[0, 0, 1] = 100.0  # before the steady state
    comps = np.zeros((1, s, n), dtype=np.int64)
    comps[0, :, 1] = 1
    comps[0, -1, 1] = 5
    confirmed = np.zeros((1, s, n), dtype=bool)
    if confirmed_from is not None:
        confirmed[0, T >= confirmed_from, 1] = True
    tracked = np.zeros((1, s, n), dtype=bool)
    tracked[0, np.isin(T, tracked_at), 1] = True
    counts = np.zeros((1, n), dtype=np.int64)

    def count(v: int) -> np.ndarray:
        c = counts.copy()
        c[0, 1] = v if first_run else 0
        return c

    return LeaderRunScores(
        observers=(0,),
        times=T,
        pos_err=pe,
        yaw_err=ye,
        components=comps,
        confirmed=confirmed,
        tracked=tracked,
        wrong=count(1),
        used=count(2),
        joint_wrong=count(3),
        joint_used=count(4),
        nees=nees,
        estimate_xy=np.full((1, s, n, 2), np.nan),
        truth_xy=np.full((1, s, n, 2), np.nan),
        world_xy=np.zeros((s, n, 2)),
    )


def _runs() -> list[LeaderRunScores]:
    """Three runs: L2 tracked in 9, 9 and 5 of the 10 final scans, first tracked after 11 s
    at 12, 13 and 17 s; confirmed from 5 s, from 11 s, never."""
    final = list(np.arange(11.0, 21.0))
    return [
        _scores([f for f in final if f != 15.0], 5.0, True),
        _scores([f for f in final if f != 12.0], 11.0, False),
        _scores([11.0, 17.0, 18.0, 19.0, 20.0], None, False),
    ]


def test_the_figures_of_the_one_filled_pair() -> None:
    m = metrics(_runs())
    pair = m["per_pair"]["L1->L2"]
    # 9 of 10 final scans is the 90 % criterion: runs 1 and 2 succeed
    assert pair["success_rate"] == pytest.approx(2 / 3)
    assert pair["time_to_first_confirmed_s"] == 8.0  # mean of 5 s and 11 s
    assert pair["hypotheses_mean"] == pytest.approx(16 / 12)
    assert pair["hypotheses_max"] == 5
    # steady-state errors: 1, 1, 7 m of 11 scans; 0.3, 0.4 rad
    assert pair["pos_rmse_m"] == pytest.approx(np.sqrt(17.0))
    assert pair["rmse_scored_percent"] == pytest.approx(300 / 11)
    assert pair["yaw_rmse_rad"] == pytest.approx(np.sqrt(0.125))
    assert pair["wrong_association_rate"] == 0.5
    assert pair["anees"] == 1.0  # NEES 4 over 4 DOF in the steady state
    assert m["per_pair"]["L1->P1"]["time_to_first_confirmed_s"] is None


def test_the_figures_over_all_pairs() -> None:
    m = metrics(_runs())
    assert m["runs"] == 3
    assert m["success_rate"] == pytest.approx(2 / 12)  # 2 of 4 pairs × 3 runs
    assert m["time_to_first_confirmed_s"] == 8.0
    assert m["hypotheses"] == {"mean": pytest.approx(16 / 48), "max": 5}
    assert m["pos_rmse_m"] == pytest.approx(np.sqrt(17.0))
    assert m["rmse_scored_percent"] == pytest.approx(100 * 9 / (3 * 4 * 11))
    assert m["yaw_rmse_rad"] == pytest.approx(np.sqrt(0.125))
    assert m["wrong_association_rate"] == 0.5  # 1 of the 2 bearings used, all pairs
    assert m["joint_wrong_association_rate"] == 0.75  # 3 of 4
    assert m["anees"] == 1.0


def test_the_final_window_includes_the_scan_ten_seconds_before_the_end() -> None:
    """Scans at 0, 10 and 20 s: the final window is [10, 20] s; L2 tracked only at 20 s is
    tracked in half of it, short of the 90 % criterion."""
    t = np.array([0.0, 10.0, 20.0])
    base = _scores([], 0.0, False)
    tracked = np.zeros((1, 3, 5), dtype=bool)
    tracked[0, 2, 1] = True

    def cut(a: np.ndarray) -> np.ndarray:
        return a[:, [0, 2, 11]]

    run = LeaderRunScores(
        **{
            **base.__dict__,
            "times": t,
            "tracked": tracked,
            "pos_err": cut(base.pos_err),
            "yaw_err": cut(base.yaw_err),
            "nees": cut(base.nees),
            "components": cut(base.components),
            "confirmed": cut(base.confirmed),
            "estimate_xy": cut(base.estimate_xy),
            "truth_xy": cut(base.truth_xy),
            "world_xy": base.world_xy[:3],
        }
    )
    assert metrics([run])["per_pair"]["L1->L2"]["success_rate"] == 0.0


def test_a_kidnapped_robot_is_refound_by_the_criterion_and_after_the_kidnap() -> None:
    """L2 kidnapped at 11 s: first tracked after 11 s at 12, 13 and 17 s (1, 2 and 6 s
    later: mean 3 s); re-found (tracked in ≥ 90 % of the final scans) in runs 1 and 2."""
    k = kidnap_metrics(_runs(), (1, 11.0, 1.0, 2.0, 0.5))
    assert k["refound_rate"] == pytest.approx(2 / 3)
    assert k["time_to_refind_s"] == 3.0
    assert k["robot"] == "L2" and k["jump"] == {"dx_m": 1.0, "dy_m": 2.0, "dyaw_rad": 0.5}
    # a fourth run that never tracks L2 again: not re-found, and no time to re-find
    k = kidnap_metrics([*_runs(), _scores([], None, False)], (1, 11.0, 1.0, 2.0, 0.5))
    assert k["refound_rate"] == 0.5 and k["time_to_refind_s"] == 3.0


def _recording() -> Recording:
    t = np.array([0.0, 1.0])
    return Recording(
        robots=("A", "B", "C"),
        platforms=("ground",) * 3,
        odometry=tuple(Odometry(t=t, velocity=np.zeros((2, 4)), sigma=np.zeros(4)) for _ in "ABC"),
        measurements=Measurements.concatenate([]),
        truth=tuple(
            GroundTruth(t=t, pose=np.tile(p, (2, 1)))
            for p in ((0, 0, 0, 0), (3, 1, 0, 0), (1, 2, 0, 0))
        ),
    )


def test_a_run_counts_errors_tracking_and_bearings_after_confirmation() -> None:
    """Leader A at 0.5 s and 0.8 s. B: error (0.3, 0.4, 0, 0.5) — 0.5 m and 0.5 rad, at the
    tolerances, tracked — then (0.3, 0.4, 0, −0.7), 0.7 rad off, not tracked; confirmed at the
    first scan only; its bearings from B then C: both used (a filter once confirmed stays
    counted), one wrong; the joint decision's both from B. C: 0.6 m off in height, not
    tracked; confirmed at the second scan, a clutter bearing before it (not counted) and its
    own. The true positions in A's frame: B at (3, 1), C at (1, 2), none in A's column."""
    nan4 = [np.nan] * 4
    error = np.array(
        [
            [nan4, [0.3, 0.4, 0.0, 0.5], [0.0, 0.0, 0.6, 0.0]],
            [nan4, [0.3, 0.4, 0.0, -0.7], [0.0, 0.0, 0.6, 0.0]],
        ]
    )
    sc = LeaderScores(
        observer=0,
        t=np.array([0.5, 0.8]),
        error=error,
        estimate=np.zeros((2, 3, 4)),
        nees=np.ones((2, 3)),
        components=np.ones((2, 3), dtype=np.int64),
        confirmed=np.array([[False, True, False], [False, False, True]]),
        assoc_origin=np.array([[NO_READING, 1, CLUTTER], [NO_READING, 2, 2]]),
        joint_origin=np.array([[NO_READING, 1, NO_READING], [NO_READING, 1, NO_READING]]),
    )
    r = _run_result([sc], _recording())
    np.testing.assert_allclose(r.pos_err[0, :, 1:], [[0.5, 0.6], [0.5, 0.6]])
    np.testing.assert_allclose(r.yaw_err[0, :, 1], [0.5, 0.7])
    assert r.tracked[0].tolist() == [[False, True, False], [False, False, False]]
    assert r.used.tolist() == [[0, 2, 1]]
    assert r.wrong.tolist() == [[0, 1, 0]]
    assert r.joint_used.tolist() == [[0, 2, 0]]
    assert r.joint_wrong.tolist() == [[0, 0, 0]]
    assert np.isnan(r.truth_xy[0, :, 0]).all()
    np.testing.assert_allclose(r.truth_xy[0, :, 1:], [[[3, 1], [1, 2]]] * 2)


def test_a_repeated_sensing_robot_is_refused() -> None:
    with pytest.raises(
        ConfigError,
        match=re.escape("--sensing: 'all' or distinct robot names from L1, L2, P1, P2, P3, got"),
    ):
        sensing_robots("L1, L1")


def test_all_robots_sense_with_all_padded() -> None:
    assert sensing_robots(" all ") == (0, 1, 2, 3, 4)
