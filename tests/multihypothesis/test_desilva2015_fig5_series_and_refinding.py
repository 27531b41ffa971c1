"""The per-scan series behind seed 002's Fig. 5 and the re-finding of a kidnapped robot
(``relloc.experiments.desilva2015``: ``_time_series``, ``tracked_by_others``, ``_rms``,
``_scored_percent``, ``_pairs``) on hand-made run scores whose values follow by hand."""

from __future__ import annotations

import numpy as np
import pytest

from relloc.experiments.desilva2015 import (
    LeaderRunScores,
    _pairs,
    _refind_text,
    _rms,
    _scored_percent,
    _time_series,
    kidnap_metrics,
    tracked_by_others,
)

N_ROBOTS = 5


def _run(
    pos: list[float], yaw: list[float], comps: list[int], observers: tuple[int, ...] = (0,)
) -> LeaderRunScores:
    """Scores of three scans (0, 1, 2 s); every sensing robot's filter of robot 4 (P3) has
    the position errors ``pos``, yaw errors ``yaw`` and components ``comps``; nothing else is
    filled in."""
    n_obs, s = len(observers), 3
    pe = np.full((n_obs, s, N_ROBOTS), np.nan)
    ye = np.full((n_obs, s, N_ROBOTS), np.nan)
    pe[:, :, 4] = pos
    ye[:, :, 4] = yaw
    c = np.zeros((n_obs, s, N_ROBOTS), dtype=np.int64)
    c[:, :, 4] = comps
    counts = np.zeros((n_obs, N_ROBOTS), dtype=np.int64)
    return LeaderRunScores(
        observers=observers,
        times=np.array([0.0, 1.0, 2.0]),
        pos_err=pe,
        yaw_err=ye,
        components=c,
        confirmed=np.zeros((n_obs, s, N_ROBOTS), dtype=bool),
        tracked=np.zeros((n_obs, s, N_ROBOTS), dtype=bool),
        wrong=counts,
        used=counts,
        joint_wrong=counts,
        joint_used=counts,
        nees=np.full((n_obs, s, N_ROBOTS), np.nan),
        estimate_xy=np.full((n_obs, s, N_ROBOTS, 2), np.nan),
        truth_xy=np.full((n_obs, s, N_ROBOTS, 2), np.nan),
        world_xy=np.zeros((s, N_ROBOTS, 2)),
    )


def test_series_are_the_rms_over_the_runs_with_a_track_at_each_scan() -> None:
    """Two runs. Position errors 3, 0, NaN m and 4, NaN, NaN m: RMS over the runs with a track
    √12.5 at 0 s, 0 at 1 s (drawn at the 1e-4 floor of the log axis), none at 2 s. Yaw errors
    0.3, 2e-5, NaN rad and 0.4, 3e-5, NaN rad: RMS 0.25 √2, 1e-4 (the
    floor, not the 2.5e-5 below it), none. Components 1, 2, 0 and 3, 4, 0: means 2, 3, 0."""
    runs = [
        _run([3.0, 0.0, np.nan], [0.3, 2e-5, np.nan], [1, 2, 0]),
        _run([4.0, np.nan, np.nan], [0.4, 3e-5, np.nan], [3, 4, 0]),
    ]
    ts = _time_series(runs)
    assert set(ts) == {"pos", "yaw", "comp"}
    assert set(ts["pos"]) == {"L1->L2", "L1->P1", "L1->P2", "L1->P3"}
    np.testing.assert_allclose(ts["pos"]["L1->P3"], [np.sqrt(12.5), 1e-4, np.nan])
    np.testing.assert_allclose(ts["yaw"]["L1->P3"], [np.sqrt(0.125), 1e-4, np.nan])
    np.testing.assert_allclose(ts["comp"]["L1->P3"], [2.0, 3.0, 0.0])
    # a pair without any track: no error at any scan, no component
    assert np.isnan(ts["pos"]["L1->L2"]).all() and np.isnan(ts["yaw"]["L1->P1"]).all()
    np.testing.assert_array_equal(ts["comp"]["L1->P2"], [0.0, 0.0, 0.0])


def test_series_are_per_sensing_robot() -> None:
    """Two sensing robots (L2 and P1): each of their filters of P3 has its own series; L2's
    own column is not a pair of L2."""
    run = _run([1.0, 2.0, 3.0], [0.1, 0.2, 0.3], [1, 1, 1], observers=(1, 2))
    run.pos_err[1, :, 4] = [5.0, 6.0, 7.0]
    ts = _time_series([run])
    np.testing.assert_allclose(ts["pos"]["L2->P3"], [1.0, 2.0, 3.0])
    np.testing.assert_allclose(ts["pos"]["P1->P3"], [5.0, 6.0, 7.0])
    assert "L2->L2" not in ts["pos"] and "P1->P1" not in ts["pos"]


def test_pairs_name_each_sensing_robot_and_teammate() -> None:
    assert _pairs((1, 3))[:4] == [(0, 0, "L2->L1"), (0, 2, "L2->P1"), (0, 3, "L2->P2"),
                                  (0, 4, "L2->P3")]  # fmt: skip
    assert _pairs((1, 3))[4:] == [(1, 0, "P2->L1"), (1, 1, "P2->L2"), (1, 2, "P2->P1"),
                                  (1, 4, "P2->P3")]  # fmt: skip


def test_tracked_by_others_leaves_out_the_robot_itself() -> None:
    """Sensing robots L1, P2 and P3 (0, 3, 4); P2 (robot 3) is kidnapped: the rows of L1 and
    P3, not its own."""
    run = _run([0.0] * 3, [0.0] * 3, [0] * 3, observers=(0, 3, 4))
    tracked = np.zeros_like(run.tracked)
    tracked[0, :, 3] = [True, False, True]
    tracked[1, :, 3] = [True, True, True]  # P2's own column: never counted
    tracked[2, :, 3] = [False, False, True]
    run = LeaderRunScores(**{**run.__dict__, "tracked": tracked})
    np.testing.assert_array_equal(
        tracked_by_others(run, 3), [[True, False, True], [False, False, True]]
    )
    # a robot that does not sense is scored by every sensing robot
    assert tracked_by_others(run, 1).shape == (3, 3)


def test_rms_and_scored_share_skip_missing_errors() -> None:
    x = np.array([[3.0, np.nan], [4.0, np.nan]])
    assert _rms(x) == pytest.approx(np.sqrt(12.5))
    assert _scored_percent(x) == 50.0
    assert np.isnan(_rms(np.array([np.nan, np.nan])))
    assert _scored_percent(np.array([np.nan, np.nan])) == 0.0
    assert np.isnan(_rms(np.empty(0))) and np.isnan(_scored_percent(np.empty(0)))


def test_a_kidnapped_robot_must_be_tracked_from_ten_seconds_before_the_end() -> None:
    """Scans at 0, 10 and 20 s, P3 (robot 4) kidnapped at 5 s and tracked by L1 at 20 s only:
    the final window is [10, 20] s, the scan at 10 s included, so it is tracked in half of it
    — not re-found — and was first tracked again 15 s after the jump."""
    run = _run([0.0] * 3, [0.0] * 3, [0] * 3)
    run.times[:] = [0.0, 10.0, 20.0]
    run.tracked[0, :, 4] = [False, False, True]
    k = kidnap_metrics([run], (4, 5.0, 1.0, 1.0, 0.0))
    assert (k["refound_rate"], k["time_to_refind_s"]) == (0.0, 15.0)
    run.tracked[0, :, 4] = [False, True, True]
    assert kidnap_metrics([run], (4, 5.0, 1.0, 1.0, 0.0))["refound_rate"] == 1.0


def test_the_report_says_when_the_kidnapped_robot_was_never_re_found() -> None:
    assert _refind_text(None) == "never re-found, so no time to re-find"
    assert _refind_text(0.8712) == "on average 0.87 s after the jump"
