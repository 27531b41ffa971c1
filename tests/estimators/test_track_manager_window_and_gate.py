"""Hand-checked keep window, ages and gate of the track manager that the behaviour tests leave
free."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import chi2

from relloc.core.contract import HeldOdometry
from relloc.core.recording import measurement_rows
from relloc.estimators.track_manager import TrackManager, TrackManagerSettings

SIGMA = np.array([0.01, 0.01, 0.01, 0.01])
Z = np.array([[np.sqrt(29.0), 0.0, np.arctan2(2.0, 5.0)]])  # 5 m ahead, 2 m up


def _manager(**changes: object) -> TrackManager:
    return TrackManager(
        TrackManagerSettings(**changes),  # type: ignore[arg-type]
        owner="l",
        robots=("l", "c"),
        odometry_sigma=[SIGMA, SIGMA],
    )


def _reading(t: float, z: np.ndarray = Z):  # type: ignore[no-untyped-def]
    return measurement_rows(
        "range_bearing_elevation",
        t=np.array([t]),
        observer=0,
        target=1,
        value=z,
        sigma=np.array([0.01, 0.01, 0.01]),
    )


def test_a_track_is_kept_exactly_keep_window_after_its_last_update() -> None:
    tm = _manager(keep_window_s=2.0)
    still = HeldOdometry.still(2)
    tm.advance(0.0, still)
    tm.measure(_reading(0.0))  # starts the track (the first reading is its initial belief)
    tm.advance(1.0, still)
    tm.measure(_reading(1.0))
    (update,) = tm.take_updates()
    assert update.age == 1.0 and update.dof == 3
    tm.advance(3.0, still)  # 2.0 s after the last update: kept
    (belief,) = tm.beliefs()
    assert belief.age == 3.0  # since creation, not since the last update
    tm.advance(3.5, still)
    assert tm.beliefs() == []
    assert [(e.t, e.kind) for e in tm.take_events()] == [(0.0, "created"), (3.5, "deleted")]


def test_the_gate_is_the_chi2_quantile_of_the_three_readings() -> None:
    assert TrackManagerSettings(gate_probability=0.99).nis_gate == pytest.approx(
        chi2.ppf(0.99, 3), rel=1e-12
    )
    assert TrackManagerSettings().nis_gate == np.inf


def test_a_reading_after_the_keep_window_starts_a_new_track() -> None:
    # nobody asks for beliefs between the events: the track, stale at the event at 3 s, is
    # still deleted (stamped 3 s) when the manager moves on, so the reading at 6 s re-creates
    # the track instead of updating it
    tm = _manager(keep_window_s=2.0)
    still = HeldOdometry.still(2)
    tm.advance(0.0, still)
    tm.measure(_reading(0.0))
    tm.advance(3.0, still)
    tm.advance(6.0, still)
    tm.measure(_reading(6.0))
    assert tm.take_updates() == []
    kinds = [(e.t, e.kind) for e in tm.take_events()]
    assert kinds == [(0.0, "created"), (3.0, "deleted"), (6.0, "recreated")]
    (belief,) = tm.beliefs()
    assert belief.age == 0.0
