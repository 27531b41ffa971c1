"""Variance inflation for time-correlated errors: the measured-autocorrelation sum and the
Gauss–Markov closed form agree, and both reduce to 1 for white errors."""

import math

import pytest

from relloc.calibration.inflation import (
    MAX_INFLATION_TERMS,
    autocorrelation_inflation,
    gauss_markov_inflation,
    search_text,
    smallest_factor,
)
from relloc.errors import ConfigError, DataError


def test_gauss_markov_closed_form_is_the_limit_of_the_autocorrelation_sum():
    period, tau = 0.1, 1.2
    a = math.exp(-period / tau)
    n = 2000  # a^n is negligible
    rho = {k * period: a**k for k in range(1, n + 1)}
    measured = autocorrelation_inflation(rho, period, horizon_s=n * period)
    assert measured == pytest.approx(gauss_markov_inflation(period, tau), rel=1e-9)
    assert gauss_markov_inflation(period, tau) == pytest.approx((1 + a) / (1 - a))


def test_white_errors_need_no_inflation():
    assert gauss_markov_inflation(0.1, 0.0) == 1.0
    assert autocorrelation_inflation({0.5: 0.0, 1.0: -0.1, 5.0: 0.0}, 0.5) == 1.0


def test_autocorrelation_sum_interpolates_and_stops_at_the_horizon():
    # ρ = 0.5 at 1 s, 0 from 2 s: readings 0.5 s apart see ρ(0.5) = 0.5 (held below the first
    # lag), ρ(1) = 0.5, ρ(1.5) = 0.25 and nothing after → f = 1 + 2·1.25
    rho = {1.0: 0.5, 2.0: 0.0, 10.0: 0.0}
    assert autocorrelation_inflation(rho, 0.5) == pytest.approx(3.5)
    assert autocorrelation_inflation({1.0: 0.5}, 0.5, horizon_s=0.5) == pytest.approx(2.0)


def test_bad_inputs_are_refused():
    with pytest.raises(ConfigError, match="no measured lag"):
        autocorrelation_inflation({}, 0.5)
    with pytest.raises(ConfigError, match="spacing"):
        autocorrelation_inflation({1.0: 0.5}, 0.0)
    with pytest.raises(ConfigError, match="period"):
        gauss_markov_inflation(0.0, 1.0)


@pytest.mark.parametrize(
    ("rho", "spacing", "horizon_s", "error", "match"),
    [
        ({math.nan: 0.5}, 0.5, 10.0, ConfigError, "lags must be > 0, got nan"),
        ({-1.0: 0.5}, 0.5, 10.0, ConfigError, "lags must be > 0"),
        ({1.0: math.nan}, 0.5, 10.0, DataError, "rho at lag 1 s is nan"),
        ({1.0: math.inf}, 0.5, 10.0, DataError, "rho at lag 1 s is inf"),
        ({1.0: 0.5}, 0.5, math.nan, ConfigError, "horizon_s"),
        ({1.0: 0.5}, 0.5, math.inf, ConfigError, "horizon_s"),
        (
            {1.0: 0.5},
            1e-9,
            10.0,
            ConfigError,
            f"spacing 1e-09 s would sum 1e\\+10 terms.*{MAX_INFLATION_TERMS}",
        ),
    ],
)
def test_autocorrelation_inflation_names_the_bad_argument(rho, spacing, horizon_s, error, match):
    """No KeyError, ValueError, MemoryError or silent NaN: the argument at fault is named."""
    with pytest.raises(error, match=match):
        autocorrelation_inflation(rho, spacing, horizon_s)


def test_autocorrelation_inflation_sums_up_to_the_term_limit():
    horizon_s = 0.5 * MAX_INFLATION_TERMS
    assert autocorrelation_inflation({1.0: 0.0}, 0.5, horizon_s) == 1.0


@pytest.mark.parametrize(
    ("period", "tau", "match"),
    [
        (0.1, math.nan, "tau must be finite and ≥ 0, got nan"),
        (0.1, math.inf, "tau must be finite"),
        (0.1, -1.0, "tau must be finite and ≥ 0, got -1"),
        (1e-20, 1.0, "period 1e-20 s is negligible against tau 1 s"),
        (math.nan, 1.0, "period"),
    ],
)
def test_gauss_markov_inflation_names_the_bad_argument(period, tau, match):
    with pytest.raises(ConfigError, match=match):
        gauss_markov_inflation(period, tau)


def test_smallest_factor_stops_at_the_first_that_meets_the_target():
    evaluated = []

    def percent(k):
        evaluated.append(k)
        return 20.0 / k**2  # 20, 8.9, 5, 2.2 % for ×1, ×1.5, ×2, ×3

    assert smallest_factor((1.0, 1.5, 2.0, 3.0), 5.0, percent) == (
        2.0,
        True,
        ((1.0, 20.0), (1.5, pytest.approx(80 / 9)), (2.0, 5.0)),
    )
    assert evaluated == [1.0, 1.5, 2.0]  # the larger factors are never replayed


def test_smallest_factor_keeps_the_largest_when_none_meets_the_target():
    k, met, tried = smallest_factor((1.0, 2.0), 1.0, lambda k: 10.0 / k)
    assert (k, met, [f for f, _ in tried]) == (2.0, False, [1.0, 2.0])
    with pytest.raises(ConfigError, match="empty grid"):
        smallest_factor((), 5.0, lambda k: 0.0)


def test_search_text_states_the_verdict_and_every_factor_tried():
    assert search_text([(1.0, 5.42), (1.5, 0.6)], True) == "met; tried ×1: 5.4 %, ×1.5: 0.6 %"
    text = search_text([(1.0, 30.0), (4.0, 12.0)], False)
    assert text.startswith("not met by any factor tried") and text.endswith("×4: 12.0 %")
