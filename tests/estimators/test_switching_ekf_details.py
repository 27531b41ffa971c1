"""Switching EKF (seed 003), details the other tests leave free: the covariance of the
triangle block, the choice of the best-conditioned triangle, the range bias, the leader-heading
block, the conditioning record of S and pair sightings of the leader."""

import math
from dataclasses import replace

import numpy as np
import pytest

from relloc.core.contract import HeldOdometry
from relloc.core.gaussian import Gaussian
from relloc.core.linalg import condition_log10
from relloc.core.recording import Measurements, measurement_rows
from relloc.estimators.switching_ekf import SwitchingEkf, SwitchingEkfSettings
from relloc.geometry.triangle import triangle_bearing
from relloc.models.airground import Mode

SETTINGS = SwitchingEkfSettings(
    range_sigma=0.05, bearing_sigma=0.03, heading_sigma=0.02, sighting_hold=0.05
)
ROBOTS = ("R_0", "R_1", "R_2", "R_3", "D_1")
#: Leader at the origin; R_2 makes a well-conditioned triangle with R_1 (angle at R_0 ≈ 51°,
#: sides of unequal length), R_3 a thin one (≈ 17°); R_1 is left of both rays R_0→R_j.
POS = {0: (0.0, 0.0), 1: (-0.6, -0.3), 2: (-0.9, 0.4), 3: (-1.2, -0.2)}
SIDES = {"R_2": 1, "R_3": 1}
PRIOR_COV = np.diag([0.04, 0.04, 0.01, 0.01])


def _dist(a, b):
    return math.hypot(POS[a][0] - POS[b][0], POS[a][1] - POS[b][1])


def _x(j):
    """Follower R_j's state: p_0 − p_j, headings 0."""
    return np.array([POS[0][0] - POS[j][0], POS[0][1] - POS[j][1], 0.0, 0.0])


def _filter(settings=SETTINGS, x0=None, robots=ROBOTS):
    x0 = _x(1) + np.array([0.05, -0.04, 0.0, 0.0]) if x0 is None else x0
    return SwitchingEkf(
        robots=robots,
        owner="R_1",
        leader="R_0",
        prior=Gaussian(x0, PRIOR_COV),
        settings=settings,
        sides=SIDES,
    )


def _ranges(pairs, bias=0.0):
    obs, tgt = zip(*pairs, strict=True)
    d = [_dist(a, b) + bias for a, b in pairs]
    return measurement_rows("range", t=np.zeros(len(pairs)), observer=obs, target=tgt, value=d)


def _sighting(j, heading_follower=0.0, heading_leader=0.0):
    x = _x(j)
    value = [[math.atan2(x[1], x[0]), heading_follower, heading_leader]]
    return measurement_rows("pair_sighting", t=np.zeros(1), observer=4, target=j, value=value)


PAIRS = [(0, 1), (0, 2), (1, 2), (0, 3), (1, 3)]


def _triangle_run(sightings, settings=SETTINGS, bias=0.0):
    f = _filter(settings)
    f.advance(0.0, HeldOdometry.still(len(ROBOTS)))
    f.measure(Measurements.concatenate([_ranges(PAIRS, bias), *sightings]))
    assert f.mode() is Mode.OTHER_PAIR_SEEN
    return f


def test_triangle_block_covariance_is_the_propagated_range_and_bearing_noise():
    f = _triangle_run([_sighting(2)])
    (record,) = [u for u in f.take_updates() if u.dof == 2]
    # R = J W Jᵀ, J = ∂(d_01, φ̄)/∂(d_01, φ_2, d_02, d_12) by central differences
    w0 = np.array([_dist(0, 1), math.atan2(*_x(2)[1::-1]), _dist(0, 2), _dist(1, 2)])

    def y(w):
        tri = triangle_bearing(w[1], w[2], w[0], w[3], 1, min_sin=SETTINGS.min_sin)
        return np.array([w[0], tri.bearing])

    J = np.zeros((2, 4))
    for k in range(4):
        dw = np.zeros(4)
        dw[k] = 1e-6
        J[:, k] = (y(w0 + dw) - y(w0 - dw)) / 2e-6
    s = SETTINGS
    W = np.diag([s.range_sigma**2, s.bearing_sigma**2, s.range_sigma**2, s.range_sigma**2])
    assert record.cond_r == pytest.approx(condition_log10(J @ W @ J.T), abs=1e-6)


def test_a_worse_conditioned_triangle_seen_too_changes_nothing():
    best_only = _triangle_run([_sighting(2)])
    both = _triangle_run([_sighting(3), _sighting(2)])
    np.testing.assert_allclose(both.belief.mean, best_only.belief.mean, atol=1e-14)
    np.testing.assert_allclose(both.belief.cov, best_only.belief.cov, atol=1e-14)


def test_range_bias_is_subtracted_from_every_range():
    # a constant bias b on every raw range, known to the filter, is the unbiased filter
    biased = _triangle_run([_sighting(2)], replace(SETTINGS, range_bias=0.3), bias=0.3)
    plain = _triangle_run([_sighting(2)])
    np.testing.assert_allclose(biased.belief.mean, plain.belief.mean, atol=1e-12)
    np.testing.assert_allclose(biased.belief.cov, plain.belief.cov, atol=1e-12)


def test_another_pair_without_a_range_updates_the_leader_heading_only():
    f = _filter(x0=_x(1))
    f.advance(0.0, HeldOdometry.still(len(ROBOTS)))
    f.measure(_sighting(2, heading_follower=-0.5, heading_leader=0.1))
    assert f.mode() is Mode.OTHER_PAIR_SEEN
    # scalar update of θ_0: gain P₃₃ / (P₃₃ + σ_h²)
    gain = 0.01 / (0.01 + SETTINGS.heading_sigma**2)
    np.testing.assert_allclose(f.belief.mean, [*_x(1)[:3], gain * 0.1], atol=1e-14)


def test_the_camera_update_records_the_conditioning_of_s_not_of_r():
    robots = ("R_0", "R_1", "D_1")
    x0 = np.array([0.6, 0.6, 0.2, 0.0])
    f = SwitchingEkf(
        robots=robots,
        owner="R_1",
        leader="R_0",
        prior=Gaussian(x0, PRIOR_COV),
        settings=SwitchingEkfSettings(bearing_sigma=0.02, heading_sigma=0.02),
        sides={},
    )
    value = [[math.atan2(0.6, 0.6), 0.2, 0.0]]
    f.measure(measurement_rows("pair_sighting", t=[0.0], observer=2, target=1, value=value))
    (record,) = f.take_updates()
    # R = 0.02² I; S = diag(0.04/d² + σ², 0.01 + σ², 0.01 + σ²) with d² = 0.72
    assert record.cond_r == pytest.approx(0.0, abs=1e-12)
    expected = math.log10((0.04 / 0.72 + 4e-4) / (0.01 + 4e-4))
    assert record.cond_s == pytest.approx(expected, rel=1e-9)


def test_a_pair_sighting_of_the_leader_is_not_a_pair_of_the_broadcast_set():
    f = _filter()
    f.advance(0.0, HeldOdometry.still(len(ROBOTS)))
    f.measure(_sighting(0))
    assert f.take_counts() == {"rows_ignored": 1}
    assert f.mode() is Mode.NONE_SEEN


def test_the_camera_block_weights_bearing_and_headings_by_their_own_sigma():
    # with a diagonal prior the bearing row (r_x, r_y) and the two heading rows (θ_i, θ_0) do not
    # share a state: each heading is a scalar update with gain P / (P + σ_h²)
    settings = SwitchingEkfSettings(bearing_sigma=0.05, heading_sigma=0.01)
    x0 = np.array([0.6, 0.6, 0.2, 0.0])
    f = SwitchingEkf(
        robots=("R_0", "R_1", "D_1"),
        owner="R_1",
        leader="R_0",
        prior=Gaussian(x0, PRIOR_COV),
        settings=settings,
        sides={},
    )
    value = [[math.atan2(0.6, 0.6), 0.3, -0.1]]
    f.measure(measurement_rows("pair_sighting", t=[0.0], observer=2, target=1, value=value))
    gain = 0.01 / (0.01 + 0.01**2)
    assert f.belief.mean[2] == pytest.approx(0.2 + gain * 0.1, abs=1e-12)
    assert f.belief.mean[3] == pytest.approx(gain * -0.1, abs=1e-12)
    assert f.belief.cov[2, 2] == pytest.approx(0.01 * (1.0 - gain), rel=1e-9)


def test_a_second_range_of_a_pair_in_one_tick_is_counted_and_the_first_used():
    # the leader–follower pair ranged both ways in one tick: R_0→R_1 first (its true distance),
    # then R_1→R_0 1 m long; the filter uses the first and counts the second
    first = _filter()
    first.advance(0.0, HeldOdometry.still(len(ROBOTS)))
    first.measure(_ranges([(0, 1)]))
    both = _filter()
    both.advance(0.0, HeldOdometry.still(len(ROBOTS)))
    long_back = measurement_rows("range", t=[0.0], observer=1, target=0, value=[_dist(0, 1) + 1])
    both.measure(Measurements.concatenate([_ranges([(0, 1)]), long_back]))
    assert both.take_counts().get("rows_ignored") == 1
    np.testing.assert_array_equal(both.belief.mean, first.belief.mean)
    np.testing.assert_array_equal(both.belief.cov, first.belief.cov)
