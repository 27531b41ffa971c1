"""Noise inflation for time-correlated errors.

A Kalman-type filter assumes each reading's error independent of the others. When the errors
of readings ``Δ`` apart are correlated, ``ρ(kΔ) = corr(e_t, e_{t+kΔ})``, the mean of ``N``
readings has variance ``(σ²/N)·f`` for large ``N``, with the variance inflation factor
(Bartlett; the integrated autocorrelation time in samples)

    f = 1 + 2 Σ_{k≥1} ρ(kΔ).

A filter that uses the readings as independent with variance ``σ²`` over-counts their
information ``f``-fold; giving it ``f σ²`` instead makes its long-run averaging honest (a short
burst of readings is then under-weighted, the price of keeping a white-noise filter).

- :func:`autocorrelation_inflation`: ``f`` from a measured autocorrelation at a few lags
  (interpolated linearly between them, clipped at 0, taken as 0 beyond
  ``CORRELATION_HORIZON_S``) — for residuals whose correlation is measured, not modelled;
- :func:`gauss_markov_inflation`: the closed form for a first-order Gauss–Markov error of time
  constant ``τ`` sampled every ``Δ``: ``ρ(kΔ) = aᵏ`` with ``a = exp(−Δ/τ)``, so
  ``f = 1 + 2a/(1 − a) = (1 + a)/(1 − a)`` (1 when τ = 0, white);
- :func:`smallest_factor`: where the correlation is not measured but its effect is, the
  smallest factor of a grid at which a replay's share of NEES beyond its χ² bound meets a
  target (the noise inflations of the seed-000 replay and of mrclam-cl), and
  :func:`search_text`, the reports' sentence on such a search.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence

import numpy as np

from relloc.errors import ConfigError, DataError

#: Lags beyond this (s) are taken as uncorrelated by :func:`autocorrelation_inflation`.
CORRELATION_HORIZON_S = 10.0
#: Most terms ``horizon/Δ`` :func:`autocorrelation_inflation` sums (8 MB of lags).
MAX_INFLATION_TERMS = 1_000_000


def autocorrelation_inflation(
    rho: Mapping[float, float], spacing: float, horizon_s: float = CORRELATION_HORIZON_S
) -> float:
    """``f = 1 + 2 Σ_{k≥1, kΔ ≤ horizon} ρ(kΔ)`` for readings ``Δ = spacing`` apart, with ``ρ``
    the correlation measured at the lags ``rho`` (s → correlation), interpolated linearly,
    clipped to [0, 1], held at its first value below the first lag and 0 beyond the last.

    ConfigError naming the argument unless the lags and ``spacing`` are finite and > 0,
    ``horizon_s`` is finite and ≥ 0 and the sum has at most ``MAX_INFLATION_TERMS`` terms;
    DataError when a measured correlation is not finite."""
    if not rho:
        raise ConfigError("autocorrelation_inflation: no measured lag correlation")
    if not (math.isfinite(spacing) and spacing > 0):
        raise ConfigError(f"autocorrelation_inflation: spacing must be > 0, got {spacing}")
    if not (math.isfinite(horizon_s) and horizon_s >= 0):
        raise ConfigError(f"autocorrelation_inflation: horizon_s must be ≥ 0, got {horizon_s}")
    if horizon_s / spacing > MAX_INFLATION_TERMS:
        raise ConfigError(
            f"autocorrelation_inflation: spacing {spacing:g} s would sum {horizon_s / spacing:.3g}"
            f" terms over the {horizon_s:g} s horizon, more than {MAX_INFLATION_TERMS}"
        )
    for lag, value in rho.items():
        if not (math.isfinite(lag) and lag > 0):
            raise ConfigError(f"autocorrelation_inflation: rho's lags must be > 0, got {lag}")
        if not math.isfinite(value):
            raise DataError(f"autocorrelation_inflation: rho at lag {lag:g} s is {value}")
    lags = np.array(sorted(rho))
    values = np.clip(np.array([rho[lag] for lag in lags]), 0.0, 1.0)
    k = np.arange(spacing, horizon_s + 1e-9, spacing)
    return float(1.0 + 2.0 * np.sum(np.interp(k, lags, values, left=values[0], right=0.0)))


def gauss_markov_inflation(period: float, tau: float) -> float:
    """``(1 + a)/(1 − a)``, ``a = exp(−period/τ)``, for a Gauss–Markov error of time constant
    ``tau`` sampled every ``period`` (1 when ``tau = 0``). ConfigError unless ``tau`` is finite
    and ≥ 0 and, for ``tau > 0``, ``period`` is finite, > 0 and not so small against ``tau``
    that ``a`` rounds to 1 (an unbounded factor)."""
    if not (math.isfinite(tau) and tau >= 0.0):
        raise ConfigError(f"gauss_markov_inflation: tau must be finite and ≥ 0, got {tau}")
    if tau == 0.0:
        return 1.0
    if not (math.isfinite(period) and period > 0):
        raise ConfigError(f"gauss_markov_inflation: period must be > 0, got {period}")
    a = math.exp(-period / tau)
    if a == 1.0:
        raise ConfigError(
            f"gauss_markov_inflation: period {period:g} s is negligible against tau {tau:g} s"
        )
    return (1.0 + a) / (1.0 - a)


def smallest_factor(
    grid: Sequence[float], target_percent: float, percent_beyond: Callable[[float], float]
) -> tuple[float, bool, tuple[tuple[float, float], ...]]:
    """``(k, met, tried)``: the first factor ``k`` of ``grid`` (in order) whose
    ``percent_beyond(k)`` is at most ``target_percent``, or the grid's last (``met`` false);
    ``tried`` the ``(k, percent)`` of every factor evaluated, up to that one."""
    if not grid:
        raise ConfigError("smallest_factor: an empty grid of factors")
    tried: list[tuple[float, float]] = []
    for k in grid:
        tried.append((k, float(percent_beyond(k))))
        if tried[-1][1] <= target_percent:
            break
    return tried[-1][0], tried[-1][1] <= target_percent, tuple(tried)


def search_text(tried: Sequence[tuple[float, float]], met: bool) -> str:
    """A report's account of a :func:`smallest_factor` search: whether the target was met and
    the share beyond the bound at every factor tried, e.g. ``met; tried ×1: 5.4 %, ×1.5: 0.6 %``."""
    verdict = "met" if met else "not met by any factor tried; the largest is used"
    return f"{verdict}; tried " + ", ".join(f"×{k:g}: {p:.1f} %" for k, p in tried)
