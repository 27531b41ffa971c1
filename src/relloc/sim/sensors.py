"""Inter-robot range/azimuth/elevation sensing from ground truth (seed 000 Eq. 2).

For an observer pose ``a`` and a target pose ``b`` (both ``(x, y, z, ψ)``), the target in the
observer's body frame is ``p = Rz(ψ_a)ᵀ (p_b − p_a)`` and the noise-free measurement is

    r = ‖p‖,   θ = atan2(p_y, p_x),   α = atan2(p_z, √(p_x² + p_y²)).

The sensor sees the target when ``min_range ≤ r ≤ max_range``, ``|θ| ≤ fov/2`` and
``|α| ≤ elevation_fov/2`` (judged on the true values: visibility is a property of the scene,
not of the noise). Noise is additive white Gaussian, ``ν ~ N(0, diag(σ_r², σ_θ², σ_α²))``;
the azimuth is wrapped to [−π, π). A range cannot be negative, so the range noise is a Gaussian
truncated to keep ``r > 0`` (redrawn), which only matters when a target is closer than a few σ_r.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from relloc.core.angles import wrap_angle
from relloc.core.recording import relative_pose
from relloc.sim.scenario import SensorSpec

Array = NDArray[np.float64]
BoolArray = NDArray[np.bool_]


def range_azimuth_elevation(rel: Array) -> Array:
    """Noise-free ``(r, θ, α)`` ``(N, 3)`` of relative positions ``rel (N, ≥3)``."""
    x, y, z = rel[:, 0], rel[:, 1], rel[:, 2]
    rho = np.hypot(x, y)
    return np.stack([np.sqrt(rho**2 + z**2), np.arctan2(y, x), np.arctan2(z, rho)], axis=1)


def visible(z_true: Array, sensor: SensorSpec) -> BoolArray:
    """Whether each noise-free ``(r, θ, α)`` lies inside the sensor's range and field of view."""
    r, th, al = z_true[:, 0], z_true[:, 1], z_true[:, 2]
    half_fov = np.deg2rad(sensor.fov_deg) / 2.0
    half_vfov = np.deg2rad(sensor.elevation_fov_deg) / 2.0
    in_fov = np.ones_like(r, dtype=bool) if sensor.fov_deg >= 360.0 else np.abs(th) <= half_fov
    return (r >= sensor.min_range) & (r <= sensor.max_range) & in_fov & (np.abs(al) <= half_vfov)


def add_noise(z_true: Array, sigma: Array, rng: np.random.Generator) -> Array:
    """``z_true + ν`` with ν ~ N(0, diag(σ²)) per row; azimuth wrapped; range kept positive."""
    sigma = np.broadcast_to(np.asarray(sigma, dtype=float), z_true.shape)
    z = z_true + sigma * rng.standard_normal(z_true.shape)
    bad = z[:, 0] <= 0.0
    while bad.any():
        z[bad, 0] = z_true[bad, 0] + sigma[bad, 0] * rng.standard_normal(int(bad.sum()))
        bad = z[:, 0] <= 0.0
    z[:, 1] = wrap_angle(z[:, 1])
    return z


def sense(
    observer_pose: Array, target_pose: Array, sensor: SensorSpec, rng: np.random.Generator
) -> tuple[Array, BoolArray]:
    """Noisy measurements of one target at matching times.

    ``observer_pose``, ``target_pose`` are ``(N, 4)`` true poses at the measurement times.
    Returns ``(z (N, 3), seen (N,))``: noise is drawn for every row (so the random stream does
    not depend on visibility) and ``seen`` marks the rows the sensor actually reports.
    """
    z_true = range_azimuth_elevation(relative_pose(observer_pose, target_pose))
    seen = visible(z_true, sensor)
    return add_noise(z_true, np.asarray(sensor.sigma), rng), seen


def measurement_times(rate_hz: float, duration_s: float) -> Array:
    """Sensor epochs ``k / rate`` for ``k = 1, 2, …`` up to ``duration_s`` (inclusive, to within
    the 1e-9 s that :meth:`relloc.core.recording.GroundTruth.at` allows).

    The first epoch is one period after the start, so every measurement follows at least one
    odometry interval. The count tolerates round-off in ``duration_s · rate_hz``; at a slow
    rate that tolerance could reach past ``duration_s``, so epochs beyond it are dropped.
    """
    n = int(np.floor(duration_s * rate_hz + 1e-9))
    epochs = np.arange(1, n + 1) / rate_hz
    return epochs[epochs <= duration_s + 1e-9]
