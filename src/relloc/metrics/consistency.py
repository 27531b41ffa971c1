"""Filter consistency: NEES, NIS, χ² bounds and averaged bands, ANEES (Bar-Shalom et al. 2001 §5.4).

* NEES ``ε = eᵀ P⁻¹ e`` (seed 000 Eq. 33) is χ²(n) for a consistent filter with ``n`` states;
  NIS ``ν S⁻¹ ν`` (Eq. 35) is χ²(m) with ``m`` measurements.
* Single-run test (Eq. 34): the fraction of values beyond the one-sided ``χ²_n(0.95)`` bound
  should be about 5 % (seed 000 Table 4 reports this percentage).
* Averaged test: the mean of ``N`` independent χ²(n) values satisfies
  ``N ε̄ ~ χ²(N n)``, so its two-sided ``p`` band is ``χ²_{Nn}((1∓p)/2) / N``.
  ANEES ``= ε̄ / n`` (ideal 1) has the same band divided by ``n``. The ``N`` values must be
  independent: NEES of independent runs at one instant (:func:`run_average_band`), never the
  time-correlated samples of one run pooled as if independent.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from relloc.errors import ConfigError, ModelError

Array = NDArray[np.float64]


def _check_probability(p: float) -> float:
    p = float(p)
    if not 0.0 < p < 1.0:
        raise ConfigError(f"probability must be in (0, 1), got {p}")
    return p


def normalised_squared(vector: ArrayLike, cov: ArrayLike) -> Array:
    """``vᵀ C⁻¹ v`` batched over leading dimensions (NEES with ``P``, NIS with ``S``)."""
    v = np.asarray(vector, dtype=float)
    C = np.asarray(cov, dtype=float)
    try:
        L = np.linalg.cholesky(0.5 * (C + np.swapaxes(C, -1, -2)))
    except np.linalg.LinAlgError as exc:
        raise ModelError("NEES/NIS: covariance is not positive definite") from exc
    w = np.linalg.solve(L, v[..., None])[..., 0]
    return np.einsum("...i,...i->...", w, w)


def nees(errors: ArrayLike, cov: ArrayLike) -> Array:
    """NEES ``eᵀ P⁻¹ e`` (seed 000 Eq. 33); ``errors (..., n)`` already angle-wrapped."""
    return normalised_squared(errors, cov)


def nis(residual: ArrayLike, innovation_cov: ArrayLike) -> Array:
    """NIS ``νᵀ S⁻¹ ν`` (seed 000 Eq. 35)."""
    return normalised_squared(residual, innovation_cov)


def chi2_upper(dof: int, p: float = 0.95) -> float:
    """One-sided bound ``χ²_dof(p)``, e.g. ``chi2_upper(4) = 9.4877`` (seed 000 Eq. 34)."""
    from scipy.stats import chi2  # imported here: scipy.stats costs seconds at process start

    return float(chi2.ppf(_check_probability(p), dof))


def mean_chi2_band(dof: int, n_samples: int, p: float = 0.95) -> tuple[float, float]:
    """Two-sided ``p`` band of the mean of ``n_samples`` independent χ²(dof) values."""
    p = _check_probability(p)
    if n_samples < 1 or dof < 1:
        raise ConfigError(f"mean_chi2_band: dof and n_samples must be ≥ 1 ({dof}, {n_samples})")
    k = dof * n_samples
    from scipy.stats import chi2

    lo, hi = chi2.ppf([(1.0 - p) / 2.0, (1.0 + p) / 2.0], k)
    return float(lo / n_samples), float(hi / n_samples)


def anees(nees_values: ArrayLike, dof: int) -> float:
    """ANEES ``= mean(ε) / n`` over all finite values (ideal 1)."""
    values = np.asarray(nees_values, dtype=float)
    values = values[np.isfinite(values)]
    if values.size == 0:
        return float("nan")
    return float(values.mean() / dof)


def anees_band(dof: int, n_samples: int, p: float = 0.95) -> tuple[float, float]:
    """Two-sided ``p`` band of :func:`anees` over ``n_samples`` independent NEES values."""
    lo, hi = mean_chi2_band(dof, n_samples, p)
    return lo / dof, hi / dof


#: Verdict rule of :func:`run_average_band`: consistent when at least this share (%) of the
#: run-averaged values lies inside the band (95 % expected; instants are correlated in time, so
#: the share fluctuates more than for independent draws).
CONSISTENT_IN_BAND_PERCENT = 80.0


def run_average_band(nees_runs: ArrayLike, dof: int, p: float = 0.95) -> dict[str, object]:
    """The averaged test done right: ``nees_runs (R, ...)`` holds NEES values of ``R``
    independent runs (axis 0) at the same instants (and subjects) on the other axes. At every
    instant the mean over the runs is compared with the two-sided ``p`` band of the mean of
    ``R`` independent χ²(dof) values (:func:`mean_chi2_band`); nothing correlated is pooled.

    Returns the shares (%) of instants inside, below (conservative) and above (over-confident)
    the band, the band, ``runs``, ``instants``, and a ``verdict``: ``"consistent"`` when the
    share inside is at least :data:`CONSISTENT_IN_BAND_PERCENT`, else ``"conservative"`` or
    ``"over-confident"`` after the side with the larger share; ``None`` (with ``reason``) for
    fewer than two runs.
    """
    v = np.asarray(nees_runs, dtype=float)
    runs = int(v.shape[0]) if v.ndim else 0
    if runs < 2:
        return {"verdict": None, "runs": runs, "reason": "needs at least two independent runs"}
    lo, hi = mean_chi2_band(dof, runs, p)
    avg = v.mean(axis=0)
    avg = avg[np.isfinite(avg)]
    if avg.size == 0:
        return {
            "in_band_percent": float("nan"),
            "band": [lo, hi],
            "runs": runs,
            "instants": 0,
            "verdict": None,
            "reason": "no instant with a value in every run",
        }
    inside = float(100.0 * np.mean((avg >= lo) & (avg <= hi)))
    below = float(100.0 * np.mean(avg < lo))
    above = float(100.0 * np.mean(avg > hi))
    if inside >= CONSISTENT_IN_BAND_PERCENT:
        verdict = "consistent"
    else:
        verdict = "conservative" if below > above else "over-confident"
    return {
        "in_band_percent": inside,
        "below_band_percent": below,
        "above_band_percent": above,
        "band": [lo, hi],
        "runs": runs,
        "instants": int(avg.size),
        "verdict": verdict,
    }


def percent_beyond(values: ArrayLike, bound: float) -> float:
    """Percentage of the finite ``values`` strictly above ``bound`` (seed 000 Table 4)."""
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    if v.size == 0:
        return float("nan")
    return float(100.0 * np.count_nonzero(v > bound) / v.size)
