"""The truth-placed association bound (``relloc.experiments.association_bound``)."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
from numpy.typing import NDArray
from test_mrclam_association import _synthetic_folder

from relloc.core.recording import CLUTTER, GroundTruth, Odometry, Recording, measurement_rows
from relloc.datasets.mrclam import load_mrclam, to_recording
from relloc.estimators.gaussian_sum import GaussianSumSettings
from relloc.experiments import mrclam_association
from relloc.experiments.association_bound import association_bound, sighting_reset_reference
from relloc.models.motion import VelocityNoise
from relloc.sim.trajectories import integrate_body_velocities

Array = NDArray[np.float64]


def _settings(clutter: float) -> GaussianSumSettings:
    sig = (0.05, 0.05, 1e-3, 0.05)
    formation = replace(mrclam_association.planar_formation(0.01), p_detect=0.9)
    return GaussianSumSettings(
        velocity_noise=VelocityNoise(observer=sig, observed=sig),
        sigma_height=0.01,
        sigma_range=0.1,
        sigma_azimuth=0.03,
        sigma_elevation=0.03,
        use_elevation=False,
        field_of_view=np.pi,
        expected_clutter=clutter,
        formation=formation,
    )


def test_bound_is_high_without_clutter_and_drops_with_it(tmp_path: Path) -> None:
    raw = to_recording(load_mrclam(_synthetic_folder(tmp_path / "d", np.random.default_rng(3))))
    clean, _ = mrclam_association._hidden_correspondence(
        raw, 5.0, 20.0, np.pi, np.random.default_rng(4), 0.0
    )
    dense, _ = mrclam_association._hidden_correspondence(
        raw, 5.0, 20.0, np.pi, np.random.default_rng(4), 20.0
    )
    b_clean = association_bound(clean, _settings(0.0))
    b_dense = association_bound(dense, _settings(20.0))
    # three robots that see each other in every frame, bearing noise 0.02 rad: a filter that
    # knows where they are takes almost only their bearings
    assert b_clean.used > 100 and b_clean.accuracy is not None and b_clean.accuracy >= 0.95
    # 20 false bearings per scan over the full circle: some fall inside the 0.03-rad gate
    assert b_dense.accuracy is not None and b_dense.accuracy < b_clean.accuracy


def test_bound_reads_the_origin_of_the_bearing_taken(tmp_path: Path) -> None:
    """The same scans with every robot bearing relabelled as clutter: the truth-placed tracks
    take the same bearings, and none of them counts as correct."""
    raw = to_recording(load_mrclam(_synthetic_folder(tmp_path / "d", np.random.default_rng(5))))
    rec, _ = mrclam_association._hidden_correspondence(
        raw, 5.0, 12.0, np.pi, np.random.default_rng(6), 0.0
    )
    m = rec.measurements
    assert m.origin is not None
    relabelled = replace(
        rec, measurements=replace(m, origin=np.where(m.kind == m.kind, CLUTTER, m.origin))
    )
    before = association_bound(rec, _settings(0.0))
    after = association_bound(relabelled, _settings(0.0))
    assert before.used == after.used > 0 and before.correct > 0
    assert after.correct == 0 and after.accuracy == 0.0


def _pair(b_truth: GroundTruth, a_velocity: Array, b_odometry: Array) -> Recording:
    """Observer A (truth: from its own held velocity, from the origin) and teammate B, whose
    truth is ``b_truth`` and whose odometry reports ``b_odometry``; A sees B at 5 s and 30 s
    (bearings of unknown correspondence whose origin is B)."""
    grid = np.arange(0.0, 60.0 + 1e-9, 0.01)
    a_pose = integrate_body_velocities(np.zeros(4), np.tile(a_velocity, (grid.size - 1, 1)), 0.01)
    span = np.array([0.0, 60.0])
    sightings = np.array([5.0, 30.0])
    return Recording(
        robots=("A", "B"),
        platforms=("ground", "ground"),
        odometry=(
            Odometry(t=span, velocity=np.tile(a_velocity, (2, 1)), sigma=np.zeros(4)),
            Odometry(t=span, velocity=np.tile(b_odometry, (2, 1)), sigma=np.zeros(4)),
        ),
        measurements=measurement_rows(
            "bearing", t=sightings, observer=0, origin=np.ones(2, np.int64), value=np.zeros((2, 1))
        ),
        truth=(GroundTruth(t=grid, pose=a_pose), b_truth),
    )


RECORDS = {"A": np.arange(0.0, 60.0, 1.0)}


def test_sighting_reset_dead_reckoning_is_exact_with_exact_odometry() -> None:
    """Both robots moving (A straight, B on a circle), the odometry telling the truth: every
    record after the first sighting (5 s) is tracked, whatever its age."""
    grid = np.arange(0.0, 60.0 + 1e-9, 0.01)
    b_velocity = np.array([0.3, 0.0, 0.0, 0.2])
    b_pose = integrate_body_velocities(
        np.array([2.0, 1.0, 0.0, 1.0]), np.tile(b_velocity, (grid.size - 1, 1)), 0.01
    )
    rec = _pair(GroundTruth(t=grid, pose=b_pose), np.array([0.1, 0.0, 0.0, 0.0]), b_velocity)
    ref = sighting_reset_reference(rec, _settings(0.0), RECORDS, pos_tol=0.01, yaw_tol=0.01)
    assert (ref.records, ref.tracked, ref.truth_missing) == (55, 55, 0)
    assert ref.fraction == 1.0


def test_sighting_reset_dead_reckoning_drifts_with_the_odometry_error() -> None:
    """B stands still but its odometry turns at 0.04 rad/s: a record is tracked while
    0.04 s⁻¹ × its age since the last sighting is within 0.5 rad (ages 0-12 s after each of
    the sightings at 5 s and 30 s: 26 of the 55 records from 5 s on; median age 13 s). A gap
    in B's truth (40-50 s) leaves out the records inside it (41-49 s): 9 fewer, all of them
    older than 12 s."""
    still = np.array([[2.0, 0.0, 0.0, 0.0]] * 2)
    turning = np.array([0.0, 0.0, 0.0, 0.04])
    rec = _pair(GroundTruth(t=np.array([0.0, 60.0]), pose=still), np.zeros(4), turning)
    ref = sighting_reset_reference(rec, _settings(0.0), RECORDS, pos_tol=0.5, yaw_tol=0.5)
    assert (ref.records, ref.tracked, ref.truth_missing) == (55, 26, 0)
    assert ref.median_age_s == 13.0
    # by age (bins 0-1-5-15-45-∞ s): ages 0-24 s after 5 s and 0-29 s after 30 s, tracked
    # up to 12 s
    assert ref.by_age.records == (2, 8, 20, 25, 0)
    assert ref.by_age.tracked == (2, 8, 16, 0, 0)
    assert [b["tracked_fraction"] for b in ref.to_dict()["by_age"]] == [1.0, 1.0, 0.8, 0.0, None]
    assert ref.to_dict()["by_age"][-1]["to_s"] is None
    gap = np.concatenate([np.arange(0.0, 41.0), np.arange(50.0, 61.0)])
    holed = GroundTruth(t=gap, pose=np.tile(still[0], (gap.size, 1)), gap_s=5.0)
    ref = sighting_reset_reference(
        _pair(holed, np.zeros(4), turning), _settings(0.0), RECORDS, pos_tol=0.5, yaw_tol=0.5
    )
    assert (ref.records, ref.tracked, ref.truth_missing) == (46, 24, 9)
    assert ref.to_dict()["tracked_fraction"] == 24 / 46


def test_sighting_reset_reference_without_records_or_sightings() -> None:
    still = GroundTruth(t=np.array([0.0, 60.0]), pose=np.array([[2.0, 0.0, 0.0, 0.0]] * 2))
    rec = _pair(still, np.zeros(4), np.zeros(4))
    none = sighting_reset_reference(rec, _settings(0.0), {}, pos_tol=0.5, yaw_tol=0.5)
    assert none.records == 0 and none.fraction is None and none.median_age_s is None
    assert none.by_age.records == (0,) * 5
    # B never sees A: its records count nothing
    unseen = sighting_reset_reference(
        rec, _settings(0.0), {"B": RECORDS["A"]}, pos_tol=0.5, yaw_tol=0.5
    )
    assert unseen.records == 0 and unseen.to_dict()["tracked_fraction"] is None
