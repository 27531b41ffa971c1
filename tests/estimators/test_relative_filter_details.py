"""Relative filters, details the other tests leave free: the TEKF at the observer's own
position, the full pseudo-linear covariance in the tracker and the BC-PLKF, the batch's
records, σ and per-subject inputs, and the initialisation constants."""

import math

import numpy as np
import pytest

from relloc.core.contract import HeldOdometry
from relloc.core.gaussian import Gaussian
from relloc.core.recording import measurement_rows
from relloc.estimators.initialisation import (
    SIGMA_UNKNOWN_YAW,
    from_first_measurement,
    known_position_unknown_yaw,
    pose_in_fov,
    poses_spread_in_fov,
)
from relloc.estimators.relative import (
    FilterSettings,
    RelativeTracker,
    update_bcplkf_arrays,
    update_plkf_arrays,
    update_tekf,
    update_tekf_arrays,
)
from relloc.estimators.relative_batch import RelativeFilterBatch, TrackSpec
from relloc.models.measurement import (
    RangeBearingNoise,
    pseudo_linear_matrix,
    pseudo_linear_measurement,
    range_bearing,
)
from relloc.models.motion import VelocityNoise

NOISE = RangeBearingNoise(sigma_r=0.1466, sigma_azimuth=0.1, sigma_elevation=0.08)
MOTION = VelocityNoise(observer=(0.0,) * 4, observed=(0.0,) * 4)


def _pseudo_noise_jacobian_fd(x: np.ndarray, z: np.ndarray) -> np.ndarray:
    """``∂/∂z ([r̃, 0, 0] − H_pmo(θ̃, α̃) x)`` by central differences."""

    def eta(zz: np.ndarray) -> np.ndarray:
        return pseudo_linear_measurement(zz) - pseudo_linear_matrix(zz) @ x

    J = np.zeros((3, 3))
    for i in range(3):
        dz = np.zeros(3)
        dz[i] = 1e-6
        J[:, i] = (eta(z + dz) - eta(z - dz)) / 2e-6
    return J


def _case():
    rng = np.random.default_rng(3)
    m = np.array([3.0, -1.5, 1.2, 0.4])
    A = rng.normal(size=(4, 4)) * 0.3
    P = A @ A.T + 0.05 * np.eye(4)
    z = range_bearing(m + rng.normal(size=4) * [0.3, 0.3, 0.2, 0.0])
    return m, P, z


def test_tekf_at_the_observer_drops_the_elevation_residual():
    # at r̂ = 0 only the range row is kept (along the measured ray): ν = (r̃, 0, 0) and
    # NIS = r̃² / (σ_p² + σ_r²) for an isotropic position prior σ_p²
    prior = Gaussian(np.zeros(4), np.diag([0.04, 0.04, 0.04, 0.1]))
    z = np.array([2.0, 0.3, 0.4])
    noise = RangeBearingNoise(sigma_r=0.1, sigma_azimuth=0.05, sigma_elevation=0.05)
    _, inn = update_tekf(prior, z, noise)
    np.testing.assert_array_equal(inn.residual, [2.0, 0.0, 0.0])
    assert inn.nis == pytest.approx(4.0 / (0.04 + 0.01), rel=1e-12)


def test_tracker_with_the_full_pseudo_linear_covariance_uses_j_sigma_jt():
    m, P, z = _case()
    settings = FilterSettings(
        kind="plkf", motion_noise=MOTION, sensor_noise=NOISE, pseudo_linear_covariance="full"
    )
    inn = RelativeTracker(Gaussian(m, P), settings).update(z)
    J = _pseudo_noise_jacobian_fd(m, z)
    expected = J @ np.diag(NOISE.variances) @ J.T
    np.testing.assert_allclose(inn.meas_cov, expected, atol=1e-8)


def test_bcplkf_with_the_full_covariance_subtracts_the_cubature_bias_of_that_covariance():
    m, P, z = _case()
    plain_mean, plain_cov, _ = update_plkf_arrays(m, P, z, NOISE, covariance="full")
    bc_mean, bc_cov, _ = update_bcplkf_arrays(m, P, z, NOISE, covariance="full")
    z_hat = range_bearing(plain_mean)
    bias = np.zeros(4)
    for i in range(3):
        for sign in (1.0, -1.0):
            zj = z_hat.copy()
            zj[i] += sign * math.sqrt(3.0 * NOISE.variances[i])
            H = pseudo_linear_matrix(zj)
            J = _pseudo_noise_jacobian_fd(m, zj)
            S = H @ P @ H.T + J @ np.diag(NOISE.variances) @ J.T
            K = P @ H.T @ np.linalg.inv(S)
            bias += K @ (pseudo_linear_measurement(zj) - H @ plain_mean) / 6.0
    np.testing.assert_allclose(bc_mean, plain_mean - bias, atol=1e-8)
    np.testing.assert_allclose(bc_cov, plain_cov)
    # the full and the simplified covariance give different compensations here
    simple_bc, _, _ = update_bcplkf_arrays(m, P, z, NOISE)
    simple_plain, _, _ = update_plkf_arrays(m, P, z, NOISE)
    assert np.abs((simple_plain - simple_bc) - bias).max() > 1e-6


def _batch():
    """A TEKF track of each of ``a`` and ``b``; every robot's odometry σ is 0."""
    specs = [
        TrackSpec(
            label="ta",
            subject="a",
            kind="tekf",
            prior_mean=np.array([3.0, 1.0, 0.5, 0.0]),
            prior_cov=np.eye(4),
        ),
        TrackSpec(
            label="tb",
            subject="b",
            kind="tekf",
            prior_mean=np.array([2.0, -2.0, 0.0, 0.0]),
            prior_cov=np.eye(4),
        ),
    ]
    zero = (0.0, 0.0, 0.0, 0.0)
    return RelativeFilterBatch(
        specs, owner="l", robots=("l", "a", "b"), odometry_sigma=[zero, zero, zero]
    )


def test_batch_predicts_each_subject_with_its_own_velocity():
    # same odometry σ: both subjects share one group; a static observer and a yaw of 0, so
    # each relative position moves by its subject's own v dt
    batch = _batch()
    velocity = np.array([[0.0] * 4, [0.5, 0.0, 0.0, 0.0], [0.0, -0.3, 0.0, 0.0]])
    odo = HeldOdometry(velocity=velocity, stamp=np.zeros(3))
    batch.advance(0.0, odo)
    batch.advance(2.0, odo)
    means = {b.track: b.mean for b in batch.beliefs()}
    np.testing.assert_allclose(means["ta"], [4.0, 1.0, 0.5, 0.0], atol=1e-12)
    np.testing.assert_allclose(means["tb"], [2.0, -2.6, 0.0, 0.0], atol=1e-12)


def test_batch_update_uses_the_row_sigma_per_axis_and_records_cond_r_of_r():
    batch = _batch()
    batch.advance(0.0, HeldOdometry.still(3))
    z = np.array([3.3, 0.25, 0.12])
    sigma = (0.1, 0.01, 0.02)  # R = diag(1e-2, 1e-4, 4e-4): λmax/λmin = 100
    batch.measure(
        measurement_rows(
            "range_bearing_elevation", t=[0.0], observer=0, target=1, value=[z], sigma=sigma
        )
    )
    (record,) = batch.take_updates()
    assert record.cond_r == pytest.approx(2.0, abs=1e-12)
    assert abs(record.cond_s - 2.0) > 0.1  # S = H P Hᵀ + R with P = I is another matrix
    noise = RangeBearingNoise(sigma_r=0.1, sigma_azimuth=0.01, sigma_elevation=0.02)
    mean, cov, _ = update_tekf_arrays(np.array([3.0, 1.0, 0.5, 0.0]), np.eye(4), z, noise)
    belief = next(b for b in batch.beliefs() if b.track == "ta")
    np.testing.assert_allclose(belief.mean, mean, atol=1e-12)
    np.testing.assert_allclose(belief.cov, cov, atol=1e-12)


def test_batch_clock_does_not_go_back_within_the_time_tolerance():
    batch = _batch()
    still = HeldOdometry.still(3)
    batch.advance(0.0, still)
    batch.advance(1.0, still)
    batch.advance(1.0 - 1e-10, still)  # one event that rounding split: accepted, no prediction
    assert batch.t == 1.0


def test_unknown_yaw_sigma_is_that_of_a_uniform_yaw_on_the_circle():
    # Var U(−π, π) = (2π)² / 12 = π² / 3
    assert SIGMA_UNKNOWN_YAW**2 == pytest.approx(math.pi**2 / 3.0, rel=1e-15)
    g = known_position_unknown_yaw(np.array([1.0, 2.0, 0.0, 0.3]), 1.0)
    assert g.cov[3, 3] == pytest.approx(math.pi**2 / 3.0, rel=1e-15)
    g = from_first_measurement(np.array([3.0, 0.2, 0.1]), np.array([0.1, 0.01, 0.01]))
    assert g.cov[3, 3] == pytest.approx(math.pi**2 / 3.0, rel=1e-15)


def test_random_poses_fill_the_elevation_view_on_both_sides():
    rng = np.random.default_rng(7)
    poses = np.array(
        [
            pose_in_fov(rng, fov_deg=90.0, range_limits=(1.0, 5.0), elevation_fov_deg=60.0)
            for _ in range(200)
        ]
    )
    elevation = np.arctan2(poses[:, 2], np.hypot(poses[:, 0], poses[:, 1]))
    half = math.radians(30.0)
    assert np.all(np.abs(elevation) <= half + 1e-12)
    # uniform on [−30°, 30°]: about half of 200 draws below the horizon
    assert 70 < np.sum(elevation < 0.0) < 130


@pytest.mark.parametrize("n", [4, 13])
def test_spread_poses_are_mirror_symmetric_about_the_forward_axis(n):
    # azimuths span the view symmetrically and the yaws are evenly spaced about 0: pose k and
    # pose n−1−k are mirror images (y → −y, yaw → −yaw)
    poses = poses_spread_in_fov(n, fov_deg=120.0, range_limits=(0.3, 15.0))
    mirror = poses[::-1] * [1.0, -1.0, 1.0, -1.0]
    if n % 2:  # with an odd count the ranges alternate symmetrically too
        np.testing.assert_allclose(poses, mirror, atol=1e-12)
    else:
        np.testing.assert_allclose(poses[:, 3], mirror[:, 3], atol=1e-12)
