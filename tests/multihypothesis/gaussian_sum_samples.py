"""The Gaussian-sum filter settings the seed-002 unit tests share."""

from __future__ import annotations

from relloc.estimators.gaussian_sum import GaussianSumSettings
from relloc.models.motion import VelocityNoise

NOISE = VelocityNoise(observer=(0.2, 0.2, 0.2, 0.1), observed=(0.2, 0.2, 0.2, 0.1))


def gs_settings(**changes: object) -> GaussianSumSettings:
    """Height σ 1 cm, range σ 2 cm, bearings σ 0.05 rad and :data:`NOISE`, with ``changes``."""
    base: dict[str, object] = dict(
        velocity_noise=NOISE,
        sigma_height=0.01,
        sigma_range=0.02,
        sigma_azimuth=0.05,
        sigma_elevation=0.05,
    )
    base.update(changes)
    return GaussianSumSettings(**base)  # type: ignore[arg-type]
