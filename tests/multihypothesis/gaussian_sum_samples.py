"""The Gaussian-sum filter settings and the one-track message the seed-002 unit tests share."""

from __future__ import annotations

from typing import Any

import numpy as np

from relloc.estimators.gaussian_sum import GaussianSumSettings
from relloc.fusion.messages import EquivalentMeasurement
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


def one_track_message(**changes: Any) -> EquivalentMeasurement:
    """Robot 0's one-track message about robot 1 at t = 0 (mean 0, covariance I, now and at
    the previous broadcast), with ``changes``."""
    fields: dict[str, Any] = {
        "sender": 0,
        "subject": 1,
        "time": 0.0,
        "means": np.zeros((1, 4)),
        "covs": np.eye(4)[None],
        "prior_means": np.zeros((1, 4)),
        "prior_covs": np.eye(4)[None],
        "weights": np.ones(1),
    }
    return EquivalentMeasurement(**{**fields, **changes})
