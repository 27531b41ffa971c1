"""Real-trajectory part of the seed-000 reproduction (its §6 experiment, Tables 3–4).

The paper replays two Pioneer robots with map-based localisation as ground truth, treats the
observed robot as if it flew 2 m above its real plane, drives the filter with the recorded
odometry and synthesises range/azimuth/elevation from the ground truth at the four Table-2
sensor settings. Here the same is done with two robots of any MRCLAM-layout dataset
(:mod:`relloc.datasets.mrclam`; default run 6), as a transformation of the dataset's
:class:`~relloc.core.recording.Recording` (:func:`to_recording`):

* the pair only; the observer's and the observed robot's **recorded odometry** ``(v, ω)`` are
  the velocity inputs ``u = (v, 0, 0, ω)``, held between records, resampled on a 100 Hz grid;
* the **truth** is the Vicon pose of both robots (interpolated at the record times, yaw on the
  circle), the observed robot's plane raised by ``height``; measurement epochs falling in a
  ground-truth gap are skipped (counted);
* the odometry comes in two versions, both replayed (:func:`prepare_replays`):

  - **calibrated** (the headline): fitted on the *calibration window* — the rest of the
    recording after the scored window, so the two are disjoint — by
    :func:`relloc.calibration.odometry.fit_odometry_model` (one latency ``τ`` and one
    first-order time constant ``T`` for the team — the commands lead the motion and the robots
    follow them through a lag — and per-robot scales ``s_v, s_ω``); the filters get the
    modelled response ``s · c_τ,T`` (:func:`relloc.calibration.odometry.calibrated_commands`)
    held on the grid, and the equivalent white noise left after that calibration
    (:func:`relloc.calibration.odometry.fit_odometry_noise`) at the time scale where the
    turn-rate error is largest: the fit over each window length of
    ``calibration_noise_windows_s`` (1 s up to 40 s, the settling time Table 3 allows) is made
    and the one with the largest σ_ω kept. The real errors are correlated over seconds, so an
    equivalent white noise is right at one time scale only; the relative yaw is corrected only
    through the observed robot's motion, slowly, so the filter must not be over-confident at any
    time scale it bridges, and the largest σ is the conservative choice;
  - **raw** (the earlier replay, kept beside): the recorded commands as they are, with the
    equivalent white noise over 1 s windows fitted over each robot's whole recording (the
    scored window included);

  the windows are stated with each fit (``calibration_window``) and the scored window beside;
* each Monte-Carlo draw adds fresh readings for the four Table-2 settings — four sensors of
  the observer (sensor ``s`` is the ``s``-th setting of :data:`TABLE2`), each stating its σ — and
  starts the PLKF, the bias-compensated PLKF and the TEKF from one arbitrary pose drawn in the
  field of view (seed 000 §6: unknown initialisation), together with relloc's yaw bank from
  the same pose, all in one :class:`~relloc.estimators.relative_batch.RelativeFilterBatch`
  (:func:`relloc.experiments.wanasinghe2014_filters.run_filters`).

The window starts ``start_after_odometry_s`` after both robots' first odometry record (they
stand still before) and lasts ``duration_s`` (160 s: the paper's 1600 NEES samples at 10 Hz),
shortened to what the dataset holds.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from relloc.calibration.odometry import (
    OdometryModelFit,
    OdometryNoiseFit,
    calibrated_commands,
    fit_odometry_model,
    fit_odometry_noise,
)
from relloc.calibration.window import CalibrationWindow, odometry_and_truth
from relloc.core.recording import (
    GroundTruth,
    Measurements,
    Odometry,
    Recording,
    measurement_rows,
    relative_pose,
)
from relloc.datasets.mrclam import MrclamDataset, load_mrclam, to_recording
from relloc.errors import ConfigError, DataError
from relloc.estimators.initialisation import fully_unknown, pose_in_fov
from relloc.estimators.relative_batch import TrackSpec
from relloc.estimators.yaw_bank import YawBankSettings
from relloc.experiments.wanasinghe2014_filters import run_filters
from relloc.models.measurement import range_bearing
from relloc.pipeline.evaluation import SeriesEvaluation
from relloc.sim.sensors import add_noise

Array = NDArray[np.float64]

#: Seed 000 Table 2: (σ_r m, σ_θ = σ_α rad, update rate Hz).
TABLE2: dict[str, tuple[float, float, float]] = {
    "case1": (0.0068, 0.0036, 10.0),
    "case2": (0.1466, 0.1, 10.0),
    "case3": (0.0068, 0.0036, 1.0),
    "case4": (0.1466, 0.1, 1.0),
}
#: Filters replayed side by side (name → update kind of :mod:`relloc.estimators.relative`);
#: "yaw bank" is relloc's initialisation (:mod:`relloc.estimators.yaw_bank`) on PLKF components.
REPLAY_FILTERS: dict[str, str] = {
    "PLKF": "plkf",
    "BC-PLKF": "bcplkf",
    "TEKF": "tekf",
    "yaw bank": "plkf",
}
#: The bias-compensated PLKF (six cubature gains per update) runs where its bias matters: the
#: noisy sensor of Table 2 (with the precise sensor the PLKF bias is below a millimetre).
BC_CASES: tuple[str, ...] = ("case2", "case4")


#: Filters of Tables 3–4 (the raw-odometry replay runs only these: the bias comparison is made
#: on the calibrated one).
TABLE_FILTERS: tuple[str, ...] = ("PLKF", "yaw bank")


def replay_filters(case: str, odometry_kind: str = "calibrated") -> tuple[str, ...]:
    """Filters replayed for a Table-2 case with ``odometry_kind`` odometry."""
    if odometry_kind == "raw":
        return TABLE_FILTERS
    return tuple(f for f in REPLAY_FILTERS if f != "BC-PLKF" or case in BC_CASES)


@dataclass(frozen=True, kw_only=True)
class ReplaySettings:
    """Which robots and which stretch of the recording are replayed, and how."""

    dataset: Path
    observer: int = 1
    observed: int = 3
    height: float = 2.0
    start_after_odometry_s: float = 5.0
    duration_s: float = 160.0
    min_duration_s: float = 20.0
    rate_hz: float = 100.0
    noise_window_s: float = 1.0
    calibration_noise_windows_s: tuple[float, ...] = (1.0, 2.0, 5.0, 10.0, 20.0, 40.0)
    init_range: tuple[float, float] = (0.3, 8.0)

    def __post_init__(self) -> None:
        if self.observer == self.observed:
            raise ConfigError("ReplaySettings.observed: must differ from the observer")
        for name in (
            "start_after_odometry_s",
            "duration_s",
            "min_duration_s",
            "rate_hz",
        ):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0) or (
                name != "start_after_odometry_s" and value == 0
            ):
                raise ConfigError(f"ReplaySettings.{name}: must be a positive number, got {value}")
        if not (math.isfinite(self.height)):
            raise ConfigError(f"ReplaySettings.height: must be finite, got {self.height}")
        if not self.calibration_noise_windows_s or any(
            not (math.isfinite(w) and w > 0) for w in self.calibration_noise_windows_s
        ):
            raise ConfigError(
                "ReplaySettings.calibration_noise_windows_s: positive window lengths, got "
                f"{self.calibration_noise_windows_s}"
            )
        lo, hi = self.init_range
        if not 0 <= lo < hi:
            raise ConfigError(
                f"ReplaySettings.init_range: need 0 ≤ min < max, got {self.init_range}"
            )


@dataclass(frozen=True)
class ReplayData:
    """The deterministic part of the replay, built once and shared by every draw.

    The pair ``robots = (observer, observed)`` on the window's grid ``t``: ``odometry`` held on
    the grid with the fitted noise σ, ``truth`` with the observed plane raised; ``valid`` marks
    the grid times outside ground-truth gaps. Each draw builds its :class:`Recording` from
    these parts and its own readings (:meth:`recording`). ``odometry_kind`` is ``"calibrated"``
    or ``"raw"`` (module docstring); ``calibration`` is the team fit of the calibrated version
    (``None`` for the raw one) and ``pair_scales`` the pair's ``(s_v, s_ω)`` from it.
    """

    source: str
    robots: tuple[str, str]
    t: Array
    odometry: tuple[Odometry, Odometry]
    truth: tuple[GroundTruth, GroundTruth]
    valid: NDArray[np.bool_]
    fits: dict[str, OdometryNoiseFit]
    skipped_epochs: dict[str, int]
    load_report: dict[str, Any]
    odometry_kind: str = "raw"
    calibration: OdometryModelFit | None = None
    pair_scales: tuple[tuple[float, float], ...] = ()

    @property
    def scored_window(self) -> CalibrationWindow:
        """The replayed (scored) stretch of the recording."""
        return CalibrationWindow(float(self.t[0]), float(self.t[-1]), self.source)

    @property
    def dt(self) -> float:
        return float(self.t[1] - self.t[0])

    def relative_truth(self, t: Array) -> Array:
        """True pose of the observed robot in the observer's frame at times ``t``."""
        return relative_pose(self.truth[0].at(t), self.truth[1].at(t))

    def recording(self, measurements: Measurements) -> Recording:
        """The pair with ``measurements``."""
        return Recording(
            robots=self.robots,
            platforms=("ground", "ground"),
            odometry=self.odometry,
            measurements=measurements,
            truth=self.truth,
            source=self.source,
        )


# ----------------------------------------------------------------------------------------------
# The experiment's transformation of the recording
# ----------------------------------------------------------------------------------------------


def _held(od: Odometry, t: Array, sigma: Array, where: str) -> Odometry:
    """``od`` held on the grid ``t[:-1]`` (zero-order hold), stating the noise ``sigma``."""
    return Odometry(t=t[:-1], velocity=od.held_at(t[:-1]), sigma=sigma, where=where)


def _raised(gt: GroundTruth, height: float) -> GroundTruth:
    """``gt`` with its plane at ``z = height``."""
    pose = np.array(gt.pose)
    pose[:, 2] = height
    return GroundTruth(t=gt.t, pose=pose, where=f"{gt.where} raised {height:g} m")


def _sigma(fit: OdometryNoiseFit) -> Array:
    """Velocity-noise σ of a ground robot whose plane is fixed: (v, lateral, 0, ω)."""
    return np.array([fit.sigma_v, fit.sigma_lateral, 0.0, fit.sigma_w])


def prepare_replay(settings: ReplaySettings) -> ReplayData:
    """The raw replay only (:func:`prepare_replays`)."""
    return _raw_replay(settings, load_mrclam(settings.dataset))


def prepare_replays(settings: ReplaySettings) -> dict[str, ReplayData]:
    """``{"calibrated": …, "raw": …}``: the replay with calibrated and with raw odometry
    (module docstring), from one load of the dataset."""
    ds = load_mrclam(settings.dataset)
    raw = _raw_replay(settings, ds)
    return {"calibrated": _calibrated_replay(settings, ds, raw), "raw": raw}


def _raw_replay(settings: ReplaySettings, ds: MrclamDataset) -> ReplayData:
    """Cut the window, hold the recorded odometry on the grid, raise the observed robot's plane,
    fit the odometry noise over each robot's whole recording."""
    obs, tgt = ds.robot(settings.observer), ds.robot(settings.observed)
    recording = to_recording(ds)
    i, j = recording.index(str(settings.observer)), recording.index(str(settings.observed))
    truth = recording.require_truth("the seed-000 replay")
    od_l, od_c = recording.odometry[i], recording.odometry[j]
    start = max(od_l.t[0], od_c.t[0]) + settings.start_after_odometry_s
    end = min(start + settings.duration_s, truth[i].t[-1], truth[j].t[-1], od_l.t[-1], od_c.t[-1])
    if end - start < settings.min_duration_s:
        raise DataError(
            f"{settings.dataset}: robots {settings.observer} and {settings.observed} share only "
            f"{max(end - start, 0.0):.1f} s of odometry and ground truth after the start; "
            f"need {settings.min_duration_s:g} s"
        )
    dt = 1.0 / settings.rate_hz
    n = math.floor((end - start) * settings.rate_hz + 1e-9)
    t = start + dt * np.arange(n + 1)
    valid = np.asarray(obs.groundtruth.at(t).valid & tgt.groundtruth.at(t).valid)
    fits = {
        label: fit_odometry_noise(
            robot,
            odometry_and_truth(robot, f"{ds.path}: robot {robot.subject}"),
            rate_hz=settings.rate_hz,
            window_s=settings.noise_window_s,
        )
        for label, robot in (("observer", obs), ("observed", tgt))
    }
    return ReplayData(
        source=f"{ds.path} robots {settings.observer} → {settings.observed}",
        robots=(recording.robots[i], recording.robots[j]),
        t=t,
        odometry=(
            _held(od_l, t, _sigma(fits["observer"]), f"{od_l.where} on the grid"),
            _held(od_c, t, _sigma(fits["observed"]), f"{od_c.where} on the grid"),
        ),
        truth=(truth[i], _raised(truth[j], settings.height)),
        valid=valid,
        fits=fits,
        skipped_epochs={
            case: int(np.count_nonzero(~valid[_epochs(t, rate)]))
            for case, (_, _, rate) in TABLE2.items()
        },
        load_report=ds.report.to_dict(),
    )


def calibration_window(ds: MrclamDataset, scored: CalibrationWindow) -> CalibrationWindow:
    """The rest of the recording after the scored window: ``[scored end, recording end]``
    (disjoint from the scored window; the robots stand still before their first command)."""
    end = float(ds.duration)
    if end <= scored.end_s:
        raise DataError(
            f"{ds.path}: the replay window {scored.describe()} reaches the end of the recording, "
            "leaving nothing to calibrate the odometry on; shorten duration_s"
        )
    return CalibrationWindow(scored.end_s, end, f"{ds.path} after the scored window")


def _calibrated_replay(settings: ReplaySettings, ds: MrclamDataset, raw: ReplayData) -> ReplayData:
    """``raw`` with the odometry calibrated on :func:`calibration_window` (module docstring)."""
    window = calibration_window(ds, raw.scored_window)
    lengths = [w for w in settings.calibration_noise_windows_s if 2 * w <= window.duration_s]
    if not lengths:
        raise window.too_little(
            f"no noise window of {settings.calibration_noise_windows_s} s fits twice"
        )
    team = fit_odometry_model(ds, window, integration_s=min(lengths))
    recording = to_recording(ds)
    odometry, fits, scales = [], {}, []
    for label, subject in (("observer", settings.observer), ("observed", settings.observed)):
        k = ds.robot_ids.index(subject)
        latency, s_v, s_w = team.latency_s, team.scale_v[k], team.scale_w[k]
        scales.append((s_v, s_w))
        candidates = [
            fit_odometry_noise(
                ds.robot(subject),
                window,
                rate_hz=settings.rate_hz,
                window_s=length,
                latency_s=latency,
                scale_v=s_v,
                scale_w=s_w,
                time_constant_s=team.time_constant_s,
            )
            for length in lengths
        ]
        fits[label] = max(candidates, key=lambda f: f.sigma_w)
        od = calibrated_commands(
            recording.odometry[recording.index(str(subject))],
            latency,
            s_v,
            s_w,
            team.time_constant_s,
        )
        odometry.append(_held(od, raw.t, _sigma(fits[label]), f"{od.where} on the grid"))
    return replace(
        raw,
        odometry=(odometry[0], odometry[1]),
        fits=fits,
        odometry_kind="calibrated",
        calibration=team,
        pair_scales=tuple(scales),
    )


def _epochs(t: Array, rate_hz: float) -> NDArray[np.int64]:
    """Grid steps of the measurement epochs at ``rate_hz`` (first one after one period)."""
    stride = max(round((1.0 / rate_hz) / float(t[1] - t[0])), 1)
    return np.arange(stride, t.size, stride, dtype=np.int64)


def replay_recording(data: ReplayData, rng: np.random.Generator) -> Recording:
    """One draw of the readings: range, azimuth and elevation synthesised from the truth with
    fresh noise at every valid epoch of each Table-2 setting — setting ``s`` is the observer's
    sensor ``s`` (in :data:`TABLE2` order), stating its σ."""
    parts = []
    for sensor, (s_r, s_b, rate) in enumerate(TABLE2.values()):
        steps = _epochs(data.t, rate)
        steps = steps[data.valid[steps]]
        sigma = np.array([s_r, s_b, s_b])
        z = add_noise(range_bearing(data.relative_truth(data.t[steps])), sigma, rng)
        parts.append(
            measurement_rows(
                "range_bearing_elevation",
                t=data.t[steps],
                observer=0,
                target=1,
                value=z,
                sigma=sigma,
                sensor=sensor,
            )
        )
    return data.recording(Measurements.concatenate(parts))


@dataclass(frozen=True)
class ReplayTrack:
    """One filter on one draw: its evaluation at its updates and the radial error
    ``|p̂| − |p|`` (m) of the position at each."""

    evaluation: SeriesEvaluation
    radial: Array


def replay_task(
    seed: np.random.SeedSequence, run_index: int, data: ReplayData, settings: ReplaySettings
) -> dict[str, dict[str, ReplayTrack]]:
    """One draw: ``{case: {filter: ReplayTrack}}`` (the filters of :func:`replay_filters`)."""
    rng = np.random.default_rng(seed)
    recording = replay_recording(data, rng)
    guess = pose_in_fov(rng, fov_deg=360.0, range_limits=settings.init_range)
    prior = fully_unknown(guess, sigma_position=settings.init_range[1] / math.sqrt(3.0))
    observer, observed = data.robots
    specs = [
        TrackSpec(
            label=f"{case}/{name}",
            subject=observed,
            kind=REPLAY_FILTERS[name],  # type: ignore[arg-type]
            prior_mean=np.asarray(prior.mean),
            prior_cov=np.asarray(prior.cov),
            sensor=sensor,
            bank=name == "yaw bank",
        )
        for sensor, case in enumerate(TABLE2)
        for name in replay_filters(case, data.odometry_kind)
    ]
    scored = run_filters(
        recording,
        specs,
        observer=observer,
        bank=YawBankSettings(),
        start=float(data.t[0]),
        end=float(data.t[-1]),
    )
    out: dict[str, dict[str, ReplayTrack]] = {}
    for case in TABLE2:
        out[case] = {}
        for name in replay_filters(case, data.odometry_kind):
            ev = scored[(observed, f"{case}/{name}")]
            p_true = data.relative_truth(ev.t)[:, :3]
            p_est = p_true + ev.error[:, :3]
            radial = np.linalg.norm(p_est, axis=-1) - np.linalg.norm(p_true, axis=-1)
            out[case][name] = ReplayTrack(evaluation=ev, radial=radial)
    return out
