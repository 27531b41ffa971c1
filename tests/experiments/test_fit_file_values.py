"""``fit.json`` values out of what the fits produce, a key of the wrong kind and a file too
large to be a fit: refused with a DataError naming the file and the key."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from relloc.calibration.camera import CameraFit
from relloc.calibration.odometry import OdometryModelFit
from relloc.calibration.window import CalibrationWindow
from relloc.errors import DataError
from relloc.experiments.fit_file import MAX_FIT_BYTES, load_fit, save_fit
from relloc.experiments.mrclam_cl import FittedModels

WINDOW = CalibrationWindow(start_s=1.0, end_s=400.0, source="run")
FIT = FittedModels(
    odometry=OdometryModelFit(
        calibration_window=WINDOW,
        latency_s=0.1,
        time_constant_s=0.0,
        scale_v=(0.9,) * 2,
        scale_w=(0.8,) * 2,
        q_v0=1e-6,
        k_v=0.01,
        q_w0=1e-6,
        k_w=0.04,
        k_wv=0.0,
        odometry_window_s=5.0,
    ),
    camera=CameraFit(
        calibration_window=WINDOW,
        bearing_offset=(0.0,) * 2,
        sigma_bearing_raw=0.007,
        bearing_inflation=25.0,
        sigma_bearing=0.035,
        range_bias_coeffs=(0.06, 0.0, 0.0, 0.0, 0.0),
        sigma_range_raw=0.04,
        range_inflation=15.0,
        sigma_range=0.17,
        range_interval_s=1.0,
        correlation={"range": {"1s": 0.8}},
        n_residuals=100,
    ),
)


def _document(tmp_path: Path) -> dict[str, Any]:
    save_fit(FIT, tmp_path / "valid.json")
    doc: dict[str, Any] = json.loads((tmp_path / "valid.json").read_text())
    return doc


def test_the_document_edited_below_reads_back(tmp_path: Path) -> None:
    save_fit(FIT, tmp_path / "fit.json")
    assert load_fit(tmp_path / "fit.json") == FIT


@pytest.mark.parametrize(
    ("section", "key", "value", "message"),
    [
        ("odometry", "k_w", -0.01, r"odometry\.k_w: must be ≥ 0, got -0\.01"),
        ("camera", "n_residuals", -1, r"camera\.n_residuals must be ≥ 0 .* got -1 and"),
        ("camera", "correlation", [0.8], r"camera\.correlation: expected an object, got a list"),
        (
            "camera",
            "correlation",
            {"range": 0.8},
            r"camera\.correlation\.range: expected an object, got 0\.8",
        ),
    ],
)
def test_a_value_out_of_range_or_of_the_wrong_kind_names_the_key(
    tmp_path: Path, section: str, key: str, value: object, message: str
) -> None:
    doc = _document(tmp_path)
    doc[section][key] = value
    path = tmp_path / "fit.json"
    path.write_text(json.dumps(doc))
    with pytest.raises(DataError, match=rf"^{path}: {message}"):
        load_fit(path)


def test_a_target_share_outside_0_100_is_refused(tmp_path: Path) -> None:
    from dataclasses import replace

    from relloc.experiments.mrclam_cl import OdometryInflation

    inflated = replace(FIT, odometry_inflation=OdometryInflation(1.5, True, 100.0, (), None, None))
    path = tmp_path / "fit.json"
    save_fit(inflated, path)
    with pytest.raises(DataError, match=rf"^{path}: .*target_percent in \(0, 100\), got 100 and"):
        load_fit(path)


def test_a_file_too_large_to_be_a_fit_is_refused_unread(tmp_path: Path) -> None:
    path = tmp_path / "fit.json"
    path.write_text(" " * (MAX_FIT_BYTES + 1))
    with pytest.raises(DataError, match=rf"^{path}: .*larger than {MAX_FIT_BYTES} bytes"):
        load_fit(path)
