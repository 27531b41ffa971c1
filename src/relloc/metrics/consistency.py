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
* One run, no independent copies (a real recording): the share beyond the bound is still a
  fair point estimate, but its samples are correlated in time, so the binomial spread
  ``√(p(1−p)/N)`` understates its uncertainty. :func:`percent_beyond_interval` gives its
  interval of confidence ``c`` by batch means over time: the span is cut into ``B`` contiguous
  blocks of equal duration, each block (every subject's samples in it) one cluster, and the
  ratio estimator ``p̂ = Σ_b k_b / Σ_b n_b`` (``k_b`` of the block's ``n_b`` samples beyond the
  bound) gets the cluster variance

      V̂ = B/(B−1) · Σ_b (k_b − p̂ n_b)² / (Σ_b n_b)²,

  valid when a block is long against the correlation time; ``p̂ ± t_{B−1}((1+c)/2) √V̂``
  (clipped to [0, 1]), and the effective sample size ``N_eff = p̂(1−p̂)/V̂`` (Bar-Shalom et al.
  2001 §5.4 for the test; batch means: Law & Kelton, *Simulation Modeling and Analysis* §9.5).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

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


#: Blocks of :func:`percent_beyond_interval` by default: ten, so that a 450 s window gives
#: 45 s blocks (longer than the seconds over which odometry errors persist on MRCLAM).
INTERVAL_BATCHES = 10


@dataclass(frozen=True)
class BeyondShare:
    """A share (%) of values beyond a bound with its interval (of confidence ``confidence``) by
    batch means (:func:`percent_beyond_interval`): ``samples`` N, ``effective_samples``
    ``N_eff`` (at most N), ``batches`` (non-empty blocks), ``batch_s`` (block duration),
    ``expected_percent`` (what a consistent filter leaves beyond the bound: 5 for a
    ``χ²(0.95)`` bound). ``interval`` and ``effective_samples`` are ``None`` with fewer than two
    non-empty blocks."""

    percent: float
    interval: tuple[float, float] | None
    samples: int
    effective_samples: float | None
    batches: int
    batch_s: float
    expected_percent: float
    confidence: float

    @property
    def verdict(self) -> str | None:
        """``"consistent"`` when the interval holds ``expected_percent``, ``"over-confident"``
        when it lies above, ``"conservative"`` below; ``None`` without an interval."""
        if self.interval is None:
            return None
        if self.interval[0] > self.expected_percent:
            return "over-confident"
        return "conservative" if self.interval[1] < self.expected_percent else "consistent"

    def to_dict(self) -> dict[str, Any]:
        return {
            "percent": self.percent,
            "interval": list(self.interval) if self.interval is not None else None,
            "samples": self.samples,
            "effective_samples": self.effective_samples,
            "batches": self.batches,
            "batch_s": self.batch_s,
            "verdict": self.verdict,
        }


def percent_beyond_interval(
    values: ArrayLike,
    times: ArrayLike,
    bound: float | ArrayLike,
    *,
    expected_percent: float = 5.0,
    batches: int = INTERVAL_BATCHES,
    confidence: float = 0.95,
) -> BeyondShare:
    """Percentage of finite ``values`` above ``bound`` with its interval of confidence
    ``confidence`` by batch means over ``times`` (module docstring): the samples of any number
    of subjects of one run, each with its time; ``bound`` a scalar or one per value;
    ``expected_percent`` what a consistent filter leaves beyond it (5 for ``χ²(0.95)``), for
    the verdict. When every block sits at ``p̂`` (e.g. none beyond anywhere) there is no spread
    to measure: ``N_eff`` is then the number of blocks and the interval Clopper–Pearson's for
    ``B p̂`` in ``B``.
    """
    c = _check_probability(confidence)
    expected = 100.0 * _check_probability(expected_percent / 100.0)
    if isinstance(batches, bool) or not isinstance(batches, int | np.integer) or batches < 2:
        raise ConfigError(f"percent_beyond_interval: batches must be an integer ≥ 2, got {batches}")
    v = np.asarray(values, dtype=float).reshape(-1)
    t = np.asarray(times, dtype=float).reshape(-1)
    if t.shape != v.shape:
        raise ConfigError(
            f"percent_beyond_interval: {t.size} times for {v.size} values; one time per value"
        )
    b = np.asarray(bound, dtype=float)
    if b.size != 1 and b.shape != v.shape:
        raise ConfigError(
            f"percent_beyond_interval: {b.size} bounds for {v.size} values; one, or one per value"
        )
    b = np.broadcast_to(b.reshape(-1) if b.size == 1 else b, v.shape)
    ok = np.isfinite(v) & np.isfinite(t)
    v, t, b = v[ok], t[ok], b[ok]
    if v.size == 0:
        return BeyondShare(float("nan"), None, 0, None, 0, float("nan"), expected, c)
    beyond = (v > b).astype(float)
    percent = float(100.0 * np.count_nonzero(beyond) / v.size)  # as percent_beyond rounds it
    p_hat = percent / 100.0
    width = float(t.max() - t.min()) / batches
    if width > 0:
        block = np.minimum((t - t.min()) / width, batches - 1).astype(np.int64)
    else:
        block = np.zeros(v.size, dtype=np.int64)
    n_b = np.bincount(block, minlength=batches).astype(float)
    k_b = np.bincount(block, weights=beyond, minlength=batches)
    used = n_b > 0
    n_b, k_b = n_b[used], k_b[used]
    m = int(n_b.size)
    if m < 2:
        return BeyondShare(percent, None, int(v.size), None, m, width, expected, c)
    from scipy.stats import beta
    from scipy.stats import t as student_t

    var = m / (m - 1) * float(np.sum((k_b - p_hat * n_b) ** 2)) / float(np.sum(n_b)) ** 2
    if var > 0.0:
        half = float(student_t.ppf((1.0 + c) / 2.0, m - 1) * np.sqrt(var))
        lo, hi = max(0.0, p_hat - half), min(1.0, p_hat + half)
        n_eff = min(float(v.size), p_hat * (1.0 - p_hat) / var)
    else:
        k = p_hat * m
        lo = float(beta.ppf((1.0 - c) / 2.0, k, m - k + 1)) if k > 0 else 0.0
        hi = float(beta.ppf((1.0 + c) / 2.0, k + 1, m - k)) if k < m else 1.0
        n_eff = float(m)
    interval = (100.0 * lo, 100.0 * hi)
    return BeyondShare(percent, interval, int(v.size), n_eff, m, width, expected, c)
