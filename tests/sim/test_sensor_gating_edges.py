"""Field-of-view, elevation and range gates of the simulated sensor at their exact edges, and
the sensor epochs."""

import numpy as np

from relloc.sim.scenario import SensorSpec
from relloc.sim.sensors import measurement_times, range_azimuth_elevation, visible


def _seen(rel, sensor):
    return visible(range_azimuth_elevation(np.array(rel, dtype=float)), sensor).tolist()


def test_azimuth_gate_is_inclusive_at_half_the_field_of_view():
    sensor = SensorSpec(fov_deg=90.0, max_range=10.0)
    # (1, ±1): θ = ±45° exactly, on the edge of a 90° view; (1, ±1.001) lies just outside.
    rel = [[1.0, 1.0, 0.0], [1.0, -1.0, 0.0], [1.0, 1.001, 0.0], [1.0, -1.001, 0.0]]
    assert _seen(rel, sensor) == [True, True, False, False]


def test_elevation_gate_is_half_the_vertical_field_of_view_both_ways():
    sensor = SensorSpec(elevation_fov_deg=90.0, max_range=10.0)
    # α = ±45° exactly is on the edge; α = atan(1.2) ≈ 50° above or below is outside.
    rel = [
        [1.0, 0.0, 1.0],
        [1.0, 0.0, -1.0],
        [1.0, 0.0, 1.2],
        [1.0, 0.0, -1.2],
        [1.0, 0.0, 0.0],
    ]
    assert _seen(rel, sensor) == [True, True, False, False, True]


def test_range_gate_includes_both_limits():
    sensor = SensorSpec(min_range=1.0, max_range=2.0)
    rel = [[1.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.999, 0.0, 0.0], [2.001, 0.0, 0.0]]
    assert _seen(rel, sensor) == [True, True, False, False]


def test_epochs_start_one_period_in_and_end_at_the_duration():
    np.testing.assert_allclose(measurement_times(10.0, 1.0), np.arange(1, 11) / 10.0)
    # 0.29 s × 100 Hz = 28.999999999999996 in floating point: still 29 epochs, the last at 0.29 s.
    tm = measurement_times(100.0, 0.29)
    assert tm.size == 29 and tm[-1] == 0.29


def test_a_slow_sensor_has_no_epoch_past_the_duration():
    # 1 mHz over 1000 s less 0.5 µs: duration × rate is within the round-off tolerance of 1,
    # but the one epoch (1000 s) lies beyond the simulated span.
    assert measurement_times(1e-3, 1000.0 - 5e-7).size == 0
    assert measurement_times(1e-3, 1000.0).tolist() == [1000.0]


def test_noise_of_each_channel_has_its_own_sigma():
    from relloc.sim.sensors import add_noise

    n = 4000
    z_true = np.tile([20.0, 0.3, -0.2], (n, 1))
    z = add_noise(z_true, np.array([0.01, 0.02, 0.03]), np.random.default_rng(11))
    # Sample σ of 4000 draws: relative standard error 1/√(2n) ≈ 1.1 %, so 5 % is > 4 SE.
    np.testing.assert_allclose((z - z_true).std(axis=0), [0.01, 0.02, 0.03], rtol=0.05)
    np.testing.assert_allclose((z - z_true).mean(axis=0), 0.0, atol=4 * 0.03 / np.sqrt(n))


def test_range_noise_is_redrawn_with_the_range_sigma_to_stay_positive():
    from relloc.sim.sensors import add_noise

    n = 4000
    z_true = np.tile([0.5, 0.0, 0.0], (n, 1))
    z = add_noise(z_true, np.array([1.0, 1e-3, 1e-3]), np.random.default_rng(12))
    assert np.all(z[:, 0] > 0.0)
    # N(0.5, 1) truncated to r > 0 (α = −0.5): mean = 0.5 + φ(0.5)/Φ(0.5) = 1.00917,
    # σ = √(1 + αλ − λ²) = 0.697 (λ = 0.50917); 4000 draws: SE 0.011, bound 4 SE.
    assert abs(z[:, 0].mean() - 1.00917) < 0.045
    assert abs(z[:, 0].std() - 0.697) < 0.035


def test_azimuth_noise_is_wrapped_into_minus_pi_to_pi():
    from relloc.sim.sensors import add_noise

    z_true = np.tile([5.0, np.pi - 0.01, 0.0], (2000, 1))
    z = add_noise(z_true, np.array([0.01, 0.1, 0.01]), np.random.default_rng(13))
    assert np.all((z[:, 1] >= -np.pi) & (z[:, 1] < np.pi))
    # About 46 % of the draws cross +π (P(ν > 0.01) for σ = 0.1) and wrap to near −π.
    assert 0.40 < np.mean(z[:, 1] < 0.0) < 0.52
