"""Closed forms of the plane geometry helpers: the triangle bearing of a 3-4-5 triangle and its
derivatives against finite differences (both sides), the inclusive collinearity limit,
classical MDS on a known configuration (asymmetric and missing distances, a non-Euclidean
matrix), and the rigid alignment of a rotated, translated and of a mirrored point set."""

from __future__ import annotations

import math

import numpy as np
import pytest

from relloc.geometry.multilateration import (
    classical_mds,
    fill_by_shortest_paths,
    rigid_alignment,
)
from relloc.geometry.triangle import triangle_bearing


def _pairwise(X: np.ndarray) -> np.ndarray:
    return np.linalg.norm(X[:, None, :] - X[None, :, :], axis=-1)


@pytest.mark.parametrize("side", [1, -1])
def test_right_triangle_bearing_and_its_derivatives(side: int) -> None:
    # a = d_0j = 3, b = d_0i = 4, c = d_ij = 5: the angle at R_0 is a right angle
    got = triangle_bearing(0.3, 3.0, 4.0, 5.0, side)
    assert got.ok
    assert got.interior_angle == pytest.approx(math.pi / 2)
    assert got.bearing == pytest.approx(0.3 + side * math.pi / 2)
    args = np.array([0.3, 3.0, 4.0, 5.0])
    eps = 1e-6
    for k in range(4):
        d = np.zeros(4)
        d[k] = eps
        hi = triangle_bearing(*(args + d), side).bearing
        lo = triangle_bearing(*(args - d), side).bearing
        assert got.d_bearing[k] == pytest.approx((hi - lo) / (2 * eps), abs=1e-7)


def test_collinearity_limit_is_inclusive() -> None:
    # equilateral triangle: sin α_0 = sin 60°; a threshold equal to it is not "below" it
    alpha = math.acos(0.5)
    got = triangle_bearing(0.0, 2.0, 2.0, 2.0, 1, min_sin=math.sin(alpha))
    assert got.ok
    assert got.bearing == pytest.approx(math.pi / 3)


def test_measured_distances_are_kept_even_where_a_path_through_others_is_shorter() -> None:
    # 0–2 measured 3 m, but 0–1–2 is 2 m: only missing entries are filled, so the measured 3
    # stays, and MDS in 1-D fits it (points at −1.5, 0, 1.5: 0–2 is 3 m, not the path's 2 m)
    D = np.array([[0.0, 1.0, 3.0], [1.0, 0.0, 1.0], [3.0, 1.0, 0.0]])
    np.testing.assert_array_equal(fill_by_shortest_paths(D), D)
    gapped = D.copy()
    gapped[1, 2] = gapped[2, 1] = np.nan
    filled = fill_by_shortest_paths(gapped)
    assert filled[1, 2] == filled[2, 1] == 4.0 and filled[0, 2] == 3.0
    X = classical_mds(D, dim=1)
    assert abs(X[0, 0] - X[2, 0]) == pytest.approx(3.0)


def test_mds_recovers_distances_from_asymmetric_and_missing_readings() -> None:
    X = np.array([[0.0, 0.0], [4.0, 0.0], [4.0, 3.0], [1.0, 5.0]])
    D = _pairwise(X)
    noisy = D.copy()
    noisy[0, 2] += 0.2  # the two directions of one link disagree; their mean is the truth
    noisy[2, 0] -= 0.2
    np.testing.assert_allclose(_pairwise(classical_mds(noisy)), D, atol=1e-9)
    # collinear chain 0–1–2 at x = 0, 1, 3 with the long link missing: filled by the path
    chain = np.array([[0.0, 1.0, np.nan], [1.0, 0.0, 2.0], [np.nan, 2.0, 0.0]])
    np.testing.assert_allclose(fill_by_shortest_paths(chain)[0, 2], 3.0)
    np.testing.assert_allclose(
        _pairwise(classical_mds(chain, dim=1)), [[0, 1, 3], [1, 0, 2], [3, 2, 0]], atol=1e-9
    )


def test_mds_drops_negative_eigen_directions_of_a_non_euclidean_metric() -> None:
    # a star: centre 1 m from three leaves that are 2 m apart. A metric (no shortest path is
    # shorter), but not Euclidean — the centre cannot be the midpoint of three pairs — so
    # B = −½ J D² J has a negative eigenvalue; that direction has no real coordinate: zero
    D = np.array([[0, 1, 1, 1], [1, 0, 2, 2], [1, 2, 0, 2], [1, 2, 2, 0]], dtype=float)
    X = classical_mds(D, dim=4)
    assert X.shape == (4, 4)
    np.testing.assert_allclose(X[:, 3], 0.0, atol=1e-12)
    # the two positive eigenvalues (2 and 2) carry the leaves' spread: Σ‖x_i − x̄‖² = 4
    assert np.sum(X[:, :2] ** 2) == pytest.approx(4.0)


def test_rigid_alignment_of_a_rotated_and_translated_set() -> None:
    rng = np.random.default_rng(4)
    a = rng.normal(size=(6, 2))
    th = 0.7
    R_true = np.array([[math.cos(th), -math.sin(th)], [math.sin(th), math.cos(th)]])
    b = a @ R_true.T + [2.0, -1.0]
    R, t = rigid_alignment(a, b)
    np.testing.assert_allclose(R, R_true, atol=1e-12)
    np.testing.assert_allclose(t, [2.0, -1.0], atol=1e-12)


def test_rigid_alignment_of_a_mirror_image_flips_the_thin_direction() -> None:
    # spread 10 along x, 0.1 along y; b is a mirrored in y. The best proper rotation keeps x
    # (identity, error 2·Σ y²); rotating by π would cost 2·Σ x²
    a = np.array([[-10.0, 0.1], [10.0, 0.1], [-10.0, -0.1], [10.0, -0.1]]) + np.array([3.0, 1.0])
    b = a * [1.0, -1.0]
    R, t = rigid_alignment(a, b)
    np.testing.assert_allclose(R, np.eye(2), atol=1e-12)
    np.testing.assert_allclose(t, [0.0, -2.0], atol=1e-12)  # centroid (3, 1) onto (3, −1)
    R_m, _ = rigid_alignment(a, b, reflection=True)
    np.testing.assert_allclose(R_m, np.diag([1.0, -1.0]), atol=1e-12)
