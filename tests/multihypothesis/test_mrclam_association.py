"""``mrclam-association`` on a small synthetic folder in MRCLAM layout (and on run 6 if present)."""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from relloc.cli import main
from relloc.experiments import mrclam_association

HEADER = "# synthetic\n# MRCLAM layout\n# for relloc tests\n# columns\n"
T0 = 1248272272.0


def _write(folder: Path, name: str, rows: list[str]) -> None:
    (folder / name).write_text(HEADER + "\n".join(rows) + "\n")


def _synthetic_folder(
    folder: Path,
    rng: np.random.Generator,
    *,
    command_scale: float = 1.0,
    range_offset: float = 0.0,
) -> Path:
    """Three robots circling in an arena and one landmark; camera rows at 5 Hz. The odometry
    reports ``command_scale`` times the true speed and turn rate, the camera ranges read
    ``range_offset`` long."""
    folder.mkdir(parents=True, exist_ok=True)
    barcodes = {1: 5, 2: 14, 3: 41, 4: 63}
    _write(folder, "Barcodes.dat", [f"{s} {b}" for s, b in barcodes.items()])
    _write(folder, "Landmark_Groundtruth.dat", ["4 0.5 0.5 0.001 0.001"])
    t = np.arange(0.0, 40.0, 0.02)
    poses = {}
    for n, (cx, cy, v, w) in {
        1: (0, 0, 0.25, 0.15),
        2: (2, 1, 0.2, -0.2),
        3: (-1, 2, 0.3, 0.1),
    }.items():
        th = 0.5 * n + w * t
        x = cx + (v / w) * np.sin(th)
        y = cy - (v / w) * np.cos(th)
        poses[n] = (x, y, th)
        gt = [
            f"{T0 + ti:.3f} {xi:.5f} {yi:.5f} {np.angle(np.exp(1j * ti_)):.5f}"
            for ti, xi, yi, ti_ in zip(t, x, y, th, strict=True)
        ]
        _write(folder, f"Robot{n}_Groundtruth.dat", gt)
        k = command_scale
        odo = [f"{T0 + ti:.3f} {k * v:.4f} {k * w:.4f}" for ti in t[::5]]
        _write(folder, f"Robot{n}_Odometry.dat", odo)
    for n in poses:
        rows = []
        for k in range(0, t.size, 10):
            xo, yo, tho = (a[k] for a in poses[n])
            targets = [(m, poses[m][0][k], poses[m][1][k]) for m in poses if m != n]
            targets.append((4, 0.5, 0.5))
            for m, xm, ym in targets:
                r = np.hypot(xm - xo, ym - yo) + range_offset + 0.05 * rng.normal()
                b = (
                    np.angle(np.exp(1j * (np.arctan2(ym - yo, xm - xo) - tho)))
                    + 0.02 * rng.normal()
                )
                rows.append(f"{T0 + t[k]:.3f} {barcodes[m]} {r:.4f} {b:.4f}")
        _write(folder, f"Robot{n}_Measurement.dat", rows)
    return folder


def short_windows(monkeypatch: pytest.MonkeyPatch) -> None:
    """Calibration, scoring and warm-up windows that fit the synthetic folder's 40 s."""
    monkeypatch.setattr(mrclam_association, "CALIBRATION_S", 5.0)
    monkeypatch.setattr(mrclam_association, "EVAL_S", 14.0)
    monkeypatch.setattr(mrclam_association, "WARMUP_S", 6.0)


@pytest.mark.slow
def test_mrclam_association_on_any_mrclam_folder(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, states_skipped_rows: Callable[..., bool]
) -> None:
    folder = _synthetic_folder(tmp_path / "data", np.random.default_rng(0))
    short_windows(monkeypatch)
    out = tmp_path / "out"
    code = main(
        [
            "reproduce",
            "mrclam-association",
            "--out",
            str(out),
            "--dataset",
            str(folder),
            "--runs",
            "2",
            "--quiet",
        ]
    )
    assert code == 0
    s = json.loads((out / "summary.json").read_text())
    # the headline is the unknown-correspondence model, the mean of its runs; sanity bound:
    # each scan holds 2 robot bearings + injected clutter, so chance is below 1/2
    runs = s["spread"]["runs"]
    assert len(runs) == 2 and runs[1]["clock_offset_s"] == pytest.approx(1 / 40)
    acc = [r["association_accuracy"] for r in runs]
    assert s["association_accuracy"] == pytest.approx(np.mean(acc))
    assert s["spread"]["association_accuracy"]["min"] == min(acc)
    # run0 is the spread's run 0: the same clutter draw, the same clock, direct fusion
    keys = mrclam_association.HEADLINE_KEYS
    assert {k: s["run0"][k] for k in keys} == {k: runs[0][k] for k in keys}
    # every camera row of the folder is a robot or the landmark
    assert s["bearings"]["unknown_subject"] == 0
    # without injected clutter no bearing taken is clutter
    assert s["unknown_no_clutter"]["wrong_clutter"] in (0.0, None)
    assert s["association_accuracy"] > 0.75
    assert s["pos_median_m"] is not None and s["pos_median_m"] < 0.3
    assert 0.0 < s["coverage"] <= 1.0
    # calibration and scoring windows are disjoint and stated
    assert s["calibration_window"]["end_s"] <= s["scored_on"]["start_s"]
    fit = s["odometry_noise"]["p_detect_in_view"]
    assert fit["calibration_window"] == s["calibration_window"]
    # the odometry and camera models are stated, and the filters' σ are the camera fit's
    assert {"latency_s", "time_constant_s", "scale_v", "scale_w"} <= set(s["odometry_model"])
    # each robot's white σ is taken at the window length that gives it its largest σ_ω, among
    # the lengths the 5 s calibration window holds twice (1 s and 2 s)
    assert set(s["odometry_noise"]["noise_window_s"]) <= {1.0, 2.0}
    assert len(s["odometry_noise"]["noise_window_s"]) == 3
    assert s["sigma_range_m"] == s["camera_model"]["sigma_range"]
    assert s["sigma_bearing_rad"] == s["camera_model"]["sigma_bearing"]
    # the shared-fusion variant and the camera model are run on the same data, beside it
    for other in (
        "unknown_ranges_all_around",
        "unknown_shared",
        "unknown_mutual_confirmed",
        "unknown_no_clutter",
        "camera",
    ):
        assert {"association_accuracy", "pos_rmse_m", "tracked_fraction"} <= set(s[other])
    lo, hi = s["field_of_view_rad"]
    assert lo == -hi and 0.0 < hi <= np.pi
    assert s["bearings"]["landmark_skipped"] > 0 and s["bearings"]["robot"] > 0
    # the tracked-fraction reference: with the calibrated commands near exact and a sighting
    # every 0.2 s, dead reckoning reset to the truth at every sighting keeps every record
    ref = s["tracking_reference"]
    assert ref["records"] > 0 and ref["tracked_fraction"] >= 0.95 and ref["median_age_s"] < 1.0
    assert "sighting_reset_reference" in (out / "report.md").read_text()
    assert states_skipped_rows((out / "report.md").read_text(), s["load_report"]["n_skipped"])
    # a sighting every 0.2 s: every record, the filter's and the reference's, is under 1 s old
    for bins in (s["tracked_by_age"], ref["by_age"]):
        assert bins[0]["from_s"] == 0.0 and bins[0]["to_s"] == 1.0
        assert bins[0]["records"] > 0 and all(b["records"] == 0 for b in bins[1:])
    assert ref["by_age"][0]["records"] == ref["records"]
    assert "time since the last sighting" in (out / "report.md").read_text()
    assert (out / s["figures"]["errors"]).is_file()


def test_the_calibration_window_fits_calibrate_the_recording(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Commands that over-report speed and turn rate by 10 % and ranges that read 0.15 m long:
    the odometry and camera models fitted on the calibration window undo both on the scoring
    window, and the filters take their σ from the camera fit."""
    from relloc.datasets.mrclam import load_mrclam, to_recording

    folder = _synthetic_folder(
        tmp_path / "data", np.random.default_rng(4), command_scale=1.1, range_offset=0.15
    )
    short_windows(monkeypatch)
    w = mrclam_association._windows(folder)
    fit = w.models.odometry
    assert fit.calibration_window == w.calibration == w.models.camera_fit.calibration_window
    assert fit.scale_v == pytest.approx((1 / 1.1,) * 3, rel=0.01)
    assert fit.scale_w == pytest.approx((1 / 1.1,) * 3, rel=0.01)
    scored = np.arange(w.t_start, w.t_end, 0.5)
    for od, (v, om) in zip(w.raw.odometry, ((0.25, 0.15), (0.2, -0.2), (0.3, 0.1)), strict=True):
        np.testing.assert_allclose(
            od.held_at(scored)[:, [0, 3]], [[v, om]] * scored.size, rtol=0.01
        )
    raw = to_recording(load_mrclam(folder)).measurements.of_kind("range_bearing")
    cal = w.raw.measurements.of_kind("range_bearing")
    rows = (raw.t >= w.t_start) & (raw.t < w.t_end) & (raw.target >= 0)
    shift = raw.value[rows, 0] - cal.value[rows, 0]
    assert np.mean(shift) == pytest.approx(0.15, abs=0.02)
    for settings in (w.models.unknown, w.models.camera):
        assert settings.sigma_range == w.models.camera_fit.sigma_range
        assert settings.sigma_azimuth == w.models.camera_fit.sigma_bearing
    # the headline's ranges are the camera's: their sensor has the camera's field of view
    assert w.models.unknown.range_in_view
    assert w.models.unknown.field_of_view == w.fov_fit.half_width_rad
    # the raw ranges' own noise (0.05 m) is what is left for the filter, give or take the
    # correlation inflation
    assert 0.04 < w.models.camera_fit.sigma_range_raw < 0.07


def test_the_scoring_window_ends_with_the_first_robots_ground_truth(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A robot whose Vicon record stops early (robot 1 of run 6 at 771.9 s of 900 s): the
    scoring window ends there, and the runs are scored, instead of asking for truth beyond it
    (a DataError before ``truth_span``)."""
    folder = _synthetic_folder(tmp_path / "data", np.random.default_rng(3))
    short_windows(monkeypatch)
    gt = folder / "Robot3_Groundtruth.dat"
    rows = gt.read_text().splitlines()
    kept = [r for r in rows if r.startswith("#") or float(r.split()[0]) <= T0 + 17.0]
    gt.write_text("\n".join(kept) + "\n")
    w = mrclam_association._windows(folder)
    assert w.ds.truth_span[1] == pytest.approx(17.0, abs=0.02)
    assert w.t_end == w.ds.truth_span[1] < w.ds.duration
    (run,) = mrclam_association._spread_runs(w, seed=5, runs=1)
    assert run["tracked_fraction"] is not None and run["coverage"] > 0.0


def test_mrclam_association_names_a_missing_folder(tmp_path: Path) -> None:
    code = main(
        [
            "reproduce",
            "mrclam-association",
            "--out",
            str(tmp_path / "o"),
            "--dataset",
            str(tmp_path / "nowhere"),
            "--quiet",
        ]
    )
    assert code == 3


def test_hidden_correspondence_turns_frames_into_scans(tmp_path: Path) -> None:
    from relloc.core.recording import CLUTTER, NO_TARGET
    from relloc.datasets.mrclam import load_mrclam, to_recording

    folder = _synthetic_folder(tmp_path / "data", np.random.default_rng(1))
    raw = to_recording(load_mrclam(folder))
    assert raw.robots == ("1", "2", "3") and raw.landmarks.shape == (1, 3)
    camera = raw.measurements.of_kind("range_bearing")
    rec, counts = mrclam_association._hidden_correspondence(
        raw, 5.0, 15.0, 0.5, np.random.default_rng(2)
    )
    m = rec.measurements
    window = (camera.t >= 5.0) & (camera.t < 15.0)
    robot_rows = window & (camera.target >= 0)
    frames = {
        (float(t), int(o)) for t, o in zip(camera.t[window], camera.observer[window], strict=True)
    }
    assert counts["robot"] == robot_rows.sum() == m.of_kind("range").size
    assert counts["landmark_skipped"] == int((window & (camera.landmark >= 0)).sum())
    assert m.of_kind("height").size == 2 * len(frames)  # 0 to each of the two other robots
    bearings = m.of_kind("bearing")
    assert np.all(bearings.target == NO_TARGET)
    assert int((bearings.origin == CLUTTER).sum()) == counts["injected"]
    assert np.all(np.abs(bearings.value[bearings.origin == CLUTTER, 0]) <= 0.5)
    # a robot's bearing keeps its value and names its robot as origin (scoring only)
    for r in np.flatnonzero(robot_rows)[:20]:
        same = (bearings.t == camera.t[r]) & (bearings.observer == camera.observer[r])
        hit = same & (bearings.value[:, 0] == camera.value[r, 1])
        assert bearings.origin[hit].tolist() == [camera.target[r]]


def test_fits_and_scans_do_not_depend_on_the_world_frame_clock_or_barcodes(
    mrclam_run6_cut, mrclam_run6_moved, tmp_path: Path
) -> None:
    """Another run in every respect the experiment could wrongly depend on: 110 s of three of
    run 6's robots, and the same recorded in a world frame turned by 2 rad and shifted, on a
    clock 123456.789 s later and with other robot barcodes (``tests/conftest.py``). The windows,
    the field of view, every fitted model and the scans built from the camera frames (with the
    same clutter draws) agree, up to the files' rounding of the poses (1e-8 m, 1e-8 rad;
    :mod:`relloc.datasets.mrclam_move`)."""
    cut = mrclam_run6_cut(tmp_path / "cut", robots=(1, 2, 3), keep_s=110.0)
    here = mrclam_association._windows(cut)
    moved = mrclam_association._windows(mrclam_run6_moved(cut, tmp_path / "moved"))
    for w in (here, moved):  # the scored part begins where the calibration ends
        assert w.t_start == w.calibration.end_s and w.t_end > w.t_start
    assert (moved.t_start, moved.t_end) == (here.t_start, here.t_end)
    assert moved.fov_fit.half_width_rad == here.fov_fit.half_width_rad
    for key in ("sigma_v", "sigma_lateral", "sigma_w", "p_detect_all_frames", "widest_range_m"):
        assert moved.models.fits[key] == pytest.approx(here.models.fits[key], rel=1e-6), key
    assert moved.models.fits["p_detect_in_view"]["p_detect"] == pytest.approx(
        here.models.fits["p_detect_in_view"]["p_detect"], rel=1e-6
    )
    for key in ("sigma_range", "sigma_bearing"):
        assert getattr(moved.models.camera_fit, key) == pytest.approx(
            getattr(here.models.camera_fit, key), rel=1e-6
        )
    np.testing.assert_allclose(moved.models.odometry.scale_w, here.models.odometry.scale_w, 1e-6)
    scans = [
        mrclam_association._hidden_correspondence(
            w.raw, w.t_start, w.t_end, w.fov_fit.half_width_rad, np.random.default_rng(5)
        )
        for w in (here, moved)
    ]
    assert scans[0][1] == scans[1][1] and scans[0][1]["robot"] > 0
    bearings = [rec.measurements.of_kind("bearing") for rec, _ in scans]
    np.testing.assert_array_equal(bearings[0].origin, bearings[1].origin)
    # the bearings are corrected by the camera's bias fit, itself fitted against the poses
    np.testing.assert_allclose(bearings[0].value, bearings[1].value, atol=1e-6)


def test_run6_camera_sees_teammates_only_inside_its_field_of_view(mrclam_run6: Path) -> None:
    """On run 6's calibration window, the in-view P_D the unknown-correspondence model uses is
    well above the all-frames share, and the ground truth puts hardly any detection outside
    the fitted field of view (else a P_D of 0 outside it would be wrong)."""
    from relloc.calibration.camera import (
        fit_detection_in_view,
        fit_detection_probability,
        fit_field_of_view,
    )
    from relloc.datasets.mrclam import load_mrclam

    folder = mrclam_run6
    ds = load_mrclam(folder)
    start = max(float(ds.robot(s).odometry.t[0]) for s in ds.robot_ids)
    window = mrclam_association.following(start, mrclam_association.CALIBRATION_S, str(folder))
    fov = fit_field_of_view(ds, window).half_width_rad  # as the experiment: on the window
    fit = fit_detection_in_view(ds, window, fov)
    everywhere = fit_detection_probability(ds, window)
    assert fit.p_detect > 2.0 * everywhere.p_detect
    assert fit.detected_outside <= 0.01 * (fit.detected_in_view + fit.detected_outside)
