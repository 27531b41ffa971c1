"""The seed-002 direct scan from hand-placed poses: detection probability, range gate and
truncation, noise σ per reading, clutter count and placement, shuffling, scan times, the kidnap
instant and the exact zero-order-hold velocities."""

import numpy as np
import pytest

from relloc.core.limits import MAX_SENSOR_RANGE_M
from relloc.errors import ConfigError
from relloc.sim.multihypothesis import (
    CLUTTER,
    DeSilvaScenario,
    _Rows,
    _scan,
    simulate,
    zoh_velocities,
)

# Observer 0 at the origin, yaw 0; teammates at body offsets (3, 4, 1.2), exactly 10 m ahead,
# behind at azimuth ≈ π − 2e-4 and 30 m away (out of the default 10 m range).
POSES = np.array(
    [
        [0.0, 0.0, 0.0, 0.0],
        [3.0, 4.0, 1.2, 0.5],
        [10.0, 0.0, 0.0, 0.0],
        [-5.0, 0.001, 0.0, 0.0],
        [30.0, 0.0, 0.0, 0.0],
    ]
)


def _scans(scenario, n=2000, poses=POSES, seed=0):
    rng = np.random.default_rng(seed)
    rows = _Rows()
    for k in range(n):
        _scan(scenario, poses, 0, float(k), rng, rows)
    return rows


def test_derived_noise_figures_and_clutter_mean():
    sc = DeSilvaScenario()
    assert abs(sc.sigma_height - 2.2360679775e-3) < 1e-12  # √5 mm
    assert abs(sc.sigma_range - 2.8284271247e-3) < 1e-12  # √8 mm
    np.testing.assert_allclose(sc.velocity_sigmas, [0.2236068, 0.2236068, 0.2236068, 0.1])
    # λV = 1e-7 · 2π · π · 10 000 mm = 0.019739
    assert abs(sc.expected_clutter - 0.0197392088) < 1e-9


def test_detection_probability_and_range_gate():
    rows = _scans(DeSilvaScenario(p_detect=0.7, clutter_density=0.0))
    rng_target = np.array([r[2] for r in rows.range])
    brg_origin = np.array([r[2] for r in rows.bearing])
    # Heights of every teammate, in range or not: 4 a scan.
    assert len(rows.height) == 4 * 2000
    for target in (1, 2, 3):  # the one exactly at max_range = 10 m included
        # Binomial(2000, 0.7): σ = 20.5, bound 4 σ.
        assert abs(np.sum(rng_target == target) - 1400) < 82
        assert abs(np.sum(brg_origin == target) - 1400) < 82
    assert not np.any(rng_target == 4) and not np.any(brg_origin == 4)


def test_noise_sigma_of_heights_ranges_and_bearings():
    sc = DeSilvaScenario(var_azimuth=0.0036, var_elevation=0.0016, clutter_density=0.0)
    rows = _scans(sc)
    h = np.array([r[3] for r in rows.height if r[2] == 1]) - 1.2
    r = np.array([r[3] for r in rows.range if r[2] == 1]) - np.sqrt(26.44)
    b = np.array([r[3:] for r in rows.bearing if r[2] == 1])
    # ~2000 draws each: sample σ within 8 % (> 4 SE of 1.6 %), mean within 4 σ/√n.
    np.testing.assert_allclose([h.std(), r.std()], [np.sqrt(5e-6), np.sqrt(8e-6)], rtol=0.08)
    az_err, el_err = b[:, 0] - np.arctan2(4.0, 3.0), b[:, 1] - np.arctan2(1.2, 5.0)
    np.testing.assert_allclose([az_err.std(), el_err.std()], [0.06, 0.04], rtol=0.08)
    assert abs(el_err.mean()) < 4 * 0.04 / np.sqrt(el_err.size)
    assert abs(az_err.mean()) < 4 * 0.06 / np.sqrt(az_err.size)
    behind = np.array([r[3] for r in rows.bearing if r[2] == 3])
    assert np.all((behind >= -np.pi) & (behind < np.pi))
    assert np.mean(behind < 0) > 0.3  # σ 0.06 from π − 2e-4: about half wrap to −π


def test_range_noise_is_truncated_to_the_sensor_limit():
    far = POSES.copy()
    far[2] = [MAX_SENSOR_RANGE_M, 0.0, 0.0, 0.0]
    sc = DeSilvaScenario(max_range=MAX_SENSOR_RANGE_M, var_range_mm2=1e6, clutter_density=0.0)
    ranges = np.array([r[3] for r in _scans(sc, n=300, poses=far).range if r[2] == 2])
    assert ranges.size > 200 and np.all(ranges <= MAX_SENSOR_RANGE_M)


def test_clutter_count_placement_and_shuffling():
    # λV = 2: density · 2π² · r_max[mm] with r_max = 10 m.
    sc = DeSilvaScenario(clutter_density=2.0 / (2 * np.pi**2 * 1e4))
    rows = _scans(sc)
    clutter = np.array([r[3:] for r in rows.bearing if r[2] == CLUTTER])
    # Poisson(2) per scan over 2000 scans: total 4000 ± 4·63.
    assert abs(clutter.shape[0] - 4000) < 253
    assert clutter[:, 0].min() >= -np.pi and clutter[:, 0].max() <= np.pi
    assert clutter[:, 1].min() >= -np.pi / 2 and clutter[:, 1].max() <= np.pi / 2
    # Uniform: a quarter in each azimuth quadrant and half above the plane (± 4 SE).
    quad = np.histogram(clutter[:, 0], bins=[-np.pi, -np.pi / 2, 0, np.pi / 2, np.pi])[0]
    assert np.all(np.abs(quad / clutter.shape[0] - 0.25) < 4 * np.sqrt(0.1875 / 4000))
    assert abs(np.mean(clutter[:, 1] > 0) - 0.5) < 4 * np.sqrt(0.25 / 4000)
    # The scan's bearings are shuffled: a clutter bearing comes first in many scans.
    first = {}
    for t, _, origin, *_ in rows.bearing:
        first.setdefault(t, origin)
    assert sum(o == CLUTTER for o in first.values()) > 200


def test_scans_start_one_direct_period_in():
    rec = simulate(DeSilvaScenario(duration=1.0), np.random.default_rng(0))
    t = np.unique(rec.measurements.t)
    np.testing.assert_allclose(t, np.arange(1, 11) / 10.0)


def test_kidnap_moves_the_robot_at_the_stated_instant():
    base = simulate(DeSilvaScenario(duration=2.0), np.random.default_rng(0))
    moved = simulate(
        DeSilvaScenario(duration=2.0, kidnap=(2, 1.0, 0.5, -0.3, 0.0)), np.random.default_rng(0)
    )
    # Grid 0.05 s: t = 1.0 is sample 20; a pure shift (dψ = 0) carries over unchanged.
    d = moved.truth[2].pose - base.truth[2].pose
    np.testing.assert_allclose(d[:20], 0.0, atol=1e-12)
    np.testing.assert_allclose(d[20:], np.tile([0.5, -0.3, 0.0, 0.0], (21, 1)), atol=1e-9)


def test_a_kidnap_after_the_last_filter_step_is_refused_naming_it():
    # 1.02 s at 20 Hz: round(20.4) = 20 steps, the last at 1.0 s. A kidnap at 1.01 s lies in
    # the run but after every pose; it crashed the simulation with an IndexError. At 1.0 s it
    # moves the last pose.
    with pytest.raises(ConfigError, match=r"kidnap\[1\] \(time\): 1.01 s is after the last"):
        DeSilvaScenario(duration=1.02, kidnap=(2, 1.01, 0.5, 0.0, 0.0))
    base = simulate(DeSilvaScenario(duration=1.02), np.random.default_rng(0))
    moved = simulate(
        DeSilvaScenario(duration=1.02, kidnap=(2, 1.0, 0.5, 0.0, 0.0)), np.random.default_rng(0)
    )
    d = moved.truth[2].pose - base.truth[2].pose
    np.testing.assert_allclose(d[:-1], 0.0, atol=1e-12)
    np.testing.assert_allclose(d[-1], [0.5, 0.0, 0.0, 0.0], atol=1e-9)


def test_zero_order_hold_velocities_invert_an_exact_arc():
    # v = 1 m/s, ω = 1 rad/s for 1 s from the origin ends at (sin 1, 1 − cos 1), yaw 1.
    poses = np.array([[[0.0, 0.0, 0.0, 0.0]], [[np.sin(1.0), 1.0 - np.cos(1.0), 0.3, 1.0]]])
    np.testing.assert_allclose(zoh_velocities(poses, 1.0)[0, 0], [1.0, 0.0, 0.3, 1.0], atol=1e-12)


def test_velocity_noise_of_the_stated_variances():
    rec = simulate(DeSilvaScenario(duration=20.0), np.random.default_rng(5))
    dz, dpsi = [], []
    for od, tr in zip(rec.odometry, rec.truth, strict=True):
        # The held command carries z and ψ exactly: v_z = Δz / dt and ω = Δψ / dt.
        dz.append(od.velocity[:-1, 2] - np.diff(tr.pose[:, 2]) * 20.0)
        dpsi.append(od.velocity[:-1, 3] - np.diff(tr.pose[:, 3]) * 20.0)
    # 5 × 400 draws: sample σ within 7 % (> 4 SE of 1.6 %); σ = √0.05 and √0.01.
    np.testing.assert_allclose([np.std(dz), np.std(dpsi)], [np.sqrt(0.05), 0.1], rtol=0.07)
