"""Cooperative localization of the five MRCLAM robots on real data (seed 001's EIF).

``relloc reproduce mrclam-cl --out DIR [--dataset PATH] [--seed S] [--executor E]
[--calibration-window first-half|second-half|:T|T:]``

Data: any folder in MRCLAM layout (default ``../shared/data/mrclam/MRCLAM_Dataset6``), loaded
with :mod:`relloc.datasets.mrclam` (unknown barcodes and duplicate stamps are counted there).
All robots start at their ground-truth pose (σ = 2 cm, 2 cm, 0.01 rad) at the first common
ground-truth time and are then estimated jointly by the centralised EIF from odometry and
camera detections, every detection at its own time stamp.

Modes × anchors (``cases`` keys ``<mode>/<anchors>``):

- modes: ``dead_reckoning`` (odometry only; no measurement is used, so its four anchor entries
  are one run), ``bearing`` (bearings only), ``range_bearing`` (ranges and bearings);
- anchors: ``none`` (robot→robot detections only), ``2_landmarks`` (plus the two most-detected
  landmarks of different clusters), ``all_landmarks`` (all landmarks), ``gps_robot1``
  (robot→robot detections plus the first robot's — robot 1 on run 6 — ground-truth pose with
  N(0, diag(0.1 m, 0.1 m, 0.03 rad)²) noise at 1 Hz while its ground truth lasts).

Error models, fitted by :mod:`relloc.calibration` on one side of the same run and checked on
the other (``heldout`` entries). ``--calibration-window``
(:func:`relloc.calibration.window.split_span`) picks the sides of the span from the first
common ground-truth time to the last ground-truth stamp (``MrclamDataset.truth_end``: a stray
row of another file after it has no truth to be scored against): ``first-half`` (the default:
fit on the first half, score the second), ``second-half`` (fit on the second half, score
the first), ``:T`` (fit up to ``T`` s, score after) or ``T:`` (fit from ``T`` s, score
before); summary.json states both,
``fit.calibration_window`` and ``scored_on``.

- odometry (:func:`relloc.calibration.odometry.fit_odometry_model`): one latency ``τ`` and one
  first-order lag ``T`` (the commands lead the motion, which follows them through the lag),
  per-robot scale factors ``s_v, s_ω`` and white input noise with
  variance rates ``q_v = q_v0 + k_v|v|`` and ``q_ω = q_ω0 + k_ω|ω| + k_ωv|v|``, the rates fitted
  over integration windows as long as the expected wait for the next landmark detection
  (:func:`relloc.calibration.camera.landmark_wait_s`, clipped to [0.5, 10] s);
- camera (:func:`relloc.calibration.camera.fit_camera`): a per-robot bearing bias that depends
  on where the target sits in the image, ``b_i(η) = c_i·(1, η, η²)``, and ``σ_η`` (MAD of what
  it leaves), a range bias ``b(η, ρ) = c·(1, η, η², ρ, ρη²)`` and ``σ_r``;
- correlation: consecutive residuals are strongly correlated (lag-correlations in
  ``fit.correlation``); a filter that treats N correlated readings as independent over-counts
  their information. We keep at most one range per (observer, target) pair every
  ``RANGE_INTERVAL_S`` and inflate both variances by the Bartlett factor ``1 + 2 Σ ρ(kΔ)`` at
  the readings' spacing (:mod:`relloc.calibration.inflation`);
- odometry noise inflation (:func:`fit_odometry_inflation`): the odometry errors are
  correlated over seconds too (command lag, scale and turn-rate errors that persist), and a
  model fitted on one stretch of driving under-states the next one's, so white input noise of
  the fitted rates leaves the filter over-confident out of sample. The calibration window is
  cut in two halves; every model is fitted on the first and the EIF of the two headline cases
  (ranges and bearings, bearings only; all landmarks) is replayed over the second, from the
  ground-truth pose at its start. The odometry σ is then multiplied by the smallest factor
  ``k`` of :data:`ODOMETRY_INFLATION_GRID` (the variance rates by ``k²``) at which that replay
  keeps its pose NEES beyond χ²₃(0.95) at most :data:`ODOMETRY_INFLATION_TARGET_PCT` of the
  time (the mean of the two cases; the percentage rule of the seed-000 replay,
  :func:`relloc.experiments.wanasinghe2014_mrclam.fit_noise_inflation`). The held-out window
  plays no part; the factor, every factor tried and both halves are in
  ``fit.odometry_inflation``.

The ratio to dead reckoning (``improvement_over_dead_reckoning``) divides dead reckoning's held-out
error, which grows with the time since the run's start, by the filter's, which does not; so it
depends on the run's length where the other three targets do not (the report says so beside the
targets). Run 6's two 450 s halves, each written as a run of its own with ``relloc mrclam cut``
(``--end 450`` and ``--start 450``) and calibrated on its first half, show it: held-out
range+bearing 0.0956 / 0.1054 m, 0.081 / 0.081 rad, NEES beyond 0.6 / 6.5 %, all met, but 14.6× /
19.2× dead reckoning (1.39 / 2.03 m); bearing-only 0.119 / 0.125 m, 0.084 / 0.083 rad, 0.8 / 6.5 %,
11.7× / 16.3×. On the whole run (900 s, the default split: scored on its held-out second half) the
same code gives 29.5× and 23.2×. The other way round (``--calibration-window second-half``: fitted
on 450–900 s, scored on 0–450 s) range+bearing gives 0.0878 m, 0.0754 rad and 0.02 % NEES beyond,
bearing-only 0.1075 m, 0.0786 rad and 0.02 %, all met, but 14.4× and 11.8× dead reckoning (1.26 m):
the scored window ends 450 s after the start. The 0.02 % says the odometry noise fitted on the later
half (inflated ×1.5, which left 4.9 % beyond on its own check quarter, 675–900 s) over-states the
earlier half's odometry error: conservative, not over-confident.

How sure one run makes the NEES figure (``nees_beyond_interval``: 95 % interval by batch means,
ten 45 s blocks of the held-out window, widened when a block lasts less than ten correlation
times of the NEES, :func:`relloc.metrics.percent_beyond_interval`). The NEES values stay
correlated over 28.7 s (range+bearing) and 31.4 s (bearing-only; ``correlation_time_s``), so a
45 s block is about 1.5 of them (``blocks_short``), where batch means alone hold the truth in
only about 0.84 of draws (``relloc bench intervals``); the interval is then widened to
Clopper–Pearson's for the effective sample size that time leaves (``correlation_samples``: 52
and 39 here, for 900 instants of five robots), and the report says so in the cell. Run 6, the
default split: range+bearing 6.25 % beyond, interval 1.4–16.6 % (batch means alone
1.5–16.4 %); bearing-only 4.95 %, 0.6–17.0 %. Both hold 5 % but reach above 10 %, twice it
(verdict inconclusive, :data:`relloc.metrics.consistency.EQUIVALENCE_FACTOR`): the target is
met on the share, but one run cannot show it is met at 95 % confidence. With
``--calibration-window second-half`` both are 0.02 %, interval 0.0–2.8 % and 0.0–3.0 %:
conservative, as said above.

summary.json keys: ``experiment``, ``seed``, ``runs`` (1: one replay of the recording),
``calibration_window_choice`` (the ``--calibration-window`` value), ``dataset``, ``robots``,
``two_landmarks`` (the subjects of the ``2_landmarks`` anchors);
``cases.<mode>/<anchors>``, scored at the output times (every ``OUTPUT_DT_S`` = 0.5 s) of the
whole replay, from the first common ground-truth time to the end (calibration and held-out
windows together): ``pos_rmse_m`` (planar) and ``heading_rmse_rad`` (per robot
"1"…"5" and ``mean`` = arithmetic mean over robots), ``final_pos_err_m`` (same layout: the
planar error at the robot's last scored output time, m),
``nees_pct_beyond`` (per-robot 3-DOF NEES above χ²₃(0.95), pooled; ``nees_beyond_interval``
its 95 % interval by batch means over time, :func:`relloc.metrics.percent_beyond_interval`,
with the verdict — over-confident, conservative, consistent or inconclusive,
:func:`relloc.metrics.consistency.share_verdict` —: :class:`relloc.metrics.BeyondShare`'s
keys), ``anees`` (mean NEES / 3),
``used`` (detections and fixes the filter used), ``rejected`` (χ² gate + degenerate geometry +
unknown barcodes + unmapped subjects), ``counts`` (the breakdown: the filter's
:class:`relloc.estimators.cooperative.Counts` ``used``, ``rejected``, ``detections_used``,
``fixes_used``, ``rejected_gate``, ``rejected_degenerate``, ``ignored_not_anchor``,
``ignored_robot_detection``, ``ignored_unused``, ``ignored_unmodelled``, ``ranges_thinned``,
``epochs``, ``stale_odometry_s`` (per robot in ``robots`` order, s without fresh odometry),
then the conversion's ``unknown_barcodes`` and ``unmapped_subjects``),
``records_without_truth`` (per robot, the output times not scored for want of valid ground
truth; robots with some only) and ``robots_without_truth`` (robots with none, left out of the
per-robot figures and their mean; also said in report.md), the same over the held-out window
(``heldout_records_without_truth``, ``heldout_robots_without_truth``),
``heldout`` (over the held-out window only, and only the means over robots:
``pos_rmse_m``, ``heading_rmse_rad``, with ``nees_pct_beyond``, ``nees_beyond_interval`` and
``anees``; no per-robot figures, no ``final_pos_err_m``),
``heading_by_landmark_gap`` (``all_landmarks`` cases with measurements only:
:func:`heading_error_by_landmark_gap`, over the whole replay: bins ``"0-1s"``, ``"1-5s"``,
``"5-infs"`` of the time since the robot last detected a landmark → ``time_share``,
``heading_rmse_rad``, ``squared_error_share``), ``note`` (``dead_reckoning`` cases only: its
anchor entries are one run); ``fit`` (the fitted models, flat: ``t_lo`` and ``t_hi``, the
calibration window's ends in s; the odometry fit,
:class:`~relloc.calibration.odometry.OdometryModelFit` without its window: ``latency_s``,
``time_constant_s``, ``scale_v`` and ``scale_w`` per robot, the variance rates ``q_v0``,
``k_v``, ``q_w0``, ``k_w``, ``k_wv`` (the filters take them times ``k²``),
``odometry_window_s``, ``unfitted_robots``; the camera fit,
:class:`~relloc.calibration.camera.CameraFit` without its window: ``bearing_offset`` per robot,
``bearing_bias_coeffs`` and ``bearing_bias_limits`` flat, robot-major, ``range_bias_coeffs``,
``sigma_bearing_raw`` / ``sigma_range_raw`` (MAD), ``bearing_inflation`` / ``range_inflation``
(variance factors), ``sigma_bearing`` / ``sigma_range`` (what the filters use, rad and m),
``range_interval_s``, ``correlation`` (``range`` and ``bearing``: lag → measured correlation;
``pair_spacing_s``: ``median``), ``n_residuals``; ``odometry_inflation``: ``k``, ``met``,
``target_percent``, ``tried`` (``k`` and its ``nees_pct_beyond`` per factor tried), ``cases``,
``fitted_on`` and ``checked_on`` (the two halves, null when not fitted), ``not_fitted`` (empty,
or why); ``calibration_window``: ``start_s``, ``end_s``, ``source``),
``scored_on`` (the held-out window, ``start_s``, ``end_s`` (s) and ``source``, on the other side
of the span from the calibration window: after it by default, before it with ``second-half``
or ``T:``; clipped to the replay's output times), ``targets`` (the issue's targets, judged on
the held-out window of the ``all_landmarks`` cases, per mode ``range_bearing`` and ``bearing``:
``pos_rmse_m`` with ``pos_ok`` (≤ 0.13 m), ``heading_rmse_rad`` with ``heading_ok``
(≤ 0.09 rad), ``improvement_over_dead_reckoning`` (dead reckoning's held-out ``pos_rmse_m``
over the filter's; null at a zero error) with ``improvement_ok`` (≥ 20), ``nees_pct_beyond``
with ``nees_ok`` (≤ 10 %) and ``nees_beyond_interval``; the whole-run figures under
``in_sample``: ``pos_rmse_m``, ``heading_rmse_rad``, ``improvement_over_dead_reckoning``,
``nees_pct_beyond``), ``paper_reference`` (the run-6 figures behind the targets: a plain joint
EKF's ``joint_ekf_pos_rmse_m`` and dead reckoning's ``dead_reckoning_pos_rmse_m``),
``load_report`` (rows the loader and :func:`relloc.datasets.mrclam.to_recording` skipped:
``n_skipped`` and ``by_reason``, reason → count; also a line in report.md,
:func:`load_report_line`). The fitted latency, scales and bearing
biases are applied to the recording before the replay (:func:`build_recording`).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from relloc.calibration.camera import CameraFit, corrected_readings, fit_camera, landmark_wait_s
from relloc.calibration.inflation import CORRELATION_HORIZON_S, search_text, smallest_factor
from relloc.calibration.odometry import (
    OdometryModelFit,
    calibrated_team,
    fit_odometry_model,
    unfitted_note,
)
from relloc.calibration.window import (
    SPLIT_CHOICES,
    CalibrationWindow,
    leading_fraction,
    split_span,
)
from relloc.core.estimates import Estimates
from relloc.core.gaussian import Gaussian
from relloc.core.recording import Measurements, Recording, measurement_rows
from relloc.errors import ConfigError, DataError
from relloc.estimators.cooperative import (
    CooperativeEstimator,
    CooperativeSettings,
    OdometryModel,
    SensorModel,
)
from relloc.experiments.registry import ReproduceArgs
from relloc.pipeline.montecarlo import run_monte_carlo
from relloc.pipeline.output import (
    figure_md,
    interval_text,
    markdown_table,
    prepare_out_dir,
    save_figure,
    skipped_rows_line,
    write_report,
    write_summary,
)
from relloc.pipeline.replay import replay

Array = NDArray[np.float64]

OUTPUT_DT_S = 0.5
INITIAL_SIGMA = (0.02, 0.02, 0.01)
GPS_SIGMA = (0.1, 0.1, 0.03)
GPS_PERIOD_S = 1.0
RANGE_INTERVAL_S = 1.0
P_GATE = 0.999
MODES = ("dead_reckoning", "bearing", "range_bearing")
ANCHORS = ("none", "2_landmarks", "all_landmarks", "gps_robot1")
#: The case ``--mcap``/``--tum`` write, and what that is.
EXPORTED_CASE = ("range_bearing", "all_landmarks")
EXPORTED_RUN = (
    "the centralised EIF with ranges, bearings and all landmarks: every robot's (x, y, heading) "
    "in the world frame, owner 'team'"
)
TARGET_POS_RMSE_M = 0.13
TARGET_HEADING_RMSE_RAD = 0.09
TARGET_IMPROVEMENT = 20.0
TARGET_NEES_PCT = 10.0
#: Factors tried on the odometry noise σ, in order (:func:`fit_odometry_inflation`).
ODOMETRY_INFLATION_GRID = (1.0, 1.5, 2.0, 3.0, 4.0)
#: The share (%) of calibration-window NEES beyond χ²₃(0.95) the chosen factor must keep.
ODOMETRY_INFLATION_TARGET_PCT = 5.0
#: The cases whose calibration-window consistency sets the factor (the targets' cases).
INFLATION_CASES = (("range_bearing", "all_landmarks"), ("bearing", "all_landmarks"))


# ----------------------------------------------------------------------------------------------
# The error models, fitted by relloc.calibration on the calibration window of the run
# ----------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class OdometryInflation:
    """The factor ``k`` on the odometry noise σ and how it was chosen
    (:func:`fit_odometry_inflation`): the models fitted on ``fitted_on``, replayed over
    ``checked_on`` (the two halves of the calibration window); per factor tried (``tried``, in
    order, up to the first that met ``target_percent``) the mean over :data:`INFLATION_CASES`
    of the % of ``checked_on``'s output times whose pose NEES is beyond χ²₃(0.95); ``met``:
    whether ``k`` meets the target (else ``k`` is the grid's largest); ``not_fitted``: why no
    factor could be fitted (a calibration window too short to cut in two usable halves: ``k``
    is then 1). The default is no inflation, fitted nowhere."""

    k: float = 1.0
    met: bool = True
    target_percent: float = ODOMETRY_INFLATION_TARGET_PCT
    tried: tuple[tuple[float, float], ...] = ()
    fitted_on: CalibrationWindow | None = None
    checked_on: CalibrationWindow | None = None
    not_fitted: str = ""


@dataclass(frozen=True)
class FittedModels:
    """The odometry and camera models, both fitted on one calibration window, and the factor
    on the odometry noise fitted there (``odometry_inflation``; none by default)."""

    odometry: OdometryModelFit
    camera: CameraFit
    odometry_inflation: OdometryInflation = OdometryInflation()

    @property
    def window(self) -> CalibrationWindow:
        """The window both models were fitted on."""
        return self.odometry.calibration_window

    def to_dict(self) -> dict[str, Any]:
        """``summary.json["fit"]``: the window's ends, every fitted value, the window."""
        odometry = {k: v for k, v in self.odometry.to_dict().items() if k != "calibration_window"}
        camera = {k: v for k, v in self.camera.to_dict().items() if k != "calibration_window"}
        inflation = self.odometry_inflation
        return {
            "t_lo": self.window.start_s,
            "t_hi": self.window.end_s,
            **odometry,
            **camera,
            "odometry_inflation": {
                "k": inflation.k,
                "met": inflation.met,
                "target_percent": inflation.target_percent,
                "tried": [{"k": k, "nees_pct_beyond": p} for k, p in inflation.tried],
                "cases": ["/".join(c) for c in INFLATION_CASES],
                "fitted_on": _window_dict(inflation.fitted_on),
                "checked_on": _window_dict(inflation.checked_on),
                "not_fitted": inflation.not_fitted,
            },
            "calibration_window": self.window.to_dict(),
        }


def _window_dict(window: CalibrationWindow | None) -> dict[str, Any] | None:
    """``window.to_dict()``, ``None`` where there is no window."""
    return None if window is None else window.to_dict()


def fit_models(ds: Any, window: CalibrationWindow) -> FittedModels:
    """Fit every error model on ``window`` (:func:`fit_error_models`), then the factor on the
    odometry noise (:func:`fit_odometry_inflation`)."""
    return replace(
        fit_error_models(ds, window), odometry_inflation=fit_odometry_inflation(ds, window)
    )


def fit_error_models(ds: Any, window: CalibrationWindow) -> FittedModels:
    """The odometry and camera models fitted on ``window``, no noise inflation; the odometry's
    variance rates over the expected wait for the next landmark detection (clipped to
    [0.5 s, the correlation horizon])."""
    integration_s = float(np.clip(landmark_wait_s(ds, window), 0.5, CORRELATION_HORIZON_S))
    return FittedModels(
        odometry=fit_odometry_model(ds, window, integration_s),
        camera=fit_camera(ds, window, range_interval_s=RANGE_INTERVAL_S),
    )


def fit_odometry_inflation(ds: Any, window: CalibrationWindow) -> OdometryInflation:
    """The smallest factor ``k`` of :data:`ODOMETRY_INFLATION_GRID` on the odometry σ at which
    the models fitted on the first half of ``window`` (:func:`fit_error_models`) keep the EIF of
    :data:`INFLATION_CASES`, replayed over the second half (from the ground-truth pose at its
    first output time where every robot has one, σ :data:`INITIAL_SIGMA`), at a mean over the
    cases of at most :data:`ODOMETRY_INFLATION_TARGET_PCT` % of pose NEES beyond χ²₃(0.95);
    the grid's largest if none does (``met`` false). Where the first half is too short to fit
    the models on, or the second has no two instants where every robot has ground truth, the
    factor is 1 and ``not_fitted`` says why. Only ``window`` is read; deterministic (the cases
    use no GPS fix, the only random input)."""
    fitted_on = leading_fraction(window.start_s, window.end_s, 0.5, window.source)
    checked_on = CalibrationWindow(fitted_on.end_s, window.end_s, window.source)
    unfitted = OdometryInflation(met=False, fitted_on=fitted_on, checked_on=checked_on)
    try:
        fitted = fit_error_models(ds, fitted_on)
    except DataError as exc:
        return replace(unfitted, not_fitted=str(exc))
    prepared = build_recording(ds, fitted, np.random.default_rng(0))
    t = prepared.out_t[
        (prepared.out_t >= checked_on.start_s) & (prepared.out_t <= checked_on.end_s)
    ]
    valid = np.all([ds.robot(r).groundtruth.at(t).valid for r in ds.robot_ids], axis=0)
    if np.count_nonzero(valid) < 2:
        reason = f"{checked_on.describe()}: no two output times where every robot has ground truth"
        return replace(unfitted, not_fitted=reason)
    t = t[int(np.argmax(valid)) :]
    check = replace(prepared, prior=_truth_prior(ds, float(t[0])), t_start=float(t[0]))
    n_lm = prepared.recording.landmarks.shape[0]

    def percent_beyond(k: float) -> float:
        inflated = replace(fitted, odometry_inflation=OdometryInflation(k=k))
        percents = []
        for mode, anchors in INFLATION_CASES:
            settings = case_settings(mode, anchors, inflated, prepared.two_landmarks, n_lm)
            run = run_filter(check, settings, t)
            percents.append(evaluate(run, ds, t, float(t[0]))["nees_pct_beyond"])
        return float(np.mean(percents))

    k, met, tried = smallest_factor(
        ODOMETRY_INFLATION_GRID, ODOMETRY_INFLATION_TARGET_PCT, percent_beyond
    )
    return replace(unfitted, k=k, met=met, tried=tried)


def _truth_prior(ds: Any, t: float) -> Gaussian:
    """Every robot at its ground-truth pose at ``t``, σ :data:`INITIAL_SIGMA`."""
    start = np.concatenate([ds.robot(r).groundtruth.at(t).pose for r in ds.robot_ids])
    return Gaussian(
        mean=start.reshape(-1), cov=np.diag(np.tile(np.square(INITIAL_SIGMA), len(ds.robot_ids)))
    )


# ----------------------------------------------------------------------------------------------
# Dataset → recording, cases, evaluation
# ----------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Prepared:
    """The calibrated recording, its prior, the output times and the bookkeeping of the
    readings it could not hold."""

    recording: Recording
    prior: Gaussian
    t_start: float
    out_t: Array
    landmark_subjects: tuple[int, ...]
    two_landmarks: tuple[int, int]
    unmapped_subjects: int


def build_recording(ds: Any, fit: FittedModels, rng: np.random.Generator) -> Prepared:
    """The dataset's recording (:func:`relloc.datasets.mrclam.to_recording`) calibrated with the
    fitted models, plus robot 1's GPS-like fixes, and the prior at the first common ground-truth
    time."""
    from relloc.datasets.mrclam import UNMAPPED_SUBJECT, to_recording

    raw = to_recording(ds)
    t_start = ds.truth_span[0]
    t_end = ds.truth_end
    out_t = np.arange(t_start, t_end, OUTPUT_DT_S)
    recording = replace(
        raw,
        odometry=calibrated_team(raw.odometry, fit.odometry),
        measurements=Measurements.concatenate(
            [corrected_readings(raw.measurements, fit.camera), gps_fixes(ds, t_start, t_end, rng)]
        ),
    )
    return Prepared(
        recording,
        _truth_prior(ds, t_start),
        t_start,
        out_t,
        tuple(raw.meta["landmark_subjects"]),
        _two_landmarks(raw.measurements, ds),
        raw.skips.skipped_by_reason().get(UNMAPPED_SUBJECT, 0),
    )


def gps_fixes(ds: Any, t_start: float, t_end: float, rng: np.random.Generator) -> Measurements:
    """Robot 1's GPS-like fixes: ground truth + ``N(0, diag(GPS_SIGMA)²)`` at 1 Hz while its
    ground truth is valid. The position noise is drawn in the robot's body frame and turned
    into the world frame by its true heading, ``e_w = R(θ) e_b``: the same distribution (the
    position σ are equal), and the same fixes relative to the robot in any world frame, so a
    run moved to another frame (``relloc mrclam move``) gives the same figures."""
    gt1 = ds.robot(ds.robot_ids[0]).groundtruth
    tg = np.arange(t_start + GPS_PERIOD_S, t_end, GPS_PERIOD_S)
    q = gt1.at(tg)
    tg, pose = tg[q.valid], q.pose[q.valid]
    e = rng.normal(size=pose.shape) * np.asarray(GPS_SIGMA)
    c, s = np.cos(pose[:, 2]), np.sin(pose[:, 2])
    e[:, 0], e[:, 1] = c * e[:, 0] - s * e[:, 1], s * e[:, 0] + c * e[:, 1]
    return measurement_rows("pose", t=tg, observer=0, value=pose + e, sigma=np.asarray(GPS_SIGMA))


def _two_landmarks(m: Measurements, ds: Any) -> tuple[int, int]:
    """The most-detected landmark and the most-detected one at least 1 m from it (indices)."""
    assert m.landmark is not None
    if len(ds.landmarks.subject) < 2:
        raise DataError(
            f"{ds.path}: mrclam-cl anchors its two_landmarks cases on two landmarks; "
            f"Landmark_Groundtruth.dat has {len(ds.landmarks.subject)}"
        )
    counts = np.bincount(m.landmark[m.landmark >= 0], minlength=len(ds.landmarks.subject))
    order = np.argsort(-counts, kind="stable")
    first = int(order[0])
    for k in order[1:]:
        if np.linalg.norm(ds.landmarks.xy[k] - ds.landmarks.xy[first]) >= 1.0:
            return first, int(k)
    return first, int(order[1])


def case_settings(
    mode: str, anchors: str, fit: FittedModels, two: tuple[int, int], n_lm: int
) -> CooperativeSettings:
    """Filter settings of one ``<mode>/<anchors>`` case (the odometry variance rates times the
    square of the fitted inflation factor)."""
    k2 = fit.odometry_inflation.k**2
    odometry = OdometryModel(
        q_v0=k2 * fit.odometry.q_v0,
        q_w0=k2 * fit.odometry.q_w0,
        k_v=k2 * fit.odometry.k_v,
        k_w=k2 * fit.odometry.k_w,
        k_wv=k2 * fit.odometry.k_wv,
        max_hold_s=1.0,
        max_step_s=0.05,
    )
    sensor = SensorModel(
        sigma_bearing=fit.camera.sigma_bearing,
        sigma_range0=fit.camera.sigma_range,
        range_bias_coeffs=fit.camera.range_bias_coeffs,
        range_min_interval_s=fit.camera.range_interval_s,
    )
    anchor_set = {
        "none": (),
        "2_landmarks": two,
        "all_landmarks": tuple(range(n_lm)),
        "gps_robot1": (),
    }
    return CooperativeSettings(
        odometry=odometry,
        sensor=sensor,
        use_bearing=mode != "dead_reckoning",
        use_range=mode == "range_bearing",
        use_robot_detections=mode != "dead_reckoning",
        anchors=anchor_set[anchors] if mode != "dead_reckoning" else (),
        use_fixes=anchors == "gps_robot1" and mode != "dead_reckoning",
        p_gate=P_GATE,
        filter="eif",
    )


def case_estimates(
    prepared: Prepared, settings: CooperativeSettings, out_t: Array
) -> tuple[Estimates, dict[str, Any]]:
    """Replay the recording from ``t_start`` through the team filter, recording at ``out_t``:
    the estimates and the filter's counts."""
    rec = prepared.recording
    estimator = CooperativeEstimator(rec.robots, prepared.prior, settings, rec.landmarks)
    estimates = replay(
        rec, [estimator], record_times=out_t, start=prepared.t_start, end=float(out_t[-1])
    )
    return estimates, estimator.counts.to_dict()


def run_filter(prepared: Prepared, settings: CooperativeSettings, out_t: Array) -> dict[str, Any]:
    """:func:`case_estimates` as ``mean (T, n, 3)``, ``cov (T, n, 3, 3)`` and the counts."""
    estimates, counts = case_estimates(prepared, settings, out_t)
    _, mean, cov = estimates.stacked(CooperativeEstimator.owner, prepared.recording.robots)
    return {"mean": mean, "cov": cov, "counts": counts}


def run_case(
    seed_sequence: np.random.SeedSequence,
    index: int,
    prepared: Prepared,
    settings: list[CooperativeSettings],
) -> dict[str, Any]:
    """Replay one case (a picklable task for :func:`run_monte_carlo`; no randomness used)."""
    return run_filter(prepared, settings[index], prepared.out_t)


def evaluate(
    result: dict[str, Any], ds: Any, out_t: Array, t_from: float, t_to: float = np.inf
) -> dict[str, Any]:
    """Accuracy and consistency against ground truth at the output times in
    ``[t_from, t_to]``. Output times where a robot has no valid ground truth are not scored:
    ``records_without_truth`` counts them per robot (robots with some only), and a robot
    without any is left out of the per-robot figures and their mean and named in
    ``robots_without_truth`` (DataError when no robot has any)."""
    from relloc.metrics import chi2_upper, nees, percent_beyond_interval, state_errors

    pos, head, final, nees_all, nees_t = {}, {}, {}, [], []
    without: dict[str, int] = {}
    dropped: list[str] = []
    for i, rid in enumerate(ds.robot_ids):
        q = ds.robot(rid).groundtruth.at(out_t)
        inside = (out_t >= t_from) & (out_t <= t_to)
        ok = q.valid & inside
        missing = int(np.count_nonzero(inside & ~q.valid))
        if missing:
            without[str(rid)] = missing
        if not ok.any():
            dropped.append(str(rid))
            continue
        err = state_errors(result["mean"][ok, i], q.pose[ok], angle_indices=(2,))
        pos[str(rid)] = float(np.sqrt(np.mean(np.sum(err[:, :2] ** 2, axis=1))))
        head[str(rid)] = float(np.sqrt(np.mean(err[:, 2] ** 2)))
        final[str(rid)] = float(np.hypot(*err[-1, :2]))
        nees_all.append(nees(err, result["cov"][ok, i]))
        nees_t.append(out_t[ok])
    if not nees_all:
        raise DataError(
            f"{ds.path}: no robot has ground truth at an output time in [{t_from:g}, {t_to:g}] s "
            "to score the estimates against"
        )
    ne = np.concatenate(nees_all)
    share = percent_beyond_interval(ne, np.concatenate(nees_t), chi2_upper(3, 0.95))
    for d in (pos, head, final):
        d["mean"] = float(np.mean(list(d.values())))
    return {
        "pos_rmse_m": pos,
        "heading_rmse_rad": head,
        "final_pos_err_m": final,
        "nees_pct_beyond": share.percent,
        "nees_beyond_interval": share.to_dict(),
        "anees": float(np.mean(ne) / 3.0),
        "records_without_truth": without,
        "robots_without_truth": dropped,
    }


GAP_BINS_S = ((0.0, 1.0), (1.0, 5.0), (5.0, np.inf))


def heading_error_by_landmark_gap(
    result: dict[str, Any], ds: Any, prepared: Prepared
) -> dict[str, dict[str, float]]:
    """Heading RMSE, share of time and share of squared heading error, binned by the time since
    the robot last detected a landmark (where does the heading error come from?). A record
    before the robot's first detection has waited without bound: it falls in the last bin, so
    the shares of the bins add up to 1."""
    from relloc.metrics import state_errors

    rows = prepared.recording.measurements
    assert rows.landmark is not None
    errs, gaps = [], []
    for i, rid in enumerate(ds.robot_ids):
        q = ds.robot(rid).groundtruth.at(prepared.out_t)
        t = prepared.out_t[q.valid]
        errs.append(state_errors(result["mean"][q.valid, i], q.pose[q.valid], (2,))[:, 2])
        seen = np.sort(rows.t[(rows.observer == i) & (rows.landmark >= 0)])
        k = np.searchsorted(seen, t, side="right") - 1
        gaps.append(np.where(k >= 0, t - seen[np.maximum(k, 0)], np.inf))
    e, g = np.concatenate(errs), np.concatenate(gaps)
    total = float(np.sum(e**2))
    out: dict[str, dict[str, float]] = {}
    for lo, hi in GAP_BINS_S:
        m = (g >= lo) & (g < hi) if np.isfinite(hi) else g >= lo  # the last bin takes ∞
        out[f"{lo:g}-{hi:g}s"] = {
            "time_share": float(m.mean()),
            "heading_rmse_rad": float(np.sqrt(np.mean(e[m] ** 2))) if m.any() else float("nan"),
            "squared_error_share": float(np.sum(e[m] ** 2) / total) if total > 0 else 0.0,
        }
    return out


def reproduce(args: ReproduceArgs) -> dict[str, Any]:
    """Fit, run every case, evaluate and write summary.json, report.md and figures."""
    from relloc.datasets.mrclam import load_mrclam
    from relloc.datasets.paths import default_mrclam_dataset

    out = prepare_out_dir(args.out_dir)
    folder = Path(args.dataset) if args.dataset is not None else default_mrclam_dataset()
    ds = load_mrclam(folder)
    t0 = ds.truth_span[0]
    spec = args.calibration_window if args.calibration_window is not None else SPLIT_CHOICES[0]
    window, scored = split_span(spec, t0, ds.truth_end, str(folder))
    fit = fit_models(ds, window)
    prepared = build_recording(ds, fit, np.random.default_rng(args.master_seed))
    first, last = (
        max(scored.start_s, prepared.t_start),
        min(scored.end_s, float(prepared.out_t[-1])),
    )
    if not last > first:
        raise ConfigError(
            f"--calibration-window {spec!r}: the scoring window [{scored.start_s:.2f}, "
            f"{scored.end_s:.2f}] s holds no span of the output times of {folder} (every "
            f"{OUTPUT_DT_S:g} s from {prepared.t_start:.2f} to {prepared.out_t[-1]:.2f} s)"
        )
    heldout = CalibrationWindow(first, last, str(folder))
    n_lm = prepared.recording.landmarks.shape[0]
    keys = [("dead_reckoning", "none")] + [(m, a) for m in MODES[1:] for a in ANCHORS]
    settings = [case_settings(m, a, fit, prepared.two_landmarks, n_lm) for m, a in keys]
    results = run_monte_carlo(
        run_case,
        len(keys),
        args.master_seed,
        executor=args.executor,
        task_args=(prepared, settings),
        description="mrclam-cl cases",
        quiet=args.quiet,
    )
    skips = prepared.recording.skips  # the loader's and the conversion's
    unknown = int(skips.skipped_by_reason().get("unknown barcode", 0))
    cases: dict[str, Any] = {}
    by_key = dict(zip(keys, results, strict=True))
    for mode in MODES:
        for anchors in ANCHORS:
            key = (mode, anchors) if mode != "dead_reckoning" else ("dead_reckoning", "none")
            res = by_key[key]
            entry = evaluate(res, ds, prepared.out_t, prepared.t_start)
            held = evaluate(res, ds, prepared.out_t, heldout.start_s, heldout.end_s)
            c = res["counts"]
            entry["used"] = int(c["used"])
            entry["rejected"] = int(c["rejected"]) + unknown + prepared.unmapped_subjects
            entry["counts"] = {
                **c,
                "unknown_barcodes": unknown,
                "unmapped_subjects": prepared.unmapped_subjects,
            }
            entry["heldout"] = {
                "pos_rmse_m": held["pos_rmse_m"]["mean"],
                "heading_rmse_rad": held["heading_rmse_rad"]["mean"],
                "nees_pct_beyond": held["nees_pct_beyond"],
                "nees_beyond_interval": held["nees_beyond_interval"],
                "anees": held["anees"],
            }
            entry["heldout_records_without_truth"] = held["records_without_truth"]
            entry["heldout_robots_without_truth"] = held["robots_without_truth"]
            if anchors == "all_landmarks" and mode != "dead_reckoning":
                entry["heading_by_landmark_gap"] = heading_error_by_landmark_gap(res, ds, prepared)
            if mode == "dead_reckoning":
                entry["note"] = "odometry only: anchors unused, identical for every anchor set"
            cases[f"{mode}/{anchors}"] = entry
    targets = _targets(cases)
    summary: dict[str, Any] = {
        "experiment": "mrclam-cl",
        "seed": args.master_seed,
        "runs": 1,
        "calibration_window_choice": spec,
        "dataset": str(folder),
        "robots": list(ds.robot_ids),
        "two_landmarks": [prepared.landmark_subjects[k] for k in prepared.two_landmarks],
        "fit": fit.to_dict(),
        "scored_on": heldout.to_dict(),
        "cases": cases,
        "targets": targets,
        "paper_reference": {"joint_ekf_pos_rmse_m": 0.13, "dead_reckoning_pos_rmse_m": 2.7},
        "load_report": {
            "n_skipped": skips.n_skipped,
            "by_reason": skips.skipped_by_reason(),
        },
    }
    if args.export is not None:
        from relloc.pipeline.export import export_estimates

        index = keys.index(EXPORTED_CASE)
        estimates, _ = case_estimates(prepared, settings[index], prepared.out_t)
        summary["export"] = export_estimates(
            args.export, estimates, prepared.recording, run=f"{folder.name}: {EXPORTED_RUN}"
        )
    figures = _figures(out, ds, prepared, by_key, cases)
    write_summary(out, summary)
    write_report(out, _report(summary, figures))
    return summary


def _inflation_text(fit: dict[str, Any]) -> str:
    """The report's sentence on the odometry noise factor and how it was chosen."""
    inf = fit["odometry_inflation"]
    if inf["not_fitted"]:
        return f"the odometry σ as fitted: no factor on it could be fitted ({inf['not_fitted']})."
    search = search_text([(t["k"], t["nees_pct_beyond"]) for t in inf["tried"]], inf["met"])
    lead = "the smallest factor at which" if inf["met"] else "the largest tried; at none do"
    return (
        f"the odometry σ multiplied by {inf['k']:g} (variance rates by its square): {lead} "
        f"{' and '.join(inf['cases'])}, with every model fitted on the first "
        f"half of the calibration window, [{inf['fitted_on']['start_s']:.0f}, "
        f"{inf['fitted_on']['end_s']:.0f}] s, and replayed over its second half, "
        f"[{inf['checked_on']['start_s']:.0f}, {inf['checked_on']['end_s']:.0f}] s, keep NEES "
        f"beyond χ²₃(0.95) at most {inf['target_percent']:g} % of the time ({search})."
    )


def _targets(cases: dict[str, Any]) -> dict[str, Any]:
    """The issue's targets for all landmarks, judged on the held-out window (the part of the
    run the models were not fitted on); the whole-run (in-sample) figures are kept beside under
    ``in_sample``."""
    dr = cases["dead_reckoning/none"]
    out: dict[str, Any] = {}
    for mode in ("range_bearing", "bearing"):
        c = cases[f"{mode}/all_landmarks"]
        held = c["heldout"]
        pos, head, nees = held["pos_rmse_m"], held["heading_rmse_rad"], held["nees_pct_beyond"]
        ratio = dr["heldout"]["pos_rmse_m"] / pos if pos > 0 else None
        out[mode] = {
            "pos_rmse_m": pos,
            "pos_ok": pos <= TARGET_POS_RMSE_M,
            "heading_rmse_rad": head,
            "heading_ok": head <= TARGET_HEADING_RMSE_RAD,
            "improvement_over_dead_reckoning": ratio,
            "improvement_ok": ratio is not None and ratio >= TARGET_IMPROVEMENT,
            "nees_pct_beyond": nees,
            "nees_ok": nees <= TARGET_NEES_PCT,
            "nees_beyond_interval": held["nees_beyond_interval"],
            "in_sample": {
                "pos_rmse_m": c["pos_rmse_m"]["mean"],
                "heading_rmse_rad": c["heading_rmse_rad"]["mean"],
                "improvement_over_dead_reckoning": dr["pos_rmse_m"]["mean"]
                / c["pos_rmse_m"]["mean"],
                "nees_pct_beyond": c["nees_pct_beyond"],
            },
        }
    return out


def _figures(
    out: Any, ds: Any, prepared: Prepared, by_key: dict[Any, Any], cases: dict[str, Any]
) -> list[tuple[str, str]]:
    from relloc.plotting.cooperative import plot_case_series, plot_grouped_bars
    from relloc.plotting.errors import plot_trajectories
    from relloc.plotting.setup import pyplot

    plt = pyplot()

    figs: list[tuple[str, str]] = []
    fig, ax = plt.subplots(figsize=(8, 4))
    plot_grouped_bars(
        ax,
        list(ANCHORS),
        {m: [cases[f"{m}/{a}"]["pos_rmse_m"]["mean"] for a in ANCHORS] for m in MODES},
        ylabel="mean position RMSE (m)",
        reference=TARGET_POS_RMSE_M,
        reference_label="target 0.13 m",
    )
    ax.set_title("Mean position RMSE by measurement mode and anchors")
    figs.append((save_figure(fig, out, "pos_rmse"), "Mean position RMSE by mode and anchors"))
    fig, ax = plt.subplots(figsize=(8, 4))
    plot_grouped_bars(
        ax,
        list(ANCHORS),
        {m: [cases[f"{m}/{a}"]["nees_pct_beyond"] for a in ANCHORS] for m in MODES},
        ylabel="NEES beyond χ²₃(0.95) (%)",
        reference=TARGET_NEES_PCT,
        reference_label="target 10 %",
        log=False,
    )
    ax.set_title("Consistency: share of NEES beyond χ²₃(0.95)")
    figs.append((save_figure(fig, out, "nees_beyond"), "Consistency: NEES beyond the χ² bound"))
    rid = ds.robot_ids[1]
    q = ds.robot(rid).groundtruth.at(prepared.out_t)
    paths = {"truth": q.pose[q.valid, :2]}
    for key in (
        ("dead_reckoning", "none"),
        ("bearing", "all_landmarks"),
        ("range_bearing", "all_landmarks"),
    ):
        paths["/".join(key)] = by_key[key]["mean"][q.valid, 1, :2]
    fig, ax = plt.subplots(figsize=(7, 6))
    plot_trajectories(ax, paths)
    ax.set_title(f"Robot {rid}: truth, dead reckoning and CL")
    figs.append((save_figure(fig, out, "robot2_paths"), f"Robot {rid} paths"))
    series = {}
    for key in (
        ("bearing", "all_landmarks"),
        ("range_bearing", "all_landmarks"),
        ("range_bearing", "none"),
    ):
        err = np.hypot(*(by_key[key]["mean"][:, 1, :2] - q.pose[:, :2]).T)
        series["/".join(key)] = np.where(q.valid, err, np.nan)
    fig, ax = plt.subplots(figsize=(8, 3.5))
    plot_case_series(ax, prepared.out_t, series, ylabel="position error (m)", log=True)
    ax.set_title(f"Robot {rid}: position error over time")
    figs.append((save_figure(fig, out, "robot2_error"), f"Robot {rid} position error"))
    return figs


def _bias_text(coeffs: list[float], limits: list[float]) -> str:
    """Each robot's bearing-bias coefficients and the bearings they were fitted over."""
    c = np.asarray(coeffs).reshape(-1, 3)
    lim = np.asarray(limits).reshape(-1, 2)
    return "; ".join(
        f"({', '.join(f'{v:+.4f}' for v in ci)}) over [{lo:+.2f}, {hi:+.2f}] rad"
        for ci, (lo, hi) in zip(c, lim, strict=True)
    )


def _heading_explanation(cases: dict[str, Any], fit: dict[str, Any]) -> str:
    """Where the bearing-only heading error comes from (measured, see
    :func:`heading_error_by_landmark_gap`)."""
    bins = cases["bearing/all_landmarks"]["heading_by_landmark_gap"]
    near, far = bins["0-1s"], bins["5-infs"]
    return (
        f"For bearing-only CL with all landmarks, {100 * far['squared_error_share']:.0f} % of "
        f"the squared heading error accrues in the {100 * far['time_share']:.0f} % of the time "
        "when a robot has seen no landmark for 5 s or more (the landmarks sit in six tight "
        f"clusters; heading RMSE {far['heading_rmse_rad']:.3f} rad there) against "
        f"{near['heading_rmse_rad']:.3f} rad within 1 s of a landmark sighting: between "
        "sightings the heading drifts with the odometry's turn-rate errors (commanded rates, "
        f"fitted turn-rate scales {min(fit['scale_w']):.2f}–{max(fit['scale_w']):.2f} after a "
        f"{fit['latency_s']:.2f} s delay and a {fit['time_constant_s']:.2f} s first-order lag; "
        "what is left is the commands' own error) and robot→robot "
        "bearings only constrain relative headings. We did not shrink the fitted noise to reach "
        "the target, because that breaks the NEES target (odometry rates fitted over 1 s "
        "windows with only an AR(1) bearing inflation gave about 50 % of NEES values beyond "
        "the bound in our trials)."
    )


def _correlation_text(correlation: dict[str, Any]) -> str:
    """The fit's residual correlation at each lag, per reading kind, for report.md: ``range
    0.82 at 0.25 s, …; bearing …`` (a lag with too few pairs of readings shows 0, as fitted,
    :func:`relloc.calibration.camera.lag_correlation`)."""
    return "; ".join(
        f"{kind} "
        + ", ".join(f"{value:.2f} at {lag.removesuffix('s')} s" for lag, value in lags.items())
        for kind, lags in correlation.items()
        if kind in ("range", "bearing")
    )


def _improvement_text(cases: dict[str, Any], held: dict[str, Any], start_s: float) -> str:
    """What the "× better than DR" ratio measures, and why it depends on the run's length;
    ``start_s`` is the run's start (s, the recording's clock), where dead reckoning starts."""
    dr = cases["dead_reckoning/none"]["heldout"]["pos_rmse_m"]
    return (
        "× better than DR: the held-out position RMSE of dead reckoning "
        f"({dr:.2f} m) over the filter's. Dead reckoning is the calibrated odometry alone from "
        "the ground-truth poses at the run's start, so its error grows with the time since "
        f"then (the window ends {held['end_s'] - start_s:.0f} s after it) while the filter's "
        "does not: "
        "unlike the other three targets, the ratio grows with the run's length and with how late "
        "the window lies. The issue's 20× is run 6's (dead reckoning about 2.7 m against a "
        "plain joint EKF's 0.13 m, over about 900 s)."
    )


def _without_truth_text(case: dict[str, Any]) -> str:
    """report.md's account of the output times and robots not scored for want of ground truth
    (:func:`evaluate`; the same in every case)."""
    parts = []
    for name, prefix in (("whole run", ""), ("held-out window", "heldout_")):
        if case[f"{prefix}records_without_truth"]:
            counts = ", ".join(
                f"robot {r}: {n}" for r, n in case[f"{prefix}records_without_truth"].items()
            )
            parts.append(f"{name}: {counts}")
    text = (
        "Output times not scored for want of valid ground truth — " + "; ".join(parts) + "."
        if parts
        else "Every robot has valid ground truth at every output time scored."
    )
    for name, prefix in (("whole run", ""), ("held-out window", "heldout_")):
        if case[f"{prefix}robots_without_truth"]:
            text += (
                f" Left out of the per-robot figures and their mean ({name}), without any "
                f"ground truth there: robots {', '.join(case[f'{prefix}robots_without_truth'])}."
            )
    return text


def load_report_line(report: dict[str, Any]) -> str:
    """report.md's account of a ``load_report`` (``n_skipped``, ``by_reason``): the rows of the
    dataset's files that the loader and the conversion to a recording skipped."""
    return skipped_rows_line(report["n_skipped"], report["by_reason"])


def _report(summary: dict[str, Any], figures: list[tuple[str, str]]) -> str:
    cases = summary["cases"]
    rows = []
    for key, c in cases.items():
        rows.append(
            [
                key,
                c["pos_rmse_m"]["mean"],
                c["heading_rmse_rad"]["mean"],
                c["final_pos_err_m"]["mean"],
                c["nees_pct_beyond"],
                c["anees"],
                c["heldout"]["pos_rmse_m"],
                c["heldout"]["nees_pct_beyond"],
                c["used"],
                c["rejected"],
            ]
        )
    table = markdown_table(
        [
            "case",
            "pos RMSE (m)",
            "heading RMSE (rad)",
            "final err (m)",
            "NEES>χ² (%)",
            "ANEES",
            "held-out pos RMSE",
            "held-out NEES>χ² (%)",
            "used",
            "rejected",
        ],
        rows,
    )
    t = summary["targets"]
    trows = [
        [
            mode,
            v["pos_rmse_m"],
            v["pos_ok"],
            v["heading_rmse_rad"],
            v["heading_ok"],
            v["improvement_over_dead_reckoning"],
            v["improvement_ok"],
            v["nees_pct_beyond"],
            v["nees_ok"],
            interval_text(v["nees_beyond_interval"]),
            f"{v['in_sample']['pos_rmse_m']:.4f} / {v['in_sample']['heading_rmse_rad']:.4f} / "
            f"{v['in_sample']['improvement_over_dead_reckoning']:.1f} / "
            f"{v['in_sample']['nees_pct_beyond']:.1f}",
        ]
        for mode, v in t.items()
    ]
    ttable = markdown_table(
        [
            "all landmarks",
            "pos RMSE",
            "≤ 0.13",
            "heading RMSE",
            "≤ 0.09",
            "× better than DR",
            "≥ 20",
            "NEES>χ² %",
            "≤ 10",
            "its 95 % interval",
            "in-sample (whole run): pos / heading / × DR / NEES %",
        ],
        trows,
    )
    held = summary["scored_on"]
    f = summary["fit"]
    fit_text = (
        f"Fitted on [{f['t_lo']:.0f}, {f['t_hi']:.0f}] s of this run: odometry latency "
        f"{f['latency_s']:.2f} s, first-order lag {f['time_constant_s']:.2f} s, speed scales "
        f"{', '.join(f'{s:.3f}' for s in f['scale_v'])}, "
        f"turn-rate scales {', '.join(f'{s:.3f}' for s in f['scale_w'])}; variance rates over "
        f"{f['odometry_window_s']:.2f} s windows (the expected wait for the next landmark "
        f"detection): q_v0 {f['q_v0']:.2e} m²/s, k_v {f['k_v']:.2e} m, q_ω0 {f['q_w0']:.2e} "
        f"rad²/s, k_ω {f['k_w']:.2e} rad, k_ωv {f['k_wv']:.2e} rad²/m; {_inflation_text(f)} "
        "Bearings: a bias per "
        "robot on (1, η, η²) = "
        f"{_bias_text(f['bearing_bias_coeffs'], f['bearing_bias_limits'])} (removed before "
        "the replay; constant offsets alone were "
        f"{', '.join(f'{o:+.4f}' for o in f['bearing_offset'])} rad), σ "
        f"{f['sigma_bearing_raw']:.4f} rad (MAD) × √{f['bearing_inflation']:.1f} (correlation "
        f"inflation) = {f['sigma_bearing']:.4f} rad. Ranges: bias coefficients on (1, η, η², ρ, "
        f"ρη²) = ({', '.join(f'{c:.3f}' for c in f['range_bias_coeffs'])}), σ "
        f"{f['sigma_range_raw']:.3f} m (MAD) × √{f['range_inflation']:.1f} = "
        f"{f['sigma_range']:.3f} m, at most one range per pair every "
        f"{f['range_interval_s']:g} s. Residual lag-correlations: "
        f"{_correlation_text(f['correlation'])}." + unfitted_note(f["unfitted_robots"])
    )
    missed = [
        f"{mode}: {name}"
        for mode, v in t.items()
        for name, ok in (
            ("position RMSE", v["pos_ok"]),
            ("heading RMSE", v["heading_ok"]),
            ("20× over dead reckoning", v["improvement_ok"]),
            ("NEES ≤ 10 %", v["nees_ok"]),
        )
        if not ok
    ]
    verdict = (
        "Every target is met."
        if not missed
        else "Missed: "
        + "; ".join(missed)
        + ". "
        + (
            _heading_explanation(cases, summary["fit"])
            if any("heading" in x for x in missed)
            else ""
        )
    )
    fitted_s = summary["fit"]["t_hi"] - summary["fit"]["t_lo"]
    in_sample = fitted_s / (fitted_s + held["end_s"] - held["start_s"])
    parts = [
        "# MRCLAM cooperative localization (seed 001 EIF on real data)",
        f"Dataset `{summary['dataset']}`, robots {summary['robots']}, seed {summary['seed']} (only "
        f"the GPS noise of robot {summary['robots'][0]}, the first, is random). Regenerate: "
        f"`relloc reproduce mrclam-cl --out DIR --dataset {summary['dataset']} "
        f"--seed {summary['seed']} --calibration-window {summary['calibration_window_choice']}`.",
        "## Targets (all landmarks), judged on the held-out window",
        f"Scored on [{held['start_s']:.0f}, {held['end_s']:.0f}] s, the part of the run outside "
        f"the calibration window [{summary['fit']['t_lo']:.0f}, {summary['fit']['t_hi']:.0f}] s "
        f"the error models were fitted on; the whole-run figures, {in_sample:.0%} of the run "
        "in-sample, are shown beside for reference only.",
        ttable,
        verdict,
        # the run starts with the calibration window or with the scoring window, whichever is first
        _improvement_text(cases, held, min(summary["fit"]["t_lo"], held["start_s"])),
        "## Every case",
        table,
        "Position / heading RMSE: per robot over every output time (0.5 s grid) with valid "
        "ground truth, then the arithmetic mean over robots. NEES: per-robot 3-DOF pose NEES "
        "pooled over robots and times against χ²₃(0.95) (5 % expected for a consistent filter); "
        "those samples are correlated in time and across robots, so the target table gives the "
        "held-out share's 95 % interval by batch means (the window cut into 10 blocks, each "
        "block's samples of every robot one sample; widened, when a block lasts less than ten "
        "correlation times, to Clopper–Pearson's interval for the effective sample size that "
        "time leaves) and its verdict: over-confident when it lies wholly above 5 %, "
        "conservative wholly below, consistent when it holds 5 % and reaches no higher than "
        "10 % (twice it), inconclusive when it holds 5 % but reaches above 10 % (not "
        "rejected, not shown consistent either). The 10 % target is judged on the share "
        "itself, as the issue states it. "
        f"`held-out`: the same over [{held['start_s']:.0f}, {held['end_s']:.0f}] s, the part of "
        "the run the models were not fitted on. "
        f"The two landmarks are subjects {summary['two_landmarks']}. "
        + _without_truth_text(cases["dead_reckoning/none"]),
        load_report_line(summary["load_report"]),
        "## Error models",
        fit_text,
        "## Figures",
        *[figure_md(fn, cap) for fn, cap in figures],
    ]
    return "\n\n".join(parts)
