"""Hand-derived facts about the motion/measurement models that the other model tests leave free:
the sinc series against 50-digit arithmetic, the air-ground process noise against a
finite-difference input map, exact symmetry of ``G Σ Gᵀ``, the near-zero range Jacobian, the
angle flags of each switching mode, the planar coincidence guard, the zero second block of a
landmark row, and the stationary start of the UWB Gauss–Markov core."""

import mpmath
import numpy as np
import pytest

from relloc.errors import ModelError
from relloc.models import airground as ag
from relloc.models.motion import VelocityNoise, process_noise, sinc_and_derivative
from relloc.models.planar_measurement import (
    RowKind,
    ScalarRows,
    bearing,
    linearise_rows,
)
from relloc.models.uwb_noise import UwbNoiseModel, sample_range_errors


def _mp_sinc(a: float) -> tuple[float, float]:
    with mpmath.workdps(50):
        x = mpmath.mpf(a)
        s = mpmath.sin(x) / x
        d = (x * mpmath.cos(x) - mpmath.sin(x)) / (x * x)
        return float(s), float(d)


@pytest.mark.parametrize("a", [3e-4, -6e-4, 9.99e-4, -9.99e-4])
def test_sinc_series_branch_is_accurate_to_double_precision(a: float) -> None:
    # below SINC_SERIES_LIMIT the series is used; its truncation error is far below 1e-15
    s, d = sinc_and_derivative(np.array([a]))
    s_ref, d_ref = _mp_sinc(a)
    assert abs(s[0] - s_ref) <= 1e-15 * abs(s_ref)
    assert abs(d[0] - d_ref) <= 1e-13 * abs(d_ref)


def test_sinc_closed_branch_matches_high_precision() -> None:
    for a in (2e-3, 0.3, -1.7):
        s, d = sinc_and_derivative(np.array([a]))
        s_ref, d_ref = _mp_sinc(a)
        assert abs(s[0] - s_ref) <= 1e-15 * abs(s_ref)
        assert abs(d[0] - d_ref) <= 1e-9 * abs(d_ref)


def test_relative_process_noise_is_exactly_symmetric() -> None:
    rng = np.random.default_rng(3)
    G = rng.normal(size=(20, 4, 8))
    noise = VelocityNoise(observer=(0.3, 0.2, 0.1, 0.05), observed=(0.4, 0.25, 0.15, 0.07))
    Q = process_noise(G, noise)
    assert np.array_equal(Q, np.swapaxes(Q, -1, -2))


def test_airground_process_noise_maps_input_noise_through_the_step() -> None:
    # Q = G diag(σv², σω², σv², σω²) Gᵀ with G = ∂x⁺/∂u taken here by central differences
    x = np.array([1.3, -0.7, 0.4, -1.1])
    u = np.array([0.8, 0.6, 1.1, -0.9])  # v_i, ω_i, v_0, ω_0
    dt, sv, sw = 0.25, 0.3, 0.05
    eps = 1e-6
    G = np.empty((4, 4))
    for j in range(4):
        d = np.zeros(4)
        d[j] = eps
        G[:, j] = (ag.relative_step(x, u + d, dt) - ag.relative_step(x, u - d, dt)) / (2 * eps)
    expected = G @ np.diag([sv**2, sw**2, sv**2, sw**2]) @ G.T
    F, Q = ag.process_noise(x, u, dt, sv, sw)
    np.testing.assert_allclose(Q, expected, rtol=1e-6, atol=1e-12)
    F_fd = np.empty((4, 4))
    for j in range(4):
        d = np.zeros(4)
        d[j] = eps
        F_fd[:, j] = (ag.relative_step(x + d, u, dt) - ag.relative_step(x - d, u, dt)) / (2 * eps)
    np.testing.assert_allclose(F, F_fd, atol=1e-8)


def test_airground_range_jacobian_is_the_unit_vector_even_very_close() -> None:
    d, H = ag.range_h(np.array([3e-4, 4e-4, 0.2, 0.1]))
    assert d == pytest.approx(5e-4)
    np.testing.assert_allclose(H[0], [0.6, 0.8, 0.0, 0.0], rtol=1e-12)


def test_airground_mode_angle_flags_follow_the_components() -> None:
    x = np.array([1.0, 2.0, 0.3, -0.4])
    # sw=1: d, φ, θ_i, θ_0; sw=2: d, φ̄, θ_0; sw=3: d — every component but d is an angle
    assert ag.mode_measurement(x, ag.Mode.PAIR_SEEN)[2] == (False, True, True, True)
    z, _, angles = ag.mode_measurement(x, ag.Mode.OTHER_PAIR_SEEN)
    assert angles == (False, True, True)
    assert z[2] == pytest.approx(-0.4)
    assert ag.mode_measurement(x, ag.Mode.NONE_SEEN)[2] == (False,)


def test_planar_bearing_refuses_targets_within_a_micrometre() -> None:
    observer = np.array([1.0, 2.0, 0.3])
    with pytest.raises(ModelError, match="coincide"):
        bearing(observer, np.array([1.0 + 5e-7, 2.0]))
    # 10 µm apart is a valid (if extreme) geometry: bearing along +x minus the heading
    assert float(bearing(observer, np.array([1.0 + 1e-5, 2.0]))) == pytest.approx(-0.3)


def test_landmark_row_has_an_empty_second_block() -> None:
    # a landmark row touches only its observer: its second block must be zero, since
    # information-form consumers scatter both blocks (index −1 clipped to robot 0)
    X = np.array([[0.0, 0.0, 0.1], [2.0, 1.0, -0.4], [-1.0, 3.0, 0.7]])
    rows = ScalarRows(
        kind=np.array([RowKind.BEARING, RowKind.RANGE, RowKind.BEARING]),
        observer=np.array([1, 2, 2]),
        target=np.array([-1, -1, 0]),
        landmark_xy=np.array([[5.0, -2.0], [4.0, 4.0], [0.0, 0.0]]),
        z=np.zeros(3),
        sigma=np.ones(3),
        group=np.arange(3),
    )
    lin = linearise_rows(X, rows)
    np.testing.assert_array_equal(lin.block_index[:, 1], [-1, -1, 0])
    np.testing.assert_array_equal(lin.blocks[:2, 1, :], np.zeros((2, 3)))
    # landmark bearing from robot 1: ∂η/∂(x, y, ψ) = (Δy/q, −Δx/q, −1), Δ = (3, −3), q = 18
    np.testing.assert_allclose(lin.blocks[0, 0], [-3 / 18, -3 / 18, -1.0])


def test_uwb_core_starts_from_its_stationary_spread() -> None:
    # a nearly frozen Gauss–Markov core (τ ≫ dt): the first reading of each link must already
    # have the stationary σ = spread, not start at zero
    model = UwbNoiseModel(
        bias=0.0, spread=0.2, outlier_rate=0.0, outlier_excess_mean=0.1, correlation_time=1e6
    )
    e = sample_range_errors(model, 1, 4000, 0.01, np.random.default_rng(5))
    assert e.shape == (1, 4000)
    assert np.std(e) == pytest.approx(0.2, rel=0.06)
