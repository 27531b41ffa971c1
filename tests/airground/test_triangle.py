"""Triangle bearing of Fig. 3 (seed 003): exact on exact data in both half-planes; refusals."""

import math

import numpy as np
import pytest

from relloc.core.angles import angle_diff
from relloc.errors import ConfigError
from relloc.geometry import side_of, triangle_bearing


def _bearing(frm, to):
    d = np.asarray(to) - np.asarray(frm)
    return math.atan2(d[1], d[0])


def _derive(p0, pj, pi, **kw):
    return triangle_bearing(
        _bearing(pj, p0),
        float(np.hypot(*(p0 - pj))),
        float(np.hypot(*(p0 - pi))),
        float(np.hypot(*(pi - pj))),
        side_of(tuple(p0), tuple(pj), tuple(pi)),
        **kw,
    )


@pytest.mark.parametrize("sign", [1, -1])
def test_exact_bearing_in_both_half_planes(sign):
    rng = np.random.default_rng(3)
    checked = 0
    for _ in range(200):
        p0, pj = rng.uniform(-3, 3, size=(2, 2))
        # put R_i on the requested side of the line R_0 -> R_j
        along = rng.uniform(-1.0, 2.0)
        off = sign * rng.uniform(0.3, 2.0)
        u = (pj - p0) / np.hypot(*(pj - p0))
        pi = p0 + along * (pj - p0) + off * np.array([-u[1], u[0]])
        assert side_of(tuple(p0), tuple(pj), tuple(pi)) == sign
        res = _derive(p0, pj, pi, min_sin=0.05)
        if not res.ok:
            assert "near-collinear" in res.reason
            continue
        assert abs(angle_diff(res.bearing, _bearing(pi, p0))) < 1e-9
        checked += 1
    assert checked > 150


def test_paper_form_matches_interior_angles():
    # β_i = β_j + π − α_1 − α_2 (paper) equals φ_j + α_0 for R_i on the left side.
    p0, pj, pi = np.array([0.0, 0.0]), np.array([-1.0, -0.5]), np.array([-0.8, 0.7])

    def angle_at(a, b, c):
        v1, v2 = b - a, c - a
        return math.acos(v1 @ v2 / (np.hypot(*v1) * np.hypot(*v2)))

    alpha1, alpha2 = angle_at(pj, p0, pi), angle_at(pi, p0, pj)
    res = _derive(p0, pj, pi)
    paper = _bearing(pj, p0) + side_of(tuple(p0), tuple(pj), tuple(pi)) * (
        math.pi - alpha1 - alpha2
    )
    assert abs(angle_diff(res.bearing, paper)) < 1e-12
    assert abs(angle_diff(res.bearing, _bearing(pi, p0))) < 1e-12


def test_refuses_near_collinear_with_reason():
    p0, pj = np.array([0.0, 0.0]), np.array([1.0, 0.0])
    for pi in (np.array([2.0, 0.05]), np.array([-1.0, 0.02])):
        res = _derive(p0, pj, pi)
        assert not res.ok and res.bearing is None
        assert "near-collinear" in res.reason and "angle at R_0" in res.reason


def test_refuses_broken_triangle_and_bad_input():
    res = triangle_bearing(0.3, 1.0, 1.0, 2.5, 1)
    assert not res.ok and "triangle inequality" in res.reason
    res = triangle_bearing(float("nan"), 1.0, 1.0, 1.0, 1)
    assert not res.ok and "phi_j" in res.reason
    res = triangle_bearing(0.0, 0.0, 1.0, 1.0, 1)
    assert not res.ok and "non-positive" in res.reason
    with pytest.raises(ConfigError, match="side"):
        triangle_bearing(0.0, 1.0, 1.0, 1.0, 0)


def test_partial_derivatives_match_finite_differences():
    args = (0.4, 1.3, 0.9, 1.1)
    res = triangle_bearing(*args, -1)
    eps = 1e-7
    for k in range(4):
        bumped = list(args)
        bumped[k] += eps
        num = angle_diff(triangle_bearing(*bumped, -1).bearing, res.bearing) / eps
        assert num == pytest.approx(res.d_bearing[k], rel=1e-5, abs=1e-6)
