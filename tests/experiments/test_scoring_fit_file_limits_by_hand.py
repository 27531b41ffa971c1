"""``fit.json`` (``relloc.experiments.fit_file``): each documented limit on a value, a length
or a window, pinned on a hand-made fit of a three-robot team with the exact error naming the
file and the key."""

from __future__ import annotations

import json
import re
from dataclasses import replace
from pathlib import Path
from typing import Any

import pytest

from relloc.calibration.camera import CameraFit
from relloc.calibration.odometry import OdometryModelFit
from relloc.calibration.window import CalibrationWindow
from relloc.errors import DataError
from relloc.experiments.fit_file import MAX_FIT_BYTES, check_fit_for, load_fit, save_fit
from relloc.experiments.mrclam_cl import FittedModels, OdometryInflation

WINDOW = CalibrationWindow(start_s=10.0, end_s=400.0, source="run")
FIT = FittedModels(
    odometry=OdometryModelFit(
        calibration_window=WINDOW,
        latency_s=0.1,
        time_constant_s=0.05,
        scale_v=(0.9, 0.9, 0.9),
        scale_w=(0.8, 0.8, 0.8),
        q_v0=1e-6,
        k_v=0.01,
        q_w0=1e-6,
        k_w=0.04,
        k_wv=0.0,
        odometry_window_s=5.0,
    ),
    camera=CameraFit(
        calibration_window=WINDOW,
        bearing_offset=(0.0, 0.0, 0.0),
        sigma_bearing_raw=0.007,
        bearing_inflation=25.0,
        sigma_bearing=0.035,
        range_bias_coeffs=(0.06,),
        sigma_range_raw=0.04,
        range_inflation=15.0,
        sigma_range=0.17,
        range_interval_s=1.0,
        correlation={"range": {"1s": 0.8}},
        n_residuals=100,
    ),
)
SPAN = (0.0, 400.0)


@pytest.mark.parametrize(
    ("section", "key", "value", "message"),
    [
        ("camera", "range_interval_s", 0, "camera.range_interval_s: must be > 0, got 0.0"),
        ("odometry", "scale_w", [0.8, 0.0, 0.8], "odometry.scale_w[1]: must be > 0, got 0.0"),
        ("odometry", "k_wv", -0.5, "odometry.k_wv: must be ≥ 0, got -0.5"),
        (
            "odometry",
            "latency_s",
            0.6,
            "odometry.latency_s: 0.6 s is outside [0, 0.5] s, where the fit searches",
        ),
        (
            "camera",
            "range_bias_coeffs",
            [],
            "camera.range_bias_coeffs: 0 values; 1 to 5 coefficients of 1, η, η², ρ, ρη²",
        ),
        ("camera", "n_residuals", True, "camera.n_residuals: expected int, got True"),
        ("camera", "sigma_range", False, "camera.sigma_range: expected float, got False"),
        (
            "camera",
            "sigma_rang",
            0.17,
            "camera.sigma_rang: unknown key; expected one of calibration_window, ",
        ),
        (
            "odometry_inflation",
            "target_percent",
            0,
            "camera.n_residuals must be ≥ 0 and odometry_inflation.target_percent in (0, 100), "
            "got 100 and 0.0",
        ),
    ],
)
def test_a_value_beyond_the_documented_limits_is_refused_naming_the_key(
    tmp_path: Path, section: str, key: str, value: Any, message: str
) -> None:
    save_fit(FIT, tmp_path / "fit.json")
    doc = json.loads((tmp_path / "fit.json").read_text())
    doc.setdefault(section, {})[key] = value
    path = tmp_path / "fit.json"
    path.write_text(json.dumps(doc))
    with pytest.raises(DataError, match="^" + re.escape(f"{path}: {message}")):
        load_fit(path)


def test_a_file_of_exactly_the_largest_size_is_read(tmp_path: Path) -> None:
    save_fit(FIT, tmp_path / "fit.json")
    text = (tmp_path / "fit.json").read_text()
    padded = text + " " * (MAX_FIT_BYTES - len(text.encode()))
    (tmp_path / "fit.json").write_text(padded)
    assert (tmp_path / "fit.json").stat().st_size == MAX_FIT_BYTES
    assert load_fit(tmp_path / "fit.json") == FIT


@pytest.mark.parametrize(
    ("fit", "message"),
    [
        (
            replace(FIT, odometry=replace(FIT.odometry, scale_w=(0.8, 0.8))),
            "odometry.scale_w: 2 values, for a team of 3 robots 3",
        ),
        (
            replace(FIT, camera=replace(FIT.camera, bearing_bias_coeffs=(0.0,) * 3)),
            "camera.bearing_bias_coeffs: 3 values, for a team of 3 robots 0 or 9",
        ),
        (
            replace(FIT, camera=replace(FIT.camera, bearing_bias_limits=(0.0,) * 3)),
            "camera.bearing_bias_limits: 3 values, for a team of 3 robots 0 or 6",
        ),
    ],
)
def test_lengths_that_do_not_fit_the_team_are_refused(fit: FittedModels, message: str) -> None:
    check_fit_for(FIT, 3, SPAN, "fit.json: ")  # the hand-made fit is of a team of three
    with pytest.raises(DataError, match="^" + re.escape(f"fit.json: {message}") + "$"):
        check_fit_for(fit, 3, SPAN, "fit.json: ")


def test_a_window_ending_after_the_recording_is_refused() -> None:
    late = CalibrationWindow(start_s=10.0, end_s=400.5, source="run")
    fit = replace(FIT, camera=replace(FIT.camera, calibration_window=late))
    with pytest.raises(
        DataError,
        match="^"
        + re.escape(
            "fit.json: camera.calibration_window: [10.00, 400.50] s of run is not inside the "
            "recording [0.00, 400.00] s"
        ),
    ):
        check_fit_for(fit, 3, SPAN, "fit.json: ")
    # within a microsecond of the end: inside
    edge = CalibrationWindow(start_s=10.0, end_s=400.0 + 1e-7, source="run")
    check_fit_for(replace(FIT, camera=replace(FIT.camera, calibration_window=edge)), 3, SPAN, "")


def test_the_inflation_check_window_must_lie_inside_the_recording() -> None:
    inflation = OdometryInflation(
        k=1.5,
        fitted_on=CalibrationWindow(start_s=10.0, end_s=200.0, source="run"),
        checked_on=CalibrationWindow(start_s=200.0, end_s=420.0, source="run"),
    )
    with pytest.raises(
        DataError,
        match="^" + re.escape("fit.json: odometry_inflation.checked_on: [200.00, 420.00] s"),
    ):
        check_fit_for(replace(FIT, odometry_inflation=inflation), 3, SPAN, "fit.json: ")
