"""TUM files of a hand-made world-frame belief whose truth covers only some records."""

from __future__ import annotations

import math

import numpy as np
from export_helpers import standing_pair

from relloc.core.estimates import BeliefSeries, Estimates
from relloc.core.recording import GroundTruth, Odometry, Recording, empty_measurements
from relloc.pipeline.export.poses import pose_set
from relloc.pipeline.export.tum_files import write_tum

H = math.sqrt(0.5)


def _recording() -> Recording:
    """Robots ``a`` and ``b`` standing still; truth known from 0 s to 2 s only."""
    return standing_pair((0.0, 2.0), [1.0, 2.0, 0.0, 0.0], [3.0, 4.0, 0.0, math.pi / 2])


def _estimates(track: str = "") -> Estimates:
    """The team's world-frame belief of ``b`` at 1 s (inside the truth) and 3 s (after it)."""
    s = BeliefSeries(
        owner="team",
        subject="b",
        track=track,
        frame="world_pose2",
        t=np.array([1.0, 3.0]),
        mean=np.array([[3.5, 4.0, math.pi / 2], [5.0, 6.0, 0.0]]),
        cov=np.stack([np.eye(3)] * 2),
        age=np.array([0.0, 2.0]),
    )
    return Estimates(estimator="hand", beliefs=(s,))


def _values(path) -> list[list[float]]:  # type: ignore[no-untyped-def]
    lines = [line for line in path.read_text().splitlines() if not line.startswith("#")]
    return [[float(v) for v in line.split()] for line in lines]


def test_the_truth_file_holds_only_the_records_with_truth(tmp_path):  # type: ignore[no-untyped-def]
    (pair,) = write_tum(tmp_path, pose_set(_estimates(), _recording()))
    assert pair.label == "team->b" and pair.poses == 2
    assert pair.estimate == tmp_path / "team" / "b.tum"
    assert pair.truth == tmp_path / "team" / "b.truth.tum"
    est = _values(pair.estimate)
    np.testing.assert_allclose(
        est,
        [[1.0, 3.5, 4.0, 0.0, 0.0, 0.0, H, H], [3.0, 5.0, 6.0, 0.0, 0.0, 0.0, 0.0, 1.0]],
        atol=1e-15,
    )
    truth = _values(pair.truth)
    np.testing.assert_allclose(truth, [[1.0, 3.0, 4.0, 0.0, 0.0, 0.0, H, H]], atol=1e-12)


def test_no_truth_file_when_no_record_has_truth(tmp_path):  # type: ignore[no-untyped-def]
    import dataclasses

    rec = dataclasses.replace(_recording(), truth=None)
    (pair,) = write_tum(tmp_path, pose_set(_estimates(), rec))
    assert pair.truth is None
    assert sorted(p.name for p in (tmp_path / "team").iterdir()) == ["b.tum"]


def test_empty_parts_of_a_track_name_add_nothing_to_the_file_name(tmp_path):  # type: ignore[no-untyped-def]
    (pair,) = write_tum(tmp_path, pose_set(_estimates("/bank//k 2/"), _recording()))
    assert pair.estimate == tmp_path / "team" / "b__bank_k_2.tum"
    assert pair.truth == tmp_path / "team" / "b__bank_k_2.truth.tum"


def test_a_relative_pose_has_truth_only_while_both_robots_have_it(tmp_path):  # type: ignore[no-untyped-def]
    """``a``'s truth ends at 2 s, ``b``'s at 4 s: the record at 3 s has no truth."""
    still = Odometry(t=np.zeros(0), velocity=np.zeros((0, 4)), sigma=np.zeros(4))
    rec = Recording(
        robots=("a", "b"),
        platforms=("ground", "ground"),
        odometry=(still, still),
        measurements=empty_measurements(),
        truth=(
            GroundTruth(t=np.array([0.0, 2.0]), pose=np.array([[1.0, 2.0, 0.0, 0.0]] * 2)),
            GroundTruth(t=np.array([0.0, 4.0]), pose=np.array([[3.0, 4.0, 0.5, math.pi / 2]] * 2)),
        ),
        source="hand-made",
        meta={},
    )
    s = BeliefSeries(
        owner="a",
        subject="b",
        track="",
        frame="relative_pose4",
        t=np.array([1.0, 3.0]),
        mean=np.array([[2.0, 2.0, 0.5, math.pi / 2], [2.0, 2.0, 0.5, math.pi / 2]]),
        cov=np.stack([np.eye(4)] * 2),
        age=np.array([0.0, 2.0]),
    )
    (pair,) = write_tum(tmp_path, pose_set(Estimates(estimator="hand", beliefs=(s,)), rec))
    assert pair.poses == 2
    # b seen from a (at (1, 2), heading 0): 2 m ahead, 2 m left, 0.5 m up, turned a quarter
    np.testing.assert_allclose(
        _values(pair.truth), [[1.0, 2.0, 2.0, 0.5, 0.0, 0.0, H, H]], atol=1e-12
    )
