"""MRCLAM folders of another layout and bad arguments, on a small synthetic folder of the MRCLAM
layout: a robot whose ground truth stops early, landmarks all within a metre, a window past the
end of the recording, a ``--duration`` or ``--robot`` the run does not hold."""

from __future__ import annotations

import dataclasses
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from mrclam_synthetic import truth_ending_before, write_mrclam_folder

from relloc.calibration.window import CalibrationWindow
from relloc.datasets.mrclam import load_mrclam, to_recording
from relloc.errors import ConfigError, DataError
from relloc.experiments.fit_file import save_fit
from relloc.experiments.mrclam_cl import _two_landmarks, fit_odometry_inflation
from relloc.experiments.mrclam_team import (
    DEFAULT_CASE,
    cooperative_node_parts,
    fit_dataset,
    prepared_team,
    window_end,
)
from relloc.experiments.wanasinghe2014_mrclam import (
    ReplaySettings,
    calibration_stretches,
    calibration_window,
    fit_noise_inflation,
)


@pytest.fixture(scope="module")
def folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """12 s of five simulated robots among six landmarks, robot 5's ground truth ending at
    5.5 s (a robot that left the motion-capture volume)."""
    out = write_mrclam_folder(tmp_path_factory.mktemp("mrclam") / "Synthetic", 12.0)
    truth_ending_before(out, 5, 5.5)
    return out


def test_odometry_inflation_is_not_fitted_where_a_robot_has_no_truth_to_check_on(
    folder: Path,
) -> None:
    ds = load_mrclam(folder)
    got = fit_odometry_inflation(ds, CalibrationWindow(0.0, 12.0, "the test window"))
    assert got.k == 1.0 and not got.met and got.tried == ()
    assert got.checked_on == CalibrationWindow(6.0, 12.0, "the test window")
    assert got.not_fitted == (
        "[6.00, 12.00] s of the test window: no two output times where every robot has ground truth"
    )


def test_landmarks_all_within_a_metre_anchor_on_the_two_most_detected() -> None:
    ds = SimpleNamespace(
        path="X",
        landmarks=SimpleNamespace(
            subject=[6, 7, 8], xy=np.array([[0.0, 0.0], [0.5, 0.0], [0.0, 0.4]])
        ),
    )
    m = SimpleNamespace(landmark=np.array([-1, 2, 2, 2, 1, 1, 0, -1]))
    assert _two_landmarks(m, ds) == (2, 1)  # type: ignore[arg-type]
    # one landmark 1 m or more from the most detected one is taken over a more detected one
    ds.landmarks.xy = np.array([[3.0, 0.0], [0.5, 0.0], [0.0, 0.4]])
    assert _two_landmarks(m, ds) == (2, 0)  # type: ignore[arg-type]


def test_a_duration_holding_no_record_time_and_a_robot_not_in_the_run_are_refused(
    folder: Path, tmp_path: Path
) -> None:
    ds, fit = fit_dataset(folder)
    prepared, _ = prepared_team(ds, fit, 0, DEFAULT_CASE)
    assert window_end(prepared, None) == float(prepared.out_t[-1])
    assert window_end(prepared, 1.0) == 1.0
    with pytest.raises(ConfigError, match=r"^--duration: 0.0 s holds no record time after"):
        window_end(prepared, 0.0)
    save_fit(fit, tmp_path / "fit.json")
    with pytest.raises(
        ConfigError, match=rf"^--robot: 'robot9' is not in {folder} \('1', '2', '3', '4', '5'\)"
    ):
        cooperative_node_parts(str(folder), "robot9", 0, tmp_path / "fit.json", None, DEFAULT_CASE)


def test_a_replay_window_reaching_the_end_of_the_recording_leaves_none_to_calibrate(
    folder: Path,
) -> None:
    ds = load_mrclam(folder)
    got = calibration_window(ds, CalibrationWindow(0.0, 5.0, "s"))
    assert (got.start_s, got.end_s) == (5.0, 12.0)
    with pytest.raises(
        DataError,
        match=rf"^{folder}: the replay window \[0.00, 12.00\] s of scored reaches the end of the "
        "recording",
    ):
        calibration_window(ds, CalibrationWindow(0.0, 12.0, "scored"))


def test_a_pair_sharing_too_little_of_the_calibration_window_is_named(folder: Path) -> None:
    recording = to_recording(load_mrclam(folder))
    settings = ReplaySettings(
        dataset=folder, observer=1, observed=5, duration_s=5.0, min_duration_s=3.0
    )
    window = CalibrationWindow(3.0, 12.0, "cal")
    # robot 5's ground truth ends at 5.5 s: 2.5 s of the window are shared
    with pytest.raises(
        DataError,
        match=r"^calibration window \[3.00, 12.00\] s of cal: robots 1 and 5 share no 3 s of "
        "odometry and ground truth",
    ):
        calibration_stretches(settings, recording, window)
    got = calibration_stretches(dataclasses.replace(settings, observed=2), recording, window)
    assert [(w.start_s, w.source) for w in got] == [
        (3.0, "cal, stretch 1"),
        (8.0, "cal, stretch 2"),
    ]


def test_noise_inflation_needs_a_fitted_replay() -> None:
    settings = ReplaySettings(dataset=Path("X"))
    with pytest.raises(ConfigError, match=r"^fit_noise_inflation: needs a fitted"):
        fit_noise_inflation(
            settings,
            None,  # type: ignore[arg-type]
            None,  # type: ignore[arg-type]
            SimpleNamespace(response=None),  # type: ignore[arg-type]
            steady_state_s=1.0,
            seed=0,
        )
