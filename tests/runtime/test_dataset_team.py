"""A recorded team (MRCLAM layout, written by the test) replayed as a runtime Recording."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from relloc.cli import main
from relloc.errors import DataError
from relloc.estimators.track_manager import TrackManagerSettings
from relloc.runtime.dataset import mrclam_team_recording
from relloc.runtime.launcher import TeamSettings
from relloc.runtime.scenario import load_team
from relloc.runtime.team import team_meta
from relloc.sim.scenario import SensorSpec

T0 = 1_000_000_000.0


def _write(folder: Path, name: str, rows: list[str]) -> None:
    (folder / name).write_text("# test\n# test\n# test\n# test\n" + "\n".join(rows) + "\n")


def _three_robot_folder(
    folder: Path, seconds: float = 40.0, odometry_after_s: float = 0.0, vicon_from_s: float = 0.0
) -> Path:
    """Three robots driving circles (Vicon at 20 Hz from ``vicon_from_s``, odometry commands at
    5 Hz, for ``odometry_after_s`` more than the Vicon)."""
    folder.mkdir(parents=True)
    _write(folder, "Barcodes.dat", ["1 5", "2 14", "3 41", "4 63"])
    _write(folder, "Landmark_Groundtruth.dat", ["4 1.0 2.0 0.001 0.002"])
    for n in (1, 2, 3):
        t = np.arange(vicon_from_s, seconds, 0.05)
        v, w = 0.2, 0.05 * n
        theta = w * t
        x = 2.0 * n + v / w * np.sin(theta)
        y = v / w * (1 - np.cos(theta))
        gt = [
            f"{T0 + ti:.3f} {xi:.5f} {yi:.5f} {np.angle(np.exp(1j * th)):.5f}"
            for ti, xi, yi, th in zip(t, x, y, theta, strict=True)
        ]
        _write(folder, f"Robot{n}_Groundtruth.dat", gt)
        odo = [f"{T0 + ti:.3f} {v} {w}" for ti in np.arange(0.0, seconds + odometry_after_s, 0.2)]
        _write(folder, f"Robot{n}_Odometry.dat", odo)
        _write(folder, f"Robot{n}_Measurement.dat", [f"{T0 + 1.0:.3f} 63 2.5 -0.2"])
    return folder


def test_recorded_team_becomes_a_recording_with_raised_planes(tmp_path):
    folder = _three_robot_folder(tmp_path / "team")
    rec = mrclam_team_recording(folder, np.random.default_rng(0), duration_s=20.0)
    assert rec.robots == ("robot1", "robot2", "robot3")
    assert rec.span == pytest.approx((0.0, 20.0))
    assert np.all(rec.truth[0].pose[:, 2] == 0.0) and np.all(rec.truth[1].pose[:, 2] == 2.0)
    np.testing.assert_allclose(rec.odometry[2].velocity[5], [0.2, 0.0, 0.0, 0.15])
    m = rec.measurements
    assert set(m.observer.tolist()) == {0} and set(m.target.tolist()) == {1, 2}
    assert set(m.kind_names()) == {"range_bearing_elevation"}
    assert m.size == 2 * 200  # 10 Hz for 20 s, both teammates always in view
    # synthesised from the truth with the sensor's noise: residuals are a few sigma at most
    truth = np.stack([rec.relative_truth(0, j, t)[0] for t, j in zip(m.t, m.target, strict=True)])
    assert np.abs(m.value[:, 0] - np.linalg.norm(truth[:, :3], axis=1)).max() < 5 * m.sigma[0, 0]
    team = load_team(str(folder), 4)
    same = team.recording
    again = load_team(str(folder), 4).recording
    np.testing.assert_array_equal(same.measurements.value, again.measurements.value)
    # the settings summary.json states for a recorded team (no scenario file to name them):
    # the folder, the seed, the tracks' settings, every robot's odometry noise fitted from the
    # recording and the observer's sensor noise, as JSON numbers
    meta = team_meta(
        team,
        TeamSettings(scenario=str(folder), out_dir=tmp_path / "out", seed=4, filter_kind="tekf"),
        TrackManagerSettings(filter="tekf", gate_probability=0.9),
    )
    assert json.loads(json.dumps(meta)) == meta
    assert meta["experiment"] == "team_up" and meta["scenario"] == (
        "recorded trajectories of team, readings synthesised (seed 000 §6)"
    )
    assert meta["source"] == same.source and str(folder) in meta["source"] and meta["seed"] == 4
    assert meta["filter"] == "tekf" and meta["gate_probability"] == 0.9
    assert list(meta["odometry_sigma"]) == ["robot1", "robot2", "robot3"]
    for i, sigma in enumerate(meta["odometry_sigma"].values()):
        assert len(sigma) == 4 and sigma == same.odometry[i].sigma.tolist()
    spec = SensorSpec()
    assert meta["sensor_sigma"] == {
        "robot1": [spec.sigma_range, spec.sigma_azimuth, spec.sigma_elevation]
    }


def test_too_short_recording_is_a_clear_error(tmp_path):
    folder = _three_robot_folder(tmp_path / "short", seconds=12.0)
    with pytest.raises(DataError, match="share only"):
        mrclam_team_recording(folder, np.random.default_rng(0))


def test_an_observer_not_in_the_folder_is_a_clear_error(tmp_path):
    folder = _three_robot_folder(tmp_path / "team", seconds=20.0)
    with pytest.raises(DataError, match=r"team: observer robot 9 not in the dataset \(robots"):
        mrclam_team_recording(folder, np.random.default_rng(0), observer=9)


def test_a_team_whose_span_is_no_whole_number_of_ticks_runs_as_processes(tmp_path):
    # the Vicon ends at 19.96 s, the odometry later: the team shares 14.96 s from 5 s after the
    # first odometry, and the clock's last 0.1 s tick (15.0 s) lies beyond it. The nodes
    # recorded a belief there, which no truth could score, and the run ended in a DataError
    folder = _three_robot_folder(
        tmp_path / "team", seconds=20.0, odometry_after_s=1.0, vicon_from_s=0.01
    )
    assert mrclam_team_recording(folder, np.random.default_rng(0)).span[1] == pytest.approx(14.96)
    out = tmp_path / "out"
    assert main(["team", "up", str(folder), "--out", str(out), "--quiet"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["agreement"]["within_tolerance"], summary["agreement"]
