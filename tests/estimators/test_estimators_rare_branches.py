"""Estimator branches that only rarer settings, call orders or hostile input reach: refused
settings and inputs (each naming where), the empty-input shortcuts of the joint and
constrained updates, and a degenerate geometry whose innovation covariance is singular."""

from __future__ import annotations

import numpy as np
import pytest

import relloc.estimators as estimators
from relloc.core.contract import HeldOdometry
from relloc.core.gaussian import Gaussian
from relloc.core.recording import Measurements, measurement_rows
from relloc.errors import ConfigError, DataError, ModelError
from relloc.estimators.eif import TeamInformation, eif_update
from relloc.estimators.initialisation import InitContext, InitPolicy, poses_spread_in_fov
from relloc.estimators.joint_ekf import ekf_predict, ekf_update
from relloc.estimators.observability_constrained import constrained_rows
from relloc.estimators.relative import (
    FilterSettings,
    RelativeTracker,
    update_plkf,
    update_plkf_arrays,
)
from relloc.estimators.relative_batch import RelativeFilterBatch, TrackSpec
from relloc.estimators.switching_ekf import SwitchingEkf, SwitchingEkfSettings
from relloc.estimators.track_manager import TrackManager, TrackManagerSettings
from relloc.estimators.uwb_range import (
    RangePairBank,
    RangePairSettings,
    RangeTeamFilter,
    RangeTeamSettings,
    RelativeDeadReckoning,
)
from relloc.estimators.yaw_bank import YawBankSettings, YawBankTracker, spread_yaw_bank
from relloc.models.airground import Mode
from relloc.models.measurement import RangeBearingNoise
from relloc.models.motion import VelocityNoise
from relloc.models.planar_measurement import LinearisedRows

MOTION = VelocityNoise(observer=(0.05, 0.05, 0.02, 0.03), observed=(0.08, 0.04, 0.02, 0.05))
SENSOR = RangeBearingNoise(sigma_r=0.05, sigma_azimuth=0.01, sigma_elevation=0.01)
PLKF = FilterSettings(kind="plkf", motion_noise=MOTION, sensor_noise=SENSOR)


def _one_row(residual: float, sigma: float) -> LinearisedRows:
    """A row on robot 0's x of a one-robot team."""
    return LinearisedRows(
        residual=np.array([residual]),
        blocks=np.array([[[1.0, 0.0, 0.0], [0.0, 0.0, 0.0]]]),
        block_index=np.array([[0, -1]]),
        sigma=np.array([sigma]),
        group=np.array([0]),
    )


def _no_rows() -> LinearisedRows:
    return LinearisedRows(
        residual=np.zeros(0),
        blocks=np.zeros((0, 2, 3)),
        block_index=np.zeros((0, 2), dtype=np.int64),
        sigma=np.ones(0),
        group=np.zeros(0, dtype=np.int64),
    )


def test_lazy_public_names_are_listed() -> None:
    names = dir(estimators)
    assert {"CooperativeEstimator", "JointEkf", "RelativeTracker"} <= set(names)
    assert names == sorted(names)


def test_joint_filters_refuse_bad_predictions_and_keep_the_belief_without_rows() -> None:
    belief = Gaussian(mean=np.zeros(3), cov=np.eye(3))
    F, Q = np.eye(3)[None], 0.01 * np.eye(3)[None]
    with pytest.raises(ModelError, match=r"team prediction: expected mean \(3,\)"):
        ekf_predict(belief, np.zeros(4), F, Q)
    with pytest.raises(ModelError, match="team prediction: non-finite predicted mean or Jacobian"):
        ekf_predict(belief, np.array([0.0, np.nan, 0.0]), F, Q)
    with pytest.raises(ModelError, match="team prediction: non-finite process noise"):
        ekf_predict(belief, np.zeros(3), F, np.full((1, 3, 3), np.inf))
    same = ekf_update(belief, _no_rows())
    np.testing.assert_array_equal(same.mean, belief.mean)
    np.testing.assert_array_equal(same.cov, belief.cov)


def test_information_update_that_overflows_the_mean_is_refused() -> None:
    """A residual of 1e300 with σ = 1e-10 puts 1e320 (∞) into the information vector."""
    info = TeamInformation.from_gaussian(Gaussian(mean=np.zeros(3), cov=np.eye(3)))
    with (
        np.errstate(over="ignore", invalid="ignore"),
        pytest.raises(ModelError, match="EIF update produced a non-finite mean"),
    ):
        eif_update(info, _one_row(1e300, 1e-10))


def test_constraining_without_directions_or_rows_changes_nothing() -> None:
    lin = _one_row(0.5, 0.1)
    out = constrained_rows(lin, np.zeros((3, 0)))
    np.testing.assert_array_equal(out.blocks, lin.blocks)
    assert constrained_rows(_no_rows(), np.ones((3, 1))).blocks.shape == (0, 2, 3)


def test_initialisation_refusals_name_the_policy() -> None:
    with pytest.raises(ConfigError, match="n: must be ≥ 1, got 0"):
        poses_spread_in_fov(0, fov_deg=90.0, range_limits=(1.0, 5.0))
    ctx = InitContext(z=np.array([2.0, 0.1, 0.0]), sensor_sigma=np.full(3, 0.01))
    with pytest.raises(ConfigError, match="initialisation 'unknown' draws a random guess"):
        InitPolicy(name="unknown")(ctx)


def test_relative_filter_refusals_name_where() -> None:
    mean, cov = np.array([2.0, 0.0, 0.0, 0.0]), np.eye(4)
    with pytest.raises(DataError, match="pair 3: measured range must be > 0"):
        update_plkf_arrays(mean, cov, np.array([0.0, 0.1, 0.0]), SENSOR, where="pair 3")
    with pytest.raises(ConfigError, match="pseudo-linear covariance: one of"):
        update_plkf(Gaussian(mean, cov), np.array([2.0, 0.1, 0.0]), SENSOR, covariance="exact")  # type: ignore[arg-type]
    with pytest.raises(ConfigError, match=r"FilterSettings\.motion_noise: must be a VelocityNoise"):
        FilterSettings(motion_noise=SENSOR, sensor_noise=SENSOR)  # type: ignore[arg-type]
    with pytest.raises(
        ConfigError, match=r"FilterSettings\.sensor_noise: must be a RangeBearingNoise"
    ):
        FilterSettings(motion_noise=MOTION, sensor_noise=MOTION)  # type: ignore[arg-type]
    with pytest.raises(ModelError, match="RelativeTracker l->c: belief must be a RelPose4"):
        RelativeTracker(Gaussian(np.zeros(3), np.eye(3)), PLKF, label="l->c")
    tracker = RelativeTracker(Gaussian(mean, cov), PLKF, label="l->c")
    with pytest.raises(DataError, match="l->c: measurement z must be 3 numbers"):
        tracker.update(["far", 0.1, 0.0])
    with pytest.raises(DataError, match="l->c: measurement z must be 3 numbers"):
        tracker.update(None)  # type: ignore[arg-type]


def test_a_tracker_certain_of_a_target_straight_above_cannot_update() -> None:
    """The target at (0, 0, 1) with a zero covariance: the pseudo-linear bearing noise
    ``ρ² σ_θ²`` vanishes with the horizontal range ``ρ``, so ``S = R`` is singular."""
    tracker = RelativeTracker(
        Gaussian(np.array([0.0, 0.0, 1.0, 0.0]), np.zeros((4, 4))), PLKF, label="l->c"
    )
    with pytest.raises(ModelError, match="innovation covariance is not positive definite at l->c"):
        tracker.update(np.array([1.0, 0.1, 1.4]))


def test_relative_batch_refuses_a_fractional_sensor_and_has_no_updates_before_any() -> None:
    good = dict(
        label="a",
        subject="c",
        kind="plkf",
        prior_mean=np.array([2.0, 0, 0, 0]),
        prior_cov=np.eye(4),
    )
    for sensor in (1.5, True):
        with pytest.raises(ConfigError, match="TrackSpec c#a: sensor must be an integer"):
            TrackSpec(**{**good, "sensor": sensor})  # type: ignore[arg-type]
    batch = RelativeFilterBatch(
        [TrackSpec(**good)],
        owner="l",
        robots=("l", "c"),
        odometry_sigma=[np.full(4, 0.1)] * 2,  # type: ignore[arg-type]
    )
    assert batch.take_updates() == []


def test_switching_ekf_refuses_a_self_leader_a_bad_prior_and_a_nan_start() -> None:
    args = dict(
        robots=("R_0", "R_1"),
        owner="R_1",
        leader="R_0",
        prior=Gaussian(np.zeros(4), np.eye(4)),
        settings=SwitchingEkfSettings(),
        sides={},
    )
    with pytest.raises(ConfigError, match="SwitchingEkf: R_1 cannot follow itself"):
        SwitchingEkf(**{**args, "leader": "R_1"})  # type: ignore[arg-type]
    with pytest.raises(DataError, match=r"SwitchingEkf R_1: prior mean must have shape \(4,\)"):
        SwitchingEkf(**{**args, "prior": Gaussian(np.zeros(3), np.eye(3))})  # type: ignore[arg-type]
    with pytest.raises(ConfigError, match=r"SwitchingEkf\.t0: not finite \(nan\)"):
        SwitchingEkf(**args, t0=float("nan"))  # type: ignore[arg-type]


def test_track_manager_settings_and_team_are_checked() -> None:
    with pytest.raises(ConfigError, match="pseudo_linear_covariance: must be 'simplified' or"):
        TrackManagerSettings(pseudo_linear_covariance="exact")  # type: ignore[arg-type]
    with pytest.raises(ConfigError, match="init: expected an InitPolicy"):
        TrackManagerSettings(init="measurement")  # type: ignore[arg-type]
    with pytest.raises(ConfigError, match="yaw_bank: expected YawBankSettings or None"):
        TrackManagerSettings(yaw_bank=12)  # type: ignore[arg-type]
    with pytest.raises(ConfigError, match=r"odometry_sigma: one \(σ_vx, σ_vy, σ_vz, σ_ω\) per"):
        TrackManager(
            TrackManagerSettings(), owner="l", robots=("l", "c"), odometry_sigma=[np.ones(4)]
        )


def test_yaw_bank_refuses_a_prior_that_is_not_a_relative_pose() -> None:
    with pytest.raises(ModelError, match=r"spread_yaw_bank: prior shapes \(4,\), \(3, 3\)"):
        spread_yaw_bank(np.zeros(4), np.eye(3), YawBankSettings())
    with pytest.raises(ModelError, match="YawBankTracker l->c: prior must be a RelPose4"):
        YawBankTracker(Gaussian(np.zeros(3), np.eye(3)), PLKF, label="l->c")


def test_yaw_bank_tracker_spreads_an_unknown_yaw_over_the_circle() -> None:
    """Yaw σ 2 rad > ``spread_above``: four hypotheses at ``φ̂₀ + 2πk/4`` (wrapped), each of
    yaw variance ``(π/4)²`` and no yaw–position covariance."""
    cov = np.eye(4)
    cov[3, 3] = 4.0
    cov[0, 3] = cov[3, 0] = 0.5
    tracker = YawBankTracker(
        Gaussian(np.array([2.0, 0.0, 0.0, 0.1]), cov), PLKF, YawBankSettings(n_components=4)
    )
    bank = tracker.bank
    expected = np.array([0.1, 0.1 + np.pi / 2, 0.1 + np.pi - 2 * np.pi, 0.1 - np.pi / 2])
    np.testing.assert_allclose(bank.means[:, 3], expected, atol=1e-12)
    np.testing.assert_allclose(bank.covs[:, 3, 3], (np.pi / 4) ** 2)
    np.testing.assert_array_equal(bank.covs[:, 0, 3], 0.0)


def _ranges(values, observer=0, target=1, kind="range", landmark=-1):  # type: ignore[no-untyped-def]
    n = len(values)
    return measurement_rows(
        kind,
        t=np.arange(n, dtype=float),
        observer=observer,
        target=target,
        landmark=landmark,
        value=np.asarray(values, dtype=float).reshape(n, 1),
    )


def test_a_first_range_of_almost_zero_leaves_the_pair_bank_without_a_direction() -> None:
    """Every hypothesis starts at the first range (1e-7 m) from the owner, where the range
    has no gradient to update with."""
    bank = RangePairBank(0, 1, ("a", "b"), MOTION, RangePairSettings())
    bank.advance(0.0, HeldOdometry.still(2))
    with pytest.raises(DataError, match=r"a->b: a hypothesis reached range 0 at t=1\.0"):
        bank.measure(_ranges([1e-7, 1.0]))


def test_range_team_uses_landmarks_and_counts_what_it_cannot_use() -> None:
    """b (free, at (1, 0)) ranged from landmark 0 at (3, 0): 2 m measured, 2 m predicted;
    a bearing row, and a range between two robots estimated at one point, are counted."""
    with pytest.raises(ConfigError, match=r"RangeTeamFilter: initial positions must be finite"):
        RangeTeamFilter(("a", "b"), [[0.0, 0.0]], RangeTeamSettings())
    f = RangeTeamFilter(
        ("a", "b", "c"),
        [[0.0, 0.0], [1.0, 0.0], [1.0, 0.0]],
        RangeTeamSettings(gate=None),
        anchors=(0,),
        landmarks=np.array([[3.0, 0.0, 0.0]]),
    )
    f.advance(0.0, HeldOdometry.still(3))
    f.measure(_ranges([2.0], observer=1, target=-1, landmark=0))
    assert f.counts.used == 1
    np.testing.assert_allclose(f.x[:2], [1.0, 0.0], atol=1e-12)
    bearing = measurement_rows(
        "bearing", t=np.zeros(1), observer=0, target=1, value=np.array([[0.1]])
    )
    f.measure(bearing)
    f.measure(_ranges([0.5], observer=1, target=2))
    assert f.counts.other == 2 and f.counts.used == 1


def test_dead_reckoning_start_must_be_one_relative_pose() -> None:
    with pytest.raises(DataError, match=r"a->b: start mean must have shape \(4,\), got \(2, 4\)"):
        RelativeDeadReckoning(0, 1, ("a", "b"), MOTION, (0.0, np.zeros((2, 4)), np.eye(4)))
    with pytest.raises(DataError, match=r"a->b: start covariance must be \(4, 4\)"):
        RelativeDeadReckoning(0, 1, ("a", "b"), MOTION, (0.0, np.zeros(4), np.eye(4)[None]))


def test_a_held_sighting_of_another_pair_leaves_the_range_alone_to_update() -> None:
    """The drone sees the pair {R_0, R_2} at t = 0.05 s; that sighting holds the pair in the
    broadcast set for 0.1 s, so at 0.1 s the follower R_1 is still in the other-pair mode but
    has no fresh sighting: only its range to the leader updates it."""
    robots = ("R_0", "R_1", "R_2", "D_1")
    p = {0: np.array([0.0, 0.0]), 1: np.array([-0.6, -0.3]), 2: np.array([-0.6, 0.3])}
    f = SwitchingEkf(
        robots=robots,
        owner="R_1",
        leader="R_0",
        prior=Gaussian(np.array([0.6, 0.3, 0.0, 0.0]), np.diag([0.04, 0.04, 0.01, 0.01])),
        settings=SwitchingEkfSettings(sighting_hold=0.1),
        sides={"R_2": 1},
    )

    def ranges(t: float):  # type: ignore[no-untyped-def]
        pairs = [(0, 1), (0, 2), (1, 2)]
        obs, tgt = zip(*pairs, strict=True)
        d = [float(np.hypot(*(p[a] - p[b]))) for a, b in pairs]
        return measurement_rows("range", t=np.full(3, t), observer=obs, target=tgt, value=d)

    sighting = measurement_rows(
        "pair_sighting", t=np.array([0.05]), observer=3, target=2, value=[[np.pi / 4, 0.0, 0.0]]
    )
    still = HeldOdometry.still(4)
    f.advance(0.05, still)
    f.measure(Measurements.concatenate([ranges(0.05), sighting]))
    f.take_counts()
    f.advance(0.1, still)
    f.measure(ranges(0.1))
    assert f.mode() is Mode.OTHER_PAIR_SEEN
    counts = f.take_counts()
    assert counts["range_applied"] == 1
    assert counts.get("triangle_applied", 0) == 0 and counts.get("leader_heading_applied", 0) == 0


def test_a_yaw_bank_rejects_a_reading_no_hypothesis_admits() -> None:
    """The first reading starts a yaw bank (yaw unknown); 0.1 s later a reading that puts the
    target 300 m away lies beyond the gate of every hypothesis: counted, and the bank's
    belief is the one the plain prediction gives."""
    settings = TrackManagerSettings(
        yaw_bank=YawBankSettings(n_components=12), gate_probability=0.999
    )

    def rows(t: float, r: float):  # type: ignore[no-untyped-def]
        return measurement_rows(
            "range_bearing_elevation",
            t=np.array([t]),
            observer=0,
            target=1,
            value=np.array([[r, 0.1, 0.05]]),
            sigma=np.array([0.05, 0.01, 0.01]),
        )

    def run(readings: list[tuple[float, float]]) -> tuple[np.ndarray, dict[str, int]]:
        tm = TrackManager(
            settings, owner="l", robots=("l", "c"), odometry_sigma=[np.full(4, 0.05)] * 2
        )
        tm.advance(0.0, HeldOdometry.still(2))
        for t, r in readings:
            tm.advance(t, HeldOdometry.still(2))
            tm.measure(rows(t, r))
        tm.advance(0.2, HeldOdometry.still(2))
        assert tm._tracks[1].bank is not None and tm._tracks[1].bank.size > 1
        (belief,) = tm.beliefs()
        return belief.mean, tm.take_counts()

    gated, counts = run([(0.0, 4.0), (0.1, 300.0)])
    clean, clean_counts = run([(0.0, 4.0)])
    assert counts == {"rows_gated": 1} and clean_counts == {}
    np.testing.assert_allclose(gated, clean, atol=1e-12)
