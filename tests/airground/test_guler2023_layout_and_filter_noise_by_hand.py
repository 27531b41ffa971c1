"""``relloc reproduce guler2023``'s case building on hand-made settings: the hexagon side
that fits the camera footprint (``hexagon_side``), the followers' offsets on it
(``hexagon_offsets``), the side of each line R_0R_j a follower sits on (``follower_sides``),
the filter's noise derived from the sensor models (``filter_settings``: Gauss–Markov
inflation (1 + a)/(1 − a), a = exp(−period/τ), of the correlated parts), the run counts of
``--runs`` and which run keeps its traces."""

from __future__ import annotations

import math

import numpy as np
import pytest

from relloc.errors import ConfigError
from relloc.experiments.guler2023 import (
    Plan,
    build_cases,
    default_plan,
    filter_settings,
    follower_sides,
    hexagon_offsets,
    hexagon_side,
    run_scenario_once,
)
from relloc.models.uwb_noise import TIERS_ROUNDED, UwbNoiseModel
from relloc.sim.airground import CameraSettings, DroneSettings

S3 = math.sqrt(3.0) / 2.0


def test_hexagon_side_fits_the_narrower_footprint_side() -> None:
    """At 2 m, a 90° × 2·atan(0.5) field of view less a 0.1 m margin leaves half-widths 1.9 and
    0.9 m. The farthest pair, √3·side apart, must fit 2·(0.9 − 0.05) = 1.7 m: 0.95 m
    (√3·0.95 = 1.645) and not 1.0 m (1.732)."""
    cam = CameraSettings(hfov=math.pi / 2, vfov=2.0 * math.atan(0.5), marker_margin=0.1)
    assert hexagon_side(cam, 2.0) == pytest.approx(0.95)
    # the drones' camera at their altitude: the documented 0.7 m
    assert hexagon_side(CameraSettings(), DroneSettings().altitude) == pytest.approx(0.7)


def test_hexagon_offsets_nearest_first_alternating_sides() -> None:
    """Side 1 m, centre (−1, 0): vertices k = 1, 5, 2, 4, 3 at (−0.5, ±√3/2), (−1.5, ±√3/2)
    and (−2, 0); the offsets are r = p_0 − p_i."""
    expected = [(0.5, -S3), (0.5, S3), (1.5, -S3), (1.5, S3), (2.0, 0.0)]
    np.testing.assert_allclose(hexagon_offsets(5, 1.0), expected, atol=1e-12)
    np.testing.assert_allclose(hexagon_offsets(1, 2.0), [(1.0, -2 * S3)], atol=1e-12)
    for bad in (0, 6):
        with pytest.raises(ConfigError, match=f"1 to 5 followers, got {bad}"):
            hexagon_offsets(bad, 1.0)


def test_follower_sides_of_the_lines_from_the_leader() -> None:
    """Followers at p_i = −r: R_1 (−0.5, √3/2), R_2 (−0.5, −√3/2), R_3 (−1.5, √3/2),
    R_4 (−1.5, −√3/2). The cross product p_j × p_1 is −√3/2, −√3/2 and −√3 for j = 2, 3, 4
    (R_1 right of each ray R_0→R_j), p_j × p_2 is +√3/2, +√3, +√3/2 for j = 1, 3, 4."""
    sc = build_cases(TIERS_ROUNDED, side=1.0)["two_drones"].scenario
    assert follower_sides(sc, 1) == {"R_2": -1, "R_3": -1, "R_4": -1}
    assert follower_sides(sc, 2) == {"R_1": 1, "R_3": 1, "R_4": 1}


def test_filter_noise_inflates_the_correlated_parts() -> None:
    """UWB every 2 ticks of 0.05 s with τ = 0.1 s / ln 3, camera every 5 ticks with the yaw
    error's τ = 0.25 s / ln 3: a = 1/3 for both, so each inflation is (1 + 1/3)/(2/3) = 2."""
    uwb = UwbNoiseModel(
        bias=0.3,
        spread=0.1,
        outlier_rate=0.0,
        outlier_excess_mean=0.0,
        correlation_time=0.1 / math.log(3.0),
    )
    cam = CameraSettings(bearing_sigma=0.03, heading_sigma=0.04)
    drone = DroneSettings(yaw_sigma=0.02, yaw_tau=0.25 / math.log(3.0))
    f = filter_settings(uwb, 0.05, 2, 5, cam, drone, (0.01, 0.02))
    assert f.range_sigma == pytest.approx(0.1 * math.sqrt(2.0))
    assert f.range_bias == 0.3
    # camera σ² plus twice the yaw-hold variance 0.0004
    assert f.bearing_sigma == pytest.approx(math.sqrt(0.0009 + 0.0008))
    assert f.heading_sigma == pytest.approx(math.sqrt(0.0016 + 0.0008))
    # input noise doubled
    assert (f.sigma_v, f.sigma_w) == pytest.approx((0.02, 0.04))
    assert f.gate_probability == 0.999 and f.sighting_hold == pytest.approx(0.25)


def test_runs_sets_every_count() -> None:
    assert default_plan(None) == Plan()
    p = default_plan(3)
    assert (p.one_drone_runs, p.two_drones_runs, p.formation_runs, p.sweep_runs) == (3, 3, 3, 3)
    assert (Plan().one_drone_runs, Plan().two_drones_runs, Plan().formation_runs) == (5, 11, 8)


def test_only_run_0_keeps_its_traces() -> None:
    case = build_cases(TIERS_ROUNDED)["formation"].with_scenario(duration=0.5)
    first, second = np.random.SeedSequence(4).spawn(2)
    assert run_scenario_once(first, 0, case, True).traces is not None
    assert run_scenario_once(second, 1, case, True).traces is None
