"""The gating filters a robot process runs compute their χ² gate quantiles when they are built
(:func:`relloc.core.kalman.prepare_gates`), so the first gate of a run costs a cache hit: the
process builds its estimator before it declares itself ready, and the one-off import of
``scipy.stats`` falls outside every timed tick."""

from __future__ import annotations

import numpy as np
from scipy.stats import chi2

from relloc.core.gaussian import Gaussian
from relloc.core.kalman import chi2_threshold, prepare_gates
from relloc.estimators.cooperative import (
    GATE_DOFS,
    CooperativeEstimator,
    CooperativeSettings,
    OdometryModel,
    SensorModel,
)
from relloc.estimators.gaussian_sum import GaussianSumFuser, GaussianSumSettings
from relloc.models.motion import VelocityNoise


def _cached(keys: list[tuple[int, float]]) -> bool:
    """Every ``(dim, probability)`` of ``keys`` is a cache hit of :func:`chi2_threshold`."""
    misses = chi2_threshold.cache_info().misses
    for dim, p in keys:
        assert chi2_threshold(dim, p) == float(chi2.ppf(p, dim))
    return chi2_threshold.cache_info().misses == misses


def test_prepare_gates_caches_every_dimension_and_probability_and_skips_an_open_gate() -> None:
    chi2_threshold.cache_clear()
    prepare_gates([3, 1, 1], 0.99, None, 0.9)
    assert chi2_threshold.cache_info().currsize == 4
    assert _cached([(1, 0.99), (3, 0.99), (1, 0.9), (3, 0.9)])


def test_the_team_filter_has_its_gate_quantiles_when_built() -> None:
    chi2_threshold.cache_clear()
    settings = CooperativeSettings(
        odometry=OdometryModel(q_v0=1e-3, q_w0=1e-3), sensor=SensorModel(sigma_bearing=0.01)
    )
    CooperativeEstimator(("A", "B"), Gaussian(np.zeros(6), np.eye(6)), settings)
    assert settings.p_gate is not None
    assert _cached([(d, settings.p_gate) for d in GATE_DOFS])


def test_the_gaussian_sum_fuser_has_its_gate_quantiles_when_built() -> None:
    noise = VelocityNoise(observer=(0.2, 0.2, 0.2, 0.1), observed=(0.2, 0.2, 0.2, 0.1))
    for elevation in (False, True):
        chi2_threshold.cache_clear()
        st = GaussianSumSettings(
            velocity_noise=noise,
            sigma_height=0.01,
            sigma_range=0.02,
            sigma_azimuth=0.05,
            sigma_elevation=0.05,
            use_elevation=elevation,
        )
        GaussianSumFuser(0, [1], st)
        nb = len(st.bearing_rows)
        gate = st.gate
        assert _cached([(nb, gate.p_gate), (nb, gate.p_birth_exclusion), (4, gate.p_gate)])
