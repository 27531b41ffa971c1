"""Robust fit of a UWB range-error model from ranges recorded beside motion capture.

The error of one reading is ``e = uwb_range − mocap_range``. We fit, robustly (medians and MADs,
so that the outliers being measured do not distort the core):

- ``bias``: the median of all errors (m), the offset a calibration would remove;
- ``link_bias_std``: the spread (sample std) of the per-link medians around ``bias`` — what is
  left after one team-wide calibration when every radio pair is not calibrated on its own;
- ``spread``: ``1.4826·MAD`` of the within-link residuals ``r = e − median_link(e)``, the σ of the
  Gaussian core;
- ``outlier_rate``: the fraction of readings with ``|r| > k·spread`` (``k = OUTLIER_K``), with the
  tail modelled peaks-over-threshold: a sign (``outlier_positive_fraction``) and an exponential
  excess beyond ``k·spread`` of mean ``outlier_excess_mean``;
- ``correlation_time``: the first-order Gauss–Markov time constant τ, taken per link as the time
  lag at which the autocorrelation of the within-link residuals first drops below 1/e (lags
  measured in seconds, since the recording is sampled irregularly), median over links —
  consecutive UWB errors are far from white.

:func:`sample_range_errors` draws errors from the fitted model (used by the air-ground simulator).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from relloc.datasets.uwb import UwbRecording
from relloc.errors import ConfigError, DataError

#: Gaussian-consistent MAD scale.
MAD_SCALE = 1.4826
#: A reading is an outlier when its within-link residual exceeds ``OUTLIER_K`` robust sigmas.
OUTLIER_K = 3.0
#: Links with fewer readings are ignored in the fit (their median is not trustworthy).
MIN_LINK_ROWS = 20
#: Longest time lag (s) searched for the 1/e decorrelation of the errors.
MAX_CORRELATION_LAG = 20.0


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
        checks = {
            "bias": math.isfinite(self.bias),
            "spread": math.isfinite(self.spread) and self.spread >= 0.0,
            "outlier_rate": 0.0 <= self.outlier_rate < 1.0,
            "outlier_excess_mean": math.isfinite(self.outlier_excess_mean)
            and self.outlier_excess_mean >= 0.0,
            "outlier_positive_fraction": 0.0 <= self.outlier_positive_fraction <= 1.0,
            "link_bias_std": math.isfinite(self.link_bias_std) and self.link_bias_std >= 0.0,
            "correlation_time": math.isfinite(self.correlation_time)
            and self.correlation_time >= 0.0,
            "outlier_k": math.isfinite(self.outlier_k) and self.outlier_k > 0.0,
        }
        for name, ok in checks.items():
            if not ok:
                raise ConfigError(f"UwbNoiseModel.{name}: invalid value {getattr(self, name)!r}")


@dataclass(frozen=True, kw_only=True)
class UwbNoiseFit:
    """The fitted model plus what it was fitted on (for reports)."""

    model: UwbNoiseModel
    n_rows: int
    n_links: int
    sample_period: float
    lag1_correlation: float
    link_biases: dict[str, float]
    rows_skipped: int

    def as_dict(self) -> dict[str, object]:
        """JSON-ready summary (``summary.json["uwb_noise_fit"]``)."""
        m = self.model
        return {
            "bias_m": m.bias,
            "spread_m": m.spread,
            "outlier_rate": m.outlier_rate,
            "outlier_threshold_sigma": m.outlier_k,
            "outlier_excess_mean_m": m.outlier_excess_mean,
            "outlier_positive_fraction": m.outlier_positive_fraction,
            "link_bias_std_m": m.link_bias_std,
            "correlation_time_s": m.correlation_time,
            "lag1_correlation": self.lag1_correlation,
            "sample_period_s": self.sample_period,
            "link_biases_m": self.link_biases,
            "n_rows": self.n_rows,
            "n_links": self.n_links,
            "rows_skipped": self.rows_skipped,
        }


def _robust_sigma(x: NDArray[np.float64]) -> float:
    return float(MAD_SCALE * np.median(np.abs(x - np.median(x))))


def _decorrelation_time(t: NDArray[np.float64], r: NDArray[np.float64]) -> float | None:
    """Time lag (s) where the autocorrelation of ``r`` first falls below 1/e (None if never)."""
    if r.size < 4 or float(np.std(r)) == 0.0:
        return None
    prev_lag, prev_rho = 0.0, 1.0
    for k in range(1, r.size - 2):
        lag = float(np.mean(t[k:] - t[:-k]))
        if lag > MAX_CORRELATION_LAG:
            return None
        rho = float(np.corrcoef(r[:-k], r[k:])[0, 1])
        if rho < math.exp(-1.0):
            frac = (prev_rho - math.exp(-1.0)) / (prev_rho - rho)
            return prev_lag + frac * (lag - prev_lag)
        prev_lag, prev_rho = lag, rho
    return None


def fitted_links(rec: UwbRecording) -> list[tuple[int, int]]:
    """Links with enough readings to enter the fit (DataError if none)."""
    links = [link for link in rec.links() if int(rec.link_mask(link).sum()) >= MIN_LINK_ROWS]
    if not links:
        raise DataError(
            f"{rec.path}: no node pair has ≥ {MIN_LINK_ROWS} readings; cannot fit UWB noise"
        )
    return links


def within_link_residuals(rec: UwbRecording) -> NDArray[np.float64]:
    """All within-link residuals ``e − median_link(e)`` of the fitted links, pooled."""
    parts = []
    for link in fitted_links(rec):
        e = rec.error[rec.link_mask(link)]
        parts.append(e - np.median(e))
    return np.concatenate(parts)


def fit_uwb_noise(rec: UwbRecording) -> UwbNoiseFit:
    """Fit :class:`UwbNoiseModel` to a recording (see module docstring for the estimators)."""
    links = fitted_links(rec)
    medians: dict[str, float] = {}
    rho: list[float] = []
    taus: list[float] = []
    periods: list[float] = []
    for link in links:
        mask = rec.link_mask(link)
        e = rec.error[mask]
        med = float(np.median(e))
        medians[f"{link[0]}-{link[1]}"] = med
        r = e - med
        t = rec.t[mask]
        if r.size > 2 and float(np.std(r)) > 0.0:
            rho.append(float(np.corrcoef(r[:-1], r[1:])[0, 1]))
        tau_link = _decorrelation_time(t, r)
        if tau_link is not None:
            taus.append(tau_link)
        if t[-1] > t[0]:
            periods.append(float((t[-1] - t[0]) / (t.size - 1)))
    pooled = within_link_residuals(rec)
    spread = _robust_sigma(pooled)
    threshold = OUTLIER_K * spread
    tail = pooled[np.abs(pooled) > threshold]
    outlier_rate = float(tail.size / pooled.size)
    excess = float(np.mean(np.abs(tail) - threshold)) if tail.size else 0.0
    positive = float(np.mean(tail > 0.0)) if tail.size else 1.0
    link_meds = np.array(list(medians.values()))
    link_bias_std = float(np.std(link_meds, ddof=1)) if link_meds.size > 1 else 0.0
    rho1 = float(np.median(rho)) if rho else 0.0
    period = float(np.median(periods)) if periods else 0.0
    tau = float(np.median(taus)) if taus else 0.0
    model = UwbNoiseModel(
        bias=float(np.median(rec.error)),
        spread=spread,
        outlier_rate=outlier_rate,
        outlier_excess_mean=excess,
        outlier_positive_fraction=positive,
        link_bias_std=link_bias_std,
        correlation_time=tau,
    )
    return UwbNoiseFit(
        model=model,
        n_rows=rec.n_rows,
        n_links=len(links),
        sample_period=period,
        lag1_correlation=rho1,
        link_biases=medians,
        rows_skipped=rec.skipped.count,
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
    offset per link, drawn once.
    """
    if n_steps < 0 or n_links < 0 or not dt > 0.0:
        raise ConfigError(
            f"sample_range_errors: bad sizes n_steps={n_steps}, n_links={n_links}, dt={dt}"
        )
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
