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
* The share beyond the bound with its uncertainty: the share is a fair point estimate, but its
  samples are correlated in time (and, on one recording, across subjects), so the binomial
  spread ``√(p(1−p)/N)`` understates its uncertainty. :func:`percent_beyond_interval` gives its
  interval of confidence ``c`` by cluster (batch) means: the samples fall into ``G`` clusters,
  and the ratio estimator ``p̂ = Σ_g k_g / Σ_g n_g`` (``k_g`` of the cluster's ``n_g`` samples
  beyond the bound) gets the cluster variance

      V̂ = G/(G−1) · Σ_g (k_g − p̂ n_g)² / (Σ_g n_g)²,

  the effective sample size ``N_eff = p̂(1−p̂)/V̂`` (at most ``N``) and the interval of Korn &
  Graubard (1998): Clopper–Pearson's for ``p̂ N_df`` successes in

      N_df = N_eff · (t_{N−1}(q) / t_{G−1}(q))²,     q = (1+c)/2,

  which, unlike ``p̂ ± t_{G−1}(q) √V̂``, stays inside [0, 1] and keeps its coverage for shares
  near 0 (5 %) and clusters of unequal share (Bar-Shalom et al. 2001 §5.4 for the test; batch
  means: Law & Kelton, *Simulation Modeling and Analysis* §9.5). The clusters must be about
  independent:

  - one run: ``B`` contiguous blocks of equal duration, each block (every subject's samples in
    it) one cluster — valid when a block is long against the correlation time. That time is
    estimated and reported beside (``correlation_time_s``): the ranks of ``value − bound``
    (ties sharing their mean rank), averaged at each instant over the subjects, form a series
    whose integrated autocorrelation time ``τ̂`` (in instants, :func:`integrated_time`, times
    the instants' mean spacing) it is; ranks, not exceedances, because a few dozen exceedances
    say little about how long an error lasts. ``relloc bench intervals``
    (:mod:`relloc.bench.intervals`: a 3-DOF NEES of AR(1) errors over 4500 samples, ten
    450-sample blocks, 300 draws, seed 20261206) measures the batch means' 95 % interval's coverage:
    0.940 / 0.950 / 0.913 / 0.847 / 0.837 with blocks of 47 / 14 / 4.5 / 2.3 / 1.4
    correlation times of the NEES, against 0.55 / 0.39 / 0.20 / 0.18 / 0.09 for the binomial
    interval; ``τ̂`` falls short of the true time by 8–23 %. Blocks shorter than about ten
    correlation times make the interval too narrow. Choosing fewer, longer blocks from ``τ̂``
    (at least ten ``τ̂`` each) raised the coverage at 2.3 correlation times to 0.930, but on a
    real run, whose NEES ranks stay correlated for tens of seconds (mrclam-cl's held-out
    450 s: about 30 s), it leaves two blocks and an interval of nearly 0–100 %, which no filter
    could fail. So the blocks stay fixed, and where they last less than ten ``τ̂``
    (``blocks_short``) the interval is widened to hold also the *correlation-time interval*:
    Clopper–Pearson's for ``p̂ N_τ`` successes in

      N_τ = p̂(1−p̂) · n_t / (s_y² · τ̂)     (at most N; ``n_t/τ̂`` when ``s_y² = 0``),

    the effective sample size of the mean of ``y_t``, the share beyond the bound at each of the
    ``n_t`` instants (over the subjects and runs there), whose variance over the instants is
    ``s_y²`` — ``N_τ = n_t/τ̂`` for one subject, up to ``S`` times that for ``S`` independent
    subjects. The same benchmark measures the widened interval's coverage at 0.993 / 1.000 /
    1.000 with blocks of 4.5 / 2.3 / 1.4 correlation times (mean width 14.5 / 19.5 / 26.8 %
    against the batch means' 11.4 / 13.8 / 17.5 %), and, for five subjects with blocks of
    1.4 correlation times sharing 0 / 50 / 90 / 97 / 99 / 100 % of their error variance, at
    0.990 / 0.963 / 0.930 / 0.960 / 0.967 / 1.000 where batch means alone hold 0.923 / 0.900 /
    0.810 / 0.783 / 0.830 / 0.830: lowest where most but not all of the error is common
    (0.960 at 90 % on another seed root, 777001). It is conservative
    for one subject: the price of an interval that keeps its word on a correlated run. Taking
    ``τ̂`` from the series ``y_t`` itself rather than from the ranks gave intervals 30–50 %
    narrower that held the truth in only 0.77–0.93 of draws (one subject, and five sharing
    90 %, at the same three correlation times; 150 draws, seed 4242), so the ranks stay;
  - independent runs (Monte Carlo): each run one cluster, ``G = R``. Blocks of time pooled over
    the runs would miss what persists through a run (an error drawn once along a direction no
    measurement sees stays in every block of its run), and the interval would be too narrow;
  - runs that replay one recording (fresh measurement noise on shared odometry): correlated
    both through a run and across the runs at one time, so the variance is two-way clustered
    (Cameron, Gelbach & Miller 2011), ``V̂ = V̂_runs + V̂_blocks − V̂_cells`` with the cells
    ``run × block`` each by the formula above (``max(V̂_runs, V̂_blocks)`` should the difference
    not be positive), and ``G = min(R, B)``; widened as for one run when the blocks are short.
* The verdict on a share from its interval (:func:`share_verdict`): *over-confident* when the
  interval lies wholly above the expected share, *conservative* wholly below, *consistent*
  when it holds it and reaches no higher than :data:`EQUIVALENCE_FACTOR` (2) times it (10 %
  for the 5 % beyond ``χ²(0.95)``, the share seed 000 §7 calls acceptable), and
  *inconclusive* when it holds it but reaches higher: a wide interval fails to reject
  consistency without showing it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from relloc.core.checks import count, floats, number, probability
from relloc.core.kalman import MAX_CHI2_DOF, chi2_threshold
from relloc.core.linalg import cholesky
from relloc.errors import ConfigError, DataError, ModelError

Array = NDArray[np.float64]


def _check_bound(bound: float | ArrayLike, what: str, shape: tuple[int, ...]) -> Array:
    """``bound`` broadcast to the values' ``shape`` if every entry is a finite number and it is
    one bound or broadcasts to ``shape`` unchanged, else ``ConfigError`` (a NaN bound would
    leave nothing beyond it)."""
    b = floats(bound, f"{what}: bound", ConfigError)
    if not np.isfinite(b).all():
        raise ConfigError(f"{what}: {np.count_nonzero(~np.isfinite(b))} bound(s) not finite")
    if b.size == 1:
        return np.broadcast_to(b.reshape(()), shape)
    try:
        if np.broadcast_shapes(b.shape, shape) == shape:
            return np.broadcast_to(b, shape)
    except ValueError:
        pass
    raise ConfigError(f"{what}: bound {b.shape} for values {shape}; one, or one per value")


def normalised_squared(vector: ArrayLike, cov: ArrayLike) -> Array:
    """``vᵀ C⁻¹ v = ‖L⁻¹ v‖²`` (``C = L Lᵀ``) batched over leading dimensions (NEES with ``P``,
    NIS with ``S``): ``vector (..., n)``, ``cov (..., n, n)`` whose leading dimensions broadcast
    (``ConfigError`` otherwise), ``n ≥ 1``. ``C`` must be finite and positive definite
    (:class:`ModelError`); a NaN in ``v`` (an error without truth: a missing record) gives NaN,
    which :func:`anees`, :func:`percent_beyond` and :func:`percent_beyond_interval` skip; an
    infinite entry of ``v`` is a :class:`DataError`."""
    v = floats(vector, "NEES/NIS: vector")
    C = floats(cov, "NEES/NIS: covariance")
    message = (
        f"NEES/NIS: vector {v.shape} and covariance {C.shape} must be (..., n) and (..., n, n) "
        "with n ≥ 1 and leading dimensions that broadcast"
    )
    if v.ndim < 1 or v.shape[-1] == 0 or C.shape[-2:] != v.shape[-1:] * 2:
        raise ConfigError(message)
    if np.isinf(v).any():
        raise DataError(f"NEES/NIS: {np.count_nonzero(np.isinf(v))} infinite vector entries")
    try:
        np.broadcast_shapes(v.shape[:-1], C.shape[:-2])
    except ValueError as exc:
        raise ConfigError(message) from exc
    w = np.linalg.solve(cholesky(C, where="NEES/NIS"), v[..., None])[..., 0]
    return np.einsum("...i,...i->...", w, w)


def nees(errors: ArrayLike, cov: ArrayLike) -> Array:
    """NEES ``eᵀ P⁻¹ e`` (seed 000 Eq. 33); ``errors (..., n)`` already angle-wrapped
    (:func:`normalised_squared`)."""
    return normalised_squared(errors, cov)


def projected_nees(error: ArrayLike, cov: ArrayLike, directions: ArrayLike) -> float:
    """NEES of an error along the ``d`` columns of ``directions`` ``N (n, d)`` only:

        ε_N = yᵀ M⁻¹ y,   y = Nᵀ P⁻¹ e,   M = Nᵀ P⁻¹ N,

    the NEES of the generalised-least-squares estimate of ``e``'s components along ``N``
    (``M⁻¹ y``, of covariance ``M⁻¹``). It is χ²(d) when ``e ~ N(0, P)``: ``y`` then has
    covariance ``M``. With ``N`` a team's unobservable directions it tests the filter along
    exactly those, where a linearised filter gains spurious information.

    Computed whitened: with ``P = L Lᵀ``, ``A = L⁻¹ N`` and ``b = L⁻¹ e``, ``y = Aᵀ b`` and
    ``M = Aᵀ A``, so ``ε_N = bᵀ A (Aᵀ A)⁻¹ Aᵀ b = ‖Uᵀ b‖²``, the squared length of ``b``'s
    projection on the columns of ``A`` (``U`` their orthonormal basis from the SVD of ``A``):
    never negative. ``P`` must be finite and positive definite (:class:`ModelError`) and the
    directions linearly independent (``M`` invertible; :class:`ConfigError`); a NaN in ``e``
    (a missing record) gives NaN, an infinite entry is a :class:`DataError`."""
    e = floats(error, "projected_nees: error").reshape(-1)
    P = floats(cov, "projected_nees: covariance")
    N = floats(directions, "projected_nees: directions")
    if (
        e.size == 0
        or P.shape != (e.size, e.size)
        or N.ndim != 2
        or N.shape[0] != e.size
        or N.shape[1] < 1
    ):
        raise ConfigError(
            f"projected_nees: error {e.shape}, covariance {P.shape} and directions {N.shape} "
            "must be (n,), (n, n) and (n, d ≥ 1) with n ≥ 1"
        )
    if not np.isfinite(N).all():
        raise ConfigError("projected_nees: the directions must be finite")
    try:
        L = cholesky(P, where="projected_nees")
    except ModelError as exc:
        raise ModelError("projected_nees: singular, indefinite or non-finite covariance") from exc
    U, singular, _ = np.linalg.svd(np.linalg.solve(L, N), full_matrices=False)
    if singular[-1] <= singular[0] * max(N.shape) * np.finfo(float).eps:  # matrix_rank's test
        raise ConfigError(f"projected_nees: the directions {N.shape} must be linearly independent")
    value = float(np.sum((U.T @ np.linalg.solve(L, e)) ** 2))
    if math.isnan(value) and np.isinf(e).any():
        raise DataError(f"projected_nees: {np.count_nonzero(np.isinf(e))} infinite error entries")
    return value


def nis(residual: ArrayLike, innovation_cov: ArrayLike) -> Array:
    """NIS ``νᵀ S⁻¹ ν`` (seed 000 Eq. 35)."""
    return normalised_squared(residual, innovation_cov)


def chi2_upper(dof: int, p: float = 0.95) -> float:
    """One-sided bound ``χ²_dof(p)``, e.g. ``chi2_upper(4) = 9.4877`` (seed 000 Eq. 34): the
    gates' quantile (:func:`relloc.core.kalman.chi2_threshold`), one computation for both.
    ``dof`` is an integer ≥ 1 (``ConfigError`` otherwise, never truncated)."""
    return chi2_threshold(
        count(dof, "chi2_upper: dof", high=MAX_CHI2_DOF),
        probability(p, "chi2_upper: p, a probability"),
    )


def mean_chi2_band(dof: int, n_samples: int, p: float = 0.95) -> tuple[float, float]:
    """Two-sided ``p`` band of the mean of ``n_samples`` independent χ²(dof) values (both
    integers ≥ 1 whose product is at most :data:`~relloc.core.kalman.MAX_CHI2_DOF`,
    ``ConfigError`` otherwise)."""
    p = probability(p, "mean_chi2_band: p, a probability")
    k = count(dof, "mean_chi2_band: dof") * count(n_samples, "mean_chi2_band: n_samples")
    count(k, "mean_chi2_band: dof · n_samples", high=MAX_CHI2_DOF)
    from scipy.stats import chi2

    lo, hi = chi2.ppf([(1.0 - p) / 2.0, (1.0 + p) / 2.0], k)
    return float(lo / n_samples), float(hi / n_samples)


def anees(nees_values: ArrayLike, dof: int) -> float:
    """ANEES ``= mean(ε) / n`` over all finite values (ideal 1): a NaN NEES is a missing record
    (:func:`normalised_squared`) and is skipped; NaN when no value is finite. ``dof`` is an
    integer ≥ 1 (``ConfigError``); a negative NEES is impossible (``DataError``)."""
    dof = count(dof, "anees: dof")
    values = floats(nees_values, "anees: nees_values")
    if np.any(values < 0.0):
        raise DataError(f"anees: {np.count_nonzero(values < 0.0)} negative NEES values")
    values = values[np.isfinite(values)]
    if values.size == 0:
        return float("nan")
    return float(values.mean() / dof)


def anees_band(dof: int, n_samples: int, p: float = 0.95) -> tuple[float, float]:
    """Two-sided ``p`` band of :func:`anees` over ``n_samples`` independent NEES values."""
    lo, hi = mean_chi2_band(dof, n_samples, p)
    return lo / dof, hi / dof


def run_average_band(nees_runs: ArrayLike, dof: int, p: float = 0.95) -> dict[str, object]:
    """The averaged test done right: ``nees_runs (R, T, ...)`` holds NEES values of ``R``
    independent runs (axis 0) at the same ``T`` instants (axis 1, in time order) and subjects
    (further axes). At every instant the mean over the runs is compared with the two-sided
    ``p`` band of the mean of ``R`` independent χ²(dof) values (:func:`mean_chi2_band`);
    nothing correlated is pooled.

    The run-averaged values of neighbouring instants are correlated, so the shares of instants
    below and above the band fluctuate more than binomial counts: each gets its 95 % interval
    by batch means over the instants (:func:`percent_beyond_interval`, ten blocks of
    consecutive instants, every subject of an instant in its block), against the
    ``(1 − p)/2`` a consistent filter leaves on each side.

    Returns the shares (%) of instants inside, below (conservative) and above (over-confident)
    the band, ``below_band_interval`` and ``above_band_interval`` (the shares' intervals and
    verdicts), the band, ``runs``, ``instants``, ``blocks_short`` (either interval's blocks
    last less than ten correlation times of the run averages, :attr:`BeyondShare.blocks_short`,
    so its verdict leans on a likely too narrow interval), and a ``verdict``:
    ``"over-confident"`` when the share above lies significantly above ``(1 − p)/2`` (its
    interval wholly above), ``"conservative"`` when the share below does, the side with the
    larger share when both do, else ``"consistent"``: neither side is significantly off (a
    significance test; each side's own interval keeps :func:`share_verdict`'s four outcomes).
    The equivalence margin of :data:`EQUIVALENCE_FACTOR` is not applied to this verdict: each
    side's interval comes from ten blocks of times, and with the margin the verdict read
    ``"inconclusive"`` for most consistent filters (statistical root 90418: 185 and 161 of 200
    draws, time-correlated and independent; all four pairs of ``relloc run``'s default job,
    whose run-averaged NEES lies in its band at 90–98 % of the times); ``None`` (with
    ``reason``) for fewer
    than two runs, and ``None`` for a single instant. ``dof`` and ``p`` are checked as in
    :func:`mean_chi2_band` whatever the runs; a negative NEES is a :class:`DataError`.
    """
    count(dof, "run_average_band: dof")
    probability(p, "run_average_band: p, a probability")
    v = floats(nees_runs, "run_average_band: nees_runs")
    if np.any(v < 0.0):
        raise DataError(f"run_average_band: {np.count_nonzero(v < 0.0)} negative NEES values")
    runs = int(v.shape[0]) if v.ndim else 0
    if runs < 2:
        return {"verdict": None, "runs": runs, "reason": "needs at least two independent runs"}
    lo, hi = mean_chi2_band(dof, runs, p)
    avg = np.atleast_1d(v.mean(axis=0))
    instant = np.broadcast_to(
        np.arange(avg.shape[0], dtype=float).reshape(-1, *[1] * (avg.ndim - 1)), avg.shape
    )
    finite = np.isfinite(avg)
    avg, instant = avg[finite], instant[finite]
    if avg.size == 0:
        return {
            "in_band_percent": float("nan"),
            "band": [lo, hi],
            "runs": runs,
            "instants": 0,
            "verdict": None,
            "reason": "no instant with a value in every run",
        }
    side = 100.0 * (1.0 - p) / 2.0
    below_share = percent_beyond_interval(-avg, instant, -lo, expected_percent=side)
    above_share = percent_beyond_interval(avg, instant, hi, expected_percent=side)
    below, above = below_share.percent, above_share.percent
    inside = 100.0 - below - above
    too_many = {
        "over-confident": above_share.verdict == "over-confident",
        "conservative": below_share.verdict == "over-confident",
    }
    verdict: str | None
    reason = {}
    if above_share.interval is None:
        verdict = None
        reason = {"reason": "one instant: no spread over time to judge the shares by"}
    elif too_many["over-confident"] and too_many["conservative"]:
        verdict = "conservative" if below > above else "over-confident"
    else:
        verdict = next((k for k, flagged in too_many.items() if flagged), "consistent")
    return {
        "in_band_percent": inside,
        "below_band_percent": below,
        "above_band_percent": above,
        "below_band_interval": below_share.to_dict(),
        "above_band_interval": above_share.to_dict(),
        "band": [lo, hi],
        "runs": runs,
        "instants": int(avg.size),
        "verdict": verdict,
        "blocks_short": bool(below_share.blocks_short or above_share.blocks_short),
        **reason,
    }


def percent_beyond(values: ArrayLike, bound: float) -> float:
    """Percentage of the finite ``values`` strictly above the finite ``bound`` (seed 000
    Table 4; one bound, or one per value: ``ConfigError`` otherwise); non-finite values
    (missing records) are skipped, NaN when none is left."""
    v = floats(values, "percent_beyond: values")
    b = _check_bound(bound, "percent_beyond", v.shape)
    ok = np.isfinite(v)
    v, b = v[ok], b[ok]
    if v.size == 0:
        return float("nan")
    return float(100.0 * np.count_nonzero(v > b) / v.size)


#: Blocks of :func:`percent_beyond_interval` by default: ten, so that a 450 s window gives
#: 45 s blocks (longer than the seconds over which odometry errors persist on MRCLAM).
INTERVAL_BATCHES = 10
#: The most time blocks :func:`percent_beyond_interval` accepts: a block index and a
#: (run, block) cell must stay exact 64-bit integers.
MAX_INTERVAL_BATCHES = 10**9
#: Time blocks shorter than this many correlation times of the values make the interval too
#: narrow (module docstring); :attr:`BeyondShare.blocks_short` says when they are.
BLOCK_CORRELATION_TIMES = 10.0
#: Equivalence margin of a share beyond a bound, as a multiple of the share a consistent
#: filter leaves there (:func:`share_verdict`). An interval that holds the expected share only
#: says the test did not reject consistency; on a single correlated recording it can be
#: 1–73 % wide and hold 5 % for a filter with ANEES 50. The verdict is ``"consistent"`` only
#: when the interval also stays at or below this many times the expected share, else
#: ``"inconclusive"``. Two, because seed 000 (Wanasinghe et al. 2014, Section 7, Table 4) calls
#: "less than 10 %" of NEES values beyond the ``χ²(0.95)`` bound acceptable: twice the 5 %
#: expected; for :func:`run_average_band`'s sides, 2 × 2.5 % = 5 % (their own verdicts only:
#: the band's verdict is a significance test, see there).
EQUIVALENCE_FACTOR = 2.0


def share_verdict(interval: tuple[float, float] | None, expected_percent: float) -> str | None:
    """The verdict on a share (%) beyond a bound from its ``interval`` (%) and the
    ``expected_percent`` a consistent filter leaves beyond it:

    * ``"over-confident"``: the interval lies wholly above the expected share;
    * ``"conservative"``: wholly below it;
    * ``"consistent"``: it holds the expected share and its upper end is at most
      :data:`EQUIVALENCE_FACTOR` × the expected share (10 % for 5 %; the end exactly there
      counts as consistent);
    * ``"inconclusive"``: it holds the expected share but reaches above that margin — the
      data do not reject consistency, and do not show it either;

    ``None`` without an interval."""
    if interval is None:
        return None
    lo, hi = interval
    if lo > expected_percent:
        return "over-confident"
    if hi < expected_percent:
        return "conservative"
    return "consistent" if hi <= EQUIVALENCE_FACTOR * expected_percent else "inconclusive"


def integrated_time(series: ArrayLike) -> float:
    """Integrated autocorrelation time ``τ = 1 + 2 Σ_{k≥1} ρ_k`` (in samples; 1 when white) of
    an evenly sampled ``series``, by Geyer's (1992) initial monotone sequence: the sums of
    adjacent sample autocorrelations ``Γ_j = ρ_{2j} + ρ_{2j+1}`` are added while positive and
    each is capped at the one before, ``τ̂ = −1 + 2 Σ_j Γ_j`` (never below 1). The same
    quantity as :mod:`relloc.calibration.inflation`'s ``f``, here estimated from the series."""
    x = floats(series, "integrated_time: series").reshape(-1)
    if not np.isfinite(x).all():
        raise DataError("integrated_time: the series must be finite (evenly sampled, no gaps)")
    n = x.size
    x = x - x.mean() if n else x
    if n < 4 or not np.any(x):
        return 1.0
    spectrum = np.fft.rfft(x, 2 * n)
    acov = np.fft.irfft(spectrum * np.conj(spectrum))[:n]
    if not 0.0 < acov[0] < np.inf:
        raise DataError(
            f"integrated_time: the series' spread, {np.ptp(x):g}, over- or underflows its "
            "variance in double precision"
        )
    rho = acov / acov[0]
    pairs = rho[: 2 * (n // 2)].reshape(-1, 2).sum(axis=1)
    first_negative = np.flatnonzero(pairs <= 0.0)
    pairs = pairs[: first_negative[0] if first_negative.size else pairs.size]
    return max(1.0, float(-1.0 + 2.0 * np.sum(np.minimum.accumulate(pairs))))


@dataclass(frozen=True)
class BeyondShare:
    """A share (%) of values beyond a bound with its interval (of confidence ``confidence``) by
    cluster means (:func:`percent_beyond_interval`): ``samples`` N, ``effective_samples``
    ``N_eff`` (at most N), ``clustering`` (``"time blocks"``, ``"runs"`` or ``"runs and time
    blocks"``), ``clusters`` ``G`` (non-empty clusters; ``min(R, B)`` for two-way clustering),
    ``runs`` R, ``batch_s`` (time block duration, ``None`` when clustered by runs alone),
    ``correlation_time_s`` (the values' correlation time, to hold against ``batch_s``:
    :attr:`blocks_short`; ``None`` when clustered by runs alone), ``correlation_samples``
    (``N_τ``, the effective sample size from that time; ``None`` when clustered by runs
    alone), ``expected_percent`` (what a consistent filter leaves beyond the bound: 5 for a
    ``χ²(0.95)`` bound). ``interval`` is the batch means' ``batch_means_interval``, widened
    to hold the correlation-time interval too when :attr:`blocks_short` (module docstring).
    ``interval``, ``batch_means_interval`` and ``effective_samples`` are ``None`` with fewer
    than two clusters."""

    percent: float
    interval: tuple[float, float] | None
    samples: int
    effective_samples: float | None
    clustering: str
    clusters: int
    runs: int
    batch_s: float | None
    correlation_time_s: float | None
    correlation_samples: float | None
    expected_percent: float
    confidence: float
    batch_means_interval: tuple[float, float] | None

    @property
    def verdict(self) -> str | None:
        """:func:`share_verdict` of the interval against ``expected_percent``:
        ``"over-confident"`` when the interval lies wholly above it, ``"conservative"`` wholly
        below, ``"consistent"`` when it holds it and reaches no higher than
        :data:`EQUIVALENCE_FACTOR` times it, ``"inconclusive"`` when it holds it but reaches
        higher (not rejected, yet too wide to call consistent); ``None`` without an
        interval."""
        return share_verdict(self.interval, self.expected_percent)

    @property
    def blocks_short(self) -> bool | None:
        """Whether the time blocks last less than :data:`BLOCK_CORRELATION_TIMES` correlation
        times, so that the interval is likely too narrow; ``None`` when clustered by runs."""
        if self.batch_s is None or self.correlation_time_s is None:
            return None
        return self.batch_s < BLOCK_CORRELATION_TIMES * self.correlation_time_s

    def to_dict(self) -> dict[str, Any]:
        return {
            "percent": self.percent,
            "interval": list(self.interval) if self.interval is not None else None,
            "samples": self.samples,
            "effective_samples": self.effective_samples,
            "clustering": self.clustering,
            "clusters": self.clusters,
            "runs": self.runs,
            "batch_s": self.batch_s,
            "correlation_time_s": self.correlation_time_s,
            "correlation_samples": self.correlation_samples,
            "blocks_short": self.blocks_short,
            "batch_means_interval": (
                list(self.batch_means_interval) if self.batch_means_interval is not None else None
            ),
            "verdict": self.verdict,
        }


def _cluster_variance(labels: NDArray[np.int64], beyond: Array, p_hat: float) -> tuple[float, int]:
    """``(V̂, G)`` of the ratio estimator over the clusters ``labels`` (module docstring)."""
    _, which = np.unique(labels, return_inverse=True)
    n_g = np.bincount(which).astype(float)
    k_g = np.bincount(which, weights=beyond)
    g = int(n_g.size)
    if g < 2:
        return 0.0, g
    return g / (g - 1) * float(np.sum((k_g - p_hat * n_g) ** 2)) / float(np.sum(n_g)) ** 2, g


def _correlation_figures(
    t: Array, margin: Array, beyond: Array, p_hat: float
) -> tuple[float, float]:
    """``(τ̂ in seconds, N_τ)`` (module docstring): ``τ̂`` the integrated correlation time of the
    ranks of ``margin`` (value − bound; ties share their mean rank) averaged at each instant,
    ``N_τ`` the effective sample size of the share ``p̂`` of ``beyond`` from it and the
    variance over the instants of the share at each instant."""
    from scipy.stats import rankdata

    instants, which = np.unique(t, return_inverse=True)
    counts = np.bincount(which).astype(float)
    tau = integrated_time(np.bincount(which, weights=rankdata(margin)) / counts)
    n_t = int(instants.size)
    tau_s = tau * float(t.max() - t.min()) / max(n_t - 1, 1)
    spread = float(np.var(np.bincount(which, weights=beyond) / counts))
    if spread <= 0.0:
        return tau_s, n_t / tau
    return tau_s, min(float(beyond.size), p_hat * (1.0 - p_hat) * n_t / (spread * tau))


def _time_blocks(t: Array, batches: int) -> tuple[NDArray[np.int64], float]:
    """Each sample's block of ``batches`` contiguous blocks of equal duration, and the duration."""
    width = float(t.max() - t.min()) / batches
    if width > 0:
        return np.minimum((t - t.min()) / width, batches - 1).astype(np.int64), width
    return np.zeros(t.size, dtype=np.int64), width


def clopper_pearson(successes: float, size: float, confidence: float) -> tuple[float, float]:
    """Clopper–Pearson's two-sided ``confidence`` interval of a proportion with ``successes``
    in ``size`` trials, both possibly fractional (an effective sample size):
    ``[B⁻¹((1−c)/2; k, n−k+1), B⁻¹((1+c)/2; k+1, n−k)]`` with the Beta quantile ``B⁻¹``, 0 and
    1 at the ends. A size beyond what the Beta quantile resolves (a NaN end) is a
    :class:`ConfigError`."""
    from scipy.stats import beta

    k = number(successes, "clopper_pearson: successes")
    n = number(size, "clopper_pearson: size")
    c = probability(confidence, "clopper_pearson: confidence, a probability")
    if not (0 < n and 0 <= k <= n):
        raise ConfigError(
            f"clopper_pearson: need 0 ≤ successes ≤ size and a finite size > 0, got {k}, {n}"
        )
    lo = float(beta.ppf((1.0 - c) / 2.0, k, n - k + 1)) if k > 0 else 0.0
    hi = float(beta.ppf((1.0 + c) / 2.0, k + 1, n - k)) if k < n else 1.0
    if np.isnan(lo) or np.isnan(hi):
        raise ConfigError(f"clopper_pearson: size {n:g} is beyond what the Beta quantile resolves")
    return lo, hi


def percent_beyond_interval(
    values: ArrayLike,
    times: ArrayLike,
    bound: float | ArrayLike,
    *,
    runs: ArrayLike | None = None,
    shared_recording: bool = False,
    expected_percent: float = 5.0,
    batches: int = INTERVAL_BATCHES,
    confidence: float = 0.95,
) -> BeyondShare:
    """Percentage of finite ``values`` above ``bound`` with its interval of confidence
    ``confidence`` by cluster means (module docstring): samples of any number of subjects, each
    with its time and, with ``runs``, the run it belongs to; ``bound`` a finite scalar or one
    per value (``ConfigError`` otherwise); values or times that are not finite (missing
    records) are skipped and not counted in ``samples``; ``expected_percent`` what a consistent
    filter leaves beyond it (5 for ``χ²(0.95)``), for the verdict. The clusters: ``batches``
    time blocks for one run (``runs`` omitted or holding one run); the runs when there are
    several, independent; the runs and the time blocks, two-way, when ``shared_recording`` says
    the runs replay one recording. When every cluster sits at ``p̂`` (e.g. none beyond
    anywhere) there is no spread to measure: ``N_eff`` is then ``G`` and the interval
    Clopper–Pearson's for ``G p̂`` in ``G``. A ``confidence`` whose ``(1+c)/2`` rounds to ½
    or 1, ``batches`` beyond :data:`MAX_INTERVAL_BATCHES`, a ``shared_recording`` that is not
    a bool, or times whose span overflows are refused (``ConfigError``, ``DataError``). Run
    indices are labels: any integers, renumbered ``0 … runs − 1`` before they are combined
    with the blocks.
    """
    c = probability(confidence, "percent_beyond_interval: confidence, a probability")
    if not 0.5 < (1.0 + c) / 2.0 < 1.0:
        raise ConfigError(
            f"percent_beyond_interval: confidence {c!r} is too close to 0 or 1 for a Student "
            "quantile in double precision"
        )
    expected = 100.0 * (
        number(
            expected_percent,
            "percent_beyond_interval: expected_percent, a probability in %",
            low=0.0,
            high=100.0,
            open_low=True,
            open_high=True,
        )
        / 100.0
    )
    batches = count(batches, "percent_beyond_interval: batches", low=2, high=MAX_INTERVAL_BATCHES)
    if not isinstance(shared_recording, (bool, np.bool_)):
        raise ConfigError(
            "percent_beyond_interval: shared_recording must be a bool, got "
            f"{shared_recording!r:.40}"
        )
    v = floats(values, "percent_beyond_interval: values").reshape(-1)
    t = floats(times, "percent_beyond_interval: times").reshape(-1)
    if t.shape != v.shape:
        raise ConfigError(
            f"percent_beyond_interval: {t.size} times for {v.size} values; one time per value"
        )
    r = np.zeros(v.size, dtype=np.int64) if runs is None else np.asarray(runs).reshape(-1)
    if r.shape != v.shape or not np.issubdtype(r.dtype, np.integer):
        raise ConfigError(
            f"percent_beyond_interval: {r.size} run indices ({r.dtype}) for {v.size} values; "
            "one integer per value"
        )
    b = _check_bound(bound, "percent_beyond_interval", v.shape)
    ok = np.isfinite(v) & np.isfinite(t)
    v, t, b = v[ok], t[ok], b[ok]
    r = np.unique(r[ok], return_inverse=True)[1].astype(np.int64)  # labels 0 … runs − 1
    if v.size and not np.isfinite(t.max() - t.min()):
        raise DataError(
            f"percent_beyond_interval: times from {t.min():g} to {t.max():g}; their span "
            "overflows double precision"
        )
    n_runs = int(np.unique(r).size)
    if v.size == 0:
        empty = (0, "time blocks", 0, 0, None, None, None, expected, c)
        return _share(float("nan"), None, None, *empty)
    beyond = (v > b).astype(float)
    percent = float(100.0 * np.count_nonzero(beyond) / v.size)  # as percent_beyond rounds it
    p_hat = percent / 100.0
    block, width = _time_blocks(t, batches)
    batch_s: float | None = width
    tau_s = n_tau = None
    if n_runs < 2 or shared_recording:  # time blocks: their values' correlation time beside
        tau_s, n_tau = _correlation_figures(t, v - b, beyond, p_hat)
    if n_runs < 2:
        clustering = "time blocks"
        var, g = _cluster_variance(block, beyond, p_hat)
    elif not shared_recording:
        clustering, batch_s = "runs", None
        var, g = _cluster_variance(r, beyond, p_hat)
    else:
        clustering = "runs and time blocks"
        v_runs, g_runs = _cluster_variance(r, beyond, p_hat)
        v_blocks, g_blocks = _cluster_variance(block, beyond, p_hat)
        v_cells, _ = _cluster_variance(r * batches + block, beyond, p_hat)
        var = v_runs + v_blocks - v_cells
        if var <= 0.0:
            var = max(v_runs, v_blocks)
        g = min(g_runs, g_blocks)
    figures = (int(v.size), clustering, g, n_runs, batch_s, tau_s, n_tau, expected, c)
    if g < 2:
        return _share(percent, None, None, *figures)
    from scipy.stats import t as student_t

    if var > 0.0:
        n_eff = min(float(v.size), p_hat * (1.0 - p_hat) / var)
        q = (1.0 + c) / 2.0
        size = n_eff * (student_t.ppf(q, v.size - 1) / student_t.ppf(q, g - 1)) ** 2
    else:
        n_eff = size = float(g)
    lo, hi = clopper_pearson(p_hat * size, size, c)
    share = _share(percent, (100.0 * lo, 100.0 * hi), n_eff, *figures)
    if not share.blocks_short or n_tau is None:
        return share
    lo_tau, hi_tau = clopper_pearson(p_hat * n_tau, n_tau, c)
    widened = (min(100.0 * lo, 100.0 * lo_tau), max(100.0 * hi, 100.0 * hi_tau))
    return replace(share, interval=widened)


def _share(
    percent: float,
    interval: tuple[float, float] | None,
    n_eff: float | None,
    samples: int,
    clustering: str,
    clusters: int,
    runs: int,
    batch_s: float | None,
    tau_s: float | None,
    n_tau: float | None,
    expected: float,
    confidence: float,
) -> BeyondShare:
    """A :class:`BeyondShare` whose interval is its batch means' one."""
    return BeyondShare(
        percent=percent,
        interval=interval,
        samples=samples,
        effective_samples=n_eff,
        clustering=clustering,
        clusters=clusters,
        runs=runs,
        batch_s=batch_s,
        correlation_time_s=tau_s,
        correlation_samples=n_tau,
        expected_percent=expected,
        confidence=confidence,
        batch_means_interval=interval,
    )
