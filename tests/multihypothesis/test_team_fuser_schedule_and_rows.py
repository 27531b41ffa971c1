"""The Gaussian-sum fuser under the estimator contract: cases the behaviour tests leave free."""

from __future__ import annotations

from typing import Any

import numpy as np

from relloc.core.contract import HeldOdometry
from relloc.core.recording import Measurements, measurement_rows
from relloc.estimators.gaussian_sum import Tracks
from relloc.experiments.desilva2015 import filter_settings
from relloc.fusion.gaussian_sum_estimator import GaussianSumEstimator
from relloc.sim.multihypothesis import DeSilvaScenario

SETTINGS = filter_settings(DeSilvaScenario(duration=3.0))
ROBOTS = ("A", "B", "C")


def _scan(t: float, *, bearing: bool = True) -> Measurements:
    at = np.array([t])
    parts = [
        measurement_rows("height", t=at, observer=0, target=1, value=[0.5]),
        measurement_rows("height", t=at, observer=0, target=1, value=[0.9], sensor=1),
        measurement_rows("range", t=at, observer=0, target=1, value=[3.2]),
        measurement_rows("range", t=at, observer=0, target=1, value=[4.0], sensor=1),
    ]
    if bearing:
        parts.append(measurement_rows("bearing_elevation", t=at, observer=0, value=[[0.3, 0.15]]))
    return Measurements.concatenate(parts)


def test_the_first_of_repeated_rows_in_a_scan_is_the_one_used() -> None:
    est = GaussianSumEstimator(ROBOTS, 0, SETTINGS)
    seen: list[Any] = []
    est.fuser.direct_scan = lambda h, r, b: seen.append((h, r, b))  # type: ignore[method-assign]
    est.advance(0.0, HeldOdometry.still(3))
    est.measure(_scan(0.0))
    ((heights, ranges, bearings),) = seen
    np.testing.assert_array_equal(heights, [0.5, np.nan])
    np.testing.assert_array_equal(ranges, [3.2, np.nan])
    np.testing.assert_array_equal(bearings, [[0.3, 0.15]])


def test_a_filter_that_regains_tracks_reports_recreated_and_its_age_restarts() -> None:
    est = GaussianSumEstimator(ROBOTS, 0, SETTINGS)
    est.advance(0.0, HeldOdometry.still(3))
    est.advance(0.5, HeldOdometry.still(3))
    est.measure(_scan(0.5))
    est.advance(1.0, HeldOdometry.still(3))
    (belief,) = est.beliefs()
    assert belief.age == 0.5  # B's filter has held tracks since the scan at 0.5
    est.fuser.tracks = Tracks.empty(SETTINGS.nscan_depth)  # (as if every track were deleted)
    est.measure(_scan(1.0, bearing=False))
    assert est.beliefs() == []
    est.advance(1.5, HeldOdometry.still(3))
    est.measure(_scan(1.5))
    est.advance(2.25, HeldOdometry.still(3))
    (belief,) = est.beliefs()
    assert belief.age == 0.75
    kinds = [(e.t, e.subject, e.kind) for e in est.take_events()]
    assert kinds == [(0.5, "B", "created"), (1.0, "B", "deleted"), (1.5, "B", "recreated")]


def test_decision_row_reports_the_joint_decision_not_the_tracks_association() -> None:
    est = GaussianSumEstimator(ROBOTS, 0, SETTINGS)
    est.advance(0.0, HeldOdometry.still(3))
    est.measure(_scan(0.0))
    (belief,) = est.beliefs()
    assert belief.info["bearing_row"] == 0.0  # B's tracks were born from bearing 0
    est.fuser.last_decision = np.array([-1, 0])  # the decision gave bearing 0 to C, none to B
    (belief,) = est.beliefs()
    assert belief.info["decision_row"] == -1.0 and belief.info["bearing_row"] == 0.0


def test_broadcasts_keep_to_the_period_counted_from_the_first_event() -> None:
    est = GaussianSumEstimator(ROBOTS, 0, SETTINGS, fusion_period=1.0)
    est.advance(10.0, HeldOdometry.still(3))
    est.measure(_scan(10.0))
    assert abs(est.quiet_until() - 11.0) < 1e-6
    est.advance(10.4, HeldOdometry.still(3))
    assert est.outbox() == [] and abs(est.quiet_until() - 11.0) < 1e-6
    est.advance(11.0, HeldOdometry.still(3))
    assert len(est.outbox()) == 1  # B's filter
    assert abs(est.quiet_until() - 12.0) < 1e-6
    est.advance(11.7, HeldOdometry.still(3))
    assert est.outbox() == [] and abs(est.quiet_until() - 12.0) < 1e-6


def test_after_a_gap_between_events_one_broadcast_and_the_period_resumes() -> None:
    # events at 0 s, then none until 5 s: one broadcast at 5.0 (the first event after the
    # broadcast times 1, 2, 3, 4, 5 s), the next at 6 s — not one at every event until the
    # schedule has caught up with the five periods missed
    est = GaussianSumEstimator(ROBOTS, 0, SETTINGS, fusion_period=1.0)
    est.advance(0.0, HeldOdometry.still(3))
    est.measure(_scan(0.0))
    sent = []
    for t in (5.0, 5.1, 5.2, 5.3, 5.4, 6.0):
        est.advance(t, HeldOdometry.still(3))
        sent.append(len(est.outbox()))
        assert est.quiet_until() > t  # nothing it sends later is stamped before its clock
    assert sent == [1, 0, 0, 0, 0, 1]
    assert abs(est.quiet_until() - 7.0) < 1e-6
