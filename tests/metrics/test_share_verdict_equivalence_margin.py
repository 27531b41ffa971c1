"""The four verdicts on a share beyond a bound, with the equivalence margin of
:data:`relloc.metrics.consistency.EQUIVALENCE_FACTOR` (2 × the expected share), by hand."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from relloc.metrics.consistency import (
    EQUIVALENCE_FACTOR,
    mean_chi2_band,
    percent_beyond_interval,
    run_average_band,
    share_verdict,
)


def test_the_margin_is_twice_the_expected_share():
    # seed 000 §7 calls < 10 % beyond chi2(0.95) acceptable: twice the 5 % expected
    assert EQUIVALENCE_FACTOR == 2.0


@pytest.mark.parametrize(
    ("interval", "expected", "verdict"),
    [
        ((5.5, 9.0), 5.0, "over-confident"),  # wholly above 5
        ((1.0, 4.5), 5.0, "conservative"),  # wholly below 5
        ((1.0, 10.0), 5.0, "consistent"),  # holds 5, upper end exactly 2 × 5
        ((5.0, 10.0), 5.0, "consistent"),  # both ends at the boundaries
        ((1.0, 5.0), 5.0, "consistent"),  # the upper end at 5 still holds it
        ((1.0, 10.0 + 1e-9), 5.0, "inconclusive"),  # holds 5, reaches above 10
        ((1.4, 73.4), 5.0, "inconclusive"),  # the audit's cooperative_shortbag pair
        ((1.0, 5.0), 2.5, "consistent"),  # a run-average side: 2 × 2.5 % = 5 %
        ((1.0, 5.0 + 1e-9), 2.5, "inconclusive"),
        ((2.6, 30.0), 2.5, "over-confident"),  # wholly above wins however wide
    ],
)
def test_share_verdict_by_hand(interval, expected, verdict):
    assert share_verdict(interval, expected) == verdict


def test_share_verdict_without_an_interval_is_none():
    assert share_verdict(None, 5.0) is None


@pytest.mark.parametrize(
    ("blocks", "upper", "verdict"),
    [
        (30, 11.5703, "inconclusive"),  # 100 (1 − 0.025^(1/30)): above 10
        (37, 9.4891, "consistent"),  # 100 (1 − 0.025^(1/37)): holds 5, below 10
        (80, 4.5064, "conservative"),  # 100 (1 − 0.025^(1/80)): below 5
    ],
)
def test_nothing_beyond_in_g_blocks_by_hand(blocks, upper, verdict):
    # no value beyond the bound: no spread over the blocks, so N_eff = G and the interval is
    # Clopper–Pearson's for 0 of G, whose upper end solves (1 − u)^G = 0.025
    share = percent_beyond_interval(np.zeros(300), np.arange(300.0), 1.0, batches=blocks)
    assert share.interval == pytest.approx((0.0, upper), abs=1e-4)
    assert share.verdict == verdict
    assert share.to_dict()["verdict"] == verdict


def test_the_beyond_share_verdict_uses_the_margin():
    share = percent_beyond_interval(np.zeros(300), np.arange(300.0), 1.0)
    assert replace(share, interval=(1.0, 10.0)).verdict == "consistent"
    assert replace(share, interval=(1.0, 10.5)).verdict == "inconclusive"
    assert replace(share, interval=(0.0, 2.0), expected_percent=1.0).verdict == "consistent"
    assert replace(share, interval=(0.0, 2.5), expected_percent=1.0).verdict == "inconclusive"


def test_run_average_band_sides_can_be_inconclusive_while_the_band_test_does_not_reject():
    # two runs of chi2(1) NEES, 1.0 at all 200 instants: inside the band (0.0253, 3.689)
    # everywhere, so 0 of 200 below and above. No spread over the ten blocks: each side's
    # interval is Clopper–Pearson's for 0 of 10, (0, 30.85) %: it holds 2.5 % but reaches above
    # 2 × 2.5 % = 5 %, so each side's own verdict is inconclusive; no side is flagged, and the
    # band's verdict, a significance test without the margin, is consistent.
    out = run_average_band(np.ones((2, 200)), 1)
    assert out["band"] == pytest.approx(list(mean_chi2_band(1, 2)))
    assert out["below_band_percent"] == 0.0 and out["above_band_percent"] == 0.0
    for side in ("below_band_interval", "above_band_interval"):
        assert out[side]["interval"] == pytest.approx([0.0, 100.0 * (1.0 - 0.025**0.1)])
        assert out[side]["verdict"] == "inconclusive"
    assert out["blocks_short"] is False
    assert out["verdict"] == "consistent"


def test_run_average_band_narrow_sides_are_consistent():
    # 2000 instants in ten blocks of 200, alternately 4 and 6 run averages above and as many
    # below the band: 2.5 % each side, intervals about 1.8–3.4 %, within 5 %
    avg = np.ones(2000)
    for block in range(10):
        k = 4 if block % 2 == 0 else 6
        at = block * 200 + np.arange(k) * (200 // k)
        avg[at] = 10.0
        avg[at + 7] = 0.001
    out = run_average_band(np.stack([avg, avg]), 1)
    assert out["below_band_percent"] == 2.5 and out["above_band_percent"] == 2.5
    for side in ("below_band_interval", "above_band_interval"):
        lo, hi = out[side]["interval"]
        assert lo < 2.5 < hi <= 5.0
        assert out[side]["verdict"] == "consistent"
    assert out["verdict"] == "consistent"


def test_run_average_band_a_flagged_side_wins_over_an_inconclusive_one():
    # every third instant far above the band (100), the others inside (1.0): a third above in
    # every block, wholly above 2.5 %; none below, (0, 30.85) % inconclusive
    out = run_average_band(np.tile(np.array([1.0, 1.0, 100.0]), (2, 40)), 1)
    assert out["above_band_interval"]["verdict"] == "over-confident"
    assert out["below_band_interval"]["verdict"] == "inconclusive"
    assert out["verdict"] == "over-confident"
