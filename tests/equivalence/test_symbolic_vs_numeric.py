"""The numeric models agree with the SymPy definitions in relloc.models.symbolic.

Continuous rates and measurement functions/Jacobians are compared at random states. Discrete
steps are compared with an accurate ODE integration of the *symbolic* rate (and its variational
equations for ``F = ∂x⁺/∂x``, ``G = ∂x⁺/∂u``): exactly for the zero-order-hold relative model,
and by their order of accuracy for the midpoint models.
"""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp

from relloc.core.angles import wrap_angle
from relloc.models import airground, measurement, motion, planar_measurement, unicycle
from relloc.models import symbolic as S

RNG_SEED = 1234


def _rate_functions(model: S.SymbolicModel):
    f = model.rate()
    X, U = sp.Matrix(model.states), sp.Matrix(model.inputs)
    return (
        model.lambdify(f, with_inputs=True),
        model.lambdify(f.jacobian(X), with_inputs=True),
        model.lambdify(f.jacobian(U), with_inputs=True),
    )


def _integrate(model: S.SymbolicModel, x0: np.ndarray, u: np.ndarray, dt: float):
    """x(dt), Φ = ∂x(dt)/∂x0 and Ψ = ∂x(dt)/∂u for constant u (variational equations)."""
    f, A, B = _rate_functions(model)
    n, q = model.n, len(model.inputs)
    c = [0.0] * len(model.parameters)  # parameters enter the outputs only

    def rhs(_t: float, z: np.ndarray) -> np.ndarray:
        x = z[:n]
        Phi = z[n : n + n * n].reshape(n, n)
        Psi = z[n + n * n :].reshape(n, q)
        Ax = np.asarray(A(list(x), list(u), c), float)
        Bx = np.asarray(B(list(x), list(u), c), float)
        dx = np.asarray(f(list(x), list(u), c), float).reshape(n)
        return np.concatenate([dx, (Ax @ Phi).ravel(), (Ax @ Psi + Bx).ravel()])

    z0 = np.concatenate([x0, np.eye(n).ravel(), np.zeros(n * q)])
    sol = solve_ivp(rhs, (0.0, dt), z0, rtol=1e-11, atol=1e-12, method="DOP853")
    z = sol.y[:, -1]
    return z[:n], z[n : n + n * n].reshape(n, n), z[n + n * n :].reshape(n, q)


def _random_relative(rng: np.random.Generator):
    x = np.array([*rng.uniform(-5, 5, 3), rng.uniform(-np.pi, np.pi)])
    u_l = np.array([*rng.uniform(-1, 1, 3), rng.uniform(-0.8, 0.8)])
    u_c = np.array([*rng.uniform(-1, 1, 3), rng.uniform(-0.8, 0.8)])
    return x, u_l, u_c


def test_relative_rate_matches_symbolic() -> None:
    rng = np.random.default_rng(RNG_SEED)
    model = S.relative_nonlinear()
    f = model.lambdify(model.rate(), with_inputs=True)
    for _ in range(20):
        x, u_l, u_c = _random_relative(rng)
        expected = np.asarray(f(list(x), [*u_l, *u_c], []), float).reshape(4)
        np.testing.assert_allclose(motion.relative_derivative(x, u_l, u_c), expected, atol=1e-12)


def test_relative_zoh_step_and_jacobians_match_integrated_symbolic_model() -> None:
    rng = np.random.default_rng(RNG_SEED + 1)
    model = S.relative_nonlinear()
    for dt in (0.05, 0.5):
        x, u_l, u_c = _random_relative(rng)
        x_ref, Phi, Psi = _integrate(model, x, np.concatenate([u_l, u_c]), dt)
        np.testing.assert_allclose(motion.relative_step(x, u_l, u_c, dt), x_ref, atol=1e-8)
        F, G = motion.relative_jacobians(x, u_l, u_c, dt)
        np.testing.assert_allclose(F, Phi, atol=1e-8)
        np.testing.assert_allclose(G, Psi, atol=1e-8)


def test_range_azimuth_elevation_and_jacobian_match_symbolic() -> None:
    rng = np.random.default_rng(RNG_SEED + 2)
    model = S.relative_nonlinear()
    h = model.lambdify(model.output_matrix())
    H = model.lambdify(model.output_jacobian())
    for _ in range(20):
        x = np.array([*rng.uniform(-5, 5, 3), rng.uniform(-np.pi, np.pi)])
        np.testing.assert_allclose(
            measurement.range_bearing(x), np.asarray(h(list(x), []), float).reshape(3), atol=1e-12
        )
        np.testing.assert_allclose(
            measurement.range_bearing_jacobian(x), np.asarray(H(list(x), []), float), atol=1e-12
        )


def test_pseudo_linear_matrix_matches_symbolic_rows() -> None:
    rng = np.random.default_rng(RNG_SEED + 3)
    model = S.relative_pseudo_linear()
    H = model.lambdify(model.output_jacobian())
    for _ in range(20):
        z = np.array([rng.uniform(0.5, 5), rng.uniform(-np.pi, np.pi), rng.uniform(-1.2, 1.2)])
        expected = np.asarray(H([0.0] * 4, list(z[1:])), float)
        np.testing.assert_allclose(measurement.pseudo_linear_matrix(z), expected, atol=1e-12)
        # at the true bearings the pseudo-linear rows give [r, 0, 0]
        p = z[0] * np.array(
            [np.cos(z[1]) * np.cos(z[2]), np.sin(z[1]) * np.cos(z[2]), np.sin(z[2])]
        )
        np.testing.assert_allclose(expected[:, :3] @ p, [z[0], 0.0, 0.0], atol=1e-12)


def _midpoint_order(step, model: S.SymbolicModel, x: np.ndarray, u: np.ndarray) -> float:
    errs = []
    for dt in (0.2, 0.1):
        x_ref, _, _ = _integrate(model, x, u, dt)
        diff = step(x, u, dt) - x_ref
        errs.append(np.linalg.norm(diff))
    return errs[0] / errs[1]


@pytest.mark.parametrize("which", ["unicycle", "airground"])
def test_midpoint_steps_are_third_order_accurate_versions_of_the_symbolic_rate(which: str) -> None:
    if which == "unicycle":
        model = S.unicycle_landmarks(1)
        x = np.array([1.0, -2.0, 0.4])
        u = np.array([1.5, 0.9])
        step = unicycle.unicycle_step
    else:
        model = S.airground_follower(1)
        x = np.array([3.0, -1.0, 0.3, -0.7])
        u = np.array([1.2, 0.8, 0.9, -0.6])
        step = airground.relative_step
    ratio = _midpoint_order(step, model, x, u)
    assert 6.0 < ratio < 10.0  # local error O(dt³): halving dt divides it by ≈ 8


def test_planar_bearing_and_range_match_symbolic() -> None:
    rng = np.random.default_rng(RNG_SEED + 5)
    xi, yi, pi, xj, yj = sp.symbols("xi yi pi xj yj")
    eta = S.planar_bearing(xi, yi, pi, xj, yj)
    rho = S.planar_range(xi, yi, xj, yj)
    args = [xi, yi, pi, xj, yj]
    f = sp.lambdify(
        args, [eta, rho, *[sp.diff(eta, a) for a in args], *[sp.diff(rho, a) for a in args]]
    )
    for _ in range(20):
        obs = np.array([*rng.uniform(-10, 10, 2), rng.uniform(-np.pi, np.pi)])
        tgt = rng.uniform(-10, 10, 2)
        vals = np.array(f(*obs, *tgt), dtype=float)
        assert abs(wrap_angle(planar_measurement.bearing(obs, tgt) - vals[0])) < 1e-12
        assert abs(planar_measurement.planar_range(obs, tgt) - vals[1]) < 1e-12
        Bo, Bt = planar_measurement.bearing_jacobians(obs, tgt)
        Ro, Rt = planar_measurement.range_jacobians(obs, tgt)
        np.testing.assert_allclose(np.concatenate([Bo, Bt]), vals[2:7], atol=1e-12)
        np.testing.assert_allclose(np.concatenate([Ro, Rt]), vals[7:12], atol=1e-12)


@pytest.mark.parametrize("mode", [1, 2, 3])
def test_airground_measurement_modes_match_symbolic(mode: int) -> None:
    rng = np.random.default_rng(RNG_SEED + 6 + mode)
    model = S.airground_follower(mode)
    h = model.lambdify(model.output_matrix())
    H = model.lambdify(model.output_jacobian())
    for _ in range(10):
        x = np.array([*rng.uniform(-8, 8, 2), *rng.uniform(-np.pi, np.pi, 2)])
        z, Hn, _ = airground.mode_measurement(x, airground.Mode(mode))
        np.testing.assert_allclose(z, np.asarray(h(list(x), []), float).reshape(-1), atol=1e-12)
        np.testing.assert_allclose(Hn, np.asarray(H(list(x), []), float), atol=1e-12)
