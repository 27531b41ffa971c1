"""Initialisation policies of seed 000 Table 1 (and from the first measurement)."""

import math

import numpy as np
import pytest

from relloc.errors import ConfigError
from relloc.estimators.initialisation import (
    POLICY_NAMES,
    SIGMA_UNKNOWN_YAW,
    FieldOfView,
    InitContext,
    InitPolicy,
    from_first_measurement,
    known_pose,
    poses_spread_in_fov,
)
from relloc.sim.sensors import range_azimuth_elevation

TRUTH = np.array([4.0, 1.0, 2.0, 0.7])
SIGMA = np.array([0.0068, 0.0036, 0.0036])


def _ctx(truth=TRUTH, seed=0):
    z = range_azimuth_elevation(truth[None, :])[0]
    return InitContext(z=z, sensor_sigma=SIGMA, truth=truth, rng=np.random.default_rng(seed))


def test_policy_names_cover_the_four_cases_and_the_measurement_start():
    assert set(POLICY_NAMES) == {"known", "known-position", "known-yaw", "unknown", "measurement"}


def test_known_pose_is_centred_on_truth_with_small_covariance():
    g = InitPolicy(name="known")(InitContext(z=np.ones(3), sensor_sigma=SIGMA, truth=TRUTH))
    np.testing.assert_allclose(g.mean, TRUTH)
    np.testing.assert_allclose(np.sqrt(np.diag(g.cov)), 0.02)
    # With an rng the mean is a draw from N(truth, P0): over many draws, the NEES averages 4.
    rng = np.random.default_rng(1)
    draws = np.array([known_pose(TRUTH, rng=rng).mean for _ in range(2000)])
    nees = np.sum((draws - TRUTH) ** 2, axis=1) / 0.02**2
    assert abs(nees.mean() - 4.0) < 3.3 * np.sqrt(8.0 / 2000)


def test_known_position_unknown_yaw():
    g = InitPolicy(name="known-position")(_ctx())
    np.testing.assert_allclose(g.mean[:3], TRUTH[:3])
    assert -math.pi <= g.mean[3] <= math.pi
    assert g.cov[3, 3] == pytest.approx(SIGMA_UNKNOWN_YAW**2)
    assert g.cov[0, 0] == pytest.approx(0.02**2)


def test_known_yaw_unknown_position_is_a_guess_inside_the_view():
    fov = FieldOfView(fov_deg=90.0, range_limits=(1.0, 10.0))
    g = InitPolicy(name="known-yaw", fov=fov)(_ctx())
    assert g.mean[3] == TRUTH[3]
    r = np.hypot(g.mean[0], g.mean[1])
    assert 1.0 <= r <= 10.0 and abs(math.atan2(g.mean[1], g.mean[0])) <= math.radians(45.0)
    assert g.cov[0, 0] == pytest.approx((10.0 / math.sqrt(3.0)) ** 2)
    assert not np.allclose(g.mean[:3], TRUTH[:3])


def test_fully_unknown_draws_position_and_yaw():
    a = InitPolicy(name="unknown")(_ctx(seed=3))
    b = InitPolicy(name="unknown")(_ctx(seed=4))
    assert not np.allclose(a.mean, b.mean)
    assert a.cov[3, 3] == pytest.approx(SIGMA_UNKNOWN_YAW**2)


def test_first_measurement_inverts_the_sensor_model_and_its_covariance():
    z = range_azimuth_elevation(TRUTH[None, :])[0]
    g = from_first_measurement(z, SIGMA)
    np.testing.assert_allclose(g.mean[:3], TRUTH[:3], atol=1e-12)
    assert g.mean[3] == 0.0
    # Monte-Carlo check of the linearised covariance of the inverse map.
    rng = np.random.default_rng(5)
    zs = z + SIGMA * rng.standard_normal((20000, 3))
    r, th, al = zs.T
    pts = np.column_stack(
        [r * np.cos(al) * np.cos(th), r * np.cos(al) * np.sin(th), r * np.sin(al)]
    )
    # Whitened by the predicted covariance, the samples have unit covariance (each entry of a
    # sample covariance of N unit normals has σ ≈ 1/√N = 0.007; allow 5σ).
    L = np.linalg.cholesky(g.cov[:3, :3])
    white = np.linalg.solve(L, (pts - g.mean[:3]).T)
    np.testing.assert_allclose(np.cov(white), np.eye(3), atol=0.035)
    assert InitPolicy(name="measurement").uses_measurement


def test_truth_based_policy_without_truth_is_a_clear_error():
    ctx = InitContext(z=np.array([1.0, 0.0, 0.0]), sensor_sigma=SIGMA)
    with pytest.raises(ConfigError, match="needs the true relative pose"):
        InitPolicy(name="known")(ctx)
    with pytest.raises(ConfigError, match="init: must be one of"):
        InitPolicy(name="guess")


def test_thirteen_poses_spread_over_the_view():
    poses = poses_spread_in_fov(13, fov_deg=120.0, range_limits=(1.0, 10.0), height=2.0)
    az = np.arctan2(poses[:, 1], poses[:, 0])
    assert poses.shape == (13, 4)
    assert az.min() == pytest.approx(-math.radians(60)) and az.max() == pytest.approx(
        math.radians(60)
    )
    assert np.all(poses[:, 2] == 2.0)
    assert len(np.unique(np.round(poses[:, 3], 6))) == 13
