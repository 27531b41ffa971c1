"""Hand-computed cases of the consistency statistics that pin details the statistical tests
leave free: the cluster variance's G/(G−1), the two-way fallback, Geyer's monotone cap, the
correlation figures of an alternating series, the ten-correlation-times rule and the widening
of the interval, the verdict at the interval's ends, and ANEES on zero and infinite values."""

from dataclasses import replace

import numpy as np
import pytest
from scipy.stats import beta
from scipy.stats import t as student_t

from relloc.metrics.consistency import (
    BeyondShare,
    anees,
    integrated_time,
    percent_beyond_interval,
)


def _indicator_values(counts: list[int], size: int) -> np.ndarray:
    """Values 1 (beyond a bound of 0.5) for the first ``k`` of each cluster of ``size``."""
    v = np.zeros((len(counts), size))
    for g, k in enumerate(counts):
        v[g, :k] = 1.0
    return v.reshape(-1)


def test_the_cluster_variance_carries_the_small_sample_factor():
    # 5 blocks of 10 samples with 0, 0, 5, 5, 0 beyond: p = 10/50 = 0.2, deviations
    # k_g - p n_g = (-2, -2, 3, 3, -2), sum of squares 30, so V = 5/4 * 30 / 50**2 = 0.015
    # and N_eff = 0.16 / 0.015 = 32/3 (below N = 50, not capped). Korn-Graubard:
    # N_df = 32/3 (t_49(0.975) / t_4(0.975))**2 and the Clopper-Pearson interval of 0.2 N_df.
    share = percent_beyond_interval(
        _indicator_values([0, 0, 5, 5, 0], 10), np.arange(50.0), 0.5, batches=5
    )
    assert share.percent == pytest.approx(20.0)
    assert share.effective_samples == pytest.approx(32.0 / 3.0, rel=1e-12)
    n_df = 32.0 / 3.0 * (student_t.ppf(0.975, 49) / student_t.ppf(0.975, 4)) ** 2
    k = 0.2 * n_df
    expected = (
        100.0 * beta.ppf(0.025, k, n_df - k + 1.0),
        100.0 * beta.ppf(0.975, k + 1.0, n_df - k),
    )
    assert share.batch_means_interval == pytest.approx(expected, rel=1e-9)


def test_two_way_clustering_falls_back_to_the_larger_one_way_variance():
    # Two runs of one recording, two blocks of 10 samples each: beyond 9, 3 (run 0) and 1, 7
    # (run 1), p = 20/40 = 0.5. Deviations k - p n per cell: [[4, -2], [-4, 2]], so
    # V_runs = 2 * (2**2 + 2**2) / 40**2 = 0.01, V_blocks = 2 * (0 + 0) / 40**2 = 0 and
    # V_cells = 4/3 * 40 / 40**2 = 1/30: V_runs + V_blocks - V_cells < 0, the fallback is
    # max(V_runs, V_blocks) = 0.01 and N_eff = 0.25 / 0.01 = 25 (with G = min(2, 2) = 2).
    values = np.concatenate([_indicator_values([9, 3], 10), _indicator_values([1, 7], 10)])
    times = np.tile(np.arange(20.0), 2)
    runs = np.repeat([0, 1], 20)
    share = percent_beyond_interval(values, times, 0.5, runs=runs, shared_recording=True, batches=2)
    assert share.clustering == "runs and time blocks" and share.clusters == 2
    assert share.percent == pytest.approx(50.0)
    assert share.effective_samples == pytest.approx(25.0, rel=1e-12)


def test_integrated_time_caps_each_pair_sum_at_the_one_before():
    # x has mean 0 and autocovariances (lags 0..6) 10, 3, 0, 1, 3, 0, -4: the pair sums are
    # 1.3, 0.1, 0.3, -0.6. Geyer's initial monotone sequence keeps 1.3, 0.1 and caps 0.3 at
    # 0.1, then stops at the negative one: tau = -1 + 2 (1.3 + 0.1 + 0.1) = 2 (2.4 uncapped).
    x = [-1.0, -1.0, -1.0, 1.0, -1.0, -1.0, 0.0, 1.0, 1.0, 0.0, 1.0, 1.0]
    assert integrated_time(x) == pytest.approx(2.0, rel=1e-12)
    assert integrated_time(np.add(x, 7.0)) == pytest.approx(2.0, rel=1e-12)  # mean removed


def _alternating(n_t: int) -> BeyondShare:
    """One subject at t = 0, 1, …, n_t − 1 s, beyond a bound of 5 at every other instant."""
    beyond = (np.arange(n_t) % 2 == 0).astype(float)
    return percent_beyond_interval(10.0 * beyond, np.arange(float(n_t)), 5.0)


def test_an_alternating_series_has_the_spacing_as_correlation_time_and_every_instant_counts():
    # Alternating ranks: lag-1 correlation about -1, so tau = 1 instant = the 1 s spacing
    # (the span, 100 s, over the 100 gaps between 101 instants). One subject: the share per
    # instant is 0 or 1, its variance over the instants p(1 - p), so N_tau = n_t / tau = 101.
    share = _alternating(101)
    assert share.correlation_time_s == pytest.approx(1.0, rel=1e-12)
    assert share.correlation_samples == pytest.approx(101.0, rel=1e-9)


def test_correlation_samples_are_capped_at_the_sample_count():
    # Three subjects at 100 instants, one always beyond, two never, except at one instant
    # where two are: the share per instant is 1/3 but once 2/3, so its variance is tiny
    # ((1/3)**2 * 0.01 * 0.99) and p(1 - p) n_t / (s_y**2 tau) is about 20 000 / tau, far
    # more than the 300 samples there are: N_tau is the 300.
    n_t = 100
    a = np.full(n_t, 10.0)
    b = np.zeros(n_t)
    b[50] = 10.0
    c = np.zeros(n_t)
    share = percent_beyond_interval(
        np.concatenate([a, b, c]), np.tile(np.arange(float(n_t)), 3), 5.0
    )
    assert share.percent == pytest.approx(100.0 * 101 / 300)
    assert share.correlation_samples == 300.0


def test_blocks_are_short_below_ten_correlation_times_not_at_ten():
    # tau = 1 s (alternating). 101 instants: ten blocks of 10 s = exactly ten correlation
    # times, not short. 71 instants: blocks of 7 s, short.
    at_ten = _alternating(101)
    assert at_ten.batch_s == pytest.approx(10.0) and at_ten.correlation_time_s == 1.0
    assert at_ten.blocks_short is False
    assert at_ten.interval == at_ten.batch_means_interval
    seven = _alternating(71)
    assert seven.batch_s == pytest.approx(7.0) and seven.correlation_time_s == 1.0
    assert seven.blocks_short is True


def test_long_blocks_keep_the_batch_means_interval_even_where_the_correlation_one_is_wider():
    # Five subjects with the same alternating values (five flips make the blocks differ):
    # tau = 1 s against 19.9 s blocks, so the blocks are long, yet N_tau (200 instants) is
    # below N_eff (capped at 1000 samples): the correlation-time interval is wider than the
    # batch means' one and must not widen it.
    n_t = 200
    beyond = (np.arange(n_t) % 2 == 0).astype(float)
    beyond[[5, 47, 88, 131, 170]] = 1.0 - beyond[[5, 47, 88, 131, 170]]
    share = percent_beyond_interval(
        np.tile(10.0 * beyond, 5), np.tile(np.arange(float(n_t)), 5), 5.0
    )
    assert share.blocks_short is False
    n_tau = share.correlation_samples
    assert n_tau == pytest.approx(200.0, rel=1e-9)
    p = share.percent / 100.0
    tau_lo = 100.0 * beta.ppf(0.025, p * n_tau, n_tau - p * n_tau + 1.0)
    assert share.batch_means_interval is not None and tau_lo < share.batch_means_interval[0]
    assert share.interval == share.batch_means_interval


def test_short_blocks_widen_the_interval_on_both_sides_to_the_correlation_one():
    # One subject, 400 instants, beyond in alternate stretches of 30 s: blocks of 39.9 s
    # against a correlation time of about 15 s are short, and the Clopper-Pearson interval
    # of p N_tau in N_tau is wider on both sides than the batch means' one: the interval is
    # the hull of the two, here the correlation-time interval itself.
    n = 400
    beyond = ((np.arange(n) // 30) % 2 == 0).astype(float)
    share = percent_beyond_interval(10.0 * beyond, np.arange(float(n)), 5.0)
    assert share.blocks_short is True
    n_tau = share.correlation_samples
    assert n_tau is not None
    p = share.percent / 100.0
    k = p * n_tau
    tau_interval = (
        100.0 * beta.ppf(0.025, k, n_tau - k + 1.0),
        100.0 * beta.ppf(0.975, k + 1.0, n_tau - k),
    )
    bm = share.batch_means_interval
    assert bm is not None
    assert tau_interval[0] < bm[0] and tau_interval[1] > bm[1]
    assert share.interval == pytest.approx(tau_interval, rel=1e-12)


def test_the_verdict_counts_an_interval_end_at_the_expected_share_as_holding_it():
    share = _alternating(101)
    assert replace(share, interval=(5.0, 9.0), expected_percent=5.0).verdict == "consistent"
    assert replace(share, interval=(1.0, 5.0), expected_percent=5.0).verdict == "consistent"
    assert replace(share, interval=(5.5, 9.0), expected_percent=5.0).verdict == "over-confident"
    assert replace(share, interval=(1.0, 4.5), expected_percent=5.0).verdict == "conservative"


def test_anees_counts_a_zero_nees_and_skips_missing_and_infinite_ones():
    # (0 + 2 + 4) / 3 / 2 = 1: a NEES of 0 (no error) is a value like any other
    assert anees([0.0, 2.0, 4.0], 2) == pytest.approx(1.0)
    # the mean over the finite values only (NaN and inf left out): (1 + 3) / 2 / 2 = 1
    assert anees([1.0, np.nan, 3.0, np.inf], 2) == pytest.approx(1.0)
