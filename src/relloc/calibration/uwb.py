"""Robust fit of the UWB range-error model (:class:`~relloc.models.uwb_noise.UwbNoiseModel`)
from ranges recorded beside motion capture.

The error of one reading is ``e = uwb_range − mocap_range``. On the rows of the window, per
radio pair ("link", only links with at least ``MIN_LINK_ROWS`` readings), we fit robustly —
medians and MADs, so that the outliers being measured do not distort the core:

- ``bias``: the median of all errors (m), the offset a calibration would remove;
- ``link_bias_std``: the spread (sample std) of the per-link medians around ``bias`` — what is
  left after one team-wide calibration when every radio pair is not calibrated on its own;
- ``spread``: ``1.4826·MAD`` of the within-link residuals ``r = e − median_link(e)``, pooled,
  the σ of the Gaussian core;
- ``outlier_rate``: the fraction of readings with ``|r| > k·spread`` (``k = OUTLIER_K``), with the
  tail modelled peaks-over-threshold: a sign (``outlier_positive_fraction``) and an exponential
  excess beyond ``k·spread`` of mean ``outlier_excess_mean`` (its maximum-likelihood estimate,
  the mean excess);
- ``correlation_time``: the first-order Gauss–Markov time constant τ (autocorrelation
  ``exp(−lag/τ)``), taken per link as the time lag at which the autocorrelation of the
  within-link residuals first drops below 1/e (lags in seconds, since the recording is sampled
  irregularly; linear interpolation between lags), median over links — consecutive UWB errors
  are far from white. ``lag1_correlation`` (median over links of the correlation of consecutive
  residuals) and ``sample_period`` (median over links of the mean sampling interval) are
  reported beside it; a link whose consecutive residuals do not both vary (the correlation is
  undefined) gives no ``lag1_correlation``.

A window whose within-link residuals have no spread (``spread`` 0: readings equal to their
link's median, such as a link reading one constant range) is refused with a
:class:`~relloc.errors.DataError` naming the window: a core σ of 0 would take every range as
exact.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from relloc.calibration.window import CalibrationWindow
from relloc.datasets.uwb import UwbRecording
from relloc.models.uwb_noise import OUTLIER_K, UwbNoiseModel

#: Gaussian-consistent MAD scale.
MAD_SCALE = 1.4826
#: Links with fewer readings in the window are ignored (their median is not trustworthy).
MIN_LINK_ROWS = 20
#: Longest time lag (s) searched for the 1/e decorrelation of the errors.
MAX_CORRELATION_LAG = 20.0


@dataclass(frozen=True, kw_only=True)
class UwbNoiseFit:
    """The fitted model plus what it was fitted on (for reports)."""

    calibration_window: CalibrationWindow
    model: UwbNoiseModel
    n_rows: int
    n_links: int
    sample_period: float
    lag1_correlation: float
    link_biases: dict[str, float]
    rows_skipped: int

    def to_dict(self) -> dict[str, object]:
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
            "calibration_window": self.calibration_window.to_dict(),
        }


def _robust_sigma(x: NDArray[np.float64]) -> float:
    return float(MAD_SCALE * np.median(np.abs(x - np.median(x))))


def _correlation(a: NDArray[np.float64], b: NDArray[np.float64]) -> float | None:
    """Correlation of ``a`` and ``b``; None where either does not vary (it is undefined)."""
    if float(np.std(a)) == 0.0 or float(np.std(b)) == 0.0:
        return None
    return float(np.corrcoef(a, b)[0, 1])


def decorrelation_time(t: NDArray[np.float64], r: NDArray[np.float64]) -> float | None:
    """Time lag (s) where the autocorrelation of ``r`` (sampled at ``t``) first falls below
    1/e, interpolated linearly between sample lags; None if it does not within
    ``MAX_CORRELATION_LAG``, ``r`` is too short or constant, or the correlation at a lag is
    undefined (one of the two overlapping stretches constant, and so every longer lag's)."""
    if r.size < 4 or float(np.std(r)) == 0.0:
        return None
    prev_lag, prev_rho = 0.0, 1.0
    for k in range(1, r.size - 2):
        lag = float(np.mean(t[k:] - t[:-k]))
        if lag > MAX_CORRELATION_LAG:
            return None
        rho = _correlation(r[:-k], r[k:])
        if rho is None:
            return None
        if rho < math.exp(-1.0):
            frac = (prev_rho - math.exp(-1.0)) / (prev_rho - rho)
            return prev_lag + frac * (lag - prev_lag)
        prev_lag, prev_rho = lag, rho
    return None


def link_masks(
    rec: UwbRecording, window: CalibrationWindow
) -> dict[tuple[int, int], NDArray[np.bool_]]:
    """Rows of each link in ``window``, for the links with enough of them to enter the fit
    (DataError naming the window if none has)."""
    inside = window.contains(rec.t)
    masks = {link: rec.link_mask(link) & inside for link in rec.links()}
    fitted = {link: m for link, m in masks.items() if int(m.sum()) >= MIN_LINK_ROWS}
    if not fitted:
        raise window.too_little(f"no node pair has ≥ {MIN_LINK_ROWS} readings to fit UWB noise")
    return fitted


def within_link_residuals(rec: UwbRecording, window: CalibrationWindow) -> NDArray[np.float64]:
    """All within-link residuals ``e − median_link(e)`` of the fitted links in ``window``."""
    parts = []
    for mask in link_masks(rec, window).values():
        e = rec.error[mask]
        parts.append(e - np.median(e))
    return np.concatenate(parts)


def fit_uwb_noise(rec: UwbRecording, window: CalibrationWindow) -> UwbNoiseFit:
    """Fit :class:`UwbNoiseModel` to the rows of ``rec`` in ``window`` (module docstring);
    DataError naming the window when no link has ``MIN_LINK_ROWS`` readings in it or the
    residuals have no spread."""
    masks = link_masks(rec, window)
    medians: dict[str, float] = {}
    rho: list[float] = []
    taus: list[float] = []
    periods: list[float] = []
    for link, mask in masks.items():
        e = rec.error[mask]
        med = float(np.median(e))
        medians[f"{link[0]}-{link[1]}"] = med
        r = e - med
        t = rec.t[mask]
        lag1 = _correlation(r[:-1], r[1:]) if r.size > 2 else None
        if lag1 is not None:
            rho.append(lag1)
        tau_link = decorrelation_time(t, r)
        if tau_link is not None:
            taus.append(tau_link)
        if t[-1] > t[0]:
            periods.append(float((t[-1] - t[0]) / (t.size - 1)))
    pooled = within_link_residuals(rec, window)
    spread = _robust_sigma(pooled)
    if not spread > 0.0:
        raise window.too_little(
            f"the {pooled.size} within-link residuals have no spread (1.4826·MAD {spread:g} m): "
            "a UWB noise σ of 0 would take every range as exact"
        )
    threshold = OUTLIER_K * spread
    tail = pooled[np.abs(pooled) > threshold]
    outlier_rate = float(tail.size / pooled.size)
    excess = float(np.mean(np.abs(tail) - threshold)) if tail.size else 0.0
    positive = float(np.mean(tail > 0.0)) if tail.size else 1.0
    link_meds = np.array(list(medians.values()))
    link_bias_std = float(np.std(link_meds, ddof=1)) if link_meds.size > 1 else 0.0
    inside = window.contains(rec.t)
    model = UwbNoiseModel(
        bias=float(np.median(rec.error[inside])),
        spread=spread,
        outlier_rate=outlier_rate,
        outlier_excess_mean=excess,
        outlier_positive_fraction=positive,
        link_bias_std=link_bias_std,
        correlation_time=float(np.median(taus)) if taus else 0.0,
    )
    return UwbNoiseFit(
        calibration_window=window,
        model=model,
        n_rows=int(inside.sum()),
        n_links=len(masks),
        sample_period=float(np.median(periods)) if periods else 0.0,
        lag1_correlation=float(np.median(rho)) if rho else 0.0,
        link_biases=medians,
        rows_skipped=rec.skipped.n_skipped,
    )
