"""tiers-uwb's report.md on a hand-made summary: the calibration sentence quotes each fitted
figure in its place (outliers as a percentage), the held-out range errors before and after the
correction, a figure that is not a number shows as a dash; and a bag is refused as its own
calibration bag whether named by its folder or by the file in it."""

from __future__ import annotations

import math
import sys
from pathlib import Path
from typing import Any

import pytest

from relloc.errors import ConfigError
from relloc.experiments import tiers_uwb
from relloc.experiments.registry import ReproduceArgs

sys.path.insert(0, str(Path(__file__).parents[1] / "datasets"))
from bag_samples import SAMPLE_MAPPING, write_bag


def _summary() -> dict[str, Any]:
    team = {
        "mode": "aligned",
        "pos_rmse_m": math.nan,
        "nees_pct_beyond": 4.0,
        "nees_beyond_interval": {"interval": [1.0, 9.0], "verdict": "consistent"},
        "converged_after_s": None,
        "baselines": {"uncalibrated": {"pos_rmse_m": 0.7}, "multilateration": {"pos_rmse_m": 0.9}},
        "anchors": [],
    }
    return {
        "bags": {
            "b": {
                "calibration": {
                    "source": "bag",
                    "window": {"source": "cal.bag", "start_s": 0.0, "end_s": 3.0},
                    "fit": {
                        "bias_m": 0.1,
                        "spread_m": 0.2,
                        "link_bias_std_m": 0.3,
                        "outlier_rate": 0.04,
                        "correlation_time_s": 0.5,
                    },
                    "bias_drift_m": 0.01,
                    "range_sigma_m": 0.05,
                    "mapping_sigma_replaced_m": 0.25,
                    "heldout": {
                        "rows": 12,
                        "raw": {"mean_m": 0.3, "rmse_m": 0.35},
                        "calibrated": {"mean_m": 0.01, "rmse_m": 0.06},
                    },
                },
                "scored_window_s": [0.0, 10.0],
                "team": {"aligned": team},
                "pairs": {},
                "loader": {
                    "skips": {"rows_skipped": 0, "by_reason": {}},
                    "stamp_offset_s": {"bag": 0.0},
                    "unknown_topics": [],
                    "uwb_readings_not_in_recording": {},
                },
            }
        }
    }


def test_the_calibration_and_held_out_sentences_quote_each_figure_in_its_place() -> None:
    text = tiers_uwb.report(_summary())
    assert (
        "Calibrated on bag `cal.bag` [0.0, 3.0] s: bias 0.100 m, spread 0.200 m, link-bias std "
        "0.300 m, outliers 4.0 %, correlation time 0.50 s, bias drift 0.010 m → σ of one range "
        "in the filters 0.050 m (it replaces the mapping's stated 0.25 m). Scored on [0.0, 10.0] s."
    ) in text
    assert (
        "Held-out range error (12 readings): raw mean 0.300 m / RMSE 0.350 m → calibrated mean "
        "0.010 m / RMSE 0.060 m."
    ) in text


def test_a_figure_that_is_not_a_number_shows_as_a_dash() -> None:
    text = tiers_uwb.report(_summary())
    assert "| team aligned (aligned) | — | 4 | 1.0–9.0 consistent | — | 0.7 | 0.9 | — |" in text
    assert "nan" not in text


def test_a_bag_is_refused_as_its_own_calibration_bag_by_folder_or_by_file(
    tmp_path: Path,
) -> None:
    bag = write_bag(tmp_path / "bag", [])
    (tmp_path / "map.toml").write_text(SAMPLE_MAPPING)
    (stored,) = [f for f in bag.iterdir() if f.suffix == ".db3"]
    for calibrate_on in (bag, stored):
        args = ReproduceArgs(
            out_dir=tmp_path / "out", bag=bag, map=tmp_path / "map.toml", calibrate_on=calibrate_on
        )
        with pytest.raises(ConfigError, match=rf"^--calibrate-on {calibrate_on}: that is the bag"):
            tiers_uwb.reproduce(args)
