"""Branches of the cooperative team filter that rarer settings or call orders reach: refused
models and calls (each naming where), robot detections switched off, a degenerate detection,
counts and joint beliefs read at odd times, and a second epoch at one instant with
first-estimates or observability-constrained Jacobians."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pytest

import relloc.estimators.cooperative as cooperative
from relloc.core.contract import HeldOdometry
from relloc.core.gaussian import Gaussian
from relloc.core.recording import empty_measurements, measurement_rows
from relloc.errors import ConfigError, ModelError
from relloc.estimators.cooperative import (
    CooperativeEstimator,
    CooperativeSettings,
    OdometryModel,
    SensorModel,
    TeamPending,
    TeamTimeline,
    accumulate_prediction,
)
from relloc.models.planar_measurement import LinearisedRows

ROBOTS = ("A", "B")
ODOMETRY = OdometryModel(q_v0=0.01, q_w0=0.01)


def _settings(**changes: object) -> CooperativeSettings:
    fields: dict[str, object] = dict(
        odometry=ODOMETRY, sensor=SensorModel(sigma_bearing=0.05), p_gate=None
    )
    fields.update(changes)
    return CooperativeSettings(**fields)  # type: ignore[arg-type]


def _team(mean_b: tuple[float, float, float] = (2.0, 0.0, 0.0), **changes: object):
    prior = Gaussian(mean=np.array([0.0, 0.0, 0.0, *mean_b]), cov=0.1 * np.eye(6))
    return CooperativeEstimator(ROBOTS, prior, _settings(**changes))


def _bearing(observer: int, target: int, value: float, t: float = 0.0):
    return measurement_rows(
        "bearing",
        t=np.array([t]),
        observer=observer,
        target=target,
        value=np.array([[value]]),
        sigma=np.array([0.05]),
    )


@pytest.mark.parametrize(
    ("make", "match"),
    [
        (
            lambda: OdometryModel(q_v0=0.0, q_w0=0.01, k_v=0.0),
            "OdometryModel: q_v0/k_v and q_w0/k_w must not all be zero",
        ),
        (
            lambda: OdometryModel(q_v0=0.01, q_w0=0.0, k_w=0.0, k_wv=0.0),
            "OdometryModel: q_v0/k_v and q_w0/k_w must not all be zero",
        ),
        (lambda: OdometryModel.from_discrete(0.1, 0.1, 0.0), "from_discrete: dt must be > 0"),
        (
            lambda: SensorModel(sigma_bearing=0.05, range_bias_coeffs=(0.0,) * 9),
            "SensorModel.range_bias_coeffs: at most",
        ),
        (
            lambda: CooperativeEstimator((), Gaussian(np.zeros(0), np.eye(0)), _settings()),
            "CooperativeEstimator: no robots",
        ),
    ],
)
def test_models_without_noise_and_empty_teams_are_refused(make, match: str) -> None:
    with pytest.raises(ConfigError, match=match):
        make()


def test_calls_before_the_first_event_are_refused_or_empty() -> None:
    est = _team()
    assert est.counts.stale_odometry_s == []
    with pytest.raises(
        ConfigError, match=r"CooperativeEstimator\.measure before the first advance"
    ):
        est.measure(_bearing(0, 1, 0.0))
    with pytest.raises(ModelError, match="team_belief before the first advance"):
        est.team_belief()
    est.measure(empty_measurements())  # nothing to do, even before the first advance
    assert est.counts.epochs == 0
    est.advance(0.0, HeldOdometry.still(2))
    _, belief = est.team_belief()
    with pytest.raises(ConfigError, match="resumed: belief of dimension 3, the team needs 6"):
        est.resumed(0.0, Gaussian(belief.mean[:3], belief.cov[:3, :3]))


def test_robot_detections_switched_off_are_counted_and_ignored() -> None:
    est = _team(use_robot_detections=False)
    est.advance(0.0, HeldOdometry.still(2))
    before = est.beliefs().mean.copy()
    est.measure(_bearing(0, 1, 0.3))
    counts = est.counts
    assert counts.ignored_robot_detection == 1 and counts.detections_used == 0
    np.testing.assert_array_equal(est.beliefs().mean, before)


def test_a_detection_of_a_robot_estimated_on_the_observer_is_rejected() -> None:
    """Both robots' priors at the origin: the bearing between them is undefined."""
    est = _team(mean_b=(0.0, 0.0, 0.0))
    est.advance(0.0, HeldOdometry.still(2))
    est.measure(_bearing(0, 1, 0.3))
    counts = est.counts
    assert counts.rejected_degenerate == 1 and counts.detections_used == 0
    np.testing.assert_array_equal(est.beliefs().mean, 0.0)


def test_stale_odometry_counts_are_the_same_before_and_after_the_motion_is_applied() -> None:
    """Robot A reported once at t = 0 and B never: A's command stops holding at
    ``max_hold_s`` = 1 s, so by t = 5 A has gone 4 s without fresh odometry and B (never
    reported, so never stale) none, whether or not the pending motion was applied yet (the
    commands held since the last applied time are read either way)."""
    est = _team()
    est.advance(0.0, HeldOdometry.still(2))
    held = HeldOdometry(velocity=np.zeros((2, 4)), stamp=np.array([0.0, np.nan]))
    est.advance(5.0, held)
    pending = est.counts.stale_odometry_s
    est.beliefs()  # applies the motion
    applied = est.counts.stale_odometry_s
    assert pending == pytest.approx([4.0, 0.0])
    assert applied == pytest.approx(pending)
    # A reports again at t = 5: its stale time stays the 4 s of [1, 5) (a closed gap)
    est = _team()
    est.advance(0.0, HeldOdometry.still(2))
    est.advance(3.0, held)
    fresh = HeldOdometry(velocity=np.zeros((2, 4)), stamp=np.array([5.0, np.nan]))
    est.advance(5.5, fresh)
    pending = est.counts.stale_odometry_s
    est.beliefs()
    assert pending == pytest.approx([4.0, 0.0])
    assert est.counts.stale_odometry_s == pytest.approx(pending)


def test_a_joint_belief_is_kept_once_per_requested_time() -> None:
    prior = Gaussian(mean=np.array([0.0, 0.0, 0.0, 2.0, 0.0, 0.0]), cov=0.1 * np.eye(6))
    est = CooperativeEstimator(ROBOTS, prior, _settings(), joint_times=[1.0])
    est.advance(0.0, HeldOdometry.still(2))
    est.advance(1.0, HeldOdometry.still(2))
    est.beliefs()
    est.beliefs()
    assert [t for t, _ in est.joint_beliefs] == [1.0]


def test_a_zero_interval_moves_nobody() -> None:
    pose = np.array([[0.0, 0.0, 0.3], [1.0, 2.0, -1.2]])
    still = np.zeros((1, 2))
    timeline = TeamTimeline(
        start=np.zeros(1), v=still + 1.0, w=still, q_v=still + 0.01, q_w=still + 0.002
    )
    pending = TeamPending.at(pose)
    accumulate_prediction(pending, timeline, 1.0, 1.0, 0.1)
    np.testing.assert_array_equal(pending.pose, pose)
    np.testing.assert_array_equal(pending.F, np.tile(np.eye(3), (2, 1, 1)))
    np.testing.assert_array_equal(pending.Q, 0.0)


@dataclass
class _RecordingFilter:
    """The real joint filter, keeping the Jacobian of every update it is handed."""

    inner: cooperative.TeamFilter
    jacobians: list[np.ndarray] = field(default_factory=list)

    def mean(self) -> np.ndarray:
        return self.inner.mean()

    def covariance(self) -> np.ndarray:
        return self.inner.covariance()

    def predict(self, mean_pred, F_blocks, Q_blocks) -> None:  # type: ignore[no-untyped-def]
        self.inner.predict(mean_pred, F_blocks, Q_blocks)

    def update(self, rows: LinearisedRows) -> None:
        self.jacobians.append(rows.dense_jacobian(2))
        self.inner.update(rows)


def _second_epoch_jacobian(monkeypatch, linearisation: str) -> np.ndarray:  # type: ignore[no-untyped-def]
    """A at the origin sees B (prior at (2, 0)) at bearing 0.3 (0 expected), which moves the
    team; then, at the same instant, B sees A: the Jacobian of that second epoch."""
    made: list[_RecordingFilter] = []
    real = cooperative.make_filter

    def recording_filter(prior, kind):  # type: ignore[no-untyped-def]
        made.append(_RecordingFilter(real(prior, kind)))
        return made[-1]

    monkeypatch.setattr(cooperative, "make_filter", recording_filter)
    est = _team(linearisation=linearisation)
    est.advance(0.0, HeldOdometry.still(2))
    est.measure(_bearing(0, 1, 0.3))
    est.measure(_bearing(1, 0, np.pi))
    assert len(made[0].jacobians) == 2
    return made[0].jacobians[1][0]


def test_a_second_epoch_at_one_instant_linearises_at_that_instants_first_estimate(
    monkeypatch,
) -> None:
    """B at (2, 0, 0) sees A at the origin: ``h = atan2(y_A − y_B, x_A − x_B) − ψ_B``, whose
    gradient there is ``(0, −½, 0 | 0, ½, −1)``. First-estimates Jacobians are that gradient
    (at the team before this instant's first epoch), the constrained ones annihilate the
    unobservable directions there (the translations and the rotation about the origin,
    ``(−y, x, 1)`` per robot), and the latest-estimate ones do neither."""
    N = np.array(
        [
            [1.0, 0.0, 0.0, 1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0, 0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0, 0.0, 2.0, 1.0],
        ]
    ).T
    at_first = np.array([0.0, -0.5, 0.0, 0.0, 0.5, -1.0])
    fej = _second_epoch_jacobian(monkeypatch, "first_estimates")
    np.testing.assert_allclose(fej, at_first, atol=1e-12)
    oc = _second_epoch_jacobian(monkeypatch, "observability_constrained")
    np.testing.assert_allclose(oc @ N, 0.0, atol=1e-12)
    latest = _second_epoch_jacobian(monkeypatch, "latest")
    assert np.abs(latest - at_first).max() > 1e-3
    assert np.abs(latest @ N).max() > 1e-3
