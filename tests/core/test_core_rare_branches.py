"""Refusals of the core data types, recorder and mixtures that only malformed input reaches
(each naming where), the shortcuts of empty input, and the control and multilateration
branches of rarer configurations."""

from __future__ import annotations

import numpy as np
import pytest
from recording_samples import three_rows

from relloc.control.drone_schedule import DroneSchedule
from relloc.control.formation import FormationController, desired_relative, formation_offsets
from relloc.core.contract import Belief, Silent
from relloc.core.estimates import Estimates, Recorder, concatenate
from relloc.core.gaussian import GaussianMixture
from relloc.core.recording import (
    FileSkips,
    GroundTruth,
    Odometry,
    Recording,
    empty_measurements,
)
from relloc.errors import ConfigError, DataError, ModelError
from relloc.geometry.multilateration import multilaterate


def _odometry(n: int = 2) -> Odometry:
    return Odometry(t=np.arange(n, dtype=float), velocity=np.zeros((n, 4)), sigma=np.zeros(4))


def test_belief_with_a_covariance_of_another_size_names_the_subject() -> None:
    with pytest.raises(DataError, match=r"belief of B: covariance \(3, 3\) does not match state 4"):
        Belief(subject="B", frame="relative", mean=np.zeros(4), cov=np.eye(3))


def test_silent_estimator_drops_what_it_receives() -> None:
    s = Silent()
    assert s.receive(["a message"]) is None
    assert s.outbox() == [] and s.take_updates() == []


def test_recorder_refuses_a_frame_change_and_empty_requests() -> None:
    rec = Recorder("est")
    rec.record(0.0, "A", [Belief(subject="B", frame="relative", mean=np.zeros(2), cov=np.eye(2))])
    with pytest.raises(ConfigError, match="frame changed from relative to global"):
        rec.record(1.0, "A", [Belief(subject="B", frame="global", mean=np.zeros(2), cov=np.eye(2))])
    with pytest.raises(ConfigError, match="stacked: no subjects of A asked for"):
        rec.results().stacked("A", [])
    with pytest.raises(ConfigError, match="concatenate: no estimates to join"):
        concatenate([])
    assert concatenate([Estimates(estimator="est")]).estimator == "est"


def test_flat_mixture_groups_must_label_every_weight() -> None:
    means, covs = np.zeros((2, 1)), np.ones((2, 1, 1))
    with pytest.raises(ModelError, match=r"GaussianMixture: groups \(3,\) must be indices ≥ 0"):
        GaussianMixture(means=means, covs=covs, weights=np.ones(2), groups=np.zeros(3, np.int64))
    with pytest.raises(ModelError, match=r"GaussianMixture: groups \(2,\) must be indices ≥ 0"):
        GaussianMixture(means=means, covs=covs, weights=np.ones(2), groups=np.array([0, -1]))


def test_truth_and_odometry_need_one_row_per_timestamp() -> None:
    with pytest.raises(DataError, match="truth: 3 timestamps but 2 poses"):
        GroundTruth(t=np.arange(3.0), pose=np.zeros((2, 4)))
    with pytest.raises(DataError, match="truth: at least two samples are needed, got 1"):
        GroundTruth(t=np.zeros(1), pose=np.zeros((1, 4)))
    with pytest.raises(DataError, match="odometry: 3 timestamps but 2 velocities"):
        Odometry(t=np.arange(3.0), velocity=np.zeros((2, 4)), sigma=np.zeros(4))
    with pytest.raises(DataError, match=r"measurements\.sigma: 2 rows but 3 timestamps"):
        three_rows(sigma=np.full((2, 3), 0.01))


def test_a_file_without_skipped_rows_says_so() -> None:
    assert FileSkips("f.csv", 3, 3).describe() == "no rows skipped"


@pytest.mark.parametrize(
    ("changes", "match"),
    [
        ({"robots": ()}, "recording.robots: a recording needs at least one robot"),
        ({"platforms": ("ground", "ground")}, "recording: 2 platforms and 1 odometry streams"),
        ({"odometry": ("fast",)}, r"recording.odometry\[0\]: expected Odometry, got str"),
        ({"truth": (_odometry(),)}, r"recording.truth\[0\]: expected GroundTruth, got Odometry"),
        ({"measurements": None}, "recording.measurements: expected a Measurements table"),
    ],
)
def test_recording_refuses_malformed_parts(changes: dict[str, object], match: str) -> None:
    fields: dict[str, object] = dict(
        robots=("A",),
        platforms=("ground",),
        odometry=(_odometry(),),
        measurements=empty_measurements(),
    )
    with pytest.raises(DataError, match=match):
        Recording(**{**fields, **changes})  # type: ignore[arg-type]


def test_recording_span_without_truth_is_that_of_the_data_or_refused() -> None:
    none = Odometry(t=np.zeros(0), velocity=np.zeros((0, 4)), sigma=np.zeros(4))
    rec = Recording(
        robots=("A",),
        platforms=("ground",),
        odometry=(none,),
        measurements=empty_measurements(),
        source="s",
    )
    with pytest.raises(DataError, match="recording 's': no data, so no time span"):
        _ = rec.span
    rec = Recording(
        robots=("A", "B"),
        platforms=("ground", "ground"),
        odometry=(none, _odometry()),
        measurements=three_rows(),
    )
    assert rec.span == (0.0, 1.0)


def test_sliding_schedule_lets_every_drone_visit_every_follower() -> None:
    s = DroneSchedule(n_followers=3, n_drones=2, dwell_steps=1)
    assert s.groups() == ((1, 2, 3), (1, 2, 3))
    visited = {f for k in range(10) for f in s.targets(k)}
    assert visited == {1, 2, 3}


def test_formation_refusals_name_where() -> None:
    with pytest.raises(ConfigError, match=r"team\.offsets: need at least one follower"):
        formation_offsets([], "team.offsets")
    with pytest.raises(ConfigError, match="formation frame: 'global' or 'leader', got 'body'"):
        desired_relative(np.zeros(2), 0.0, "body")  # type: ignore[arg-type]
    ctl = FormationController(offsets=((1.0, 0.0), (0.0, 1.0)), frame="leader")
    with pytest.raises(ConfigError, match=r"FormationController: follower 3 outside 1\.\.2"):
        ctl.command(3, np.zeros(4), (0.0, 0.0))


def test_multilateration_without_pairs_or_free_points_returns_the_initial_guess() -> None:
    initial = np.array([[1.0, 2.0]])
    fixed = np.array([[0.0, 0.0], [3.0, 0.0]])
    out = multilaterate(initial, fixed, [], np.zeros(0))
    np.testing.assert_array_equal(out, initial)
    none_free = multilaterate(np.zeros((0, 2)), fixed, [(0, 1)], np.array([3.0]))
    assert none_free.shape == (0, 2)
