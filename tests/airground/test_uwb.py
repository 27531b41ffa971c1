"""TIERS UWB loader (validated, counted skips) and the UWB error sampler."""

import numpy as np
import pytest

from relloc.datasets.paths import default_uwb_csv
from relloc.datasets.uwb import load_uwb_csv
from relloc.errors import ConfigError, DataError
from relloc.models.uwb_noise import UwbNoiseModel, sample_range_errors

HEADER = "timestamp,node1,node2,uwb_range,mocap_range,tb_node1_yaw,tb_node2_yaw,error\n"


def _row(t, a, b, uwb, mocap):
    return f"{t},{a}.0,{b}.0,{uwb},{mocap},0.1,0.2,{uwb - mocap}\n"


def test_shared_tiers_recording_loads():
    path = default_uwb_csv()
    if not path.is_file():
        pytest.skip(f"shared UWB data not found at {path} (outside the workspace)")
    rec = load_uwb_csv(path)
    assert rec.n_rows == 8712 and rec.skipped.n_skipped == 0
    assert rec.links() == [(1, 3), (1, 4), (1, 5), (3, 4), (3, 5), (4, 5)]


def test_malformed_rows_are_counted_with_reasons(tmp_path):
    rows = [HEADER]
    good = [_row(100.0 + 0.1 * k, 1, 3, 2.0 + 0.01 * k, 1.9 + 0.01 * k) for k in range(30)]
    rows += good[:10]
    rows.append("100.95,1.0,3.0,abc,1.9,0.1,0.2,0.1\n")  # not a number
    rows.append("100.96,1.0,3.0,2.0,1.9,0.1\n")  # short row
    rows.append("100.97,1.0,1.0,2.0,1.9,0.1,0.2,0.1\n")  # node with itself
    rows.append("50.0,1.0,3.0,2.0,1.9,0.1,0.2,0.1\n")  # back in time
    rows.append("100.98,1.0,3.0,nan,1.9,0.1,0.2,0.1\n")  # NaN
    rows.append("100.99,1.0,3.0,2.0,1.9,0.1,0.2,0.5\n")  # inconsistent error column
    rows.append("\n")  # blank line: ignored, not an error
    rows += good[10:]
    path = tmp_path / "bad.csv"
    path.write_text("".join(rows))
    rec = load_uwb_csv(path)
    assert rec.n_rows == 30
    assert rec.skipped.n_skipped == 6
    text = " ".join(e.text for e in rec.skipped.examples)
    for reason in ("not a number", "columns", "node1 = node2", "back in time"):
        assert reason in text
    assert rec.skipped.examples[0].line == 12
    assert "6 rows skipped" in rec.skipped.describe()


def test_unusable_files_raise_data_error_naming_the_file(tmp_path):
    empty = tmp_path / "empty.csv"
    empty.write_text("")
    with pytest.raises(DataError, match=r"empty\.csv.*empty file"):
        load_uwb_csv(empty)
    nocol = tmp_path / "nocol.csv"
    nocol.write_text("timestamp,node1,node2,uwb_range\n1,1,2,3\n")
    with pytest.raises(DataError, match="mocap_range"):
        load_uwb_csv(nocol)
    allbad = tmp_path / "allbad.csv"
    allbad.write_text(HEADER + "x,y,z,1,2,3,4,5\n")
    with pytest.raises(DataError, match="no usable row"):
        load_uwb_csv(allbad)
    with pytest.raises(DataError, match="not found"):
        load_uwb_csv(tmp_path / "missing.csv")


def test_sampler_statistics_and_validation():
    m = UwbNoiseModel(
        bias=0.35,
        spread=0.075,
        outlier_rate=0.04,
        outlier_excess_mean=0.15,
        outlier_positive_fraction=0.9,
        correlation_time=1.2,
    )
    e = sample_range_errors(m, 20000, 3, 0.1, np.random.default_rng(5)) - m.bias
    core = e[np.abs(e) < 3 * m.spread]
    assert np.std(core) == pytest.approx(0.075, rel=0.1)
    frac = np.mean(np.abs(e) > 3 * m.spread)
    assert 0.03 < frac < 0.05
    col = e[:, 0]
    ok = (np.abs(col[:-1]) < 3 * m.spread) & (np.abs(col[1:]) < 3 * m.spread)
    lag1 = np.corrcoef(col[:-1][ok], col[1:][ok])[0, 1]
    assert lag1 > 0.8  # Gauss–Markov core: exp(−0.1/1.2) ≈ 0.92 (slightly less once truncated)
    with pytest.raises(ConfigError, match="outlier_rate"):
        UwbNoiseModel(bias=0.0, spread=0.1, outlier_rate=1.5, outlier_excess_mean=0.1)


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("bias", "0.3"),
        ("bias", None),
        ("spread", True),
        ("outlier_rate", "0.1"),
        ("outlier_rate", 1.0),
        ("outlier_positive_fraction", float("nan")),
        ("outlier_k", 0.0),
        ("link_bias_std", -0.1),
        ("correlation_time", float("inf")),
    ],
)
def test_noise_model_refuses_a_bad_field_by_name(field, value):
    """Before: a string or None gave a raw TypeError, a bool was taken as a number."""
    base = dict(bias=0.0, spread=0.1, outlier_rate=0.0, outlier_excess_mean=0.1)
    with pytest.raises(ConfigError, match=rf"UwbNoiseModel\.{field}: "):
        UwbNoiseModel(**{**base, field: value})
