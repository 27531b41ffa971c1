"""Numerical edge cases of the relative estimators: a long run, innovations across ±π, a zero
time step, a measurement at the prior, a singular prior, and NaN refused where it comes in."""

from __future__ import annotations

import math

import numpy as np
import pytest

from relloc.core.gaussian import Gaussian, GaussianMixture
from relloc.core.kalman import kalman_update
from relloc.errors import ConfigError, DataError, ModelError, RellocError
from relloc.estimators.kernels import join_symmetric
from relloc.estimators.relative import (
    FilterSettings,
    RelativeTracker,
    predict_arrays,
)
from relloc.estimators.switching_ekf import block_update
from relloc.estimators.uwb_range import RelativeDeadReckoning
from relloc.models.measurement import RangeBearingNoise, range_bearing
from relloc.models.motion import VelocityNoise, relative_step

KINDS = ("plkf", "tekf", "bcplkf")
U_L = np.array([0.3, 0.0, 0.0, 0.2])
U_C = np.array([0.4, 0.1, 0.0, -0.3])
PRIOR = Gaussian(np.array([3.0, 1.0, 0.5, 0.3]), np.diag([1.0, 1.0, 1.0, 0.3]))


def _settings(kind: str, sigma_z: float = 0.05, sigma_u: float = 0.05) -> FilterSettings:
    return FilterSettings(
        kind=kind,  # type: ignore[arg-type]
        motion_noise=VelocityNoise(observer=(sigma_u,) * 4, observed=(sigma_u,) * 4),
        sensor_noise=RangeBearingNoise(
            sigma_r=sigma_z, sigma_azimuth=sigma_z, sigma_elevation=sigma_z
        ),
    )


@pytest.mark.parametrize("kind", KINDS)
def test_a_long_run_keeps_the_covariance_positive_definite(kind):
    """10⁴ predict/update steps (yaw turning 500 rad in all): the covariance stays finite and
    positive definite (symmetric by construction), every azimuth residual within [−π, π]."""
    rng = np.random.default_rng(7)
    tracker = RelativeTracker(PRIOR, _settings(kind))
    truth = PRIOR.mean.copy()
    for _ in range(10_000):
        tracker.predict(U_L, U_C, 0.1)
        truth = relative_step(truth, U_L, U_C, 0.1)
        z = range_bearing(truth[:3]) + rng.normal(0.0, 0.01, 3)
        z[1] = (z[1] + math.pi) % (2 * math.pi) - math.pi
        residual = tracker.update(z).residual
        assert abs(residual[1]) <= math.pi
    P = tracker.belief.cov
    assert np.array_equal(P, P.T)
    assert np.linalg.eigvalsh(P).min() > 0.0
    yaw = tracker.belief.mean[3]
    assert abs(yaw) > 400.0  # states are not wrapped (relloc.core.angles), only residuals
    assert abs(math.remainder(yaw - truth[3], 2 * math.pi)) < 0.01


@pytest.mark.parametrize("kind", KINDS)
def test_azimuth_across_pi_gives_a_small_residual(kind):
    """Prior just below +π, measurement just above −π: the residual is the short way round."""
    prior = Gaussian(np.array([-3.0, 1e-3, 0.0, 0.0]), np.eye(4) * 0.01)
    tracker = RelativeTracker(prior, _settings(kind))
    inn = tracker.update([3.0, -math.pi + 1e-3, 0.0])
    assert np.abs(inn.residual).max() < 0.01
    assert abs(tracker.belief.mean[1]) < 1e-2


def test_switching_ekf_wraps_every_angle_residual():
    belief = Gaussian(np.zeros(2), np.eye(2))
    z, h = np.array([math.pi - 1e-3, -math.pi + 1e-3]), np.array([-math.pi + 1e-3, math.pi - 1e-3])
    res = block_update(belief, z, h, np.eye(2), np.eye(2) * 0.01, (True, True), None)
    assert res.accepted
    # residuals −2e-3 and +2e-3 (not ±(2π − 2e-3)), gain 1/1.01
    assert np.allclose(res.belief.mean, np.array([-2e-3, 2e-3]) / 1.01, atol=1e-12)


@pytest.mark.parametrize("kind", KINDS)
def test_zero_time_step_leaves_the_belief_unchanged(kind):
    tracker = RelativeTracker(PRIOR, _settings(kind))
    tracker.predict(U_L, U_C, 0.0)
    assert np.array_equal(tracker.belief.mean, PRIOR.mean)
    assert np.array_equal(tracker.belief.cov, PRIOR.cov)
    mean, cov = predict_arrays(PRIOR.mean, PRIOR.cov, U_L, U_C, 0.0, _settings(kind).motion_noise)
    assert np.array_equal(mean, PRIOR.mean) and np.array_equal(cov, PRIOR.cov)


@pytest.mark.parametrize("kind", ("plkf", "tekf"))
@pytest.mark.parametrize("sigma", (1e-9, 1e6))
def test_measurement_at_the_prior_with_tiny_or_huge_noise(kind, sigma):
    tracker = RelativeTracker(PRIOR, _settings(kind, sigma_z=sigma))
    inn = tracker.update(range_bearing(PRIOR.mean[:3]))
    assert inn.nis == pytest.approx(0.0, abs=1e-12)
    assert np.allclose(tracker.belief.mean, PRIOR.mean, atol=1e-12)
    assert np.linalg.eigvalsh(tracker.belief.cov).min() > -1e-12


@pytest.mark.parametrize("kind", KINDS)
def test_a_singular_prior_is_kept(kind):
    """A prior of covariance 0 (certain) is not moved by a measurement that agrees with it."""
    prior = Gaussian(PRIOR.mean, np.zeros((4, 4)))
    tracker = RelativeTracker(prior, _settings(kind))
    tracker.update(range_bearing(prior.mean[:3]))
    assert np.allclose(tracker.belief.mean, prior.mean, atol=1e-12)
    assert np.array_equal(tracker.belief.cov, np.zeros((4, 4)))


def test_a_large_time_step_stays_finite():
    tracker = RelativeTracker(PRIOR, _settings("plkf"))
    tracker.predict(U_L, U_C, 1e6)
    assert np.isfinite(tracker.belief.cov).all()
    tracker.update(range_bearing(tracker.belief.mean[:3]))
    assert np.linalg.eigvalsh(join_symmetric(tracker._cov)).min() > 0.0


@pytest.mark.parametrize("dt", [None, "abc", -0.1, math.nan, math.inf, 1e150])
def test_a_time_step_that_is_not_a_number_or_negative_is_a_config_error(dt):
    """None and text raised a raw TypeError/ValueError; a step of 1e150 s (beyond
    ``MAX_TIME_STEP_S``) overflowed the covariance to inf silently."""
    with pytest.raises(
        ConfigError,
        match=r"relative (filter|tracker): dt: (expected a number|must be a finite number)",
    ):
        predict_arrays(PRIOR.mean, PRIOR.cov, U_L, U_C, dt, _settings("plkf").motion_noise)
    with pytest.raises(
        ConfigError,
        match=r"relative (filter|tracker): dt: (expected a number|must be a finite number)",
    ):
        RelativeTracker(PRIOR, _settings("plkf")).predict(U_L, U_C, dt)


# ------------------------------------------------------------------ NaN where it comes in
#
# kalman_update does not check the prior mean (see relloc.core.kalman): every estimator checks
# it where it enters.


def test_kalman_update_refuses_nan_that_reaches_s_or_the_nis():
    with pytest.raises(ModelError, match="at team"):
        kalman_update(np.zeros(2), np.eye(2), [np.nan], [[1.0, 0.0]], [[1.0]], where="team")


@pytest.mark.parametrize(
    "make",
    [
        lambda: Gaussian(np.array([np.nan, 0.0]), np.eye(2)),
        lambda: GaussianMixture(
            means=np.full((1, 4), np.nan), covs=np.eye(4)[None], weights=np.ones(1)
        ),
        lambda: predict_arrays(
            [np.nan, 0, 0, 0], np.eye(4), U_L, U_C, 0.1, _settings("plkf").motion_noise
        ),
        lambda: _settings("tekf").update_arrays([np.nan, 0, 0, 0], np.eye(4), [1.0, 0, 0]),
        lambda: _settings("plkf").update_arrays(PRIOR.mean, PRIOR.cov, [1.0, np.nan, 0]),
        lambda: RelativeTracker(PRIOR, _settings("plkf")).update([1.0, 0.0, np.inf]),
        lambda: RelativeTracker(PRIOR, _settings("plkf")).predict(U_L, [np.nan, 0, 0, 0], 0.1),
    ],
)
def test_nan_is_refused_where_it_enters_an_estimator(make):
    with pytest.raises(RellocError):
        make()


def _dead_reckoning(start):
    noise = _settings("plkf").motion_noise
    return RelativeDeadReckoning(0, 1, ("a", "b"), noise, start)


@pytest.mark.parametrize(
    ("start", "error"),
    [
        ((0.0, [np.nan, 0.0, 0.0, 0.0], np.eye(4)), DataError),
        ((0.0, np.zeros(4), np.full((4, 4), np.inf)), DataError),
        ((0.0, np.zeros(3), np.eye(4)), DataError),
        ((0.0, np.zeros(4), np.eye(3)), DataError),
        ((math.nan, np.zeros(4), np.eye(4)), ConfigError),
    ],
)
def test_dead_reckoning_refuses_a_bad_start_naming_the_pair(start, error):
    with pytest.raises(error, match="a->b"):
        _dead_reckoning(start)
