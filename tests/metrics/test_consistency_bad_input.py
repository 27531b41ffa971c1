"""Bad input to the consistency metrics: ConfigError (a bad dof, count, bound or shape),
ModelError (a covariance that is not finite and positive definite) or DataError (impossible
values), never a raw numpy error or an impossible result (a negative NEES, a NaN band)."""

from __future__ import annotations

import numpy as np
import pytest

from relloc.errors import ConfigError, DataError, ModelError
from relloc.metrics.consistency import (
    anees,
    anees_band,
    chi2_upper,
    clopper_pearson,
    integrated_time,
    mean_chi2_band,
    nees,
    nis,
    percent_beyond,
    percent_beyond_interval,
    projected_nees,
)

NAN = float("nan")


@pytest.mark.parametrize(
    "P", [-np.eye(2), np.array([[1.0, 2.0], [2.0, 1.0]]), np.full((2, 2), NAN), np.zeros((2, 2))]
)
def test_projected_nees_refuses_a_covariance_that_is_not_positive_definite(P) -> None:
    # -I gave -1.0, an impossible NEES
    with pytest.raises(ModelError, match="projected_nees"):
        projected_nees([1.0, 0.0], P, [[1.0], [0.0]])


@pytest.mark.parametrize(
    "N", [[[0.0], [0.0]], [[1.0, 1.0], [0.0, 0.0]], [[1.0, 2.0], [1.0, 2.0]], [[NAN], [1.0]]]
)
def test_projected_nees_refuses_directions_that_are_not_independent(N) -> None:
    # zero or repeated columns gave a raw LinAlgError
    with pytest.raises(ConfigError, match="projected_nees: the directions"):
        projected_nees([1.0, 0.0], np.eye(2), N)


def test_projected_nees_of_a_missing_error_is_nan_and_otherwise_never_negative() -> None:
    assert np.isnan(projected_nees([NAN, 0.0], np.eye(2), [[1.0], [0.0]]))
    rng = np.random.default_rng(5)
    for _ in range(50):
        A = rng.normal(size=(5, 5))
        P = A @ A.T + 1e-6 * np.eye(5)  # badly conditioned
        assert projected_nees(rng.normal(size=5), P, rng.normal(size=(5, 2))) >= 0.0
    # and its singular-covariance error keeps saying so
    with pytest.raises(ModelError, match="singular"):
        projected_nees([1.0, 0.0], -np.eye(2), [[1.0], [0.0]])


@pytest.mark.parametrize("f", [nees, nis])
def test_nees_and_nis_refuse_a_non_finite_covariance(f) -> None:
    # a NaN covariance gave a NaN NEES that anees then dropped without a word
    with pytest.raises(ModelError, match="not finite at NEES/NIS"):
        f([1.0, 0.0], np.full((2, 2), NAN))
    with pytest.raises(ModelError, match="NEES/NIS"):
        f(np.ones((2, 2)), np.stack([np.eye(2), np.diag([1.0, np.inf])]))


@pytest.mark.parametrize(
    ("e", "P"),
    [
        ([1.0, 0.0, 0.0], np.eye(2)),  # was a raw ValueError
        ([1.0, 0.0], [1.0, 1.0]),  # was an AxisError
        (np.ones((3, 2)), np.broadcast_to(np.eye(2), (4, 2, 2))),
        (1.0, 1.0),
    ],
)
def test_nees_refuses_shapes_that_do_not_fit(e, P) -> None:
    with pytest.raises(ConfigError, match="NEES/NIS: vector"):
        nees(e, P)


def test_nees_of_a_missing_error_stays_nan_and_anees_skips_it() -> None:
    values = nees(np.array([[1.0, 0.0], [NAN, 0.0]]), np.eye(2))
    assert values[0] == 1.0 and np.isnan(values[1])
    assert anees(values, 2) == 0.5


@pytest.mark.parametrize("dof", [0, -1, 2.5, NAN, True, "2"])
def test_anees_refuses_a_dof_that_is_not_a_positive_integer(dof) -> None:
    # 0 gave inf, -1 gave -1.5
    with pytest.raises(ConfigError, match="anees: dof"):
        anees([1.0, 2.0], dof)


def test_anees_refuses_negative_nees() -> None:
    with pytest.raises(DataError, match="anees: 1 negative"):
        anees([-1.0, 2.0, NAN], 2)
    with pytest.raises(DataError, match="negative"):
        anees([-np.inf, 2.0], 2)
    assert anees(np.array([2.0, 4.0]), np.int64(3)) == pytest.approx(1.0)


def test_a_nan_bound_is_refused_not_read_as_nothing_beyond() -> None:
    # a NaN bound gave 0 % beyond
    with pytest.raises(ConfigError, match="percent_beyond: 1 bound"):
        percent_beyond([1.0, 10.0], NAN)
    with pytest.raises(ConfigError, match="percent_beyond_interval: 1 bound"):
        percent_beyond_interval([1.0, 10.0, 3.0], [0.0, 1.0, 2.0], NAN)
    with pytest.raises(ConfigError, match="percent_beyond_interval: 1 bound"):
        percent_beyond_interval([1.0, 10.0, 3.0], [0.0, 1.0, 2.0], [1.0, NAN, 2.0])
    with pytest.raises(ConfigError, match="bound"):
        percent_beyond([1.0], np.inf)


@pytest.mark.parametrize("dof", [2.7, NAN, 0, True])
def test_chi2_upper_refuses_a_dof_that_is_not_a_positive_integer(dof) -> None:
    # 2.7 was truncated to 2, NaN gave a raw ValueError
    with pytest.raises(ConfigError, match="chi2_upper: dof"):
        chi2_upper(dof)


@pytest.mark.parametrize(("dof", "n"), [(2, NAN), (2, 2.5), (2.5, 2), (NAN, 2), (2, 0), (0, 2)])
def test_chi2_bands_refuse_counts_that_are_not_positive_integers(dof, n) -> None:
    # (2, NaN) gave (nan, nan); (2, 2.5) was accepted
    with pytest.raises(ConfigError, match="mean_chi2_band"):
        mean_chi2_band(dof, n)
    with pytest.raises(ConfigError, match="mean_chi2_band"):
        anees_band(dof, n)
    assert mean_chi2_band(np.int64(2), np.int64(3)) == pytest.approx(mean_chi2_band(2, 3))


def test_integrated_time_refuses_a_series_with_gaps() -> None:
    # gave 1.0, as if white
    with pytest.raises(DataError, match="integrated_time"):
        integrated_time([1.0, NAN, 2.0, 3.0, 4.0])


@pytest.mark.parametrize(("k", "n"), [(1.0, np.inf), (np.inf, np.inf), (NAN, 5.0), (1.0, NAN)])
def test_clopper_pearson_refuses_an_infinite_or_nan_count(k, n) -> None:
    # (1, inf) gave (0, nan)
    with pytest.raises(ConfigError, match="clopper_pearson"):
        clopper_pearson(k, n, 0.9)
