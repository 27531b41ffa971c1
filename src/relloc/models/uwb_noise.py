"""UWB range-error model: a biased, time-correlated Gaussian core with a heavy one-sided tail.

The error of one reading is ``e = uwb_range − true_range``. :class:`UwbNoiseModel` holds

- ``bias``: the common offset (m) a team calibration removes;
- ``link_bias_std``: the spread of the per-link offsets around ``bias`` (what is left when
  every radio pair is not calibrated on its own);
- ``spread``: σ of the Gaussian core;
- ``correlation_time``: τ of the core as a first-order Gauss–Markov process (0: white);
- the outliers, peaks-over-threshold: with probability ``outlier_rate`` a reading lies beyond
  ``outlier_k·spread``, positive with probability ``outlier_positive_fraction``, its excess
  beyond the threshold exponential with mean ``outlier_excess_mean``.

:func:`sample_range_errors` draws errors from it (used by the air-ground simulator); the model
is fitted to a recording by :func:`relloc.calibration.uwb.fit_uwb_noise`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from relloc.core.checks import count, number, positive
from relloc.errors import ConfigError

#: A reading is an outlier when its deviation from its link's offset exceeds ``OUTLIER_K`` σ.
OUTLIER_K = 3.0


@dataclass(frozen=True, kw_only=True)
class UwbNoiseModel:
    """Fitted (or chosen) UWB range-error model; all lengths in metres, times in seconds."""

    bias: float
    spread: float
    outlier_rate: float
    outlier_excess_mean: float
    outlier_positive_fraction: float = 1.0
    link_bias_std: float = 0.0
    correlation_time: float = 0.0
    outlier_k: float = OUTLIER_K

    def __post_init__(self) -> None:
        """Every field a finite number (never a string, ``None`` or a bool): ``bias`` any,
        ``outlier_rate`` in ``[0, 1)``, ``outlier_positive_fraction`` in ``[0, 1]``,
        ``outlier_k`` > 0, the others ≥ 0; ConfigError naming the field otherwise."""
        where = "UwbNoiseModel."
        number(self.bias, where + "bias")
        number(self.outlier_rate, where + "outlier_rate", low=0.0, high=1.0, open_high=True)
        number(self.outlier_positive_fraction, where + "outlier_positive_fraction", low=0, high=1)
        positive(self.outlier_k, where + "outlier_k")
        for name in ("spread", "outlier_excess_mean", "link_bias_std", "correlation_time"):
            number(getattr(self, name), where + name, low=0.0)


#: The fit of :func:`relloc.calibration.uwb.fit_uwb_noise` to the TIERS UWB recording (the
#: guler2023 calibration), rounded: a data-free model for examples and tests.
TIERS_ROUNDED = UwbNoiseModel(
    bias=0.35,
    spread=0.075,
    outlier_rate=0.04,
    outlier_excess_mean=0.15,
    outlier_positive_fraction=0.9,
    link_bias_std=0.1,
    correlation_time=1.2,
)


def sample_range_errors(
    model: UwbNoiseModel,
    n_steps: int,
    n_links: int,
    dt: float,
    rng: np.random.Generator,
    *,
    include_bias: bool = True,
    link_bias: bool = False,
) -> NDArray[np.float64]:
    """Draw range errors ``(n_steps, n_links)`` from ``model`` at sampling period ``dt``.

    Core: a first-order Gauss–Markov sequence per link, stationary σ = ``spread`` and
    ``e_{k+1} = a e_k + σ√(1−a²) w_k`` with ``a = exp(−dt/τ)`` (white when τ = 0). With
    probability ``outlier_rate`` a reading is replaced by ``±(k·spread + Exp(excess_mean))``.
    ``include_bias`` adds the common ``bias``; ``link_bias`` adds one ``N(0, link_bias_std²)``
    offset per link, drawn once. ``n_steps`` and ``n_links`` are integers ≥ 0, ``dt`` a finite
    number > 0, ``model`` a :class:`UwbNoiseModel` and ``rng`` a numpy ``Generator``; anything
    else is a ConfigError naming the argument.
    """
    where = "sample_range_errors: "
    if not isinstance(model, UwbNoiseModel):
        raise ConfigError(f"{where}model: expected a UwbNoiseModel, got {type(model).__name__}")
    if not isinstance(rng, np.random.Generator):
        raise ConfigError(f"{where}rng: expected a numpy Generator, got {type(rng).__name__}")
    n_steps = count(n_steps, where + "n_steps", low=0)
    n_links = count(n_links, where + "n_links", low=0)
    dt = positive(dt, where + "dt")
    a = math.exp(-dt / model.correlation_time) if model.correlation_time > 0.0 else 0.0
    drive = model.spread * math.sqrt(1.0 - a * a)
    core = np.empty((n_steps, n_links))
    state = rng.normal(0.0, model.spread, n_links)
    for k in range(n_steps):
        core[k] = state
        state = a * state + drive * rng.standard_normal(n_links)
    is_outlier = rng.random((n_steps, n_links)) < model.outlier_rate
    sign = np.where(rng.random((n_steps, n_links)) < model.outlier_positive_fraction, 1.0, -1.0)
    magnitude = model.outlier_k * model.spread + rng.exponential(
        max(model.outlier_excess_mean, 1e-12), (n_steps, n_links)
    )
    out = np.where(is_outlier, sign * magnitude, core)
    if include_bias:
        out = out + model.bias
    if link_bias and model.link_bias_std > 0.0:
        out = out + rng.normal(0.0, model.link_bias_std, n_links)[None, :]
    return out
