"""mrclam-cl's summary and report on hand-made figures: the targets judged on the held-out
window (each threshold met at equality), the filter settings of a case, robot 1's GPS-like
fixes, the two anchoring landmarks, and the report's sentences (the verdict, the share of the
run in-sample, the heading error's source, the ratio to dead reckoning, the records without
truth, the odometry factor and the bearing biases)."""

from __future__ import annotations

from dataclasses import replace
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest

from relloc.calibration.camera import CameraFit
from relloc.calibration.odometry import OdometryModelFit
from relloc.calibration.window import CalibrationWindow
from relloc.core.recording import measurement_rows
from relloc.datasets.mrclam import GroundTruth
from relloc.experiments import mrclam_cl
from relloc.experiments.mrclam_cl import FittedModels, OdometryInflation

WINDOW = CalibrationWindow(1.0, 401.0, "run")
#: Odometry inflation fitted on the two halves of WINDOW, met at ×1.5.
INFLATION = OdometryInflation(
    k=1.5,
    met=True,
    target_percent=5.0,
    tried=((1.0, 9.5), (1.5, 4.3)),
    fitted_on=CalibrationWindow(1.0, 201.0, "run"),
    checked_on=CalibrationWindow(201.0, 401.0, "run"),
)


def _fit(inflation: OdometryInflation = INFLATION) -> FittedModels:
    """Round hand-made models of two robots (not fitted: the figures below are by hand)."""
    return FittedModels(
        odometry=OdometryModelFit(
            calibration_window=WINDOW,
            latency_s=0.1,
            time_constant_s=0.25,
            scale_v=(0.9, 0.95),
            scale_w=(0.8, 1.02),
            q_v0=1e-6,
            k_v=0.01,
            q_w0=2e-6,
            k_w=0.04,
            k_wv=0.003,
            odometry_window_s=5.0,
        ),
        camera=CameraFit(
            calibration_window=WINDOW,
            bearing_offset=(0.01, -0.02),
            sigma_bearing_raw=0.007,
            bearing_inflation=25.0,
            sigma_bearing=0.035,
            range_bias_coeffs=(0.06, 0.0, 0.0, 0.0, 0.0),
            sigma_range_raw=0.04,
            range_inflation=16.0,
            sigma_range=0.16,
            range_interval_s=1.0,
            correlation={"range": {"1s": 0.8}},
            n_residuals=100,
        ),
        odometry_inflation=inflation,
    )


WHOLE_SHARE = {"interval": [20.0, 40.0], "verdict": "over-confident"}


def _case(
    whole: tuple[float, float, float], held: tuple[float, float, float], tag: str
) -> dict[str, Any]:
    """One case: whole-run (pos, heading, NEES %) and held-out (pos, heading, NEES %)."""
    return {
        "pos_rmse_m": {"mean": whole[0]},
        "heading_rmse_rad": {"mean": whole[1]},
        "final_pos_err_m": {"mean": 0.5},
        "nees_pct_beyond": whole[2],
        "nees_beyond_interval": WHOLE_SHARE,
        "anees": 1.0,
        "heldout": {
            "pos_rmse_m": held[0],
            "heading_rmse_rad": held[1],
            "nees_pct_beyond": held[2],
            "nees_beyond_interval": {"interval": [1.0, 9.0], "verdict": tag},
            "anees": 1.0,
        },
        "used": 10,
        "rejected": 1,
        "records_without_truth": {},
        "robots_without_truth": [],
        "heldout_records_without_truth": {},
        "heldout_robots_without_truth": [],
    }


def _cases() -> dict[str, Any]:
    """Dead reckoning 3.0 m over the whole run and 2.5 m held out; range+bearing held out at
    0.125 m (20× exactly), 0.09 rad and 10 % (each target met at equality); bearing-only at
    0.13 m (met at equality, but 2.5/0.13 ≈ 19.2×), 0.1 rad and 12.5 % (missed)."""
    dr = _case((3.0, 0.3, 60.0), (2.5, 0.3, 70.0), "dead")
    dr["records_without_truth"] = {"3": 4}
    dr["heldout_records_without_truth"] = {"3": 2}
    dr["heldout_robots_without_truth"] = ["5"]
    bearing = _case((0.12, 0.08, 6.0), (0.13, 0.1, 12.5), "bearing held out")
    bearing["heading_by_landmark_gap"] = {
        "0-1s": {"time_share": 0.5, "heading_rmse_rad": 0.05, "squared_error_share": 0.1},
        "1-5s": {"time_share": 0.2, "heading_rmse_rad": 0.08, "squared_error_share": 0.1},
        "5-infs": {"time_share": 0.3, "heading_rmse_rad": 0.2, "squared_error_share": 0.8},
    }
    return {
        "dead_reckoning/none": dr,
        "range_bearing/all_landmarks": _case(
            (0.1, 0.05, 4.0), (0.125, 0.09, 10.0), "range+bearing held out"
        ),
        "bearing/all_landmarks": bearing,
    }


def test_the_targets_are_judged_on_the_held_out_window_each_met_at_equality() -> None:
    got = mrclam_cl._targets(_cases())
    assert list(got) == ["range_bearing", "bearing"]
    rb, b = got["range_bearing"], got["bearing"]
    assert (rb["pos_rmse_m"], rb["heading_rmse_rad"], rb["nees_pct_beyond"]) == (0.125, 0.09, 10.0)
    assert rb["improvement_over_dead_reckoning"] == 20.0  # 2.5 m / 0.125 m, both held out
    assert rb["pos_ok"] and rb["heading_ok"] and rb["improvement_ok"] and rb["nees_ok"]
    assert rb["nees_beyond_interval"]["verdict"] == "range+bearing held out"
    assert b["pos_rmse_m"] == 0.13 and b["pos_ok"]
    assert b["improvement_over_dead_reckoning"] == pytest.approx(2.5 / 0.13)
    assert not b["heading_ok"] and not b["improvement_ok"] and not b["nees_ok"]
    assert rb["in_sample"] == pytest.approx(
        {
            "pos_rmse_m": 0.1,
            "heading_rmse_rad": 0.05,
            "improvement_over_dead_reckoning": 30.0,
            "nees_pct_beyond": 4.0,
        }
    )


def _summary() -> dict[str, Any]:
    cases = _cases()
    return {
        "dataset": "run",
        "robots": [1, 2],
        "seed": 7,
        "calibration_window_choice": "first-half",
        "two_landmarks": [6, 9],
        "cases": cases,
        "targets": mrclam_cl._targets(cases),
        "fit": _fit().to_dict(),
        "scored_on": {"start_s": 401.0, "end_s": 801.0, "source": "run"},
        "load_report": {"n_skipped": 0, "by_reason": {}},
    }


def test_the_report_states_the_missed_targets_and_the_share_of_the_run_in_sample() -> None:
    text = mrclam_cl._report(_summary(), [])
    assert (
        "Scored on [401, 801] s, the part of the run outside the calibration window [1, 401] s "
        "the error models were fitted on; the whole-run figures, 50% of the run in-sample, "
        "are shown beside for reference only."
    ) in text
    assert (
        "Missed: bearing: heading RMSE; bearing: 20× over dead reckoning; bearing: NEES ≤ 10 %. "
        "For bearing-only CL with all landmarks, 80 % of the squared heading error accrues in "
        "the 30 % of the time when a robot has seen no landmark for 5 s or more"
    ) in text
    assert (
        "| range_bearing | 0.125 | yes | 0.09 | yes | 20 | yes | 10 | yes | 1.0–9.0 range+bearing "
        "held out | 0.1000 / 0.0500 / 30.0 / 4.0 |"
    ) in text
    assert "20.0–40.0" not in text  # the whole run's interval is not the target's


def test_every_target_met_is_said_without_an_explanation() -> None:
    summary = _summary()
    summary["targets"]["bearing"].update(heading_ok=True, improvement_ok=True, nees_ok=True)
    text = mrclam_cl._report(summary, [])
    assert "Every target is met." in text and "Missed" not in text
    assert "squared heading error accrues" not in text


def test_the_heading_sentence_quotes_the_far_and_near_bins_and_the_fitted_odometry() -> None:
    text = mrclam_cl._heading_explanation(_cases(), _fit().to_dict())
    assert (
        "heading RMSE 0.200 rad there) against 0.050 rad within 1 s of a landmark sighting"
    ) in text
    assert (
        "fitted turn-rate scales 0.80–1.02 after a 0.10 s delay and a 0.25 s first-order lag"
    ) in text


def test_the_ratio_sentence_quotes_the_held_out_dead_reckoning_and_the_window_end() -> None:
    """The window's end is stated from the run's start (1 s here), where dead reckoning starts."""
    held = {"start_s": 401.0, "end_s": 801.0}
    text = mrclam_cl._improvement_text(_cases(), held, 1.0)
    assert text.startswith(
        "× better than DR: the held-out position RMSE of dead reckoning (2.50 m) over the filter's."
    )
    assert "(the window ends 800 s after it)" in text


def test_records_and_robots_without_truth_are_named_per_window() -> None:
    text = mrclam_cl._without_truth_text(_cases()["dead_reckoning/none"])
    assert text == (
        "Output times not scored for want of valid ground truth — whole run: robot 3: 4; "
        "held-out window: robot 3: 2. Left out of the per-robot figures and their mean "
        "(held-out window), without any ground truth there: robots 5."
    )
    assert mrclam_cl._without_truth_text(_case((1, 1, 1), (1, 1, 1), "x")) == (
        "Every robot has valid ground truth at every output time scored."
    )


def test_the_odometry_factor_sentence_names_both_halves_and_every_factor_tried() -> None:
    text = mrclam_cl._inflation_text(_fit().to_dict())
    assert text == (
        "the odometry σ multiplied by 1.5 (variance rates by its square): the smallest factor "
        "at which range_bearing/all_landmarks and bearing/all_landmarks, with every model "
        "fitted on the first half of the calibration window, [1, 201] s, and replayed over its "
        "second half, [201, 401] s, keep NEES beyond χ²₃(0.95) at most 5 % of the time (met; "
        "tried ×1: 9.5 %, ×1.5: 4.3 %)."
    )
    unfitted = _fit(OdometryInflation(met=False, not_fitted="too short")).to_dict()
    assert mrclam_cl._inflation_text(unfitted) == (
        "the odometry σ as fitted: no factor on it could be fitted (too short)."
    )


def test_the_bearing_biases_are_written_per_robot_with_their_limits() -> None:
    text = mrclam_cl._bias_text([0.01, -0.02, 0.003, 0.0, 0.1, -0.2], [-0.5, 0.6, -0.4, 0.45])
    assert text == (
        "(+0.0100, -0.0200, +0.0030) over [-0.50, +0.60] rad; "
        "(+0.0000, +0.1000, -0.2000) over [-0.40, +0.45] rad"
    )


def test_a_case_takes_the_odometry_rates_times_the_factor_squared_and_its_own_readings() -> None:
    fit = _fit(replace(INFLATION, k=2.0))
    rb = mrclam_cl.case_settings("range_bearing", "2_landmarks", fit, (3, 5), 6)
    assert rb.odometry.q_v0 == pytest.approx(4e-6) and rb.odometry.k_w == pytest.approx(0.16)
    assert rb.odometry.k_wv == pytest.approx(0.012) and rb.odometry.q_w0 == pytest.approx(8e-6)
    assert rb.use_range and rb.use_bearing and rb.anchors == (3, 5) and not rb.use_fixes
    bearing = mrclam_cl.case_settings("bearing", "all_landmarks", fit, (3, 5), 6)
    assert not bearing.use_range and bearing.anchors == (0, 1, 2, 3, 4, 5)
    gps = mrclam_cl.case_settings("bearing", "gps_robot1", fit, (3, 5), 6)
    assert gps.use_fixes and gps.anchors == ()
    dr = mrclam_cl.case_settings("dead_reckoning", "gps_robot1", fit, (3, 5), 6)
    assert not (dr.use_fixes or dr.use_bearing or dr.use_range or dr.use_robot_detections)
    assert dr.anchors == ()


def _standing_robot(heading: float) -> SimpleNamespace:
    """A dataset whose first robot stands at (1, 2) m with ``heading`` for 10 s."""
    t = np.arange(0.0, 10.01, 0.1)
    one = np.ones(t.size)
    truth = GroundTruth(t=t, x=one, y=2 * one, theta=heading * one, gap_threshold=0.5)
    return SimpleNamespace(robot_ids=(1,), robot=lambda r: SimpleNamespace(groundtruth=truth))


def test_gps_fixes_come_each_second_after_the_start_with_body_frame_noise() -> None:
    # seed 917341: used nowhere else in the tests; the same draws under two true headings
    fixes0 = mrclam_cl.gps_fixes(_standing_robot(0.0), 0.0, 5.0, np.random.default_rng(917341))
    fixes90 = mrclam_cl.gps_fixes(
        _standing_robot(np.pi / 2), 0.0, 5.0, np.random.default_rng(917341)
    )
    # the prior holds the truth at the start: the first fix comes one period later
    np.testing.assert_array_equal(fixes0.t, [1.0, 2.0, 3.0, 4.0])
    np.testing.assert_array_equal(fixes0.observer, [0, 0, 0, 0])
    np.testing.assert_allclose(fixes0.sigma[:, :3], np.tile([0.1, 0.1, 0.03], (4, 1)))
    e0 = fixes0.value[:, :2] - [1.0, 2.0]
    e90 = fixes90.value[:, :2] - [1.0, 2.0]
    assert np.all(np.abs(e0) > 0)
    # e_w = R(θ) e_b: a quarter turn maps (a, b) to (−b, a)
    np.testing.assert_allclose(e90, np.column_stack([-e0[:, 1], e0[:, 0]]), atol=1e-12)
    np.testing.assert_allclose(fixes90.value[:, 2] - np.pi / 2, fixes0.value[:, 2], atol=1e-12)


def test_the_second_anchor_is_the_most_detected_landmark_at_least_a_metre_away() -> None:
    ds = SimpleNamespace(
        path="X",
        landmarks=SimpleNamespace(
            subject=[6, 7, 8, 9],
            xy=np.array([[0.0, 0.0], [0.5, 0.0], [1.0, 0.0], [5.0, 5.0]]),
        ),
    )
    seen = [0] * 5 + [1] * 4 + [2] * 3 + [3]
    rows = measurement_rows(
        "bearing", t=np.arange(13.0), observer=0, landmark=seen, value=np.zeros((13, 1))
    )
    assert mrclam_cl._two_landmarks(rows, ds) == (0, 2)  # exactly 1 m away counts


def test_the_prior_puts_every_robot_at_its_truth_with_the_documented_sigmas() -> None:
    prior = mrclam_cl._truth_prior(_standing_robot(0.5), 3.0)
    np.testing.assert_allclose(prior.mean, [1.0, 2.0, 0.5])
    # σ = 2 cm, 2 cm, 0.01 rad
    np.testing.assert_allclose(prior.cov, np.diag([4e-4, 4e-4, 1e-4]), rtol=1e-12)


def test_output_times_without_truth_are_counted_only_inside_the_scored_window() -> None:
    """Truth over [0, 1] s and [4, 20] s: the record at 2 s has none, the ones at 5–20 s do."""
    t = np.concatenate([np.arange(0.0, 1.01, 0.1), np.arange(4.0, 20.01, 0.1)])
    z = np.zeros(t.size)
    truth = GroundTruth(t=t, x=z, y=z, theta=z, gap_threshold=0.5)
    ds = SimpleNamespace(
        robot_ids=(1,), robot=lambda r: SimpleNamespace(groundtruth=truth), path="hand"
    )
    out_t = np.array([0.0, 2.0, 5.0, 10.0])
    result = {"mean": np.zeros((4, 1, 3)), "cov": np.tile(np.eye(3), (4, 1, 1, 1))}
    assert mrclam_cl.evaluate(result, ds, out_t, 0.0)["records_without_truth"] == {"1": 1}
    assert mrclam_cl.evaluate(result, ds, out_t, 5.0)["records_without_truth"] == {}


def test_the_load_report_line_gives_the_count_of_each_reason() -> None:
    line = mrclam_cl.load_report_line({"n_skipped": 3, "by_reason": {"unknown barcode": 3}})
    assert line == "Input rows of the dataset skipped (not used): 3 (3 unknown barcode)."


def test_a_replay_without_heading_error_gives_every_bin_a_zero_share() -> None:
    out_t = np.array([0.0, 2.0, 6.0])
    rows = measurement_rows("bearing", t=[1.5], observer=0, landmark=0, value=[[0.0]])
    prepared = SimpleNamespace(recording=SimpleNamespace(measurements=rows), out_t=out_t)
    got = mrclam_cl.heading_error_by_landmark_gap(
        {"mean": np.zeros((3, 1, 3))}, _standing_robot(0.0), prepared
    )
    assert [b["squared_error_share"] for b in got.values()] == [0.0, 0.0, 0.0]
    assert [b["time_share"] for b in got.values()] == pytest.approx([1 / 3, 1 / 3, 1 / 3])


def test_the_residual_correlations_read_as_text_not_a_dict() -> None:
    fitted = {
        "range": {"0.25s": 0.8184, "60s": 0.5346},
        "bearing": {"0.25s": 0.4722, "60s": -0.1338},
        "pair_spacing_s": {"median": 0.244},
    }
    assert mrclam_cl._correlation_text(fitted) == (
        "range 0.82 at 0.25 s, 0.53 at 60 s; bearing 0.47 at 0.25 s, -0.13 at 60 s"
    )
