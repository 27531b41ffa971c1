"""Yaw banks, range-only filters and the observability-constrained rows: Bayes weights with
the likelihood's normaliser, the merge, prune and collapse rules of the yaw bank, the ring
prior and the constant-velocity noise of the range filters, and constrained landmark rows — details
the other tests leave free."""

import math

import numpy as np
import pytest
from scipy.stats import norm

from relloc.core.angles import wrap_angle
from relloc.core.contract import HeldOdometry
from relloc.core.gaussian import GaussianMixture
from relloc.core.kalman import Innovation
from relloc.core.recording import measurement_rows
from relloc.estimators.observability_constrained import constrained_rows, unobservable_directions
from relloc.estimators.uwb_range import (
    RangePairBank,
    RangePairSettings,
    RangeTeamFilter,
    RangeTeamSettings,
)
from relloc.estimators.yaw_bank import YawBankSettings, reduce_bank, reweight
from relloc.models.motion import VelocityNoise
from relloc.models.planar_measurement import LinearisedRows

STILL = VelocityNoise(observer=(0.0,) * 4, observed=(0.0,) * 4)


def test_reweight_includes_the_determinant_of_s():
    # equal NIS, |S₂| = 4³ |S₁|: N(ν; 0, S₂) / N(ν; 0, S₁) = 4^(−3/2) = 1/8
    S = np.stack([np.eye(3), 4.0 * np.eye(3)])
    inn = Innovation(
        residual=np.zeros((2, 3)), cov=S, nis=np.array([1.0, 1.0]), meas_cov=np.copy(S)
    )
    np.testing.assert_allclose(reweight(np.ones(2), inn), [1.0, 0.125], rtol=1e-12)


def _bank(yaws, yaw_vars, weights):
    k = len(yaws)
    means = np.zeros((k, 4))
    means[:, 0] = 3.0
    means[:, 3] = yaws
    covs = np.zeros((k, 4, 4))
    covs[:, :3, :3] = 0.01 * np.eye(3)
    covs[:, 3, 3] = yaw_vars
    return GaussianMixture(means=means, covs=covs, weights=np.asarray(weights, dtype=float))


def test_merge_uses_the_spread_of_the_yaw_difference():
    # |φ₁ − φ_best| = 0.3 ≤ 1 · √(0.01 + 0.16) ≈ 0.41: merged, though 0.3 > σ₁ = 0.1
    bank = _bank([0.0, 0.3, math.pi], [0.16, 0.01, 0.16], [1.0, 0.5, 0.5])
    out = reduce_bank(bank, YawBankSettings(merge_sigmas=1.0))
    np.testing.assert_allclose(out.weights, [0.75, 0.0, 0.25], rtol=1e-12)


def test_merge_measures_the_yaw_difference_on_the_circle():
    # 3.1 and −3.1 are 2π − 6.2 ≈ 0.083 apart on the circle, well within 1 σ of the difference
    bank = _bank([3.1, -3.1, 0.0], [0.01, 0.01, 0.01], [1.0, 0.5, 0.5])
    out = reduce_bank(bank, YawBankSettings(merge_sigmas=1.0))
    np.testing.assert_allclose(out.weights, [0.75, 0.0, 0.25], rtol=1e-12)


def test_collapse_once_the_best_holds_exactly_the_collapse_weight():
    bank = _bank([0.0, math.pi], [0.01, 0.04], [3.0, 1.0])  # best holds 3/4 exactly
    out = reduce_bank(bank, YawBankSettings(collapse_weight=0.75))
    assert out.alive.tolist() == [True, False]
    # the dropped slot takes the best component's whole state, covariance included
    np.testing.assert_array_equal(out.means[1], bank.means[0])
    np.testing.assert_array_equal(out.covs[1], bank.covs[0])


def test_prune_threshold_is_relative_to_the_weight_after_merging():
    # weights 1 and 0.9 at one yaw merge to 1.9; 0.0015 < 1e-3 · 1.9 is pruned
    bank = _bank([0.0, 0.0, math.pi], [0.01, 0.01, 0.01], [1.0, 0.9, 0.0015])
    out = reduce_bank(bank, YawBankSettings(prune_ratio=1e-3, collapse_weight=1.0))
    assert out.alive.tolist() == [True, False, False]


def _range_row(t, r, sigma):
    return measurement_rows("range", t=[t], observer=0, target=1, value=[[r]], sigma=[sigma])


def test_range_pair_weights_follow_the_gaussian_likelihood_of_the_range():
    bank = RangePairBank(0, 1, ("a", "b"), STILL, RangePairSettings())
    bank.advance(0.0, HeldOdometry.still(2))
    bank.measure(_range_row(0.0, 2.0, 0.1))  # starts the ring
    bank.means = np.array([[2.0, 0.0, 0.0, 0.0], [0.0, 2.0, 0.0, 0.0]])
    bank.covs = np.stack([np.diag([0.01, 0.01, 0.01, 0.1]), np.diag([0.01, 0.04, 0.01, 0.1])])
    bank.log_w = np.zeros(2)
    bank.measure(_range_row(0.0, 2.1, 0.1))
    # radial variances 0.01 and 0.04: S = 0.02 and 0.05
    like = norm.pdf(2.1, loc=2.0, scale=np.sqrt([0.02, 0.05]))
    _, _, w = bank.mixture()
    np.testing.assert_allclose(w, like / like.sum(), rtol=1e-10)


def _ring(r0, sigma):
    bank = RangePairBank(0, 1, ("a", "b"), STILL, RangePairSettings(n_bearing=12, n_yaw=2))
    bank.advance(0.0, HeldOdometry.still(2))
    bank.measure(_range_row(0.0, r0, sigma))
    return bank


def test_ring_components_have_the_row_range_sigma_along_their_ray():
    bank = _ring(3.0, 0.2)  # the row's σ, not the settings' sigma_range = 0.1
    for mean, cov in zip(bank.means, bank.covs, strict=True):
        u = mean[:2] / np.linalg.norm(mean[:2])
        t = np.array([-u[1], u[0]])
        np.testing.assert_allclose(cov[:2, :2] @ u, 0.04 * u, atol=1e-12)
        np.testing.assert_allclose(cov[:2, :2] @ t, (3.0 * math.pi / 12) ** 2 * t, atol=1e-12)


def test_a_ring_smaller_than_the_range_noise_is_never_narrower_across_than_along():
    # r₀ π / n = 0.005 < σ = 0.2: the tangential σ is floored at σ
    bank = _ring(0.02, 0.2)
    for cov in bank.covs:
        np.testing.assert_allclose(cov[:2, :2], 0.04 * np.eye(2), atol=1e-12)


def test_range_pair_belief_averages_yaws_on_the_circle():
    bank = _ring(3.0, 0.1)
    bank.means = np.array([[3.0, 0.0, 0.0, 3.0], [3.0, 0.0, 0.0, -3.0]])
    bank.covs = np.stack([np.diag([0.01, 0.01, 0.01, 0.01])] * 2)
    bank.log_w = np.zeros(2)
    (belief,) = bank.beliefs()
    # the circular mean of ±3 rad with equal weights is π
    assert abs(float(wrap_angle(belief.mean[3]))) == pytest.approx(math.pi, abs=1e-12)


def test_range_team_prediction_adds_the_white_acceleration_noise():
    q, sp, sv, dt = 0.05, 0.5, 0.2, 2.0
    settings = RangeTeamSettings(q=q, sigma_position=sp, sigma_velocity=sv)
    f = RangeTeamFilter(("a", "b"), np.array([[0.0, 0.0], [5.0, 0.0]]), settings, anchors=[1])
    f.advance(0.0, HeldOdometry.still(2))
    f.advance(dt, HeldOdometry.still(2))
    # x⁺ = x + dt v: Var p = σp² + dt² σv² + q dt³/3, Cov(p, v) = dt σv² + q dt²/2,
    # Var v = σv² + q dt
    pos = sp**2 + dt**2 * sv**2 + q * dt**3 / 3
    cross = dt * sv**2 + q * dt**2 / 2
    vel = sv**2 + q * dt
    expected = np.array(
        [[pos, 0, cross, 0], [0, pos, 0, cross], [cross, 0, vel, 0], [0, cross, 0, vel]]
    )
    np.testing.assert_allclose(f.P, expected, rtol=1e-12)


def test_a_range_from_an_anchor_is_recorded_for_the_free_robot():
    f = RangeTeamFilter(
        ("a", "b"), np.array([[0.0, 0.0], [5.0, 0.0]]), RangeTeamSettings(), anchors=[1]
    )
    f.advance(0.0, HeldOdometry.still(2))
    f.measure(measurement_rows("range", t=[0.0], observer=1, target=0, value=[[5.1]]))
    (record,) = f.take_updates()
    assert record.subject == "a"


def test_a_constrained_landmark_row_is_projected_within_its_one_block():
    # one landmark: d = 1, the rotation about it; a landmark row of robot 1 has one block, and
    # the least change that annihilates n (robot 1's rows of N) is h − (h·n) nᵀ/(n·n)
    X = np.array([[1.0, 2.0, 0.3], [4.0, -1.0, 1.2]])
    N = unobservable_directions(X, np.array([[2.0, 2.0]]), fixed=False)
    h = np.array([0.3, -0.7, 1.0])
    lin = LinearisedRows(
        residual=np.array([0.1]),
        blocks=np.array([[h, np.zeros(3)]]),
        block_index=np.array([[1, -1]]),
        sigma=np.array([0.1]),
        group=np.array([0]),
    )
    out = constrained_rows(lin, N)
    n = N[3:6, 0]
    np.testing.assert_allclose(out.blocks[0, 0], h - (h @ n) / (n @ n) * n, atol=1e-12)
    np.testing.assert_array_equal(out.blocks[0, 1], 0.0)
    assert out.blocks[0, 0] @ n == pytest.approx(0.0, abs=1e-12)
