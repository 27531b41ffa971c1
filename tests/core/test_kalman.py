"""The one Kalman update (Joseph form, batched) and the one χ² gate (gate first, then update)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.stats import chi2

import relloc.core.kalman as kalman
from relloc.core.kalman import chi2_threshold, gated_update, kalman_update
from relloc.errors import ConfigError, ModelError


def _problem(rng: np.random.Generator, n: int = 4, m: int = 2, batch: tuple[int, ...] = ()):  # type: ignore[no-untyped-def]
    A = rng.normal(size=(*batch, n, n))
    P = A @ np.swapaxes(A, -1, -2) + np.eye(n)
    B = rng.normal(size=(*batch, m, m))
    R = 0.1 * (B @ np.swapaxes(B, -1, -2)) + 0.05 * np.eye(m)
    return (
        rng.normal(size=(*batch, n)),
        P,
        rng.normal(size=(*batch, m)),
        rng.normal(size=(*batch, m, n)),
        R,
    )


def _textbook(x, P, nu, H, R):  # type: ignore[no-untyped-def]
    S = H @ P @ H.T + R
    K = P @ H.T @ np.linalg.inv(S)
    return x + K @ nu, (np.eye(len(x)) - K @ H) @ P, float(nu @ np.linalg.solve(S, nu)), S


def test_update_equals_the_textbook_kalman_filter_with_the_optimal_gain() -> None:
    x, P, nu, H, R = _problem(np.random.default_rng(0))
    mean, cov, inn = kalman_update(x, P, nu, H, R)
    ref_mean, ref_cov, ref_nis, ref_S = _textbook(x, P, nu, H, R)
    np.testing.assert_allclose(mean, ref_mean, atol=1e-12)
    np.testing.assert_allclose(cov, ref_cov, atol=1e-12)
    np.testing.assert_allclose(inn.cov, ref_S, atol=1e-12)
    assert inn.nis == pytest.approx(ref_nis, rel=1e-12)
    assert inn.residual is nu and inn.meas_cov is R


def test_batched_update_equals_one_update_per_entry() -> None:
    x, P, nu, H, R = _problem(np.random.default_rng(1), batch=(3, 2))
    mean, cov, inn = kalman_update(x, P, nu, H, R)
    assert mean.shape == (3, 2, 4) and cov.shape == (3, 2, 4, 4) and inn.nis.shape == (3, 2)  # type: ignore[union-attr]
    for idx in np.ndindex(3, 2):
        one = kalman_update(x[idx], P[idx], nu[idx], H[idx], R[idx])
        np.testing.assert_allclose(mean[idx], one[0], atol=1e-13)
        np.testing.assert_allclose(cov[idx], one[1], atol=1e-13)
        assert inn.nis[idx] == pytest.approx(float(one[2].nis), rel=1e-13)  # type: ignore[index]


@settings(derandomize=True, max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), n=st.integers(1, 6), m=st.integers(1, 4))
def test_joseph_form_stays_symmetric_and_never_adds_uncertainty(seed: int, n: int, m: int) -> None:
    x, P, nu, H, R = _problem(np.random.default_rng(seed), n=n, m=m)
    _, cov, inn = kalman_update(x, P, nu, H, R)
    np.testing.assert_array_equal(cov, cov.T)
    scale = float(np.abs(P).max())
    assert np.linalg.eigvalsh(cov).min() > -1e-10 * scale
    assert np.linalg.eigvalsh(P - cov).min() > -1e-9 * scale  # P⁺ ≤ P⁻
    assert float(inn.nis) >= 0.0


def test_an_innovation_covariance_that_is_not_positive_definite_names_the_place() -> None:
    with pytest.raises(ModelError, match="not positive definite at pair 1-2"):
        kalman_update(
            np.zeros(4), -np.eye(4), np.zeros(3), np.eye(3, 4), np.zeros((3, 3)), where="pair 1-2"
        )
    with pytest.raises(ModelError, match="not positive definite at block 3"):
        gated_update(
            np.zeros(2), -np.eye(2), np.zeros(2), np.eye(2), np.zeros((2, 2)), 0.9, where="block 3"
        )


def test_chi2_threshold_matches_scipy_is_cached_and_rejects_bad_input() -> None:
    for dim, p in ((1, 0.95), (2, 0.99), (4, 0.9), (3, 0.999)):
        assert chi2_threshold(dim, p) == pytest.approx(chi2.ppf(p, dim), rel=1e-15)
    hits = chi2_threshold.cache_info().hits
    chi2_threshold(2, 0.99)
    assert chi2_threshold.cache_info().hits == hits + 1
    with pytest.raises(ConfigError, match="probability"):
        chi2_threshold(2, 1.0)
    with pytest.raises(ConfigError, match="probability"):
        chi2_threshold(2, 0.0)
    with pytest.raises(ConfigError, match="dim"):
        chi2_threshold(0, 0.5)


def _unit_s(residual: list[float]):  # type: ignore[no-untyped-def]
    """A 2-D block with ``S = I``, so that ``NIS = ‖ν‖²``."""
    return np.array([1.0, -1.0]), 0.5 * np.eye(2), np.array(residual), np.eye(2), 0.5 * np.eye(2)


def test_gate_accepts_up_to_the_threshold_and_then_equals_the_update() -> None:
    gamma = chi2_threshold(2, 0.95)
    inside = _unit_s([np.sqrt(gamma - 1e-6), 0.0])
    mean, cov, inn, accepted = gated_update(*inside, 0.95, where="range")
    assert accepted and inn.nis == pytest.approx(gamma - 1e-6)
    ref_mean, ref_cov, ref_inn = kalman_update(*inside)
    np.testing.assert_array_equal(mean, ref_mean)  # the same arithmetic, bit for bit
    np.testing.assert_array_equal(cov, ref_cov)
    np.testing.assert_array_equal(inn.cov, ref_inn.cov)
    assert inn.nis == float(ref_inn.nis)


def test_gate_rejects_beyond_the_threshold_without_computing_the_update(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    outside = _unit_s([np.sqrt(chi2_threshold(2, 0.95) + 1e-6), 0.0])
    x, P = outside[0], outside[1]

    def no_update(*_: object) -> None:
        raise AssertionError("the update of a rejected block was computed")

    monkeypatch.setattr(kalman, "_correct", no_update)
    mean, cov, inn, accepted = gated_update(*outside, 0.95)
    assert not accepted and mean is x and cov is P
    assert inn.nis == pytest.approx(chi2_threshold(2, 0.95) + 1e-6)


def test_no_gate_probability_always_updates() -> None:
    far = _unit_s([30.0, -40.0])
    mean, _, inn, accepted = gated_update(*far, None)
    assert accepted and inn.nis == pytest.approx(2500.0)
    np.testing.assert_array_equal(mean, kalman_update(*far)[0])


def test_gated_update_takes_one_block() -> None:
    x, P, nu, H, R = _problem(np.random.default_rng(2), batch=(2,))
    with pytest.raises(ModelError, match="one block"):
        gated_update(x, P, nu, H, R, 0.9, where="batch")
