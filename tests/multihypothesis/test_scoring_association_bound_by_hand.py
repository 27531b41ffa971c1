"""The truth-placed association bound and the sighting-reset reference
(``relloc.experiments.association_bound``) on tiny hand-built recordings whose counts follow
from the geometry by hand."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from test_association_bound import _settings

from relloc.core.recording import CLUTTER, GroundTruth, Odometry, Recording, measurement_rows
from relloc.experiments.association_bound import (
    AssociationBound,
    association_bound,
    last_sightings,
    sighting_reset_reference,
)

Array = NDArray[np.float64]
RECORDS = {"A": np.arange(0.0, 60.0, 1.0)}
STILL_B = np.array([2.0, 0.0, 0.0, 0.0])


def _still(pose: Array, t: Array | None = None, gap_s: float | None = None) -> GroundTruth:
    t = np.array([0.0, 60.0]) if t is None else t
    pose = np.tile(pose, (t.size, 1))
    return (
        GroundTruth(t=t, pose=pose) if gap_s is None else GroundTruth(t=t, pose=pose, gap_s=gap_s)
    )


def _pair(
    b_truth: GroundTruth, b_odometry: Array, sightings: Array, origin: list[int] | None = None
) -> Recording:
    """Observer A standing at the origin (exact, zero odometry) and teammate B, whose odometry
    reports ``b_odometry``; A's bearings at ``sightings`` come from B (or from ``origin``)."""
    span = np.array([0.0, 60.0])
    return Recording(
        robots=("A", "B"),
        platforms=("ground", "ground"),
        odometry=(
            Odometry(t=span, velocity=np.zeros((2, 4)), sigma=np.zeros(4)),
            Odometry(t=span, velocity=np.tile(b_odometry, (2, 1)), sigma=np.zeros(4)),
        ),
        measurements=measurement_rows(
            "bearing",
            t=sightings,
            observer=0,
            origin=np.ones(sightings.size, np.int64) if origin is None else np.array(origin),
            value=np.zeros((sightings.size, 1)),
        ),
        truth=(_still(np.zeros(4)), b_truth),
    )


def test_a_record_exactly_at_the_tolerance_counts_as_tracked() -> None:
    """Nothing moves and nothing is reported moving: the reset dead reckoning is exact, so
    with zero tolerances every one of the 55 records from the first sighting on is within
    them (the tolerances are inclusive)."""
    rec = _pair(_still(STILL_B), np.zeros(4), np.array([5.0, 30.0]))
    ref = sighting_reset_reference(rec, _settings(0.0), RECORDS, pos_tol=0.0, yaw_tol=0.0)
    assert (ref.records, ref.tracked) == (55, 55)


def test_a_sideways_drift_counts_in_the_position_error() -> None:
    """B stands still (heading 0) but its odometry slides it sideways at 0.01 m/s: the
    position error is 0.01 m/s × the age, all of it across B's heading. With a 0.055-m
    tolerance the records up to 5 s after each sighting (5 s and 30 s) are tracked: 12 of 55."""
    rec = _pair(_still(STILL_B), np.array([0.0, 0.01, 0.0, 0.0]), np.array([5.0, 30.0]))
    ref = sighting_reset_reference(rec, _settings(0.0), RECORDS, pos_tol=0.055, yaw_tol=0.5)
    assert (ref.records, ref.tracked) == (55, 12)
    assert ref.by_age.tracked == (2, 8, 2, 0, 0)


def test_dead_reckoning_starts_at_a_sighting_older_than_the_first_record() -> None:
    """Records start at 10 s, after the first sighting (5 s): the drift of B's sideways
    odometry (0.01 m/s) counts from 5 s, so only the 10-s record (5 s old) of the first
    sighting is within 0.055 m, and the 30-35 s records of the second: 7 of 50."""
    rec = _pair(_still(STILL_B), np.array([0.0, 0.01, 0.0, 0.0]), np.array([5.0, 30.0]))
    records = {"A": np.arange(10.0, 60.0, 1.0)}
    ref = sighting_reset_reference(rec, _settings(0.0), records, pos_tol=0.055, yaw_tol=0.5)
    assert (ref.records, ref.tracked) == (50, 7)


def test_a_heading_error_across_pi_is_wrapped() -> None:
    """B stands still facing 3.1 rad; its odometry turns at 0.01 rad/s, so its dead-reckoned
    heading passes π a few seconds after each sighting. The heading error is at most
    0.01 × 29 s = 0.29 rad once wrapped: every one of the 55 records is within 0.5 rad."""
    rec = _pair(
        _still(np.array([2.0, 0.0, 0.0, 3.1])),
        np.array([0.0, 0.0, 0.0, 0.01]),
        np.array([5.0, 30.0]),
    )
    ref = sighting_reset_reference(rec, _settings(0.0), RECORDS, pos_tol=0.5, yaw_tol=0.5)
    assert (ref.records, ref.tracked) == (55, 55)


def test_a_sighting_inside_a_truth_gap_leaves_its_records_out() -> None:
    """B's truth has a 6-s gap (2-8 s, bridged only up to 5 s) around the first sighting
    (5 s): the pose it would be reset to is not measured, so the 25 records of ages 0-24 s
    after it are left out as truth-missing, and the 30 records after the second sighting
    (30 s) are counted."""
    t = np.concatenate([np.arange(0.0, 3.0), np.arange(8.0, 61.0)])
    rec = _pair(_still(STILL_B, t, gap_s=5.0), np.zeros(4), np.array([5.0, 30.0]))
    ref = sighting_reset_reference(rec, _settings(0.0), RECORDS, pos_tol=0.5, yaw_tol=0.5)
    assert (ref.records, ref.tracked, ref.truth_missing) == (30, 30, 25)
    d = ref.to_dict()
    assert (d["records"], d["tracked"], d["truth_missing"]) == (30, 30, 25)


def _trio(azimuths: Array, origins: list[int], a_truth: GroundTruth | None = None) -> Recording:
    """Observer A at the origin facing +x, B at (2, 0) (azimuth 0), C at (0, 2) (azimuth
    π/2); A scans at 1 s and 2 s, each scan the bearings ``azimuths`` labelled ``origins``."""
    span = np.array([0.0, 10.0])
    n = azimuths.size
    odometry = Odometry(t=span, velocity=np.zeros((2, 4)), sigma=np.zeros(4))
    return Recording(
        robots=("A", "B", "C"),
        platforms=("ground",) * 3,
        odometry=(odometry,) * 3,
        measurements=measurement_rows(
            "bearing",
            t=np.repeat([1.0, 2.0], n),
            observer=0,
            origin=np.tile(np.asarray(origins, np.int64), 2),
            value=np.tile(azimuths, 2)[:, None],
        ),
        truth=(
            a_truth or GroundTruth(t=span, pose=np.zeros((2, 4))),
            GroundTruth(t=span, pose=np.tile([2.0, 0.0, 0.0, 0.0], (2, 1))),
            GroundTruth(t=span, pose=np.tile([0.0, 2.0, 0.0, 0.0], (2, 1))),
        ),
    )


def test_each_truth_placed_track_takes_the_bearing_of_its_teammate() -> None:
    """Two scans, each with one exact bearing per teammate: B's track takes the first
    bearing row (azimuth 0), C's the second (π/2): 4 bearings used, all correct."""
    bound = association_bound(_trio(np.array([0.0, np.pi / 2]), [1, 2]), _settings(0.0))
    assert (bound.used, bound.correct, bound.accuracy) == (4, 4, 1.0)


def test_a_bearing_from_another_teammate_is_not_correct() -> None:
    """The same bearings with their origins swapped (the bearing at B's azimuth came from C
    and the other way round): the tracks take the same 4 bearings, none of them from the
    teammate the track is of."""
    bound = association_bound(_trio(np.array([0.0, np.pi / 2]), [2, 1]), _settings(0.0))
    assert (bound.used, bound.correct, bound.accuracy) == (4, 0, 0.0)


def test_a_scan_where_the_observer_truth_is_missing_is_skipped() -> None:
    """A's truth has a gap (0.5-9 s, bridged up to 1 s) over the scan at 2 s but a sample at
    1 s: only the first scan is placed, its 2 bearings used and correct."""
    a_truth = GroundTruth(t=np.array([0.0, 0.5, 1.0, 9.0, 10.0]), pose=np.zeros((5, 4)), gap_s=1.0)
    bound = association_bound(_trio(np.array([0.0, np.pi / 2]), [1, 2], a_truth), _settings(0.0))
    assert (bound.used, bound.correct) == (2, 2)


def test_no_bearing_taken_has_no_accuracy() -> None:
    assert AssociationBound(used=0, correct=0).accuracy is None
    assert AssociationBound(used=0, correct=0).to_dict() == {
        "accuracy": None,
        "used": 0,
        "correct": 0,
    }
    assert AssociationBound(used=4, correct=3).to_dict()["accuracy"] == 0.75


def test_only_bearings_from_the_teammate_are_sightings_of_it() -> None:
    """A's bearings at 5 s (from B), 20 s (clutter) and 30 s (from B): the last sighting of B
    at 4, 5, 25 and 40 s is none, 5 s, 5 s and 30 s; A is never sighted by A's bearings."""
    rec = _pair(_still(STILL_B), np.zeros(4), np.array([5.0, 20.0, 30.0]), [1, CLUTTER, 1])
    last = last_sightings(rec, 0, 1, np.array([4.0, 5.0, 25.0, 40.0]), "bearing")
    np.testing.assert_array_equal(last, [np.nan, 5.0, 5.0, 30.0])
    assert np.isnan(last_sightings(rec, 0, 0, np.array([25.0]), "bearing")).all()
