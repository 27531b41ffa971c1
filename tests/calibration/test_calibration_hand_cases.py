"""Hand-computed cases of the inflation, window, turn-rate and UWB fits that pin details the
recovery tests leave free: ρ beyond the last measured lag, a whole-span leading fraction, the
block statistics' conventions, the pair residual's sign and validity, and the 1/e lag of
series whose sample correlations are known exactly."""

import math

import numpy as np
import pytest

from relloc.calibration.inflation import autocorrelation_inflation
from relloc.calibration.odometry import OdometryModelFit
from relloc.calibration.turn_rate import pair_turn_rate_residual, residual_stats
from relloc.calibration.uwb import decorrelation_time, fit_uwb_noise
from relloc.calibration.window import CalibrationWindow, leading_fraction, spanning
from relloc.datasets.mrclam import GroundTruth
from relloc.datasets.uwb import load_uwb_csv

E_INV = math.exp(-1.0)


def test_correlation_beyond_the_last_measured_lag_is_zero():
    # lags 1, 2, 3 s at a 1 s spacing: ρ(1) = 0.5 measured, ρ(2) = ρ(3) = 0 beyond it
    assert autocorrelation_inflation({1.0: 0.5}, 1.0, 3.0) == pytest.approx(2.0)
    # and interpolated between measured lags: ρ(1) = 0.6, ρ(2) = 0.4, ρ(3) = 0.2, ρ(4) = 0
    rho = {1.0: 0.6, 3.0: 0.2}
    assert autocorrelation_inflation(rho, 1.0, 4.0) == pytest.approx(1.0 + 2.0 * 1.2)


def test_a_leading_fraction_of_one_is_the_whole_span():
    assert leading_fraction(2.0, 10.0, 1.0, "r") == CalibrationWindow(2.0, 10.0, "r")


def test_residual_stats_conventions_by_hand():
    # dt = 1 s, blocks of 2 s: block means 0 and 2, their (population) std 1
    e = np.array([0.0, 0.0, 2.0, 2.0])
    stats = residual_stats(e, np.ones(4, bool), block_s=2.0, dt=1.0)
    assert stats.blocks == 2 and stats.block_std == pytest.approx(1.0)
    # the mean and std are of the valid samples only: the invalid 100 is left out
    e = np.array([1.0, 3.0, 1.0, 3.0, 100.0])
    stats = residual_stats(e, np.array([True, True, True, True, False]), block_s=2.0, dt=1.0)
    assert stats.mean == pytest.approx(2.0) and stats.std == pytest.approx(1.0)
    assert stats.samples == 4
    # one block: no spread of block means to measure
    one = residual_stats(np.arange(3.0), np.ones(3, bool), block_s=2.0, dt=1.0)
    assert one.blocks == 1 and math.isnan(one.block_std)
    # blocks of a whole number of steps: 2.4 s at 1 s steps are blocks of 2 s, and the
    # random walk uses the blocks' real length: sigma_B sqrt(2 * 8) = 1 * 4
    rounded = residual_stats(np.array([0.0, 0.0, 2.0, 2.0]), np.ones(4, bool), block_s=2.4, dt=1.0)
    assert rounded.block_s == pytest.approx(2.0)
    assert rounded.yaw_random_walk(8.0) == pytest.approx(4.0)


def _fit(window: CalibrationWindow, scale_w: tuple[float, float]) -> OdometryModelFit:
    return OdometryModelFit(
        calibration_window=window,
        latency_s=0.0,
        time_constant_s=0.0,
        scale_v=(1.0, 1.0),
        scale_w=scale_w,
        q_v0=1e-6,
        k_v=0.0,
        q_w0=1e-6,
        k_w=0.0,
        k_wv=0.0,
        odometry_window_s=1.0,
    )


def test_the_pair_residual_is_robot_j_minus_robot_i_where_both_are_valid(synthetic):
    """Robot 1 turns at 0.8 of its commands, robot 2 at 1.0; the fit says 0.8 and 2.0. The
    calibrated model explains robot 1 and leaves robot 2 −1.0 times its command, so the
    relative residual ``e_2 − e_1`` is robot 2's. Robot 2's ground truth has a gap: the
    relative residual is taken where both are valid."""
    rng = np.random.default_rng(5)
    r1 = synthetic.commanded_robot(1, rng, duration=50.0, scale_w=0.8)
    r2 = synthetic.commanded_robot(2, rng, duration=50.0)
    gt = r2.groundtruth
    keep = (gt.t < 30.0) | (gt.t > 32.0)
    gap = GroundTruth(
        t=gt.t[keep], x=gt.x[keep], y=gt.y[keep], theta=gt.theta[keep], gap_threshold=0.5
    )
    r2 = synthetic.robot(2, gap, r2.odometry)
    ds = synthetic.dataset([r1, r2])
    held_out = CalibrationWindow(26.0, 46.0, "synthetic")
    res = pair_turn_rate_residual(
        ds, (1, 2), _fit(CalibrationWindow(2.0, 24.0, "synthetic"), (0.8, 2.0)), {"h": held_out}
    )
    one, two, rel = (res.stats[who]["h"]["calibrated"] for who in ("1", "2", "relative"))
    # a 20 s window on the 0.02 s grid: 1000 times, all valid for robot 1
    assert one.samples == 1000
    assert 800 < two.samples < 1000 and rel.samples == two.samples
    # robot 1 is explained up to the ground truth's sampling (a few mrad/s); robot 2 keeps its
    # whole command (std about 0.29 rad/s for commands uniform in ±0.5 rad/s)
    assert one.std < 0.02 and two.std > 0.2
    # e_2 − e_1 with e_1 about 0: robot 2's residual, not its negative
    assert abs(two.mean) > 0.005
    assert rel.mean == pytest.approx(two.mean, abs=1e-3)
    assert rel.std == pytest.approx(two.std, rel=0.05)


def test_decorrelation_time_of_series_with_known_sample_correlations():
    # [1, 1, -1, -1] x 5, one reading a second: the lag-1 sample correlation (of the 19
    # overlapping pairs, each stretch about its own mean) is 1/18, below 1/e, so the 1/e
    # crossing is interpolated between lag 0 (ρ = 1) and lag 1 s.
    p4 = np.tile([1.0, 1.0, -1.0, -1.0], 5)
    crossing = (1.0 - E_INV) / (1.0 - 1.0 / 18.0)
    assert decorrelation_time(np.arange(20.0), p4) == pytest.approx(crossing, rel=1e-12)
    # the lag is the mean spacing of the pairs: a first gap of 3 s makes it 21/19 s
    t = np.concatenate([[0.0], 3.0 + np.arange(19.0)])
    assert decorrelation_time(t, p4) == pytest.approx(crossing * 21.0 / 19.0, rel=1e-12)
    # [1, 1, 1, 1, -1, -1, -1, -1] x 3: ρ(1) = 25/44, ρ(2) = 1/10; the crossing lies
    # between lags 1 and 2, interpolated from ρ(1), not from ρ(0)
    p8 = np.tile([1.0] * 4 + [-1.0] * 4, 3)
    rho1, rho2 = 25.0 / 44.0, 0.1
    expected = 1.0 + (rho1 - E_INV) / (rho1 - rho2)
    assert decorrelation_time(np.arange(24.0), p8) == pytest.approx(expected, rel=1e-12)


def test_decorrelation_time_ignores_lags_of_two_overlapping_readings():
    # correlated at every lag with three or more overlapping readings (ρ ≥ 0.5); two readings
    # always correlate ±1 and say nothing, so the lag of 4 s (−1 here) is never looked at
    assert decorrelation_time(np.arange(6.0), np.array([0.0, 1.0, 2.0, 3.0, 4.0, 3.5])) is None


def test_decorrelation_time_looks_at_a_lag_of_exactly_the_longest():
    # readings 10 s apart: ρ(10 s) = 25/44 above 1/e, ρ(20 s) = 1/10 below; 20 s is the
    # longest lag searched, and it is searched
    p8 = np.tile([1.0] * 4 + [-1.0] * 4, 3)
    tau = decorrelation_time(10.0 * np.arange(24.0), p8)
    rho1, rho2 = 25.0 / 44.0, 0.1
    assert tau == pytest.approx(10.0 + 10.0 * (rho1 - E_INV) / (rho1 - rho2), rel=1e-12)


def test_uwb_fit_takes_medians_over_links_and_the_sample_std_of_their_biases(tmp_path):
    """Three links of exactly ``MIN_LINK_ROWS`` = 20 readings, each the square wave
    [1, 1, −1, −1] x 5 about its own offset (0.1, 0.2, 0.6 m), read every 1, 2 and 10 s. Each
    link's 1/e lag is 0.6693 of its spacing (ρ(1 step) = 1/18), so the correlation time is
    the median 2 x 0.6693 s; the sample period the median 2 s; the link-bias spread the
    sample std of the offsets, √(((−0.2)² + (−0.1)² + 0.3²) / 2) = √0.07."""
    wave = np.tile([1.0, 1.0, -1.0, -1.0], 5)
    lines = []
    for (a, b), offset, spacing, shift in (
        ((1, 2), 0.1, 1.0, 0.0),
        ((1, 3), 0.2, 2.0, 0.01),
        ((2, 3), 0.6, 10.0, 0.02),
    ):
        mocap = 2.0 + a + b
        for k, e in enumerate((wave + offset).tolist()):
            uwb = mocap + e
            t = 1000.0 + spacing * k + shift
            lines.append((t, f"{t!r},{a},{b},{uwb!r},{mocap!r},0.1,0.2,{uwb - mocap!r}\n"))
    path = tmp_path / "links.csv"
    header = "timestamp,node1,node2,uwb_range,mocap_range,tb_node1_yaw,tb_node2_yaw,error\n"
    path.write_text(header + "".join(row for _, row in sorted(lines)))
    rec = load_uwb_csv(path)
    assert rec.n_rows == 60
    fit = fit_uwb_noise(rec, spanning(rec.t, "links"))
    assert fit.n_links == 3
    assert list(fit.link_biases.values()) == pytest.approx([0.1, 0.2, 0.6], abs=1e-9)
    assert fit.model.link_bias_std == pytest.approx(math.sqrt(0.07), rel=1e-9)
    step_crossing = (1.0 - E_INV) / (1.0 - 1.0 / 18.0)
    assert fit.model.correlation_time == pytest.approx(2.0 * step_crossing, rel=1e-9)
    assert fit.sample_period == pytest.approx(2.0, rel=1e-9)
