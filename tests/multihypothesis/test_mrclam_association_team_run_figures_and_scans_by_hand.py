"""The figures ``relloc reproduce mrclam-association`` reports for one team run
(``relloc.experiments.mrclam_association``: ``_evaluate``, ``_scored``, ``_tracked_by_age``,
``_spread``, ``_verdict``, ``_share``, ``_seconds``, ``_by_age_table``, ``_clock``) on
hand-made observer scores whose figures follow by hand."""

from __future__ import annotations

import numpy as np
import pytest
from test_association_bound import _settings

from relloc.core.recording import (
    CLUTTER,
    GroundTruth,
    Measurements,
    Odometry,
    Recording,
    measurement_rows,
)
from relloc.experiments import mrclam_association as ma
from relloc.experiments.multihypothesis_scores import NO_READING, LeaderScores

NAMES = ["R1", "R2", "R3"]
#: the run's first tick: records are scored from T0 + WARMUP_S (10 s) on
T0 = 100.0
NAN4 = [np.nan] * 4
N = NO_READING


def _obs(
    observer: int,
    t: list[float],
    error: list[list[list[float]]],
    confirmed: list[list[bool]],
    assoc: list[list[int]],
    joint: list[list[int]],
) -> LeaderScores:
    s = len(t)
    return LeaderScores(
        observer=observer,
        t=np.array(t),
        error=np.array(error, dtype=float),
        estimate=np.zeros((s, 3, 4)),
        nees=np.ones((s, 3)),
        components=np.ones((s, 3), dtype=np.int64),
        confirmed=np.array(confirmed, dtype=bool),
        assoc_origin=np.array(assoc, dtype=np.int64),
        joint_origin=np.array(joint, dtype=np.int64),
    )


def _team() -> list[LeaderScores]:
    """R1 (robot 0) records at 105 s (5 s after T0: before the warm-up ends, not scored),
    110 s (exactly the warm-up: scored) and 120 s:

    - R2 (robot 1): 9 m off at 105 s; (0.3, 0.4) m in the plane, 7 m in height (not scored:
      planar error) and 0.5 rad at 110 s — 0.5 m, 0.5 rad, tracked (inclusive); (0.6, 0.8) m,
      0.1 rad at 120 s — 1 m, not tracked. Confirmed from 110 s; its dominant track took a
      bearing of R2 at 105 s (before confirmation: not counted), of R2 at 110 s (correct) and
      a clutter bearing at 120 s. The joint decision gave it R2's bearing at 110 s and R3's
      at 120 s.
    - R3 (robot 2): no track at 105 s and 110 s; at 120 s on the spot but −0.6 rad off (not
      tracked: |yaw| > 0.5), confirmed there, having taken R2's bearing (wrong robot); the
      joint decision gave it its own bearing at 105 s (unconfirmed: not counted) and 120 s.

    R2 (robot 1) records at 112 s: R1 0.1 m off, confirmed, its own bearing; R3 no track.
    R3 (robot 2) records only at 105 s (before the warm-up): nothing scored, nothing used."""
    r1 = _obs(
        0,
        [T0 + 5.0, T0 + 10.0, T0 + 20.0],
        [
            [NAN4, [9.0, 0.0, 0.0, 0.0], NAN4],
            [NAN4, [0.3, 0.4, 7.0, 0.5], NAN4],
            [NAN4, [0.6, 0.8, 0.0, 0.1], [0.0, 0.0, 0.0, -0.6]],
        ],
        [[False, False, False], [False, True, False], [False, False, True]],
        [[N, 1, 2], [N, 1, N], [N, CLUTTER, 1]],
        [[N, N, 2], [N, 1, N], [N, 2, 2]],
    )
    r2 = _obs(
        1,
        [T0 + 12.0],
        [[[0.1, 0.0, 0.0, 0.0], NAN4, NAN4]],
        [[True, False, False]],
        [[0, N, N]],
        [[N, N, N]],
    )
    r3 = _obs(2, [T0 + 5.0], [[NAN4, NAN4, NAN4]], [[False] * 3], [[N] * 3], [[N] * 3])
    return [r1, r2, r3]


def test_the_team_figures_follow_by_hand() -> None:
    """Bearings used after confirmation: R1's R2 filter 2 (1 correct, 1 clutter), its R3
    filter 1 (another robot's), R2's R1 filter 1 (correct): 4 used, 2 correct, 1 clutter,
    1 wrong robot. Joint decision: 3 counted (R2's at 110 s, R3's at 120 s for R1's R2 filter:
    1 correct; R3's own at 120 s: correct) — 2 of 3. Scored records: R1's 0.5, 1.0, 0.0 m and
    R2's 0.1 m; yaw 0.5, 0.1, 0.6, 0.0 rad; tracked 2 of 4. Coverage: 4 scored of 6 possible
    (R1: 2 records after the warm-up × 2 teammates, R2: 1 × 2, R3: none)."""
    figures, rows = ma._evaluate(_team(), T0, NAMES)
    assert figures["association_accuracy"] == 0.5
    assert figures["association_accuracy_joint"] == pytest.approx(2 / 3)
    assert figures["wrong_clutter"] == 0.25
    assert figures["wrong_robot"] == 0.25
    assert figures["pos_rmse_m"] == pytest.approx(np.sqrt((0.25 + 1.0 + 0.0 + 0.01) / 4))
    assert figures["pos_median_m"] == pytest.approx(0.3)
    assert figures["yaw_rmse_rad"] == pytest.approx(np.sqrt((0.25 + 0.01 + 0.36 + 0.0) / 4))
    assert figures["tracked_fraction"] == 0.5
    assert figures["coverage"] == pytest.approx(4 / 6)
    r1 = figures["per_observer"]["R1"]
    assert r1["association_accuracy"] == pytest.approx(1 / 3)
    assert r1["bearings_used"] == 3
    assert r1["pos_rmse_m"] == pytest.approx(np.sqrt(1.25 / 3))
    assert r1["tracked_fraction"] == pytest.approx(1 / 3)
    assert r1["coverage"] == 0.75
    r2 = figures["per_observer"]["R2"]
    assert (r2["association_accuracy"], r2["bearings_used"]) == (1.0, 1)
    assert r2["pos_rmse_m"] == pytest.approx(0.1)
    assert (r2["tracked_fraction"], r2["coverage"]) == (1.0, 0.5)
    # R3 scored nothing and used nothing: no figure, coverage 0 (not a division by zero)
    assert figures["per_observer"]["R3"] == {
        "association_accuracy": None,
        "bearings_used": 0,
        "pos_rmse_m": None,
        "tracked_fraction": None,
        "coverage": 0.0,
    }
    # one row per observer: its name, then its figures in the summary's order
    assert [r[0] for r in rows] == NAMES
    assert rows[2] == ["R3", None, 0, None, None, 0.0]
    assert rows[0][1:] == list(r1.values())


def test_a_run_without_confirmed_tracks_or_scored_records_has_no_figures() -> None:
    """Every observer before the warm-up ends and never confirmed: no figure but coverage,
    which is None too (no record after the warm-up)."""
    silent = [
        _obs(i, [T0 + 1.0], [[NAN4] * 3], [[False] * 3], [[N] * 3], [[N] * 3]) for i in range(3)
    ]
    figures, _ = ma._evaluate(silent, T0, NAMES)
    for key in ma.HEADLINE_KEYS:
        assert figures[key] is None, key


def test_only_clutter_taken_is_all_wrong_clutter() -> None:
    """One confirmed filter whose dominant track took only clutter: accuracy 0, all of it
    clutter, none another robot's."""
    scores = [
        _obs(
            0,
            [T0 + 10.0],
            [[NAN4, [0.0] * 4, NAN4]],
            [[False, True, False]],
            [[N, CLUTTER, N]],
            [[N, CLUTTER, N]],
        ),
    ]
    figures, _ = ma._evaluate(scores, T0, NAMES)
    assert (figures["association_accuracy"], figures["wrong_clutter"]) == (0.0, 1.0)
    assert figures["wrong_robot"] == 0.0 and figures["association_accuracy_joint"] == 0.0


def test_a_pair_of_robots_with_one_scored_record_is_fully_covered() -> None:
    """Two robots; R1 records once after the warm-up with a track of R2: 1 of 1 possible."""
    one = LeaderScores(
        observer=0,
        t=np.array([T0 + 10.0]),
        error=np.array([[NAN4, [0.1, 0.0, 0.0, 0.0]]]),
        estimate=np.zeros((1, 2, 4)),
        nees=np.ones((1, 2)),
        components=np.ones((1, 2), dtype=np.int64),
        confirmed=np.array([[False, True]]),
        assoc_origin=np.array([[N, 1]]),
        joint_origin=np.array([[N, 1]]),
    )
    figures, _ = ma._evaluate([one], T0, ["R1", "R2"])
    assert figures["per_observer"]["R1"]["coverage"] == 1.0 and figures["coverage"] == 1.0


def test_scored_records_are_planar_after_the_warm_up() -> None:
    r1 = _team()[0]
    pe, ye, ok, tracked = ma._scored(r1, T0)
    np.testing.assert_allclose(pe[1:, 1], [0.5, 1.0])
    np.testing.assert_allclose(ye[2, 1:], [0.1, 0.6])
    assert ok.tolist() == [[False, False, False], [False, True, False], [False, True, True]]
    # tracked where within the tolerances, whether scored or not (9 m off at 105 s is not)
    assert tracked.tolist() == [[False, False, False], [False, True, False], [False, False, False]]


def _three_standing(end_s: float, measurements: Measurements, truth: bool) -> Recording:
    """Robots 1, 2 and 3 standing from 0 to ``end_s`` s with ``measurements``, one landmark at
    (0.5, 0.5), and each robot's ground truth at the origin when ``truth``."""
    span = np.array([0.0, end_s])
    still = Odometry(t=span, velocity=np.zeros((2, 4)), sigma=np.zeros(4))
    return Recording(
        robots=("1", "2", "3"),
        platforms=("ground",) * 3,
        odometry=(still,) * 3,
        measurements=measurements,
        truth=tuple(GroundTruth(t=span, pose=np.zeros((2, 4))) for _ in range(3))
        if truth
        else None,
        landmarks=np.array([[0.5, 0.5, 0.0]]),
    )


def _sightings() -> Recording:
    """R1 reads a bearing of R2 at 108 s, a clutter bearing at 109 s and R3's at 125 s
    (after its last record); R2 reads R1 at 111 s."""
    return _three_standing(
        200.0,
        measurement_rows(
            "bearing",
            t=np.array([108.0, 109.0, 111.0, 125.0]),
            observer=np.array([0, 0, 1, 0]),
            origin=np.array([1, CLUTTER, 0, 2]),
            value=np.zeros((4, 1)),
        ),
        truth=True,
    )


def test_tracked_by_age_counts_scored_records_after_a_sighting() -> None:
    """Scored records: R1's of R2 at 110 s (2 s after the sighting at 108 s, tracked) and
    120 s (12 s, not tracked); R1's of R3 at 120 s (no sighting of R3 before it: left out);
    R2's of R1 at 112 s (1 s after 111 s, tracked). Bins 0-1-5-15-45-∞ s."""
    by_age = ma._tracked_by_age(_team(), _sightings(), T0, _settings(0.0))
    assert by_age.records == (0, 2, 1, 0, 0)
    assert by_age.tracked == (0, 2, 0, 0, 0)


def test_spread_over_runs_skips_runs_without_a_figure() -> None:
    runs = [
        {k: None for k in ma.HEADLINE_KEYS} | {"pos_rmse_m": 1.0, "coverage": 0.5},
        {k: None for k in ma.HEADLINE_KEYS} | {"pos_rmse_m": 6.0, "coverage": None},
        {k: None for k in ma.HEADLINE_KEYS} | {"pos_rmse_m": 2.0, "coverage": 0.8},
    ]
    spread = ma._spread(runs)
    assert spread["pos_rmse_m"] == {"mean": 3.0, "min": 1.0, "max": 6.0}  # the mean, not 2
    assert spread["coverage"] == pytest.approx({"mean": 0.65, "min": 0.5, "max": 0.8})
    assert spread["association_accuracy"] is None
    assert ma._headline({**runs[0], "per_observer": {}}) == runs[0]


def test_report_texts_of_a_figure() -> None:
    assert ma._verdict(0.9, 0.9) == "0.900, met"
    assert ma._verdict(0.8999, 0.9) == "0.900, missed"
    assert ma._verdict(None, 0.9) == "not measured (no confirmed track)"
    assert (ma._share(None), ma._share(0.12345)) == ("—", "0.123")
    assert (ma._seconds(None), ma._seconds(12.34)) == ("—", "12.3 s")


def test_by_age_table_sets_the_filter_beside_the_reference() -> None:
    bins = [
        {"from_s": 0.0, "to_s": 1.0, "records": 3, "tracked_fraction": 2 / 3},
        {"from_s": 45.0, "to_s": None, "records": 0, "tracked_fraction": None},
    ]
    ref = [
        {"from_s": 0.0, "to_s": 1.0, "records": 8, "tracked_fraction": 0.75},
        {"from_s": 45.0, "to_s": None, "records": 2, "tracked_fraction": 1.0},
    ]
    lines = ma._by_age_table(bins, ref).splitlines()
    assert "time since the last sighting" in lines[0] and "reference: tracked" in lines[0]
    assert lines[2].split("|")[1].strip() == "0–1 s"
    assert [c.strip() for c in lines[2].split("|")[2:6]] == ["3", "0.667", "8", "0.75"]
    assert lines[3].split("|")[1].strip() == "≥ 45 s"


def test_the_filter_clock_starts_late_by_the_offset() -> None:
    class W:
        t_start, t_end = 10.0, 11.0

    np.testing.assert_allclose(ma._clock(W(), 0.0), 10.0 + np.arange(20) / 20)  # type: ignore[arg-type]
    late = ma._clock(W(), 0.01)  # type: ignore[arg-type]
    assert late[0] == 10.01 and late.size == 20 and late[-1] < 11.0


def test_a_fit_record_leaves_out_its_window() -> None:
    fit = {"sigma_range": 0.1, "calibration_window": {"start_s": 0.0}, "n_residuals": 7}
    assert ma._fit_record(fit) == {"sigma_range": 0.1, "n_residuals": 7}


def _camera_rows() -> Recording:
    """Camera frames (range, bearing; a robot's barcode or a landmark) of three robots:
    R1 at 1 s reads R2 (2 m, 0.1 rad) and the landmark, at 2 s R2 (3 m, −0.2 rad) and R3
    (4 m, 0.3 rad); R2 at 1.5 s reads only the landmark, at 3 s R1 (the end of the window:
    left out)."""
    return _three_standing(
        10.0,
        measurement_rows(
            "range_bearing",
            t=np.array([1.0, 1.0, 1.5, 2.0, 2.0, 3.0]),
            observer=np.array([0, 0, 1, 0, 0, 1]),
            target=np.array([1, -1, -1, 1, 2, 0]),
            landmark=np.array([-1, 0, 0, -1, -1, -1]),
            value=np.array(
                [[2.0, 0.1], [1.0, 0.0], [1.0, 0.0], [3.0, -0.2], [4.0, 0.3], [2.0, 0.0]]
            ),
        ),
        truth=False,
    )


def test_camera_frames_become_scans_of_unknown_bearings() -> None:
    """Frames in [1, 3) s without clutter: 3 robot readings, 2 landmark readings skipped, one
    frame (R1 at 2 s) with two robots; every frame, the landmark-only one too, gives a height
    0 to each other robot; each robot reading a range to its robot and a bearing whose origin
    is that robot, in time order."""
    rec, counts = ma._hidden_correspondence(
        _camera_rows(), 1.0, 3.0, 0.5, np.random.default_rng(0), 0.0
    )
    assert counts == {
        "robot": 3,
        "landmark_skipped": 2,
        "injected": 0,
        "scans_with_several_robots": 1,
    }
    m = rec.measurements
    heights = m.of_kind("height")
    assert heights.t.tolist() == [1.0, 1.0, 1.5, 1.5, 2.0, 2.0]
    assert heights.observer.tolist() == [0, 0, 1, 1, 0, 0]
    assert heights.target.tolist() == [1, 2, 0, 2, 1, 2]
    assert np.all(heights.value[:, 0] == 0.0)
    ranges = m.of_kind("range")
    assert ranges.t.tolist() == [1.0, 2.0, 2.0] and ranges.target.tolist() == [1, 1, 2]
    assert ranges.value[:, 0].tolist() == [2.0, 3.0, 4.0]
    bearings = m.of_kind("bearing")
    assert bearings.t.tolist() == [1.0, 2.0, 2.0]
    pairs = zip(bearings.origin.tolist(), bearings.value[:, 0].tolist(), strict=True)
    assert sorted(pairs) == [
        (1, -0.2),
        (1, 0.1),
        (2, 0.3),
    ]
    assert bearings.origin[0] == 1 and bearings.value[0, 0] == 0.1
    assert rec.meta["clutter_per_scan"] == 0.0 and rec.meta["field_of_view_rad"] == 0.5


def test_injected_clutter_spreads_over_both_sides_of_the_view() -> None:
    """20 false bearings per scan on average over the 3 frames (seed root 44171, used nowhere
    else in the tests): every one inside ±0.5 rad, on both sides of the axis, labelled
    clutter and counted; the robot bearings are kept."""
    rec, counts = ma._hidden_correspondence(
        _camera_rows(), 1.0, 3.0, 0.5, np.random.default_rng(44171), 20.0
    )
    b = rec.measurements.of_kind("bearing")
    clutter = b.value[b.origin == CLUTTER, 0]
    assert clutter.size == counts["injected"] > 30
    assert np.all(np.abs(clutter) <= 0.5) and clutter.min() < -0.25 and clutter.max() > 0.25
    assert sorted(b.origin[b.origin != CLUTTER].tolist()) == [1, 1, 2]
