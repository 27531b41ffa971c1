"""``leader_scores`` (``relloc.experiments.multihypothesis_scores``) on hand-made beliefs of
observer A over a three-robot recording with two scans: what it lays out where, and the exact
errors for beliefs it cannot place."""

from __future__ import annotations

import re
from typing import Any

import numpy as np
import pytest

from relloc.core.contract import Belief
from relloc.core.estimates import Recorder
from relloc.core.recording import (
    CLUTTER,
    GroundTruth,
    Measurements,
    Odometry,
    Recording,
    measurement_rows,
)
from relloc.errors import DataError
from relloc.experiments.multihypothesis_scores import NO_READING, leader_scores

KIND = "bearing_elevation"


def _recording() -> Recording:
    """A at the origin; B and C standing still; A scans at 0.5 s (bearing rows from C,
    clutter, B) and at 0.8 s (from B, C)."""
    t = np.array([0.0, 1.0])
    rows = Measurements.concatenate(
        [
            measurement_rows(
                KIND, t=[0.5] * 3, observer=0, value=np.zeros((3, 2)), origin=[2, CLUTTER, 1]
            ),
            measurement_rows(KIND, t=[0.8] * 2, observer=0, value=np.zeros((2, 2)), origin=[1, 2]),
        ]
    )
    return Recording(
        robots=("A", "B", "C"),
        platforms=("ground", "ground", "ground"),
        odometry=tuple(Odometry(t=t, velocity=np.zeros((2, 4)), sigma=np.zeros(4)) for _ in "ABC"),
        measurements=rows,
        truth=tuple(
            GroundTruth(t=t, pose=np.tile(p, (2, 1)))
            for p in ((0, 0, 0, 0), (3, 1, 0, 0.5), (-2, 2, 0, -1.0))
        ),
    )


def _belief(subject: str, mean: Any, **info: float) -> Belief:
    full = {"components": 1.0, "confirmed": 1.0, "scan_t": 0.5, "bearing_row": -1.0}
    full["decision_row"] = -1.0
    full.update(info)
    return Belief(
        subject=subject,
        frame="relative_pose4",
        mean=np.asarray(mean, float),
        cov=np.eye(4),
        info=full,
    )


def test_the_estimate_is_the_belief_mean_as_recorded() -> None:
    rec = _recording()
    mean = np.array([3.5, 1.0, 0.0, 0.5])  # 0.5 m off B in x
    recorder = Recorder("gaussian_sum")
    recorder.record(0.5, "A", [_belief("B", mean, bearing_row=2.0, decision_row=0.0)])
    sc = leader_scores(recorder.results(), rec, 0, np.array([0.5, 0.8]), KIND)
    np.testing.assert_array_equal(sc.estimate[0, 1], [3.5, 1.0, 0.0, 0.5])
    np.testing.assert_allclose(sc.error[0, 1], [0.5, 0.0, 0.0, 0.0], atol=1e-12)
    assert (sc.assoc_origin[0, 1], sc.joint_origin[0, 1]) == (1, 2)
    assert np.isnan(sc.estimate[1]).all() and sc.assoc_origin[1].tolist() == [NO_READING] * 3


def test_a_belief_between_record_times_is_refused() -> None:
    rec = _recording()
    recorder = Recorder("gaussian_sum")
    recorder.record(0.7, "A", [_belief("B", [3, 1, 0, 0.5])])
    with pytest.raises(DataError, match="beliefs recorded outside the given record times"):
        leader_scores(recorder.results(), rec, 0, np.array([0.5, 0.8]), KIND)


def test_a_belief_without_any_record_time_is_refused() -> None:
    rec = _recording()
    recorder = Recorder("gaussian_sum")
    recorder.record(0.5, "A", [_belief("B", [3, 1, 0, 0.5])])
    with pytest.raises(DataError, match="beliefs recorded outside the given record times"):
        leader_scores(recorder.results(), rec, 0, np.array([]), KIND)


def test_a_scan_time_that_is_not_a_scan_of_the_observer_is_refused() -> None:
    """The belief names row 0 of a scan at 0.7 s, where A has no scan (its scans are at 0.5 s
    and 0.8 s): the row is not in the recording."""
    rec = _recording()
    recorder = Recorder("gaussian_sum")
    recorder.record(0.8, "A", [_belief("B", [3, 1, 0, 0.5], scan_t=0.7, bearing_row=0.0)])
    with pytest.raises(
        DataError, match=re.escape("bearing row 0 of the scan at t=0.7 is not in the recording")
    ):
        leader_scores(recorder.results(), rec, 0, np.array([0.5, 0.8]), KIND)


def test_the_error_names_the_row_that_is_not_in_its_scan() -> None:
    """Two records of B: row 1 of the 0.5-s scan (there), then row 2 of the 0.8-s scan (which
    has two rows): the second is named."""
    rec = _recording()
    recorder = Recorder("gaussian_sum")
    recorder.record(0.5, "A", [_belief("B", [3, 1, 0, 0.5], bearing_row=1.0)])
    recorder.record(0.8, "A", [_belief("B", [3, 1, 0, 0.5], scan_t=0.8, bearing_row=2.0)])
    with pytest.raises(
        DataError, match=re.escape("bearing row 2 of the scan at t=0.8 is not in the recording")
    ):
        leader_scores(recorder.results(), rec, 0, np.array([0.5, 0.8]), KIND)
    ok = Recorder("gaussian_sum")
    ok.record(0.5, "A", [_belief("B", [3, 1, 0, 0.5], bearing_row=1.0)])
    ok.record(0.8, "A", [_belief("B", [3, 1, 0, 0.5], scan_t=0.8, bearing_row=1.0)])
    sc = leader_scores(ok.results(), rec, 0, np.array([0.5, 0.8]), KIND)
    assert sc.assoc_origin[:, 1].tolist() == [CLUTTER, 2]
