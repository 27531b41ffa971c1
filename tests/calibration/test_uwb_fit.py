"""The UWB error-model fit recovers a known model (bias, spread, outliers, correlation time)
from seeded synthetic recordings, fits only its window, and refuses windows without data."""

import numpy as np
import pytest

from relloc.calibration.uwb import fit_uwb_noise, within_link_residuals
from relloc.calibration.window import CalibrationWindow, spanning
from relloc.datasets.paths import default_uwb_csv
from relloc.datasets.uwb import load_uwb_csv
from relloc.errors import DataError
from relloc.models.uwb_noise import UwbNoiseModel, sample_range_errors

HEADER = "timestamp,node1,node2,uwb_range,mocap_range,tb_node1_yaw,tb_node2_yaw,error\n"
LINKS = ((1, 2), (1, 3), (2, 3))


def _row(t, a, b, uwb, mocap):
    return f"{t},{a}.0,{b}.0,{uwb},{mocap},0.1,0.2,{uwb - mocap}\n"


def _recording(tmp_path, errors, dt=0.1):
    """A time-ordered csv with ``errors[:, link]`` on the three links, ``dt`` apart."""
    lines = []
    for link, (a, b) in enumerate(LINKS):
        mocap = 2.0 + link
        for k, e in enumerate(errors[:, link]):
            lines.append(_row(1000.0 + dt * k + 0.01 * link, a, b, mocap + e, mocap))
    body = sorted(lines, key=lambda r: float(r.split(",")[0]))
    path = tmp_path / "synthetic.csv"
    path.write_text(HEADER + "".join(body))
    return load_uwb_csv(path)


def test_shared_tiers_recording_fits():
    path = default_uwb_csv()
    if not path.is_file():
        pytest.skip(f"shared UWB data not found at {path} (outside the workspace)")
    rec = load_uwb_csv(path)
    window = spanning(rec.t, str(rec.path))
    fit = fit_uwb_noise(rec, window)
    m = fit.model
    # the recording's UWB reads long: a positive bias of tens of cm, a few-cm core
    assert 0.2 < m.bias < 0.5 and 0.03 < m.spread < 0.15
    assert 0.0 < m.outlier_rate < 0.1 and m.outlier_positive_fraction > 0.5
    assert m.correlation_time > 0.2  # consecutive errors are strongly correlated
    assert fit.n_rows == rec.n_rows
    d = fit.to_dict()
    assert set(d) >= {"bias_m", "spread_m", "outlier_rate", "calibration_window"}
    assert d["calibration_window"] == window.to_dict()


def test_fit_recovers_a_known_white_model(tmp_path):
    rng = np.random.default_rng(11)
    truth = UwbNoiseModel(
        bias=0.3,
        spread=0.05,
        outlier_rate=0.03,
        outlier_excess_mean=0.2,
        outlier_positive_fraction=1.0,
    )
    rec = _recording(tmp_path, sample_range_errors(truth, 2000, 3, 0.1, rng))
    fit = fit_uwb_noise(rec, spanning(rec.t, "synthetic"))
    m = fit.model
    assert m.bias == pytest.approx(0.3, abs=0.01)
    assert m.spread == pytest.approx(0.05, rel=0.1)
    # 6000 readings: the outlier fraction beyond 3σ is 0.03 + 0.0027 (Gaussian tail) ± ~0.007
    assert 0.02 < m.outlier_rate < 0.045
    assert m.outlier_positive_fraction > 0.9
    assert m.outlier_excess_mean == pytest.approx(0.2, rel=0.25)
    assert m.correlation_time == pytest.approx(0.0, abs=0.15)  # white draws
    assert fit.n_links == 3 and fit.sample_period == pytest.approx(0.1)


def test_fit_recovers_a_known_correlation_time_and_link_biases(tmp_path):
    rng = np.random.default_rng(4)
    truth = UwbNoiseModel(
        bias=0.2,
        spread=0.04,
        outlier_rate=0.0,
        outlier_excess_mean=0.0,
        correlation_time=1.5,
        link_bias_std=0.05,
    )
    errors = sample_range_errors(truth, 3000, 3, 0.1, rng, link_bias=True)
    rec = _recording(tmp_path, errors)
    fit = fit_uwb_noise(rec, spanning(rec.t, "synthetic"))
    # 300 s per link, τ = 1.5 s: the 1/e lag is estimated to about ±15 %
    assert fit.model.correlation_time == pytest.approx(1.5, rel=0.25)
    assert fit.lag1_correlation == pytest.approx(np.exp(-0.1 / 1.5), abs=0.02)
    offsets = errors.mean(axis=0)
    assert list(fit.link_biases.values()) == pytest.approx(list(offsets), abs=0.02)
    assert fit.model.link_bias_std == pytest.approx(np.std(offsets, ddof=1), abs=0.01)


def test_fit_uses_only_its_window(tmp_path):
    rng = np.random.default_rng(8)
    white = UwbNoiseModel(bias=0.0, spread=0.02, outlier_rate=0.0, outlier_excess_mean=0.0)
    errors = sample_range_errors(white, 1000, 3, 0.1, rng)
    errors[:500] += 0.3  # the first 50 s read 0.3 m long, the rest 0.5 m
    errors[500:] += 0.5
    rec = _recording(tmp_path, errors)
    first = fit_uwb_noise(rec, CalibrationWindow(1000.0, 1049.95, "synthetic"))
    second = fit_uwb_noise(rec, CalibrationWindow(1050.0, 1100.0, "synthetic"))
    assert first.model.bias == pytest.approx(0.3, abs=0.01)
    assert second.model.bias == pytest.approx(0.5, abs=0.01)
    assert first.n_rows == 1500 and second.n_rows == 1500
    assert within_link_residuals(rec, first.calibration_window).size == 1500


def test_fit_refuses_a_window_without_enough_readings(tmp_path):
    rng = np.random.default_rng(0)
    white = UwbNoiseModel(bias=0.0, spread=0.02, outlier_rate=0.0, outlier_excess_mean=0.0)
    rec = _recording(tmp_path, sample_range_errors(white, 100, 3, 0.1, rng))
    with pytest.raises(DataError, match=r"\[1000.00, 1001.00\] s of short: no node pair has ≥ 20"):
        fit_uwb_noise(rec, CalibrationWindow(1000.0, 1001.0, "short"))
