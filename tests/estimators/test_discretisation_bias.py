"""The shared predict does not bias yaw; a forward-Euler predict does (by about ω dt / 2)."""

import numpy as np

from relloc.estimators.relative import predict_arrays, update_plkf_arrays
from relloc.models.measurement import RangeBearingNoise, range_bearing
from relloc.models.motion import (
    VelocityNoise,
    process_noise,
    relative_derivative,
    relative_jacobians,
    relative_step,
)

MOTION = VelocityNoise(observer=(0.02, 0.02, 0.01, 0.01), observed=(0.02, 0.02, 0.01, 0.01))
PRECISE = RangeBearingNoise(sigma_r=0.0068, sigma_azimuth=0.0036, sigma_elevation=0.0036)


def _euler_predict(mean, cov, u_l, u_c, dt):  # type: ignore[no-untyped-def]
    """Forward Euler for the mean (the discretisation the issue warns about), same P update."""
    F, G = relative_jacobians(mean, u_l, u_c, dt)
    return mean + dt * relative_derivative(mean, u_l, u_c), F @ cov @ F.T + process_noise(G, MOTION)


def _mean_yaw_error(use_euler: bool) -> float:
    dt, steps = 0.1, 300
    u_l = np.array([0.2, 0.0, 0.0, 0.0])
    u_c = np.array([1.0, 0.0, 0.0, 0.5])
    truth = np.array([3.0, 0.0, 2.0, 0.0])
    mean = truth + np.array([0.1, -0.1, 0.05, 0.2])  # the filter starts off the truth
    cov = np.diag([0.01, 0.01, 0.01, 0.05])
    errors = []
    for _ in range(steps):
        truth = relative_step(truth, u_l, u_c, dt)
        if use_euler:
            mean, cov = _euler_predict(mean, cov, u_l, u_c, dt)
        else:
            mean, cov = predict_arrays(mean, cov, u_l, u_c, dt, MOTION)
        mean, cov, _ = update_plkf_arrays(mean, cov, range_bearing(truth), PRECISE)
        errors.append(mean[3] - truth[3])
    return float(np.mean(errors[steps // 2 :]))


def test_exact_predict_has_no_yaw_bias_where_euler_has_about_half_omega_dt() -> None:
    # noise-free odometry and measurements: any steady yaw error is discretisation bias
    half_omega_dt = 0.5 * 0.5 * 0.1
    assert abs(_mean_yaw_error(use_euler=False)) < 0.01 * half_omega_dt
    euler_bias = abs(_mean_yaw_error(use_euler=True))
    assert 0.5 * half_omega_dt < euler_bias < 1.5 * half_omega_dt
