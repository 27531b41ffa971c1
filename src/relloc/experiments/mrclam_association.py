"""Multi-hypothesis relative localization on MRCLAM with unknown bearing correspondence.

``relloc reproduce mrclam-association --out DIR [--dataset PATH] [--seed S] [--runs N]``

Real data (Leung, Barfoot & Liu, IJRR 2011; any folder in MRCLAM layout, default run 6): every
robot runs a fuser (:class:`~relloc.fusion.gaussian_sum_estimator.GaussianSumEstimator`) with
one Gaussian-sum filter per other robot, as in seed 002. The dataset becomes a
:class:`~relloc.core.recording.Recording` (:func:`relloc.datasets.mrclam.to_recording`), whose
camera rows of one time stamp (a camera frame) form a scan (:func:`_hidden_correspondence`).
Each robot-to-robot row keeps its *range* with its barcode (known correspondence, like the
paper's ranging sensor) but its *bearing* goes, without the barcode, into the scan's bearing
set, together with ``CLUTTER_PER_SCAN`` injected false bearings (Poisson, seeded), uniform
over the camera's field of view (the widest |bearing| of any row, ±0.59 rad in run 6; the
filter's clutter density is set to match). Landmark rows are not used (counted in
``bearings.landmark_skipped``): the camera sees the static landmarks far more often than the
robots (about 3 : 1 in run 6), and as static, persistent false bearings they are a different
problem (mapping) from the uniform clutter of seed 002. The robots are planar: the bearing
sensor is azimuth-only and the height difference is a known 0 ± 1 cm. Odometry (the commanded
v, ω, calibrated as below) drives the prediction on a 20 Hz filter clock
(:func:`relloc.pipeline.replay.replay` with ``clock``): the frames stamped since the previous
tick are fused at a tick, each as its own scan, and the beliefs are recorded at the ticks that
fused a frame of their robot.

Sensor models (both on the same data):

- **unknown correspondence** (the headline): seed 002's separate sensors — the filter is told
  neither whose bearing is whose nor that a robot with a range in a frame has its bearing in
  it. Its bearing detection probability is the camera's: ``P_D`` of a teammate *inside* the
  field of view (:func:`relloc.calibration.camera.fit_detection_in_view`), times the
  probability that the track's predicted azimuth lies inside it
  (``GaussianSumSettings.field_of_view``). Seed 002's constant ``P_D`` (the share of all
  frames showing a given teammate, 0.13 in run 6) is wrong for a camera with a ±0.59 rad view:
  with it a missed detection says nothing about where a track is, and a drifting track takes
  clutter for its robot whenever the robot is out of view (on run 6, with mutual and indirect
  fusion: association accuracy 0.41, tracked fraction 0.045). The ranges are the camera's
  too, so the range sensor has the same field of view (``GaussianSumSettings.range_in_view``):
  a range of a teammate says it is inside the view, a frame without one that it is outside or
  missed (``1 − P_D``) — where the teammate is, not which bearing is its. The filter still
  takes the two detections as independent, as seed 002's separate sensors are, although on
  MRCLAM one camera detection gives both: a teammate in view and missed counts against a
  track twice (``1 − P_D`` for the range, ``1 − P_D P_G`` for the bearing). The same model with
  seed 002's all-around ranging, where the presence of a range says nothing, is reported
  beside (``unknown_ranges_all_around``); it was the headline model before, and every figure
  below that does not name the in-view range is of it. Direct fusion only: on real
  data the mutual and indirect fusion of seed 002 spread the teammates' unresolved yaw
  hypotheses (their filters see each pair in short bursts) and lower both figures; that
  variant is reported beside (``unknown_shared``), and so is a restricted sharing
  (``unknown_mutual_confirmed``: a fuser broadcasts only its confirmed filters and fuses only
  the mutual messages, ``GaussianSumSettings.share_confirmed_only`` and ``indirect_fusion``),
  and the model on the same frames without injected clutter (``unknown_no_clutter``: what is
  left is telling robots apart).

  The in-view range was chosen on the development windows (cuts of run 6 from 256 s and from
  476 s, each scored on the 240 s after its own 60 s calibration window, 316.0–556.0 s and
  536.0–771.9 s, clutter seeds 99–101, one run each) before the scoring window was run: there,
  against all-around ranging, the association accuracy went from 0.624 to 0.658 and from
  0.514 to 0.595 (means of the three seeds), the tracked fraction from 0.477 to 0.502 and from
  0.227 to 0.296. A positive-only variant (a range says "in view", its absence nothing) gave
  accuracy 0.579 and 0.526, tracked 0.512 and 0.316: more tracked records, fewer correct
  bearings. It is not used because it is not the sensor's likelihood (a sensor that sees only
  inside the view makes the absence of a reading evidence too), not for its figures. Why the
  in-view range helps: on the
  first window, at the records where the observer had ranged the teammate under 0.5 s before,
  the dominant track was tracked in only 52 % of them; in the failures its range was right
  (median error 0.04 m) and its azimuth 0.51 rad off (median), often outside the view, where
  its missed bearing cost it nothing and the range kept confirming it. On the scoring window
  afterwards (``relloc reproduce mrclam-association``, seed 2026, 5 runs) the headline went
  from accuracy 0.633 (0.562–0.726) to 0.726 (0.683–0.833) and from tracked 0.343
  (0.311–0.384) to 0.359 (0.315–0.404); the all-around row, run 0, still gives 0.579 / 0.311.
  The accuracy gain is about the spread's width, the tracked gain inside it.

  A detection probability by range was tried and not adopted. Over 316–771 s of run 6 the
  camera detects an in-view teammate with probability 0.06 under 1 m, 0.40–0.50 at 1–2.5 m
  and 0.22–0.36 beyond; ``P_D(r̂)`` in 1 m bins (fitted on each development window's 60 s of
  calibration, the constant where a bin has under 20 pairs), used for the tracks, the births
  and the in-view range, gave accuracy 0.660 and 0.567, tracked 0.486 and 0.283 on the two
  development windows (seeds 99–101): no better than the constant's 0.658 / 0.502 and
  0.595 / 0.296. The calibration window is too short to fill the bins.
- **camera** (``camera``, the second row): range and bearing come from one detection, so the
  fuser runs with ``ranges_mark_detections`` (a robot with a range in a frame has its bearing
  in the set, one without has none) and with mutual and indirect fusion; in run 6 only 71 of
  2,932 scans show two or more robots, so this mostly measures clutter rejection.

Spread. A single run's figures depend by chance on where the clutter falls and on which
filter tick each camera frame is fused at (a 1e-9 s change of the clock once moved the camera
model's accuracy from 0.918 to 0.887). The unknown-correspondence model therefore runs
``--runs`` times (default ``SPREAD_RUNS``): run ``k`` draws its clutter from seed ``k`` of
``--seed`` and starts its filter clock ``k/(runs · 20 Hz)`` seconds late; the headline is the
mean, with the min and max and every run in ``spread``. The other models run once, on run
0's recording, and the one with seed 002's mutual and indirect fusion is the most sensitive of
them: on run 6 a 1e-9 relative change of the range σ moved its tracked fraction from 0.167 to
0.180 (accuracy 0.744 both, median error 1.68 → 1.78 m). Run 6 moved to another world frame,
clock and barcodes (``relloc mrclam move``; the fits, which read the turned ground truth,
differ by about 1e-9) gives every figure of the headline, its spread, the bound, the reference
and three other rows to 1e-7, the camera row's with the same associations (its yaw RMSE
7e-4 rad apart), and that row at 0.776 / 0.190 against 0.744 / 0.167: the same sensitivity,
not a dependence on the frame.

Error models, all fitted (:mod:`relloc.calibration`, the fits mrclam-cl uses) on a
calibration window — the first ``CALIBRATION_S`` seconds after every robot has started moving
(``calibration_window``) — while the scoring uses the next ``EVAL_S`` seconds (``scored_on``;
fewer where a robot's ground truth ends sooner, ``MrclamDataset.truth_span``), so nothing is
fitted on the data it is scored on:

- odometry (``fit_odometry_model``, ``odometry_model``): one latency ``τ`` and first-order lag
  ``T`` for the team (the robot follows its command ``c(t − τ)`` through ``ẏ = (c(t − τ) −
  y)/T``) and per-robot scales ``s_v, s_ω``; the filter is driven by the calibrated commands
  ``s · c_τ,T`` (``calibrated_team``), and its white input noise is the equivalent σ that
  they leave, at the window length (1 s up to 40 s, where the window holds it twice) that
  gives each robot its largest σ_ω (``fit_largest_odometry_noise`` with the same τ, T, s;
  ``odometry_noise``, its ``noise_window_s`` per robot), the RMS over robots, floored — the
  filters bridge gaps of seconds to minutes between sightings and must not be over-confident
  at any of those time scales (the rule of the seed-000 replay, :mod:`relloc.calibration.
  odometry`). Against the 1 s windows used before, on development windows of run 6 disjoint
  from the calibration and scoring windows (315.94–555.94 s and 535.94–771.0 s, clutter seeds
  99–101; σ_ω 0.152 against 0.089 rad/s, σ_v 0.058 against 0.042 m/s) the association
  accuracy rose from 0.525 to 0.658 and the tracked fraction from 0.288 to 0.307 (mean of the
  six runs); the rule was chosen there, before the scoring window was run;
- camera (``fit_camera``, ``camera_model``): every camera row has the per-robot bearing bias
  ``b_i(η̃) = c_i·(1, η̃, η̃²)`` removed from its bearing and the range bias
  ``b(η̃, ρ̃) = c·(1, η̃, η̃², ρ̃, ρ̃η̃²)`` from its range (``corrected_readings``, at the
  measured reading, as fitted) before the bearings lose their barcodes; the filter's bearing
  and range σ (``sigma_bearing_rad``, ``sigma_range_m``) are the MAD σ of what the biases
  leave times ``√(1 + 2 Σ ρ(kΔ))``: the variance is inflated by the Bartlett factor of the
  residuals' measured correlation at the readings' spacing (the filter fuses every range:
  ``RANGE_INTERVAL_S`` = 0);
- the detection probabilities (``fit_detection_in_view``, ``fit_detection_probability``).

The field of view, which sets where the injected clutter falls and where the camera can see,
is the widest (measured) bearing in the calibration window too (``field_of_view_window``).
So is the range span of the filters (``max_range``, ``RANGE_MARGIN`` times the widest robot
range of the window): the uniform prior of a new track's range is over the ranges the sensor
gives, not over a fixed 20 m. The robots being planar, a new track's height variance is the
height reference's (:func:`planar_formation`), not Eq. 13's 0.05 m².

Calibrating the commands and the camera (against the raw held commands, uncorrected camera rows
and the hand-set σ 0.2 m / 0.03 rad before) changed little on run 6 (seed 2026, 5 runs;
calibration window 15.94–75.94 s, scored 75.94–315.94 s): association accuracy 0.612 → 0.608,
tracked 0.352 → 0.348, position RMSE 2.12 → 2.12 m, median 0.73 → 0.66 m, yaw RMSE 0.96 → 1.00
rad, wrong: clutter 0.193 → 0.169, another robot 0.195 → 0.223 (each but the clutter share
within the other's min–max over the runs); the camera model's tracked fraction fell from 0.43 to
0.28 (median error 0.48 → 0.93 m) and the truth-placed bound with clutter from 0.868 to 0.852,
both with the fitted, correlation-inflated range σ (0.38 m against 0.2 m): with the calibration
but σ 0.2 m / 0.03 rad (run 0's recording only) the camera model tracked 0.45 and the bound was
0.866, so those two losses are the range σ's (the price of a white-noise filter fed every
reading of a correlated error, :mod:`relloc.calibration.inflation`). The tracks are lost to
drift that a better dead reckoning does not remove (report.md, "Why tracks are lost"). Those
figures predate the loader's rounding of the relative stamps to 1 µs
(:mod:`relloc.datasets.mrclam`), which moved every stamp by up to 1.2e-7 s and the calibrated
figures to 0.625 (0.579–0.716), tracked 0.336, wrong robot 0.204: a change of the kind the
spread above samples, and inside it. The odometry noise at each robot's largest-σ_ω window
length (above) then replaced the 1 s windows; on the scoring window (seed 2026, 5 runs) it
moved the association accuracy from 0.625 (0.579–0.716) to 0.633 (0.562–0.726) and the
tracked fraction from 0.336 (0.288–0.368) to 0.343 (0.311–0.384), both inside the spread: the
gain seen on the development windows did not carry over to the scoring window. Run 0's other
models moved more: the camera model's tracked fraction from 0.319 to 0.523 (median error
1.39 → 0.41 m, accuracy 0.967 → 0.978), the no-clutter variant's accuracy from 0.798 to 0.680
and tracked fraction from 0.341 to 0.292, the shared-fusion variant's accuracy from 0.355 to
0.450.

Gates (tried, not adopted). The fuser updates a track with the bearings inside its ``P_G``
gate (seed 002's 0.95: 1.96σ in azimuth) and starts no track inside a wider exclusion gate
(``GateSettings.p_birth_exclusion``, 3.9σ), so a bearing between the two is neither used nor
starts a track. On run 6 this band is where a drifted track's own teammate often appears: on a
development window (315.94–555.94 s; clutter seed 99; odometry noise of 1 s windows), at the
records where a teammate had just been sighted the dominant track was more than 0.5 m off in
32 % of them while the sighting itself was within 0.5 m of the truth in all, and in 69 % of
those the dominant track had taken no bearing. With the 1 s odometry noise, over both
development windows × clutter seeds 99–101, widening the update gate to the exclusion gate
(one gate at 0.9999, also in the weights' ``P_G``) raised the association accuracy from 0.525
to 0.643 and the tracked fraction from 0.288 to 0.323, and births from every bearing outside
the 0.95 gate (seed 002's literal rule) gave 0.577 / 0.304; a smaller bearing and range σ
(0.012 rad / 0.1 m, or the uninflated 0.0055 rad / 0.041 m) gave 0.521 / 0.281 and
0.512 / 0.273. Neither gate change is used: on the synthetic folder of
``tests/multihypothesis/test_mrclam_association.py``, where two robots stand at about the same
bearing from the third when the filters start, they let that observer's two filters keep the
swapped pair — each following the other robot's bearings at its own range, which the ranges
cannot tell apart — to the end of the scoring window (1 s odometry noise; accuracy of its two
runs 0.99 and 0.89 with the two gates; 0.63 and 0.62 with one gate; 0.99 and 0.62 with births
from every out-of-gate bearing).

Sharing confirmed tracks (reported beside, not the headline). A teammate's mutual sighting
carries the relative yaw that one robot's short bursts leave open, but seed 002's sharing
also spreads every unresolved hypothesis (``unknown_shared``). The restricted policy
``unknown_mutual_confirmed`` sends only confirmed filters and fuses only mutual messages. On
the development windows (clutter seeds 99–101, the means of six runs) it gave association
accuracy 0.584 against direct fusion's 0.658 and tracked fraction 0.391 against 0.307
(coverage 0.853 against 0.740; median error 0.57 against 0.71 m). On the scoring window, run
0 (seed 2026), the figures were 0.549 against 0.579 and 0.337 against 0.311 (coverage 0.837
against 0.746; yaw RMSE 0.66 against 0.96 rad): the tracked fraction lies inside the direct
model's spread over its five runs (0.311–0.384), so the development gain did not carry over,
while the yaw error fell. It trades association accuracy for tracked
fraction and reaches neither target, so the headline stays with direct fusion. Both kinds
of wrong bearing rise (run 0: clutter 0.179 against 0.161, another robot 0.272 against 0.260
of those used) with the coverage: the messages keep filters holding tracks for more of the
time, while their robot is out of view too (a likely cause, not measured separately). With
the in-view range the trade stays on the development windows (clutter seeds 99–101, one run
each): mutual fusion of confirmed tracks gave accuracy 0.642 and 0.589 against direct
fusion's 0.658 and 0.595, tracked 0.607 and 0.347 against 0.502 and 0.296 (with all-around
ranges, accuracy / tracked: 0.546 / 0.518 and 0.537 / 0.290). On the scoring window, run 0
(seed 2026), it gave 0.809 / 0.472 against the headline's 0.726 / 0.359 (mean of 5 runs):
better in both there, but that was seen only after scoring, so the headline stays with
direct fusion, the model chosen before.

What a filter could score (``association_bound``): the fuser's own bearing step with one track
per teammate at its true relative pose (:mod:`relloc.experiments.association_bound`), on run
0's scans with and without the injected clutter — the accuracy that perfect tracks reach
under the definition of ``association_accuracy`` (report.md, "Definitions"). For
``tracked_fraction`` the reference ``tracking_reference`` gives a filter the exact relative pose
at every sighting and lets it dead-reckon between them
(:func:`relloc.experiments.association_bound.sighting_reset_reference`).

summary.json keys: ``experiment, seed, runs, dataset, window_s, scored_on,
calibration_window_s, calibration_window, clutter_per_scan, field_of_view_rad,
field_of_view_window`` (``scored_on`` and the two windows: ``start_s``, ``end_s`` in s and the
``source`` folder), ``odometry_noise`` (what the filters were given, fitted on the calibration
window: ``sigma_v``, ``sigma_lateral`` (m/s) and ``sigma_w`` (rad/s), the RMS over robots of
each robot's σ at its ``noise_window_s`` (s, one per robot in dataset order), floored at
``MIN_SIGMA_V`` / ``MIN_SIGMA_W``; ``p_detect_in_view``, the in-view detection fit
(:class:`~relloc.calibration.camera.InViewDetectionFit`: ``p_detect``, ``half_width_rad``,
``pairs_in_view``, ``detected_in_view``, ``detected_outside``, its ``calibration_window``);
``p_detect_all_frames``, seed 002's constant ``P_D``, reported only; ``widest_range_m``, the
widest robot range of the window (null: none), and ``range_span_m``, the filters'
``max_range``), ``odometry_model`` (:class:`~relloc.calibration.odometry.OdometryModelFit`
without its window: ``latency_s``, ``time_constant_s``, ``scale_v`` and ``scale_w`` per robot,
the variance rates ``q_v0``, ``k_v``, ``q_w0``, ``k_w``, ``k_wv`` over ``odometry_window_s``
windows, reported and not used by the filters, ``unfitted_robots``) and
``camera_model`` (:class:`~relloc.calibration.camera.CameraFit` without its window:
``bearing_offset`` per robot, ``bearing_bias_coeffs`` and ``bearing_bias_limits`` flat,
robot-major, ``range_bias_coeffs``, ``sigma_bearing_raw`` / ``sigma_range_raw`` (MAD),
``bearing_inflation`` / ``range_inflation`` (variance factors), ``sigma_bearing`` /
``sigma_range``, ``range_interval_s``, ``correlation`` (``range`` and ``bearing``: lag → measured
correlation; ``pair_spacing_s``: ``median``), ``n_residuals``; both windows are
``calibration_window``), ``sigma_range_m``, ``sigma_bearing_rad`` (the filters' σ, m and rad),
``association_accuracy`` (fraction of the bearings used by the dominant track of a filter that
really came from that robot, after its first confirmation), ``association_accuracy_joint`` (of
the fuser's one-to-one decision), ``wrong_clutter`` and ``wrong_robot`` (shares of those
bearings that were injected clutter or another robot), ``pos_rmse_m``, ``pos_median_m``
(dominant track vs Vicon ground truth, planar position, after 10 s), ``yaw_rmse_rad``,
``tracked_fraction`` (records with the dominant track within 0.5 m and 0.5 rad, of the records
with a track), ``coverage`` (records with a track, of all records × teammates, after 10 s) —
all the unknown-correspondence means over the runs, null where no run has a value —,
``spread`` (``runs``: one entry per run, its ``run`` index, ``clock_offset_s`` and the nine
figures above; per figure ``mean, min, max``), ``run0`` (run 0's figures, the same as
``spread.runs[0]``, with ``per_observer``: robot ``"R1"``… → ``association_accuracy``,
``bearings_used`` (count after the first confirmation), ``pos_rmse_m``, ``tracked_fraction``,
``coverage``), ``unknown_ranges_all_around``, ``unknown_shared``,
``unknown_mutual_confirmed``, ``unknown_no_clutter`` and ``camera`` (the other models' nine
figures, run 0's frames, no ``per_observer``), ``association_bound`` (``with_clutter``,
``no_clutter``: ``accuracy``, ``used`` bearings, ``correct``), ``tracking_reference`` (dead
reckoning reset to the truth at every sighting,
:func:`~relloc.experiments.association_bound.sighting_reset_reference`, on run 0's records:
``tracked_fraction`` of ``records``, ``tracked``, ``truth_missing``, ``median_age_s``;
``by_age``: by the time since the last sighting), ``tracked_by_age`` (the headline's run 0,
the same bins: ``from_s``, ``to_s``, ``records``, ``tracked_fraction``), ``bearings`` (run 0's
counts over the scoring window: ``robot`` bearings, ``landmark_skipped`` rows, ``injected``
clutter bearings, ``scans_with_several_robots``; ``unknown_subject``: camera rows of no other
robot and no landmark, skipped by the conversion, over the whole run; and ``truth_missing``:
filter ticks × robots where the Vicon pose is not valid (inside a gap longer than the
dataset's gap threshold, or outside its span), scored against the interpolated pose),
``scans`` (camera frames in the scoring window, every robot's), ``load_report`` (the loader's
rows read, kept and skipped, :class:`relloc.datasets.mrclam.LoadReport`: ``folder``,
``n_skipped``, ``skipped_by_reason``, ``files`` → ``rows_read``, ``rows_kept``, ``skipped``,
``examples``), ``figures`` (``errors``: the figure's file name).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from relloc.association.hypotheses import FormationSettings
from relloc.calibration.camera import (
    CameraFit,
    corrected_readings,
    fit_camera,
    fit_detection_in_view,
    fit_detection_probability,
    fit_field_of_view,
)
from relloc.calibration.odometry import (
    OdometryModelFit,
    calibrated_team,
    fit_largest_odometry_noise,
    fit_odometry_model,
    unfitted_note,
)
from relloc.calibration.window import CalibrationWindow, following
from relloc.core.estimates import Estimates
from relloc.core.recording import (
    CLUTTER,
    Measurements,
    Recording,
    measurement_rows,
)
from relloc.datasets.mrclam import UNMAPPED_SUBJECT, MrclamDataset, load_mrclam, to_recording
from relloc.datasets.paths import default_mrclam_dataset
from relloc.errors import DataError
from relloc.estimators.gaussian_sum import GaussianSumSettings
from relloc.experiments.association_bound import (
    TrackedByAge,
    association_bound,
    last_sightings,
    sighting_reset_reference,
)
from relloc.experiments.multihypothesis_scores import NO_READING, LeaderScores, leader_scores
from relloc.experiments.registry import ReproduceArgs
from relloc.fusion.gaussian_sum_estimator import bearing_kind, scan_times, team
from relloc.models.motion import VelocityNoise
from relloc.pipeline.export import export_estimates
from relloc.pipeline.montecarlo import spawn_seeds
from relloc.pipeline.output import (
    figure_md,
    markdown_table,
    prepare_out_dir,
    save_figure,
    skipped_rows_line,
    write_report,
    write_summary,
)
from relloc.pipeline.replay import feed_ticks, replay

Array = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

FILTER_RATE = 20.0
CALIBRATION_S = 60.0
EVAL_S = 240.0
CLUTTER_PER_SCAN = 1.0
SIGMA_HEIGHT = 0.01
#: integration window (s) of the variance rates of ``fit_odometry_model`` (reported, not used
#: by the filter; the filter's white σ is ``fit_largest_odometry_noise``'s)
ODOMETRY_WINDOW_S = 1.0
#: the filter fuses every range (none is thinned), so ``fit_camera`` inflates the range σ for
#: the correlation at the readings' own spacing
RANGE_INTERVAL_S = 0.0
WARMUP_S = 10.0
#: floors of the fitted odometry noise (a perfect fit would leave the filter no process noise)
MIN_SIGMA_V = 0.02
MIN_SIGMA_W = 0.02
POS_TOL_M = 0.5
YAW_TOL_RAD = 0.5
FUSION_PERIOD_S = 1.0
#: the range span of the filters (``max_range``: uniform birth prior over ``[0, span]``, and
#: tracks beyond it deleted) is this multiple of the widest robot range of the calibration
#: window (seed 002's range space is the sensor's, not a fixed 20 m)
RANGE_MARGIN = 1.5
#: What ``--mcap``/``--tum`` write (:func:`relloc.experiments.registry.exported_run`).
EXPORTED_RUN = (
    "run 0 of the unknown-correspondence model (direct fusion): every robot's dominant track of "
    "each teammate in its body frame, at the ticks its scans are fed at"
)
#: runs of the spread (``--runs``): clutter draws and filter-clock offsets
SPREAD_RUNS = 5
#: issue 14's targets for the unknown-correspondence model
TARGET_ACCURACY = 0.90
TARGET_TRACKED = 0.5
HEADLINE_KEYS = (
    "association_accuracy",
    "association_accuracy_joint",
    "wrong_clutter",
    "wrong_robot",
    "pos_rmse_m",
    "pos_median_m",
    "yaw_rmse_rad",
    "tracked_fraction",
    "coverage",
)


def _hidden_correspondence(
    rec: Recording,
    t_start: float,
    t_last: float,
    fov: float,
    rng: np.random.Generator,
    clutter_per_scan: float = CLUTTER_PER_SCAN,
) -> tuple[Recording, dict[str, int]]:
    """Seed 002's sensing from the camera frames stamped in ``[t_start, t_last)``.

    Every frame of a robot becomes a scan: the range of each robot it read (known
    correspondence, ``"range"`` rows), a height difference of 0 to every other robot (planar,
    ``"height"`` rows) and the set of bearings of unknown correspondence (``"bearing"`` rows,
    ``origin`` the robot read) with Poisson(``clutter_per_scan``) false bearings uniform over
    ``±fov`` added (``origin`` ``CLUTTER``), shuffled. Landmark readings are not used (counted).
    """
    m = rec.measurements.of_kind("range_bearing")
    assert m.landmark is not None
    n = rec.n_robots
    counts = {"robot": 0, "landmark_skipped": 0, "injected": 0, "scans_with_several_robots": 0}
    known: dict[str, list[tuple[float, int, int, float]]] = {"height": [], "range": []}
    bearings: list[tuple[float, int, int, float]] = []
    for i in range(n):
        mine = (m.observer == i) & (m.t >= t_start) & (m.t < t_last)
        for stamp in np.unique(m.t[mine]):
            rows = np.flatnonzero(mine & (m.t == stamp))
            robot = rows[m.target[rows] >= 0]
            counts["robot"] += robot.size
            counts["landmark_skipped"] += int((m.landmark[rows] >= 0).sum())
            counts["scans_with_several_robots"] += int(robot.size >= 2)
            t = float(stamp)
            known["height"].extend((t, i, j, 0.0) for j in range(n) if j != i)
            known["range"].extend((t, i, int(m.target[r]), float(m.value[r, 0])) for r in robot)
            scan = [(int(m.target[r]), float(m.value[r, 1])) for r in robot]
            n_clutter = int(rng.poisson(clutter_per_scan))
            counts["injected"] += n_clutter
            scan.extend((CLUTTER, float(b)) for b in rng.uniform(-fov, fov, n_clutter))
            bearings.extend((t, i, *scan[k]) for k in rng.permutation(len(scan)))
    parts = []
    for kind, rows_of_kind in known.items():
        a = _by_time(np.array(rows_of_kind, dtype=float).reshape(-1, 4))
        parts.append(
            measurement_rows(
                kind,
                t=a[:, 0],
                observer=a[:, 1].astype(np.int64),
                target=a[:, 2].astype(np.int64),
                value=a[:, 3],
            )
        )
    b = _by_time(np.array(bearings, dtype=float).reshape(-1, 4))
    parts.append(
        measurement_rows(
            "bearing",
            t=b[:, 0],
            observer=b[:, 1].astype(np.int64),
            origin=b[:, 2].astype(np.int64),
            value=b[:, 3],
        )
    )
    hidden = replace(
        rec,
        measurements=Measurements.concatenate(parts),
        meta={**rec.meta, "clutter_per_scan": clutter_per_scan, "field_of_view_rad": fov},
    )
    return hidden, counts


def _by_time(columns: Array) -> Array:
    """Rows whose first column is the time, sorted by it (stable: a scan keeps its order)."""
    return columns[np.argsort(columns[:, 0], kind="stable")]


def _estimates(
    rec: Recording, settings: GaussianSumSettings, clock: Array, *, sharing: bool
) -> tuple[Estimates, dict[str, Array]]:
    """Every robot's fuser on the filter clock (mutual and indirect fusion when ``sharing``):
    the estimates, recorded at the ticks each observer's scans are fed at, and those ticks
    per observer."""
    sensing = list(range(rec.n_robots))
    stamps = scan_times(rec.measurements, rec.robots, sensing, settings)
    times = {name: np.unique(feed_ticks(st, clock)) for name, st in stamps.items()}
    estimates = replay(
        rec,
        team(rec.robots, sensing, settings, sharing=sharing, fusion_period=FUSION_PERIOD_S),
        clock=clock,
        record_times=times,
    )
    return estimates, times


def _scores(
    estimates: Estimates, rec: Recording, times: dict[str, Array], settings: GaussianSumSettings
) -> list[LeaderScores]:
    """The scores of each observer at its ticks."""
    kind = bearing_kind(settings)
    return [
        leader_scores(estimates, rec, i, times[rec.robots[i]], kind) for i in range(rec.n_robots)
    ]


def _run(
    rec: Recording, settings: GaussianSumSettings, clock: Array, *, sharing: bool
) -> list[LeaderScores]:
    """Every robot's fuser on the filter clock, scored (:func:`_estimates`, :func:`_scores`)."""
    estimates, times = _estimates(rec, settings, clock, sharing=sharing)
    return _scores(estimates, rec, times, settings)


@dataclass(frozen=True)
class _Models:
    """The two sensor models and what was fitted for them on the calibration window."""

    unknown: GaussianSumSettings
    camera: GaussianSumSettings
    fits: dict[str, Any]
    odometry: OdometryModelFit
    camera_fit: CameraFit


def _widest_range(ds: MrclamDataset, window: CalibrationWindow) -> float | None:
    """The widest range of any robot-to-robot detection in ``window`` (``None``: none)."""
    widest = [
        float(np.max(m.range[sel]))
        for m in (ds.robot(s).measurements for s in ds.robot_ids)
        if (sel := window.contains(m.t) & ds.is_robot(m.subject)).any()
    ]
    return max(widest) if widest else None


def planar_formation(sigma_height: float) -> FormationSettings:
    """Seed 002's formation settings (Eq. 13) for robots on one floor: the birth height
    variance is the height reference's ``σ_h²`` instead of Eq. 13's 0.05 m².

    An azimuth-only bearing gives no elevation, so a birth's elevation is ``arcsin(h/r)`` and
    its height is the height reading ``h`` itself, known to ``σ_h``. With Eq. 13's 0.05 m² the
    birth weight carries ``N(h; h, 0.05)`` (1.8 m⁻¹) while an existing track of the same robot
    gets ``N(h; ẑ, P_zz + σ_h²)`` (about 28 m⁻¹ at ``σ_h`` = 1 cm): every new track started
    about 16 times too light against the tracks it competes with, whatever the data say."""
    f = FormationSettings()
    var = f.birth_variances
    return replace(f, birth_variances=(var[0], var[1], sigma_height**2, var[3]))


def _settings(ds: MrclamDataset, window: CalibrationWindow, fov: float) -> _Models:
    """Filter settings of both sensor models (module docstring), all fitted on ``window``: the
    odometry model (latency, lag, per-robot scales; :func:`fit_odometry_model`) and the
    equivalent white noise the calibrated commands leave (RMS over robots of the σ fitted at
    each robot's largest-σ_ω window length, floored), the camera's range and bearing σ
    (:func:`fit_camera`, correlation-inflated), the clutter density matching the injected
    clutter and, for the unknown-correspondence model, the field of view and ``P_D`` inside it;
    both models take the range span from ``window`` (:func:`_widest_range`) and the planar
    birth of :func:`planar_formation`."""
    odometry = fit_odometry_model(ds, window, ODOMETRY_WINDOW_S)
    camera_fit = fit_camera(ds, window, range_interval_s=RANGE_INTERVAL_S)
    fits = [
        fit_largest_odometry_noise(
            ds.robot(s),
            window,
            rate_hz=FILTER_RATE,
            latency_s=odometry.latency_s,
            scale_v=odometry.scale_v[i],
            scale_w=odometry.scale_w[i],
            time_constant_s=odometry.time_constant_s,
        )
        for i, s in enumerate(ds.robot_ids)
    ]
    sv = max(float(np.sqrt(np.mean([f.sigma_v**2 for f in fits]))), MIN_SIGMA_V)
    sl = max(float(np.sqrt(np.mean([f.sigma_lateral**2 for f in fits]))), MIN_SIGMA_V)
    sw = max(float(np.sqrt(np.mean([f.sigma_w**2 for f in fits]))), MIN_SIGMA_W)
    sig = (sv, sl, 1e-3, sw)
    in_view = fit_detection_in_view(ds, window, fov)
    widest = _widest_range(ds, window)
    base = GaussianSumSettings(
        velocity_noise=VelocityNoise(observer=sig, observed=sig),
        sigma_height=SIGMA_HEIGHT,
        sigma_range=camera_fit.sigma_range,
        sigma_azimuth=camera_fit.sigma_bearing,
        sigma_elevation=camera_fit.sigma_bearing,
        use_elevation=False,
        expected_clutter=CLUTTER_PER_SCAN * np.pi / fov,
        formation=planar_formation(SIGMA_HEIGHT),
    )
    if widest is not None:
        base = replace(base, max_range=RANGE_MARGIN * widest)
    unknown = replace(
        base,
        field_of_view=fov,
        range_in_view=True,
        expected_clutter=CLUTTER_PER_SCAN,  # over its bearing space, the field of view
        formation=replace(base.formation, p_detect=in_view.p_detect),
    )
    camera = replace(base, ranges_mark_detections=True)
    return _Models(
        unknown=unknown,
        camera=camera,
        fits={
            "sigma_v": sv,
            "sigma_lateral": sl,
            "sigma_w": sw,
            "noise_window_s": [f.window_s for f in fits],
            "p_detect_in_view": in_view.to_dict(),
            "p_detect_all_frames": fit_detection_probability(ds, window).p_detect,
            "widest_range_m": widest,
            "range_span_m": base.max_range,
        },
        odometry=odometry,
        camera_fit=camera_fit,
    )


def calibrated_recording(ds: MrclamDataset, models: _Models) -> Recording:
    """The dataset as a Recording (:func:`relloc.datasets.mrclam.to_recording`) with the fitted
    models applied: every robot's commands calibrated (:func:`calibrated_team`) and the camera
    rows' bearing and range biases removed (:func:`corrected_readings`)."""
    raw = to_recording(ds)
    return replace(
        raw,
        odometry=calibrated_team(raw.odometry, models.odometry),
        measurements=corrected_readings(raw.measurements, models.camera_fit, ranges=True),
    )


@dataclass(frozen=True)
class _Window:
    """The run's calibration and scoring windows, the field of view and the models; ``raw``
    is the dataset as a Recording with the fitted models applied (:func:`calibrated_recording`)."""

    folder: Path
    ds: MrclamDataset
    raw: Recording
    calibration: CalibrationWindow
    t_start: float
    t_end: float
    fov_fit: Any
    models: _Models


def _windows(folder: Path) -> _Window:
    """Calibration window (``CALIBRATION_S`` after every robot has started moving), the
    scoring window after it (``EVAL_S``, cut short where the first robot's ground truth ends:
    ``truth_span``), the field of view and the fitted models."""
    ds = load_mrclam(folder)
    starts = [float(ds.robot(s).odometry.t[0]) for s in ds.robot_ids if ds.robot(s).odometry.t.size]
    if len(starts) != len(ds.robot_ids) or len(starts) < 2:
        raise DataError(f"{folder}: needs odometry for at least two robots")
    calibration = following(max(starts), CALIBRATION_S, str(folder))
    t_start = calibration.end_s
    t_end = min(t_start + EVAL_S, ds.truth_span[1])
    if t_end - t_start < 2 * WARMUP_S:
        raise DataError(
            f"{folder}: too short for a {EVAL_S:.0f} s evaluation after calibration "
            f"(scoring window [{t_start:.1f}, {t_end:.1f}] s, ground truth of every robot "
            f"up to {ds.truth_span[1]:.1f} s)"
        )
    fov_fit = fit_field_of_view(ds, calibration)
    models = _settings(ds, calibration, fov_fit.half_width_rad)
    raw = calibrated_recording(ds, models)
    return _Window(folder, ds, raw, calibration, t_start, t_end, fov_fit, models)


def _clock(w: _Window, offset: float) -> Array:
    """The filter clock of the scoring window, started ``offset`` seconds late."""
    return np.arange(w.t_start + offset, w.t_end, 1.0 / FILTER_RATE)


def _spread_runs(w: _Window, seed: int, runs: int) -> list[dict[str, Any]]:
    """The unknown-correspondence model ``runs`` times: run ``k`` draws its own clutter
    (seed ``k`` of ``seed``) and starts its filter clock ``k/(runs·FILTER_RATE)`` s late, so
    that the runs sample the two things a single run's figure depends on by chance (where
    the clutter falls, and which tick each camera frame is fused at)."""
    out = []
    for k, ss in enumerate(spawn_seeds(seed, runs)):
        offset = k / (runs * FILTER_RATE)
        clock = _clock(w, offset)
        rec, _ = _hidden_correspondence(
            w.raw, clock[0], clock[-1], w.fov_fit.half_width_rad, np.random.default_rng(ss)
        )
        names = [f"R{name}" for name in rec.robots]
        figures, _ = _evaluate(_run(rec, w.models.unknown, clock, sharing=False), clock[0], names)
        out.append({"run": k, "clock_offset_s": offset, **_headline(figures)})
    return out


def _fit_record(fit: dict[str, Any]) -> dict[str, Any]:
    """A fit's record without its window (the calibration window, stated once)."""
    return {k: v for k, v in fit.items() if k != "calibration_window"}


def _headline(figures: dict[str, Any]) -> dict[str, Any]:
    return {k: figures[k] for k in HEADLINE_KEYS}


def _spread(runs: list[dict[str, Any]]) -> dict[str, Any]:
    """Mean, min and max over the runs of every headline figure (None where a run has none)."""
    out: dict[str, Any] = {}
    for key in HEADLINE_KEYS:
        v = [r[key] for r in runs if r[key] is not None]
        out[key] = (
            {"mean": float(np.mean(v)), "min": float(np.min(v)), "max": float(np.max(v))}
            if v
            else None
        )
    return out


def reproduce(args: ReproduceArgs) -> dict[str, Any]:
    """Run the fusers on the dataset window; write summary.json, report.md and a figure."""
    out = prepare_out_dir(args.out_dir)
    folder = Path(args.dataset) if args.dataset is not None else default_mrclam_dataset()
    w = _windows(folder)
    fov = w.fov_fit.half_width_rad
    runs = args.runs if args.runs is not None else SPREAD_RUNS
    spread_runs = _spread_runs(w, args.master_seed, runs)
    spread = _spread(spread_runs)
    clock = _clock(w, 0.0)
    rng = np.random.default_rng(spawn_seeds(args.master_seed, runs)[0])
    rec, counts = _hidden_correspondence(w.raw, clock[0], clock[-1], fov, rng)
    counts["unknown_subject"] = rec.skips.skipped_by_reason().get(UNMAPPED_SUBJECT, 0)
    counts["truth_missing"] = sum(
        int((~w.ds.robot(s).groundtruth.at(clock).valid).sum()) for s in w.ds.robot_ids
    )
    n_scans = sum(
        st.size
        for st in scan_times(
            rec.measurements, rec.robots, range(rec.n_robots), w.models.unknown
        ).values()
    )
    names = [f"R{name}" for name in rec.robots]
    estimates, times = _estimates(rec, w.models.unknown, clock, sharing=False)
    scores = _scores(estimates, rec, times, w.models.unknown)
    reference = sighting_reset_reference(
        rec,
        w.models.unknown,
        {name: t[t - clock[0] >= WARMUP_S] for name, t in times.items()},
        pos_tol=POS_TOL_M,
        yaw_tol=YAW_TOL_RAD,
    )
    unknown, rows = _evaluate(scores, clock[0], names)
    all_around = replace(w.models.unknown, range_in_view=False)
    ranges_all_around, _ = _evaluate(_run(rec, all_around, clock, sharing=False), clock[0], names)
    shared, _ = _evaluate(_run(rec, w.models.unknown, clock, sharing=True), clock[0], names)
    mutual_settings = w.models.unknown.with_sharing_policy("mutual-confirmed")
    mutual, _ = _evaluate(_run(rec, mutual_settings, clock, sharing=True), clock[0], names)
    clean, _ = _hidden_correspondence(w.raw, clock[0], clock[-1], fov, rng, 0.0)
    clean_settings = replace(w.models.unknown, expected_clutter=0.0)
    no_clutter, _ = _evaluate(_run(clean, clean_settings, clock, sharing=False), clock[0], names)
    bound = {
        "with_clutter": association_bound(rec, w.models.unknown).to_dict(),
        "no_clutter": association_bound(clean, clean_settings).to_dict(),
    }
    camera, _ = _evaluate(_run(rec, w.models.camera, clock, sharing=True), clock[0], names)
    summary: dict[str, Any] = {
        "experiment": "mrclam-association",
        "seed": args.master_seed,
        "runs": runs,
        "dataset": str(folder),
        "window_s": [w.t_start, w.t_end],
        "scored_on": {"start_s": w.t_start, "end_s": w.t_end, "source": str(folder)},
        "calibration_window_s": [w.calibration.start_s, w.calibration.end_s],
        "calibration_window": w.calibration.to_dict(),
        "clutter_per_scan": CLUTTER_PER_SCAN,
        "field_of_view_rad": [-fov, fov],
        "field_of_view_window": w.fov_fit.calibration_window.to_dict(),
        "odometry_noise": w.models.fits,
        "odometry_model": _fit_record(w.models.odometry.to_dict()),
        "camera_model": _fit_record(w.models.camera_fit.to_dict()),
        "sigma_range_m": w.models.unknown.sigma_range,
        "sigma_bearing_rad": w.models.unknown.sigma_azimuth,
        **{k: spread[k]["mean"] if spread[k] is not None else None for k in HEADLINE_KEYS},
        "spread": {"runs": spread_runs, **spread},
        "run0": unknown,
        "unknown_ranges_all_around": _headline(ranges_all_around),
        "unknown_shared": _headline(shared),
        "unknown_mutual_confirmed": _headline(mutual),
        "unknown_no_clutter": _headline(no_clutter),
        "association_bound": bound,
        "tracking_reference": reference.to_dict(),
        "tracked_by_age": _tracked_by_age(scores, rec, clock[0], w.models.unknown).to_list(),
        "camera": _headline(camera),
        "bearings": counts,
        "scans": n_scans,
        "load_report": w.ds.report.to_dict(),
    }
    if args.export is not None:
        summary["export"] = export_estimates(
            args.export, estimates, rec, run=f"{folder.name}: {EXPORTED_RUN}"
        )
    fig_name = _figure(out, scores, clock[0], names)
    summary["figures"] = {"errors": fig_name}
    write_summary(out, summary)
    write_report(out, _report(summary, rows, fig_name))
    return summary


def _report(s: dict[str, Any], rows: list[list[Any]], fig_name: str) -> str:
    """report.md: the unknown-correspondence model first, its spread, then the others."""
    labels = (
        ("association accuracy (dominant tracks)", "association_accuracy"),
        ("association accuracy (joint GNN decision)", "association_accuracy_joint"),
        ("bearings used that were clutter", "wrong_clutter"),
        ("bearings used that were another robot", "wrong_robot"),
        ("position RMSE vs Vicon (m)", "pos_rmse_m"),
        ("median position error (m)", "pos_median_m"),
        ("yaw RMSE (rad)", "yaw_rmse_rad"),
        ("records tracked (0.5 m, 0.5 rad)", "tracked_fraction"),
        ("records with a track", "coverage"),
    )
    sp = s["spread"]
    comparison = markdown_table(
        [
            "figure",
            f"unknown correspondence (mean of {s['runs']} runs)",
            "min",
            "max",
            "ranges all around (run 0)",
            "+ mutual/indirect fusion (run 0)",
            "+ mutual fusion of confirmed tracks (run 0)",
            "no injected clutter (run 0)",
            "camera: range marks detection (run 0)",
        ],
        [
            [
                label,
                s[key],
                sp[key]["min"] if sp[key] else None,
                sp[key]["max"] if sp[key] else None,
                s["unknown_ranges_all_around"][key],
                s["unknown_shared"][key],
                s["unknown_mutual_confirmed"][key],
                s["unknown_no_clutter"][key],
                s["camera"][key],
            ]
            for label, key in labels
        ],
        digits=3,
    )
    per_run = markdown_table(
        ["run", "clock offset (s)", "association accuracy", "tracked", "pos RMSE (m)"],
        [
            [
                r["run"],
                r["clock_offset_s"],
                r["association_accuracy"],
                r["tracked_fraction"],
                r["pos_rmse_m"],
            ]
            for r in sp["runs"]
        ],
        digits=4,
    )
    table = markdown_table(
        [
            "observer",
            "association accuracy",
            "bearings used",
            "pos RMSE (m)",
            "tracked",
            "coverage",
        ],
        rows,
        digits=3,
    )
    c = s["bearings"]
    fits = s["odometry_noise"]
    pin = fits["p_detect_in_view"]
    ref = s["tracking_reference"]
    t0, t1 = s["window_s"]
    c0, c1 = s["calibration_window_s"]
    fov = s["field_of_view_rad"][1]
    bound = s["association_bound"]["with_clutter"]["accuracy"]
    bound_side = _target_side(bound, TARGET_ACCURACY, "above", "within")
    ref_side = _target_side(
        ref["tracked_fraction"],
        TARGET_TRACKED,
        "above the reference: even a filter reset to the truth at every sighting misses it",
        "below the reference, so the data do not rule it out",
    )
    return f"""# MRCLAM: relative localization with unknown bearing correspondence

Dataset `{s["dataset"]}`, seed {s["seed"]}. **Calibration window** {c0:.2f}–{c1:.2f} s (odometry
and camera models, detection probability); **scoring window** {t0:.2f}–{t1:.2f} s. Bearings
of robots lose their barcodes and are mixed with {c["injected"]} injected false bearings (run 0),
uniform over the camera's field of view ±{fov:.2f} rad ({s["clutter_per_scan"]} per scan on
average); ranges keep their barcodes; {c["landmark_skipped"]} landmark rows are not used.
{c["scans_with_several_robots"]} of {s["scans"]} scans hold bearings of two or more robots.
{skipped_rows_line(s["load_report"]["n_skipped"], s["load_report"]["skipped_by_reason"])}

{_models_text(s)}

**Unknown correspondence** (the headline, seed 002's separate sensors): the filter is not told
whose bearing is whose, nor that a robot with a range in the frame has its bearing in it; its
bearing ``P_D`` is the camera's: {pin["p_detect"]:.3f} for a teammate inside the field of view
(fitted: {pin["detected_in_view"]} of {pin["pairs_in_view"]} in-view pairs of the calibration
window), times the probability that the track's predicted azimuth lies inside it (over all
frames the share is {fits["p_detect_all_frames"]:.3f}, the constant ``P_D`` of seed 002's model).
The ranges come from the same camera, so the range sensor shares its field of view: a range
of a teammate says that it is in view, a frame without one that it is out of view or missed
— where the teammate is, not which bearing is its (the two detections are still taken as
independent, so a teammate in view and missed counts twice against a track). The next column
is the same model with seed 002's all-around ranging, where a range's presence says nothing.
Direct fusion only; the same model with seed 002's mutual and indirect fusion is the column
after, and with mutual fusion of confirmed tracks only the one after that. **Camera** (second row
of the issue): range and bearing come from one detection, so a robot with a range has its
bearing in the set (P_D = 1) and one without has none (P_D = 0) — with one robot in most frames
this gives the bearing's identity away.

{comparison}

Spread: run k draws its own clutter and starts the filter clock k/({s["runs"]}·{FILTER_RATE:g} Hz)
late (which tick each frame is fused at); the headline is the mean.

{per_run}

Per observer (unknown correspondence, run 0):

{table}

{figure_md(fig_name, "log10 position error of the dominant track of every filter")}

Targets (issue 14, unknown correspondence): association accuracy ≥ {TARGET_ACCURACY} —
{_verdict(s["association_accuracy"], TARGET_ACCURACY)}; records tracked ≥ {TARGET_TRACKED} —
{_verdict(s["tracked_fraction"], TARGET_TRACKED)}.

**Definitions.** *Association accuracy*: at every record (a filter tick at which the observer
fused a camera frame), for every teammate whose filter has tracks and has been confirmed at
least once, the bearing the dominant (heaviest) track took in the last scan — the per-scan
maximum of seed 002's formation weights, false alarm ``w(1 − P_D P_G)`` against detected
``w P_D N/κ`` — is looked up in the recording's ``origin``; the accuracy is the share that
came from that teammate. Records whose dominant track took no bearing, and periods without a
track (before a first birth, after a deletion), do not count: they show in "records with a
track". *Records tracked*: of the records with a track (after {WARMUP_S:g} s), the share whose
dominant track is within {POS_TOL_M} m and {YAW_TOL_RAD} rad of the truth, over every teammate
(one seen rarely or never counts as much as one in view). Seed 002 reports neither figure: its
Fig. 5 gives the number of confirmed tracks and the RMS position and heading error of each
filter's dominant hypothesis over time, in simulation.

**What any filter could score here.** A filter that knew where every teammate is would still
take a false bearing whenever its teammate is in view but not detected (1 − P_D) and a false
bearing falls close to the predicted azimuth. Placing one track per teammate at the true
relative pose in the same fuser and reading which bearing each takes (run 0's scans,
:mod:`relloc.experiments.association_bound`) gives
{_share(s["association_bound"]["with_clutter"]["accuracy"])} with the injected clutter and
{_share(s["association_bound"]["no_clutter"]["accuracy"])} without: with
{s["clutter_per_scan"]} false bearing per scan and the fitted P_D the {TARGET_ACCURACY} target
is {bound_side} what perfect tracks reach under this definition.

*Records tracked* has a reference rather than a bound. Between two sightings of a teammate a
filter that fuses only its own readings learns nothing new about it; give it the exact relative
pose, yaw included (which one range and bearing never give), at every sighting, and let it
dead-reckon both robots with their calibrated commands until the next
(``sighting_reset_reference``, run 0's records): it keeps
{_share(ref["tracked_fraction"])} of {ref["records"]} records within {POS_TOL_M} m and
{YAW_TOL_RAD} rad (median {_seconds(ref["median_age_s"])} since the last sighting). The drift
between sightings alone costs the rest; the gap from this reference down to the filter's
{_share(s["tracked_fraction"])} is the relative yaw a sighting leaves open and the bearings
taken wrongly. The {TARGET_TRACKED} target lies {ref_side}. By the time since the observer
last saw the teammate (run 0; a filter's records with a track, the reference's after a first
sighting):

{_by_age_table(s["tracked_by_age"], ref["by_age"])}

The paper (seed 002) has no real-data experiment. Why tracks are lost here: a robot sees a
given teammate in short bursts (``P_D`` {pin["p_detect"]:.2f} inside the view, and a teammate
is in view only part of the time), often too briefly to fix the relative yaw, which only the
motion between sightings makes observable. Between bursts a track drifts with its yaw error,
and nothing corrects it: the ranges come only with camera detections, not from an always-on
ranging sensor as in seed 002, so an unseen robot gives no range either (its absence says
only that the robot is out of view or was missed). The drifted track
then takes another robot's bearing or a false one for its own — the no-clutter column shows
how much of the loss is telling robots apart rather than rejecting clutter. The odometry is
not the limit: the commands are calibrated (latency, lag, scales, above), and on run 6 the
same figures with the raw held commands, the uncorrected camera and σ 0.2 m / 0.03 rad were
within this spread (module docstring). The robots move slowly (about 0.06 m/s), so a burst of
a few seconds moves a teammate little more than the range noise: a better dead reckoning does
not resolve the relative yaw that a short burst leaves open. A filter of a teammate that has
left the view keeps no range, and its track can go on feeding on another robot's bearings (the
"another robot" row): with an in-view ``P_D`` this low, two robots at one bearing with one of
them missed is a cheap explanation. Mutual and indirect fusion spread the unresolved yaw
hypotheses of the teammates' filters, and a message only shares each local hypothesis's
weight among its outcomes (so that the common odometry is not counted twice), so it cannot
select the heading hypothesis that a pair of mutual sightings agrees on; hence direct fusion
for the headline. "Records tracked" counts the records with a track; "records with a track"
says how many there are.

Model choices stated here (both fitted or fixed before scoring): the range span of the filters
is {s["odometry_noise"]["range_span_m"]:.2f} m ({RANGE_MARGIN:g} × the widest robot range of the
calibration window) and a new track's height variance is the height reference's
({SIGMA_HEIGHT:g} m)², not Eq. 13's 0.05 m² (the robots are planar; :func:`planar_formation`).
"""


def _by_age_table(filter_bins: list[dict[str, Any]], reference_bins: list[dict[str, Any]]) -> str:
    """Records and tracked share by time since the last sighting, the filter's beside the
    reference's (:class:`relloc.experiments.association_bound.TrackedByAge`)."""
    rows = [
        [
            f"{f['from_s']:g}–{f['to_s']:g} s" if f["to_s"] is not None else f"≥ {f['from_s']:g} s",
            f["records"],
            f["tracked_fraction"],
            r["records"],
            r["tracked_fraction"],
        ]
        for f, r in zip(filter_bins, reference_bins, strict=True)
    ]
    return markdown_table(
        [
            "time since the last sighting",
            "filter: records",
            "filter: tracked",
            "reference: records",
            "reference: tracked",
        ],
        rows,
        digits=3,
    )


def _models_text(s: dict[str, Any]) -> str:
    """The fitted odometry and camera models, as applied to every model's recording."""
    o, c, n = s["odometry_model"], s["camera_model"], s["odometry_noise"]
    return (
        f"**Error models** (fitted on the calibration window, applied before any filter runs): "
        f"the commands act {o['latency_s']:.2f} s late through a {o['time_constant_s']:.2f} s "
        f"first-order lag, speed scales {', '.join(f'{v:.3f}' for v in o['scale_v'])}, "
        f"turn-rate scales {', '.join(f'{v:.3f}' for v in o['scale_w'])}; the calibrated "
        f"commands leave a white input noise of σ_v {n['sigma_v']:.4f} m/s, σ_lateral "
        f"{n['sigma_lateral']:.4f} m/s, σ_ω {n['sigma_w']:.4f} rad/s (RMS over robots, each "
        f"at the window length giving its largest σ_ω: "
        f"{', '.join(f'{v:g}' for v in n['noise_window_s'])} s). Camera: each robot's bearing "
        f"bias on (1, η, η²) and the range bias on (1, η, η², ρ, ρη²) = "
        f"({', '.join(f'{v:.3f}' for v in c['range_bias_coeffs'])}) are removed from every "
        f"row; bearing σ {c['sigma_bearing_raw']:.4f} rad (MAD) × √{c['bearing_inflation']:.1f} "
        f"(correlation inflation) = {s['sigma_bearing_rad']:.4f} rad, range σ "
        f"{c['sigma_range_raw']:.3f} m × √{c['range_inflation']:.1f} = "
        f"{s['sigma_range_m']:.3f} m (every range fused, inflated at the readings' spacing "
        f"{c['correlation']['pair_spacing_s']['median']:.2f} s)."
        + unfitted_note(o["unfitted_robots"])
    )


def _target_side(reached: float | None, target: float, above: str, below: str) -> str:
    """``above`` when ``target`` lies above what was ``reached`` (or nothing was), else
    ``below``."""
    return above if reached is None or target > reached else below


def _share(value: float | None) -> str:
    return "—" if value is None else f"{value:.3f}"


def _seconds(value: float | None) -> str:
    return "—" if value is None else f"{value:.1f} s"


def _verdict(value: float | None, target: float) -> str:
    if value is None:
        return "not measured (no confirmed track)"
    return f"{value:.3f}, {'met' if value >= target else 'missed'}"


def _evaluate(
    scores: list[LeaderScores], t0: float, names: list[str]
) -> tuple[dict[str, Any], list[list[Any]]]:
    """Association accuracy and tracking error of one team run, overall and per observer
    (planar position error; records from ``WARMUP_S`` after ``t0``)."""
    rows, all_pe, all_ye, all_tr = [], [], [], []
    n_cov = n_rec = 0
    used_total = correct_total = j_used_total = j_correct_total = clutter_total = 0
    per_obs: dict[str, Any] = {}
    own = np.arange(len(names))[None, :]
    for sc in scores:
        i = sc.observer
        pe, ye, ok, tracked = _scored(sc, t0)
        after = (sc.t - t0) >= WARMUP_S
        conf = np.cumsum(sc.confirmed, axis=0) > 0
        used = conf & (sc.assoc_origin != NO_READING)
        u, c = int(used.sum()), int((used & (sc.assoc_origin == own)).sum())
        used_total += u
        correct_total += c
        clutter_total += int((used & (sc.assoc_origin == CLUTTER)).sum())
        j_used = conf & (sc.joint_origin != NO_READING)
        j_used_total += int(j_used.sum())
        j_correct_total += int((j_used & (sc.joint_origin == own)).sum())
        per_obs[names[i]] = {
            "association_accuracy": c / u if u else None,
            "bearings_used": u,
            "pos_rmse_m": float(np.sqrt(np.mean(pe[ok] ** 2))) if ok.any() else None,
            "tracked_fraction": float(tracked[ok].mean()) if ok.any() else None,
            "coverage": float(ok.sum() / max(int(after.sum()) * (len(names) - 1), 1)),
        }
        rows.append([names[i], *per_obs[names[i]].values()])
        all_pe.append(pe[ok])
        all_ye.append(ye[ok])
        all_tr.append(tracked[ok])
        n_cov += int(ok.sum())
        n_rec += int(after.sum()) * (len(names) - 1)
    pe_all, ye_all, tr_all = np.concatenate(all_pe), np.concatenate(all_ye), np.concatenate(all_tr)
    figures = {
        "association_accuracy": correct_total / used_total if used_total else None,
        "association_accuracy_joint": j_correct_total / j_used_total if j_used_total else None,
        "wrong_clutter": clutter_total / used_total if used_total else None,
        "wrong_robot": (used_total - correct_total - clutter_total) / used_total
        if used_total
        else None,
        "pos_rmse_m": float(np.sqrt(np.mean(pe_all**2))) if pe_all.size else None,
        "pos_median_m": float(np.median(pe_all)) if pe_all.size else None,
        "yaw_rmse_rad": float(np.sqrt(np.mean(ye_all**2))) if ye_all.size else None,
        "tracked_fraction": float(tr_all.mean()) if tr_all.size else None,
        "coverage": n_cov / n_rec if n_rec else None,
        "per_observer": per_obs,
    }
    return figures, rows


def _scored(sc: LeaderScores, t0: float) -> tuple[Array, Array, BoolArray, BoolArray]:
    """The planar position and |yaw| errors of one observer's dominant tracks, the records
    scored (a track, ``WARMUP_S`` after ``t0``) and those tracked (within ``POS_TOL_M`` and
    ``YAW_TOL_RAD``), indexed ``[record, teammate]``."""
    pe = np.linalg.norm(sc.error[..., :2], axis=-1)
    ye = np.abs(sc.error[..., 3])
    ok = np.isfinite(pe) & ((sc.t - t0) >= WARMUP_S)[:, None]
    return pe, ye, ok, (pe <= POS_TOL_M) & (ye <= YAW_TOL_RAD)


def _tracked_by_age(
    scores: list[LeaderScores], rec: Recording, t0: float, settings: GaussianSumSettings
) -> TrackedByAge:
    """The scored records of every observer by the time since it last saw the teammate
    (:func:`relloc.experiments.association_bound.last_sightings`; records before a first
    sighting are left out), and how many of them are tracked."""
    kind = bearing_kind(settings)
    ages, flags = [], []
    for sc in scores:
        _, _, ok, tracked = _scored(sc, t0)
        for j in range(rec.n_robots):
            if j == sc.observer:
                continue
            s = last_sightings(rec, sc.observer, j, sc.t, kind)
            sel = ok[:, j] & np.isfinite(s)
            ages.append(sc.t[sel] - s[sel])
            flags.append(tracked[sel, j])
    return TrackedByAge.count(np.concatenate(ages), np.concatenate(flags))


def _figure(out: Path, scores: list[LeaderScores], t0: float, names: list[str]) -> str:
    from relloc.plotting.multihypothesis import plot_series
    from relloc.plotting.setup import pyplot

    plt = pyplot()

    fig, axes = plt.subplots(len(scores), 1, figsize=(10, 2.2 * len(scores)), sharex=True)
    for ax, sc in zip(np.atleast_1d(axes), scores, strict=True):
        i = sc.observer
        pe = np.linalg.norm(sc.error[..., :2], axis=-1)
        series = {names[j]: np.maximum(pe[:, j], 1e-3) for j in range(len(names)) if j != i}
        plot_series(ax, sc.t - t0, series, ylabel=f"{names[i]}: error (m)", log10=True)
    np.atleast_1d(axes)[0].set_title("Position error of each leader's dominant teammate tracks")
    return save_figure(fig, out, "mrclam_association_errors")
