"""Hand-computed noise models and measurement rows of the cooperative team filter that the
behaviour tests leave free."""

from __future__ import annotations

import numpy as np
import pytest

from relloc.core.recording import measurement_rows
from relloc.estimators.cooperative import (
    CooperativeSettings,
    Counts,
    HeldCommands,
    OdometryModel,
    SensorModel,
    command_timeline,
    detection_rows,
)


def test_lost_variance_grows_with_the_square_of_the_age_and_caps_the_heading() -> None:
    model = OdometryModel(q_v0=0.01, q_w0=0.01, lost_speed=0.5, lost_turn_rate=0.2)
    pos, yaw = model.lost_variance(np.array([-1.0, 2.0, 10.0]))
    # (V a)², and min((Ω a)², π²/3): the variance of a heading uniform on the circle
    np.testing.assert_allclose(pos, [0.0, 1.0, 25.0])
    np.testing.assert_allclose(yaw, [0.0, 0.16, np.pi**2 / 3])


def test_noise_rates_of_a_command() -> None:
    model = OdometryModel(q_v0=0.01, q_w0=0.02, k_v=0.1, k_w=0.2, k_wv=0.3)
    q_v, q_w = model.rates(np.array([-2.0]), np.array([0.5]))
    np.testing.assert_allclose(q_v, [0.01 + 0.1 * 2.0])
    np.testing.assert_allclose(q_w, [0.02 + 0.2 * 0.5 + 0.3 * 2.0])


def test_discrete_noise_becomes_a_rate() -> None:
    # seed 001's per-step input noise σ at steps of dt is the variance rate q = σ² dt
    model = OdometryModel.from_discrete(0.1, 0.2, 0.5)
    assert model.q_v0 == pytest.approx(0.1**2 * 0.5)
    assert model.q_w0 == pytest.approx(0.2**2 * 0.5)
    assert model.max_step_s == 0.5


def test_detection_rows_correct_the_biases_and_scale_the_range_noise() -> None:
    sensor = SensorModel(
        sigma_bearing=0.02,
        sigma_range0=0.1,
        sigma_range_rel=0.1,
        range_bias_coeffs=(0.05,),
        bearing_bias=0.1,
    )
    settings = CooperativeSettings(
        odometry=OdometryModel(q_v0=0.01, q_w0=0.01), sensor=sensor, use_range=True
    )
    batch = measurement_rows(
        "range_bearing", t=np.array([1.0]), observer=0, target=1, value=np.array([[3.0, 0.4]])
    )
    rows = detection_rows(batch, np.array([0]), np.zeros((0, 2)), settings, 0, {}, Counts())
    bearing, rng = rows.select(rows.kind == rows.kind[0]), rows.select(rows.kind != rows.kind[0])
    np.testing.assert_allclose(bearing.z, [0.4 - 0.1])
    np.testing.assert_allclose(bearing.sigma, [0.02])
    np.testing.assert_allclose(rng.z, [3.0 - 0.05])
    np.testing.assert_allclose(rng.sigma, [np.sqrt(0.1**2 + (0.1 * 3.0) ** 2)])


def test_timeline_inputs_and_rates_of_fresh_silent_and_expired_robots() -> None:
    # one interval (0, 1]; robot 0 commanded at 0, robot 1 has never reported, robot 2's
    # command of −3 s expired at −1 s, robot 3's of −2 s expires exactly at the start
    held = HeldCommands(
        begin=np.array([0.0]),
        end=np.array([1.0]),
        stamp=np.array([[0.0, np.nan, -3.0, -2.0]]),
        v=np.array([[1.0, 0.0, 0.7, 0.7]]),
        w=np.array([[0.1, 0.0, 0.2, 0.2]]),
        in_force=np.array([np.nan, np.nan, -3.0, -2.0]),
    )
    model = OdometryModel(
        q_v0=0.01, q_w0=0.02, k_v=0.1, k_w=0.2, stale_q_v=0.5, stale_q_w=0.6, max_hold_s=2.0
    )
    timeline, _ = command_timeline(held, model)
    np.testing.assert_array_equal(timeline.start, [0.0])
    np.testing.assert_allclose(timeline.v, [[1.0, 0.0, 0.0, 0.0]])
    np.testing.assert_allclose(timeline.w, [[0.1, 0.0, 0.0, 0.0]])
    np.testing.assert_allclose(timeline.q_v, [[0.01 + 0.1 * 1.0, 0.01, 0.5, 0.5]])
    np.testing.assert_allclose(timeline.q_w, [[0.02 + 0.2 * 0.1, 0.02, 0.6, 0.6]])


def _two_robots(settings: CooperativeSettings, prior_var: np.ndarray):  # type: ignore[no-untyped-def]
    from relloc.core.gaussian import Gaussian
    from relloc.estimators.cooperative import CooperativeEstimator

    mean = np.array([0.0, 0.0, 0.0, 2.0, 0.0, 0.0])
    return CooperativeEstimator(("a", "b"), Gaussian(mean, np.diag(prior_var)), settings)


def test_the_nis_of_a_bearing_uses_its_variance() -> None:
    # robot b 2 m ahead of a: ∂β/∂(y_a, ψ_a, y_b) = (−½, −1, ½), so H P Hᵀ = 0.015 with P =
    # 0.01 I; σ_β = 0.02: S = 0.0154, and a bearing of 0.1 rad has NIS 0.01 / 0.0154
    from relloc.core.contract import HeldOdometry

    settings = CooperativeSettings(
        odometry=OdometryModel(q_v0=0.01, q_w0=0.01),
        sensor=SensorModel(sigma_bearing=0.02),
        p_gate=None,
    )
    est = _two_robots(settings, np.full(6, 0.01))
    est.advance(0.0, HeldOdometry.still(2))
    est.measure(measurement_rows("bearing", t=np.array([0.0]), observer=0, target=1, value=[[0.1]]))
    (record,) = est.take_updates()
    assert record.dof == 1
    assert record.nis == pytest.approx(0.01 / 0.0154, rel=1e-9)


@pytest.mark.parametrize(("p_gate", "used"), [(0.3, 0), (0.5, 1)])
def test_a_range_and_bearing_pair_is_gated_with_two_degrees_of_freedom(
    p_gate: float, used: int
) -> None:
    # the same geometry; the range 2.1 m (∂r/∂(x_a, x_b) = (−1, 1): H P Hᵀ = 0.02, σ_r = 0.1,
    # S_r = 0.03) and the bearing 0.1 rad, uncorrelated under P, have NIS
    # 0.01/0.0154 + 0.01/0.03 = 0.983: inside χ²₂(0.5) = 2 ln 2 = 1.386 (though beyond
    # χ²₁(0.5) = 0.455), outside χ²₂(0.3) = −2 ln 0.7 = 0.713
    from scipy.stats import chi2

    from relloc.core.contract import HeldOdometry

    nis = 0.01 / 0.0154 + 0.01 / 0.03
    settings = CooperativeSettings(
        odometry=OdometryModel(q_v0=0.01, q_w0=0.01),
        sensor=SensorModel(sigma_bearing=0.02, sigma_range0=0.1),
        use_range=True,
        p_gate=p_gate,
    )
    assert (nis <= chi2.ppf(p_gate, 2)) == bool(used) and nis > chi2.ppf(0.5, 1)
    est = _two_robots(settings, np.full(6, 0.01))
    est.advance(0.0, HeldOdometry.still(2))
    est.measure(
        measurement_rows(
            "range_bearing", t=np.array([0.0]), observer=0, target=1, value=[[2.1, 0.1]]
        )
    )
    assert est.counts.detections_used == used
    assert est.counts.rejected_gate == 1 - used


def test_a_belief_carries_the_heading_uncertainty_into_the_position() -> None:
    # robot a drives 1 m along x with a heading variance of 0.01: its y variance becomes
    # (∂y/∂ψ)² · 0.01 = 1² · 0.01, plus the (tiny) input noise
    from relloc.core.contract import HeldOdometry

    settings = CooperativeSettings(
        odometry=OdometryModel(q_v0=1e-8, q_w0=1e-8), sensor=SensorModel(sigma_bearing=0.02)
    )
    est = _two_robots(settings, np.array([1e-12, 1e-12, 0.01, 1e-12, 1e-12, 1e-12]))
    est.advance(0.0, HeldOdometry.still(2))
    moving = HeldOdometry(
        velocity=np.array([[1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 0.0]]),
        stamp=np.array([0.0, 0.0]),
    )
    est.advance(1.0, moving)
    stack = est.beliefs()
    np.testing.assert_allclose(stack.mean[0], [1.0, 0.0, 0.0], atol=1e-12)
    assert stack.cov[0, 1, 1] == pytest.approx(0.01, rel=1e-4)


def test_reading_a_belief_midway_does_not_change_the_later_one() -> None:
    # robot a drives along x at 1 m/s for 2 s with heading noise q_ω = 0.01 rad²/s: y is the
    # integral of the heading, Var y(t) ≈ q t³ / 3. Reading the belief at 1 s (where the
    # 0.1 s steps break anyway) must leave the 2 s belief as it is: the input noise of the
    # first second is carried through the second second's motion
    from relloc.core.contract import HeldOdometry

    settings = CooperativeSettings(
        odometry=OdometryModel(q_v0=1e-8, q_w0=0.01), sensor=SensorModel(sigma_bearing=0.02)
    )
    v = np.array([[1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 0.0]])
    covs = []
    for read_midway in (False, True):
        est = _two_robots(settings, np.full(6, 1e-12))
        est.advance(0.0, HeldOdometry.still(2))
        est.advance(1.0, HeldOdometry(velocity=v, stamp=np.array([0.0, 0.0])))
        if read_midway:
            est.beliefs()
        est.advance(2.0, HeldOdometry(velocity=v, stamp=np.array([1.0, 1.0])))
        covs.append(est.beliefs().cov[0])
    np.testing.assert_allclose(covs[1], covs[0], rtol=1e-9, atol=1e-15)
    assert covs[0][1, 1] == pytest.approx(0.01 * 2.0**3 / 3.0, rel=0.03)
    assert covs[0][2, 2] == pytest.approx(0.01 * 2.0, rel=1e-6)
