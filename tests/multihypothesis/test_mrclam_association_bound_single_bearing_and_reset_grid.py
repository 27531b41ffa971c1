"""Corners of the truth-placed association bound and the sighting-reset reference
(``relloc.experiments.association_bound``) that the by-hand tests leave open: an observer with
a single bearing, the reference without records, and the last record dead-reckoned up to its
own time."""

from __future__ import annotations

import numpy as np
from test_association_bound import RECORDS, _pair, _settings
from test_scoring_association_bound_by_hand import _pair as _standing_pair

from relloc.core.recording import GroundTruth, Odometry, Recording, measurement_rows
from relloc.experiments.association_bound import (
    TrackedByAge,
    association_bound,
    sighting_reset_reference,
)
from relloc.sim.trajectories import integrate_body_velocities


def test_an_observer_with_a_single_bearing_is_placed() -> None:
    """A (at the origin facing +x) reads one bearing in the whole recording, B's (azimuth 0,
    B at (2, 0)); B and C read nothing. B's truth-placed track takes it (used, correct); C's
    track (at (0, 2), azimuth π/2) takes none."""
    span = np.array([0.0, 10.0])
    still = Odometry(t=span, velocity=np.zeros((2, 4)), sigma=np.zeros(4))
    rec = Recording(
        robots=("A", "B", "C"),
        platforms=("ground",) * 3,
        odometry=(still,) * 3,
        measurements=measurement_rows(
            "bearing",
            t=np.array([1.0]),
            observer=0,
            origin=np.array([1], np.int64),
            value=np.zeros((1, 1)),
        ),
        truth=tuple(
            GroundTruth(t=span, pose=np.tile(p, (2, 1)))
            for p in ([0.0, 0.0, 0.0, 0.0], [2.0, 0.0, 0.0, 0.0], [0.0, 2.0, 0.0, 0.0])
        ),
    )
    bound = association_bound(rec, _settings(0.0))
    assert (bound.used, bound.correct, bound.accuracy) == (1, 1, 1.0)


def test_the_reference_without_records_counts_nothing() -> None:
    still = GroundTruth(t=np.array([0.0, 60.0]), pose=np.array([[2.0, 0.0, 0.0, 0.0]] * 2))
    rec = _pair(still, np.zeros(4), np.zeros(4))
    for records in ({}, {"A": np.empty(0)}):
        d = sighting_reset_reference(rec, _settings(0.0), records, pos_tol=0.5, yaw_tol=0.5)
        assert d.to_dict() | {"by_age": None} == {
            "tracked_fraction": None,
            "records": 0,
            "tracked": 0,
            "truth_missing": 0,
            "median_age_s": None,
            "by_age": None,
        }
        assert d.by_age.tracked == (0,) * 5


def test_the_last_record_is_dead_reckoned_to_its_own_time() -> None:
    """B drives a 1 m/s circle and its odometry tells the truth: with a 5-mm tolerance every
    record after the first sighting is tracked, the last one (59 s) too — its odometry is read
    at 59 s, not a tick or two before (2 cm at 1 m/s)."""
    grid = np.arange(0.0, 60.0 + 1e-9, 0.01)
    b_velocity = np.array([1.0, 0.0, 0.0, 0.2])
    b_pose = integrate_body_velocities(
        np.array([2.0, 1.0, 0.0, 1.0]), np.tile(b_velocity, (grid.size - 1, 1)), 0.01
    )
    rec = _pair(GroundTruth(t=grid, pose=b_pose), np.array([0.1, 0.0, 0.0, 0.0]), b_velocity)
    ref = sighting_reset_reference(rec, _settings(0.0), RECORDS, pos_tol=0.005, yaw_tol=0.005)
    assert (ref.records, ref.tracked, ref.truth_missing) == (55, 55, 0)


def test_dead_reckoning_is_read_on_a_grid_that_starts_at_the_first_sighting() -> None:
    """A stands still; B drives a 1 m/s circle and its odometry tells the truth. A sees B at
    2 s (the first stamp of the recording: the odometry grid starts there) and 30 s, and
    records from 2 s on: with a 5-mm tolerance every record is tracked — B's odometry is read
    at the sighting's own tick (index 0 of the grid) and at each record's."""
    grid = np.arange(0.0, 60.0 + 1e-9, 0.01)
    b_velocity = np.array([1.0, 0.0, 0.0, 0.2])
    b_pose = integrate_body_velocities(
        np.array([2.0, 1.0, 0.0, 1.0]), np.tile(b_velocity, (grid.size - 1, 1)), 0.01
    )
    rec = _standing_pair(GroundTruth(t=grid, pose=b_pose), b_velocity, np.array([2.0, 30.0]))
    records = {"A": np.arange(2.0, 60.0, 1.0)}
    ref = sighting_reset_reference(rec, _settings(0.0), records, pos_tol=0.005, yaw_tol=0.005)
    assert (ref.records, ref.tracked, ref.truth_missing) == (58, 58, 0)


def test_a_pair_with_a_single_record_is_counted() -> None:
    """One record of A at 10 s, 5 s after B's sighting at 5 s; nothing moves: tracked."""
    still = GroundTruth(t=np.array([0.0, 60.0]), pose=np.array([[2.0, 0.0, 0.0, 0.0]] * 2))
    rec = _pair(still, np.zeros(4), np.zeros(4))
    ref = sighting_reset_reference(
        rec, _settings(0.0), {"A": np.array([10.0])}, pos_tol=0.5, yaw_tol=0.5
    )
    assert (ref.records, ref.tracked, ref.median_age_s) == (1, 1, 5.0)


def test_the_age_bins_are_listed_edge_to_edge() -> None:
    """Ages 0.5, 1 (on an edge: the bin it starts), 4.9, 50 and 3 s, tracked the first three:
    each bin states its edges, the last one open (``to_s`` None)."""
    by_age = TrackedByAge.count(
        np.array([0.5, 1.0, 4.9, 50.0, 3.0]), np.array([True, True, True, False, False])
    )
    assert by_age.to_list() == [
        {"from_s": 0.0, "to_s": 1.0, "records": 1, "tracked_fraction": 1.0},
        {"from_s": 1.0, "to_s": 5.0, "records": 3, "tracked_fraction": 2 / 3},
        {"from_s": 5.0, "to_s": 15.0, "records": 0, "tracked_fraction": None},
        {"from_s": 15.0, "to_s": 45.0, "records": 0, "tracked_fraction": None},
        {"from_s": 45.0, "to_s": None, "records": 1, "tracked_fraction": 0.0},
    ]
