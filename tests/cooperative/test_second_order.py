"""Second-order bearing/range terms: the Hessians are those of the measurement functions, the
mean and variance match sampling where the expansion holds, a row whose linearisation fails
is de-weighted, and the Jacobians (their null space) are left alone."""

import numpy as np
import pytest

from relloc.estimators.second_order import (
    relative_position_covariance,
    relative_position_hessians,
    second_order_rows,
)
from relloc.models.planar_measurement import RowKind, ScalarRows, bearing, linearise_rows
from relloc.models.planar_measurement import planar_range as range_of


def _rows(kind, observer, target, landmark_xy=None, z=0.0, sigma=0.1):
    m = len(kind)
    return ScalarRows(
        kind=np.asarray(kind, dtype=np.int64),
        observer=np.asarray(observer, dtype=np.int64),
        target=np.asarray(target, dtype=np.int64),
        landmark_xy=np.zeros((m, 2)) if landmark_xy is None else np.asarray(landmark_xy, float),
        z=np.full(m, z),
        sigma=np.full(m, sigma),
        group=np.arange(m, dtype=np.int64),
    )


@pytest.mark.parametrize("d", [(3.0, 1.0), (-2.0, 5.0), (0.5, -4.0)])
def test_hessians_match_finite_differences(d):
    d = np.array(d)
    Hb, Hr = relative_position_hessians(d[None])
    origin = np.zeros(3)
    eps = 1e-4
    for f, H in ((lambda x: bearing(origin, x), Hb[0]), (lambda x: range_of(origin, x), Hr[0])):
        fd = np.zeros((2, 2))
        for a in range(2):
            for b in range(2):
                ea, eb = np.eye(2)[a] * eps, np.eye(2)[b] * eps
                fd[a, b] = (f(d + ea + eb) - f(d + ea - eb) - f(d - ea + eb) + f(d - ea - eb)) / (
                    4 * eps * eps
                )
        assert H == pytest.approx(fd, abs=1e-5)


def test_relative_position_covariance_of_robot_and_landmark_targets():
    rng = np.random.default_rng(3)
    A = rng.normal(size=(6, 6))
    P = A @ A.T
    Pd = relative_position_covariance(P, np.array([0, 1]), np.array([1, -1]))
    J = np.zeros((2, 6))
    J[:, 3:5], J[:, 0:2] = np.eye(2), -np.eye(2)
    assert Pd[0] == pytest.approx(J @ P @ J.T)
    assert Pd[1] == pytest.approx(P[3:5, 3:5])


def test_mean_and_variance_match_sampling_where_the_expansion_holds():
    # seed 41: not used while developing the second-order terms
    rng = np.random.default_rng(41)
    X = np.array([[0.0, 0.0, 0.2], [8.0, 0.5, 0.0]])
    P = np.diag([0.5, 0.5, 1e-6, 0.8, 0.8, 1e-6])
    P[0, 1] = P[1, 0] = 0.3  # correlated x, y: the bearing's second-order mean is not zero
    P[3, 4] = P[4, 3] = 0.5
    rows = _rows([RowKind.BEARING, RowKind.RANGE], [0, 0], [1, 1])
    lin = linearise_rows(X, rows)
    out = second_order_rows(lin, rows, X, P)
    samples = rng.multivariate_normal(X.reshape(-1), P, size=1_000_000).reshape(-1, 2, 3)
    d = samples[:, 1, :2] - samples[:, 0, :2]
    eta = np.arctan2(d[:, 1], d[:, 0]) - samples[:, 0, 2]
    rho = np.hypot(d[:, 0], d[:, 1])
    J = np.zeros((2, 6))
    for r in range(2):
        J[r, 0:3], J[r, 3:6] = lin.blocks[r, 0], lin.blocks[r, 1]
    linear_var = np.diag(J @ P @ J.T)
    excess, extra_var = np.zeros(2), np.zeros(2)
    for r, values in enumerate((eta, rho)):
        h0 = rows.z[r] - lin.residual[r]
        # the second-order mean is the mean the linearisation misses
        assert np.mean(values) - h0 == pytest.approx(lin.residual[r] - out.residual[r], rel=0.05)
        excess[r] = np.var(values) - linear_var[r]
        extra_var[r] = out.sigma[r] ** 2 - lin.sigma[r] ** 2
    # the bearing's variance beyond the linear one: the quadratic term carries a good part of
    # it (the rest is fourth-order: first × third derivatives)
    assert 0.3 * excess[0] < extra_var[0] < excess[0]
    # the range's fourth-order terms reduce its variance here; the quadratic term's variance
    # is added regardless, so a range row is de-weighted, never over-weighted
    assert excess[1] < 0 < extra_var[1]


def test_a_row_the_linearisation_fails_on_is_de_weighted_and_jacobians_stay():
    X = np.array([[0.0, 0.0, 0.0], [6.0, 0.0, 0.0], [60.0, 0.0, 0.0]])
    P = np.diag(np.tile([25.0, 25.0, 0.04], 3))
    rows = _rows(
        [RowKind.BEARING, RowKind.BEARING, RowKind.BEARING, RowKind.POSE_X],
        [0, 0, 0, 0],
        [1, 2, -1, -1],
        landmark_xy=[[0, 0], [0, 0], [0.0, 600.0], [0, 0]],
    )
    lin = linearise_rows(X, rows)
    out = second_order_rows(lin, rows, X, P)
    # s/ρ ≈ 1.2 at 6 m: the extra variance (s²/q)² ≈ 1.9 rad² swamps σ² = 0.01 rad²
    assert out.sigma[0] ** 2 == pytest.approx(0.01 + (50.0 / 36.0) ** 2, rel=1e-9)
    # s/ρ ≈ 0.12 at 60 m: a small share; a far landmark (P_d = P_oo): smaller still
    assert out.sigma[1] ** 2 == pytest.approx(0.01 + (50.0 / 3600.0) ** 2, rel=1e-9)
    assert out.sigma[2] ** 2 - 0.01 < out.sigma[1] ** 2 - 0.01
    assert out.sigma[3] == lin.sigma[3] and out.residual[3] == lin.residual[3]
    # isotropic P_d: the bearing's second-order mean vanishes
    assert out.residual[:2] == pytest.approx(lin.residual[:2])
    np.testing.assert_array_equal(out.blocks, lin.blocks)
    np.testing.assert_array_equal(out.block_index, lin.block_index)
