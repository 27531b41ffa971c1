"""Shared predict, TEKF and PLKF updates, batched equivalence and the stateful tracker."""

import numpy as np
import pytest

from relloc.core.gaussian import Gaussian
from relloc.core.kalman import kalman_update
from relloc.errors import ConfigError, DataError, ModelError
from relloc.estimators.relative import (
    FilterSettings,
    RelativeTracker,
    predict,
    predict_arrays,
    update_bcplkf,
    update_bcplkf_arrays,
    update_plkf,
    update_plkf_arrays,
    update_tekf,
    update_tekf_arrays,
)
from relloc.models.measurement import RangeBearingNoise, range_bearing
from relloc.models.motion import VelocityNoise, process_noise, relative_jacobians

MOTION = VelocityNoise(observer=(0.05, 0.05, 0.02, 0.03), observed=(0.08, 0.04, 0.02, 0.05))
PRECISE = RangeBearingNoise(sigma_r=0.0068, sigma_azimuth=0.0036, sigma_elevation=0.0036)
NOISY = RangeBearingNoise(sigma_r=0.1466, sigma_azimuth=0.1, sigma_elevation=0.1)


def _textbook_kf(x, P, z, H, R):  # type: ignore[no-untyped-def]
    S = H @ P @ H.T + R
    K = P @ H.T @ np.linalg.inv(S)
    return x + K @ (z - H @ x), (np.eye(len(x)) - K @ H) @ P


def test_ekf_equals_linear_kf_on_a_linear_model() -> None:
    """With ω_l = 0 and a still observed robot the motion is linear (F = I, x⁺ = x − dt v_l);
    with a linear measurement the shared update must equal the textbook Kalman filter."""
    rng = np.random.default_rng(0)
    x = np.array([2.0, 1.0, 0.5, 0.3])
    A = rng.normal(size=(4, 4))
    P = A @ A.T + np.eye(4)
    u_l = np.array([0.4, -0.2, 0.1, 0.0])
    u_c = np.array([0.0, 0.0, 0.0, 0.3])
    dt = 0.1
    mean, cov = predict_arrays(x, P, u_l, u_c, dt, MOTION)
    F, G = relative_jacobians(x, u_l, u_c, dt)
    np.testing.assert_allclose(F, np.eye(4), atol=1e-15)
    expected_mean = x + dt * np.array([-0.4, 0.2, -0.1, 0.3])
    np.testing.assert_allclose(mean, expected_mean, atol=1e-15)
    np.testing.assert_allclose(cov, P + process_noise(G, MOTION), atol=1e-14)
    H = rng.normal(size=(3, 4))
    R = np.diag([0.1, 0.2, 0.3])
    z = rng.normal(size=3)
    new_mean, new_cov, inn = kalman_update(mean, cov, z - H @ mean, H, R)
    kf_mean, kf_cov = _textbook_kf(mean, cov, z, H, R)
    np.testing.assert_allclose(new_mean, kf_mean, atol=1e-12)
    np.testing.assert_allclose(new_cov, kf_cov, atol=1e-12)
    S = H @ cov @ H.T + R
    assert inn.nis == pytest.approx((z - H @ mean) @ np.linalg.solve(S, z - H @ mean))


def test_plkf_is_exact_from_a_diffuse_prior_without_noise_where_tekf_is_not() -> None:
    tiny = RangeBearingNoise(sigma_r=1e-9, sigma_azimuth=1e-9, sigma_elevation=1e-9)
    truth = np.array([3.0, -2.0, 1.5, 0.4])
    z = range_bearing(truth)
    prior = Gaussian(mean=np.array([-1.0, 4.0, 0.0, 0.0]), cov=np.diag([1e4, 1e4, 1e4, 10.0]))
    plkf, _ = update_plkf(prior, z, tiny)
    np.testing.assert_allclose(plkf.mean[:3], truth[:3], atol=1e-6)
    tekf, _ = update_tekf(prior, z, tiny)
    assert np.linalg.norm(tekf.mean[:3] - truth[:3]) > 0.5


def test_tekf_wraps_the_azimuth_residual() -> None:
    prior = Gaussian(mean=np.array([-3.0, 0.03, 0.5, 0.0]), cov=np.eye(4) * 0.01)
    z = np.array([np.hypot(3.0, 0.5), -np.pi + 0.02, np.arctan2(0.5, 3.0)])
    _, inn = update_tekf(prior, z, PRECISE)
    assert abs(inn.residual[1]) < 0.1


@pytest.mark.parametrize("covariance", ["simplified", "full"])
def test_batched_updates_equal_single_pair_updates(covariance: str) -> None:
    rng = np.random.default_rng(3)
    n = 5
    means = rng.normal(size=(n, 4)) * [2, 2, 1, 1] + [3, 0, 1, 0]
    A = rng.normal(size=(n, 4, 4)) * 0.1
    covs = A @ np.swapaxes(A, -1, -2) + 0.01 * np.eye(4)
    z = range_bearing(means + rng.normal(size=(n, 4)) * 0.1)
    u_l, u_c = rng.normal(size=(n, 4)), rng.normal(size=(n, 4))
    pm, pc = predict_arrays(means, covs, u_l, u_c, 0.05, MOTION)
    batched = {
        "tekf": update_tekf_arrays(pm, pc, z, NOISY),
        "plkf": update_plkf_arrays(pm, pc, z, NOISY, covariance=covariance),
        "bcplkf": update_bcplkf_arrays(pm, pc, z, NOISY, covariance=covariance),
    }
    for i in range(n):
        g = predict(Gaussian(mean=means[i], cov=covs[i]), u_l[i], u_c[i], 0.05, MOTION)
        np.testing.assert_allclose(g.mean, pm[i], atol=1e-14)
        singles = {
            "tekf": update_tekf(g, z[i], NOISY),
            "plkf": update_plkf(g, z[i], NOISY, covariance=covariance),  # type: ignore[arg-type]
            "bcplkf": update_bcplkf(g, z[i], NOISY, covariance=covariance),  # type: ignore[arg-type]
        }
        for kind, (belief, inn) in singles.items():
            b_mean, b_cov, b_inn = batched[kind]
            np.testing.assert_allclose(belief.mean, b_mean[i], atol=1e-12)
            np.testing.assert_allclose(belief.cov, b_cov[i], atol=1e-12)
            assert inn.nis == pytest.approx(float(b_inn.nis[i]))
            assert np.all(np.linalg.eigvalsh(belief.cov) > 0)


def test_tracker_applies_the_pure_functions() -> None:
    settings = FilterSettings(kind="plkf", motion_noise=MOTION, sensor_noise=PRECISE)
    start = Gaussian(mean=np.array([2.0, 1.0, 1.0, 0.2]), cov=np.eye(4) * 0.1)
    tracker = RelativeTracker(start, settings, label="l1->c1")
    u_l, u_c = np.array([0.3, 0, 0, 0.1]), np.array([0.2, 0, 0, -0.1])
    z = np.array([2.5, 0.45, 0.41])
    tracker.predict(u_l, u_c, 0.1)
    inn = tracker.update(z)
    expected, expected_inn = update_plkf(predict(start, u_l, u_c, 0.1, MOTION), z, PRECISE)
    np.testing.assert_allclose(tracker.belief.mean, expected.mean)
    np.testing.assert_allclose(tracker.belief.cov, expected.cov)
    assert inn.nis == pytest.approx(expected_inn.nis)


def test_bad_input_is_reported_with_its_place() -> None:
    settings = FilterSettings(kind="tekf", motion_noise=MOTION, sensor_noise=PRECISE)
    tracker = RelativeTracker(Gaussian(mean=np.ones(4), cov=np.eye(4)), settings, label="l1->c2")
    with pytest.raises(DataError, match=r"l1->c2.*NaN"):
        tracker.update(np.array([1.0, np.nan, 0.0]))
    with pytest.raises(DataError, match="range must be > 0"):
        tracker.update(np.array([0.0, 0.1, 0.0]))
    with pytest.raises(DataError, match="u_l"):
        tracker.predict(np.zeros(3), np.zeros(4), 0.1)
    with pytest.raises(ConfigError, match="kind"):
        FilterSettings(kind="ukf", motion_noise=MOTION, sensor_noise=PRECISE)  # type: ignore[arg-type]
    with pytest.raises(ConfigError, match="pseudo_linear_covariance"):
        FilterSettings(motion_noise=MOTION, sensor_noise=PRECISE, pseudo_linear_covariance="x")  # type: ignore[arg-type]
    # a tracker cannot start from a covariance that is not PSD: refused where it is made
    with pytest.raises(ModelError, match="Gaussian: covariance is not positive semi-definite"):
        Gaussian(mean=np.ones(4), cov=-np.eye(4))
    with pytest.raises(ModelError, match="not positive definite at pair 7"):
        update_tekf_arrays(
            np.ones(4), -np.eye(4), np.array([1.0, 0.1, 0.0]), PRECISE, where="pair 7"
        )
