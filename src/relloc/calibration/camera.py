"""Camera error models fitted against ground truth: bearing offset and noise, range bias and
noise, the residuals' time correlation, the detection probability and the field of view.

**Residuals** (:func:`camera_residuals`). Every detection ``z = (ρ̃, η̃)`` in the window whose
observer's and target's ground truth are valid (a landmark's position is known) gives
``e_ρ = ρ̃ − ρ(truth)`` and ``e_η = wrap(η̃ − η(truth))``, with ``ρ, η`` of
:mod:`relloc.models.planar_measurement`.

**Fit** (:func:`fit_camera`):

- bearing: a per-robot camera offset, the median of ``e_η`` over ``|e_η| < BEARING_INLIER_RAD``
  (0 with ``MIN_OFFSET_ROWS`` rows or fewer), and a per-robot bias that depends on where the
  target sits in the image, ``b_i(η) = c_i·(1, η, η²)`` (a lens's distortion and a camera
  mounted slightly off the robot's axis both bend the measured bearing smoothly across the
  image), fitted by least squares on the same inliers and applied at ``η`` clipped to the
  range it was fitted on (the offset alone with ``BEARING_BIAS_MIN_ROWS`` rows or fewer);
  ``σ_η = 1.4826·MAD`` of what the bias leaves — medians and MADs so that the rare
  wrong-barcode outliers, which the filter's χ² gate removes, do not set the core. The
  degree (2) was chosen on the calibration window of MRCLAM run 6: the correlation-inflated
  ``σ_η`` is 0.047 rad with the offset alone, 0.042 with a line and 0.036 with a quadratic or
  a cubic;
- range: the bias ``b(η, ρ) = c·(1, η, η², ρ, ρη²)`` (:func:`~relloc.models.planar_measurement.
  range_bias_features`) by least squares on the residuals ``|e_ρ| < RANGE_INLIER_M``, then
  ``σ_ρ = 1.4826·MAD`` of ``e_ρ − b``;
- correlation: the correlation of a residual with the same (observer, target) pair's residual
  ``lag`` seconds later (:func:`lag_correlation`) at ``CORRELATION_LAGS_S``. Consecutive
  residuals are strongly correlated, so a filter that treats them as independent over-counts
  their information; the variance inflation :func:`~relloc.calibration.inflation.
  autocorrelation_inflation` at the readings' spacing (the median gap between consecutive
  detections of a pair for bearings, at least the caller's ``range_interval_s`` for ranges —
  the filter keeps one range per pair per interval), summed up to the longest measured lag,
  gives the σ the filter should assume, ``σ·√f``.

The fit refuses (DataError naming the window) a window with fewer than ``MIN_RESIDUALS``
detections, or fewer than ``MIN_RESIDUALS`` bearing or range inliers (a camera whose every
bearing is off by more than ``BEARING_INLIER_RAD`` has no core to fit), and a σ of 0 (residuals
without spread: every reading would be taken as exact).

**Correction** (:func:`corrected_readings`): a recording's camera rows with the fitted bearing
bias ``b_i(η̃)`` removed from every bearing and, when asked, the fitted range bias
``b(η̃, ρ̃)`` (:meth:`CameraFit.range_bias`) from every range, both evaluated at the measured
reading as they were fitted.

**Detection probability** (:func:`fit_detection_probability`): ``P_D`` = the share of (camera
frame, other robot) pairs in which that robot is detected — the camera's narrow field of view
makes this far below the 0.95 often assumed, and assuming 0.95 would make every frame without
a teammate strong evidence that a false bearing is it.

**Detection probability in view** (:func:`fit_detection_in_view`): the same share over the
pairs whose ground truth puts the other robot inside the field of view, for a filter whose
``P_D`` depends on where it predicts the teammate.

**Field of view** (:func:`fit_field_of_view`): the half-width, the widest ``|η̃|`` of any
detection in the window.

**Landmark wait** (:func:`landmark_wait_s`): the expected time from a random instant to a
robot's next landmark detection, the horizon over which odometry must carry the pose.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, replace

import numpy as np
from numpy.typing import NDArray

from relloc.calibration.inflation import autocorrelation_inflation
from relloc.calibration.window import CalibrationWindow
from relloc.core.angles import wrap_angle
from relloc.core.recording import Measurements, kind_code
from relloc.datasets.mrclam import MrclamDataset
from relloc.errors import ConfigError
from relloc.models.planar_measurement import range_bias_features

Array = NDArray[np.float64]

#: Gaussian-consistent MAD scale.
MAD_SCALE = 1.4826
#: Fewest residuals in the window for a camera fit, and fewest bearing and range inliers.
MIN_RESIDUALS = 20
#: Bearing residuals beyond this (rad) are outliers for the offset and σ_η fits.
BEARING_INLIER_RAD = 0.1
#: Range residuals beyond this (m) are outliers for the bias and σ_ρ fits.
RANGE_INLIER_M = 1.0
#: A robot's bearing offset needs more inlier rows than this (else 0).
MIN_OFFSET_ROWS = 10
#: Terms of the bearing bias ``b(η) = c·(1, η, η²)`` (module docstring).
BEARING_BIAS_TERMS = 3
#: A robot's bearing bias ``b(η)`` needs more inlier rows than this (else its offset alone).
BEARING_BIAS_MIN_ROWS = BEARING_BIAS_TERMS * MIN_OFFSET_ROWS
#: Lags (s) at which the residual correlation is measured. They reach a minute because the
#: MRCLAM range error depends on where the robot sits in the image and stays correlated for
#: tens of seconds (about 0.6 at 10 s on run 6); the inflation sums the measured correlation up
#: to the longest lag (cutting it at 10 s would over-count the ranges' information).
CORRELATION_LAGS_S = (0.25, 0.5, 1.0, 2.0, 5.0, 10.0, 20.0, 40.0, 60.0)
#: A later residual counts as ``lag`` later when it is within this (s) of ``t + lag``.
LAG_TOLERANCE_S = 0.25
#: Fewest residual pairs for a lag correlation (else 0).
MIN_LAG_PAIRS = 10
#: Clip of the detection probability (a pair never / always seen is not evidence of 0 or 1).
P_DETECT_LIMITS = (0.05, 0.95)


@dataclass(frozen=True)
class CameraResiduals:
    """Camera residuals against ground truth: one row per usable detection; ``observer`` is
    the robot's index in ``ds.robot_ids``, ``subject`` the detected subject."""

    observer: NDArray[np.int64]
    subject: NDArray[np.int64]
    t: Array
    range: Array
    bearing: Array
    range_error: Array
    bearing_error: Array

    def pair_key(self) -> NDArray[np.int64]:
        """One integer per (observer, subject) pair."""
        return np.asarray(self.observer * 1000 + self.subject, dtype=np.int64)


def camera_residuals(ds: MrclamDataset, window: CalibrationWindow) -> CameraResiduals:
    """``z − h(truth)`` of every detection in ``window`` whose truth is valid."""
    lm = {int(s): xy for s, xy in zip(ds.landmarks.subject, ds.landmarks.xy, strict=True)}
    cols: list[list[Array]] = [[] for _ in range(7)]
    for index, rid in enumerate(ds.robot_ids):
        m = ds.robot(rid).measurements
        sel = window.contains(m.t)
        t, subj = m.t[sel], m.subject[sel]
        q = ds.robot(rid).groundtruth.at(t)
        tx, ty = np.full(t.size, np.nan), np.full(t.size, np.nan)
        ok = q.valid.copy()
        for s in np.unique(subj):
            k = subj == s
            if int(s) in lm:
                tx[k], ty[k] = lm[int(s)]
            elif int(s) in ds.robots:
                qq = ds.robot(int(s)).groundtruth.at(t[k])
                tx[k], ty[k] = qq.x, qq.y
                ok[k] &= qq.valid
            else:
                ok[k] = False
        dx, dy = tx - q.x, ty - q.y
        er = m.range[sel] - np.hypot(dx, dy)
        eb = np.asarray(wrap_angle(m.bearing[sel] - (np.arctan2(dy, dx) - q.theta)))
        for c, v in zip(
            cols,
            (np.full(t.size, index), subj, t, m.range[sel], m.bearing[sel], er, eb),
            strict=True,
        ):
            c.append(v[ok])
    arr = [np.concatenate(c) for c in cols]
    return CameraResiduals(
        arr[0].astype(np.int64), arr[1].astype(np.int64), arr[2], arr[3], arr[4], arr[5], arr[6]
    )


def mad_sigma(x: Array) -> float:
    """Robust σ: ``1.4826 · median(|x − median(x)|)``."""
    return float(MAD_SCALE * np.median(np.abs(x - np.median(x))))


def lag_correlation(
    res: CameraResiduals, values: Array, keep: NDArray[np.bool_], lag: float
) -> float:
    """Correlation of ``values`` with the same pair's value ``lag`` seconds later (within
    ``LAG_TOLERANCE_S``), over the rows ``keep``; 0 with fewer than ``MIN_LAG_PAIRS`` pairs
    (none when ``keep`` holds no row)."""
    a, b = [], []
    key = res.pair_key()
    for k in np.unique(key[keep]):
        idx = np.flatnonzero((key == k) & keep)
        tt, vv = res.t[idx], values[idx]
        j = np.searchsorted(tt, tt + lag)
        ok = j < tt.size
        ok[ok] &= np.abs(tt[j[ok]] - tt[ok] - lag) < LAG_TOLERANCE_S
        a.append(vv[ok])
        b.append(vv[j[ok]])
    if sum(v.size for v in a) < MIN_LAG_PAIRS:
        return 0.0
    x, y = np.concatenate(a), np.concatenate(b)
    return float(np.corrcoef(x, y)[0, 1])


def pair_spacing_s(res: CameraResiduals) -> float:
    """Median gap between consecutive detections of one pair (the bearings' sampling
    interval); the first correlation lag when no pair is detected twice."""
    key = res.pair_key()
    order = np.lexsort((res.t, key))
    gaps = np.diff(res.t[order])[np.diff(key[order]) == 0]
    return float(np.median(gaps)) if gaps.size else CORRELATION_LAGS_S[0]


def bearing_bias_features(bearing: Array) -> Array:
    """Regressors ``(1, η, η²)`` of the bearing-bias model, shape ``(…, 3)``."""
    return np.stack([np.ones_like(bearing), bearing, bearing**2], axis=-1)


@dataclass(frozen=True)
class CameraFit:
    """Bearing offsets (rad, per robot in ``ds.robot_ids`` order) and σ, range-bias
    coefficients and σ, each σ raw (MAD) and inflated for the residual correlation
    (``sigma = sigma_raw·√inflation``), the range interval the inflation assumes, the measured
    lag correlations and how many residuals entered.

    ``bearing_bias_coeffs``: per robot, :data:`BEARING_BIAS_TERMS` coefficients ``c_i`` of
    ``b_i(η) = c_i·(1, η, η²)`` (robot-major, flat), with ``bearing_bias_limits`` the ``(lo, hi)``
    bearings each was fitted over (flat); empty: the offsets are the whole bias
    (:meth:`bearing_bias`)."""

    calibration_window: CalibrationWindow
    bearing_offset: tuple[float, ...]
    sigma_bearing_raw: float
    bearing_inflation: float
    sigma_bearing: float
    range_bias_coeffs: tuple[float, ...]
    sigma_range_raw: float
    range_inflation: float
    sigma_range: float
    range_interval_s: float
    correlation: dict[str, dict[str, float]]
    n_residuals: int
    bearing_bias_coeffs: tuple[float, ...] = ()
    bearing_bias_limits: tuple[float, ...] = ()

    def to_dict(self) -> dict[str, object]:
        """JSON-ready record (the window as ``calibration_window``)."""
        return {**asdict(self), "calibration_window": self.calibration_window.to_dict()}

    def bearing_bias(self, observer: NDArray[np.int64], bearing: Array) -> Array:
        """The fitted bias of each measured ``bearing`` of robot ``observer`` (indices in
        ``ds.robot_ids`` order): ``b_i(clip(η, lo_i, hi_i))``, or the offset without a bias."""
        if not self.bearing_bias_coeffs:
            return np.asarray(self.bearing_offset)[observer]
        return evaluate_bearing_bias(
            np.asarray(self.bearing_bias_coeffs).reshape(-1, BEARING_BIAS_TERMS),
            np.asarray(self.bearing_bias_limits).reshape(-1, 2),
            observer,
            bearing,
        )

    def range_bias(self, bearing: Array, rng: Array) -> Array:
        """The fitted range bias ``b(η, ρ) = c·(1, η, η², ρ, ρη²)`` at the measured bearings
        and ranges (:func:`~relloc.models.planar_measurement.range_bias_features`)."""
        c = np.asarray(self.range_bias_coeffs, dtype=float)
        return np.asarray(range_bias_features(bearing, rng)[..., : c.size] @ c, dtype=np.float64)


def corrected_readings(m: Measurements, fit: CameraFit, *, ranges: bool = False) -> Measurements:
    """``m``'s ``range_bearing`` rows with the bearing bias ``b_i(η̃)`` of each row's observer
    removed from the bearing and, with ``ranges``, the range bias ``b(η̃, ρ̃)`` from the range,
    both at the measured ``(ρ̃, η̃)`` (the fits' regressors); other rows unchanged."""
    rows = m.kind == kind_code("range_bearing")
    value = np.array(m.value)
    rho, eta = value[rows, 0], value[rows, 1]
    if ranges:
        value[rows, 0] = rho - fit.range_bias(eta, rho)
    value[rows, 1] = eta - fit.bearing_bias(m.observer[rows], eta)
    return replace(m, value=value)


def evaluate_bearing_bias(
    coeffs: Array, limits: Array, observer: NDArray[np.int64], bearing: Array
) -> Array:
    """``b_i(clip(η, lo_i, hi_i))`` per row, from per-robot ``coeffs (n, 3)`` and
    ``limits (n, 2)``."""
    lim = limits[observer]
    eta = np.clip(bearing, lim[:, 0], lim[:, 1])
    return np.einsum("mk,mk->m", bearing_bias_features(eta), coeffs[observer])


def _bearing_bias(
    res: CameraResiduals, good: NDArray[np.bool_], offsets: Array
) -> tuple[Array, Array]:
    """Per robot, the coefficients ``(n, 3)`` of ``b(η)`` by least squares on its inlier rows
    and the bearing range ``(n, 2)`` they span; with too few rows the offset alone, over all
    bearings."""
    coeffs = np.zeros((offsets.size, BEARING_BIAS_TERMS))
    limits = np.tile([-np.pi, np.pi], (offsets.size, 1))
    for i, offset in enumerate(offsets):
        sel = good & (res.observer == i)
        if sel.sum() <= BEARING_BIAS_MIN_ROWS:
            coeffs[i, 0] = offset
            continue
        eta = res.bearing[sel]
        coeffs[i], *_ = np.linalg.lstsq(
            bearing_bias_features(eta), res.bearing_error[sel], rcond=None
        )
        limits[i] = eta.min(), eta.max()
    return coeffs, limits


def _bearing_offsets(res: CameraResiduals, good: NDArray[np.bool_], n_robots: int) -> Array:
    """Median inlier bearing residual per observer (0 with too few rows)."""
    offsets = []
    for i in range(n_robots):
        sel = good & (res.observer == i)
        offsets.append(
            float(np.median(res.bearing_error[sel])) if sel.sum() > MIN_OFFSET_ROWS else 0.0
        )
    return np.asarray(offsets)


def fit_camera(
    ds: MrclamDataset, window: CalibrationWindow, *, range_interval_s: float
) -> CameraFit:
    """Fit the camera's bearing and range error models on ``window`` (module docstring);
    DataError naming the window when it holds too few detections or inliers, or the residuals
    have no spread."""
    if not (np.isfinite(range_interval_s) and range_interval_s >= 0):
        raise ConfigError(f"fit_camera: range_interval_s must be ≥ 0, got {range_interval_s}")
    res = camera_residuals(ds, window)
    if res.t.size < MIN_RESIDUALS:
        raise window.too_little(f"fewer than {MIN_RESIDUALS} detections with ground truth")
    good_b = np.abs(res.bearing_error) < BEARING_INLIER_RAD
    good_r = np.abs(res.range_error) < RANGE_INLIER_M
    for name, good, limit in (
        ("bearing", good_b, f"{BEARING_INLIER_RAD:g} rad"),
        ("range", good_r, f"{RANGE_INLIER_M:g} m"),
    ):
        if good.sum() < MIN_RESIDUALS:
            raise window.too_little(
                f"{good.sum()} of {res.t.size} {name} residuals within {limit} of the truth, "
                f"fewer than the {MIN_RESIDUALS} inliers a {name} fit needs"
            )
    offsets = _bearing_offsets(res, good_b, len(ds.robot_ids))
    coeffs_b, limits_b = _bearing_bias(res, good_b, offsets)
    eb = res.bearing_error - evaluate_bearing_bias(coeffs_b, limits_b, res.observer, res.bearing)
    sigma_b = mad_sigma(eb[good_b])
    X = range_bias_features(res.bearing, res.range)
    coeffs, *_ = np.linalg.lstsq(X[good_r], res.range_error[good_r], rcond=None)
    er = res.range_error - X @ coeffs
    sigma_r = mad_sigma(er[good_r])
    for name, sigma in (("bearing", sigma_b), ("range", sigma_r)):
        if not sigma > 0:
            raise window.too_little(
                f"{name} residuals without spread (σ {sigma:g}): a σ of 0 would take every "
                "reading as exact"
            )
    rho_r = {lag: lag_correlation(res, er, good_r, lag) for lag in CORRELATION_LAGS_S}
    rho_b = {lag: lag_correlation(res, eb, good_b, lag) for lag in CORRELATION_LAGS_S}
    spacing = pair_spacing_s(res)
    horizon = max(CORRELATION_LAGS_S)
    f_b = autocorrelation_inflation(rho_b, spacing, horizon)
    f_r = autocorrelation_inflation(rho_r, max(spacing, range_interval_s), horizon)
    return CameraFit(
        calibration_window=window,
        bearing_offset=tuple(float(o) for o in offsets),
        sigma_bearing_raw=sigma_b,
        bearing_inflation=f_b,
        sigma_bearing=float(sigma_b * np.sqrt(f_b)),
        range_bias_coeffs=tuple(float(c) for c in coeffs),
        sigma_range_raw=sigma_r,
        range_inflation=f_r,
        sigma_range=float(sigma_r * np.sqrt(f_r)),
        range_interval_s=range_interval_s,
        correlation={
            "range": {f"{lag:g}s": v for lag, v in rho_r.items()},
            "bearing": {f"{lag:g}s": v for lag, v in rho_b.items()},
            "pair_spacing_s": {"median": spacing},
        },
        n_residuals=int(res.t.size),
        bearing_bias_coeffs=tuple(float(c) for c in coeffs_b.reshape(-1)),
        bearing_bias_limits=tuple(float(v) for v in limits_b.reshape(-1)),
    )


@dataclass(frozen=True)
class DetectionProbabilityFit:
    """``P_D`` (clipped to ``P_DETECT_LIMITS``) and the counts it came from."""

    calibration_window: CalibrationWindow
    p_detect: float
    frames: int
    pairs: int
    detected_pairs: int

    def to_dict(self) -> dict[str, object]:
        """JSON-ready record (the window as ``calibration_window``)."""
        return {**asdict(self), "calibration_window": self.calibration_window.to_dict()}


def fit_detection_probability(
    ds: MrclamDataset, window: CalibrationWindow
) -> DetectionProbabilityFit:
    """``P_D``: the share of (camera frame, other robot) pairs in ``window`` in which that
    robot is detected (a frame is a distinct measurement time stamp of an observer); DataError
    naming the window when it holds no such pair."""
    seen = pairs = frames = 0
    n_other = len(ds.robot_ids) - 1
    for s in ds.robot_ids:
        meas = ds.robot(s).measurements
        sel = window.contains(meas.t)
        n_frames = np.unique(meas.t[sel]).size
        frames += n_frames
        pairs += n_frames * n_other
        robots = sel & ds.is_robot(meas.subject) & (meas.subject != s)
        seen += np.unique(np.stack([meas.t[robots], meas.subject[robots]]), axis=1).shape[1]
    if not pairs:
        raise window.too_little(
            f"no (camera frame, other robot) pair to fit the detection probability on "
            f"({frames} frames, {n_other} other robots)"
        )
    return DetectionProbabilityFit(
        calibration_window=window,
        p_detect=float(np.clip(seen / pairs, *P_DETECT_LIMITS)),
        frames=frames,
        pairs=pairs,
        detected_pairs=seen,
    )


@dataclass(frozen=True)
class InViewDetectionFit:
    """``P_D`` of a teammate *inside* the field of view ``±half_width_rad`` (clipped to
    ``P_DETECT_LIMITS``), the (frame, robot) pairs it came from, and the detections of robots
    the ground truth puts outside it (a check that the field of view is right)."""

    calibration_window: CalibrationWindow
    half_width_rad: float
    p_detect: float
    pairs_in_view: int
    detected_in_view: int
    detected_outside: int

    def to_dict(self) -> dict[str, object]:
        """JSON-ready record (the window as ``calibration_window``)."""
        return {**asdict(self), "calibration_window": self.calibration_window.to_dict()}


def fit_detection_in_view(
    ds: MrclamDataset, window: CalibrationWindow, half_width_rad: float
) -> InViewDetectionFit:
    """``P_D`` inside the field of view: over the camera frames in ``window`` (distinct time
    stamps of an observer) and every other robot whose true bearing from the observer,
    ``wrap(atan2(Δy, Δx) − θ)`` on the ground truth, lies inside ``±half_width_rad``, the
    share detected (pairs with invalid ground truth are left out); DataError naming the window
    when it holds no such pair. :func:`fit_detection_probability` is the same share over all
    pairs; the camera's narrow view makes the two differ by the fraction of the time a
    teammate is in view."""
    if not (np.isfinite(half_width_rad) and 0.0 < half_width_rad <= np.pi):
        raise ConfigError(
            f"fit_detection_in_view: half_width_rad must lie in (0, π]: {half_width_rad}"
        )
    pairs = seen = outside = 0
    for s in ds.robot_ids:
        meas = ds.robot(s).measurements
        sel = window.contains(meas.t)
        frames = np.unique(meas.t[sel])
        q = ds.robot(s).groundtruth.at(frames)
        for o in ds.robot_ids:
            if o == s:
                continue
            p = ds.robot(o).groundtruth.at(frames)
            bearing = np.abs(wrap_angle(np.arctan2(p.y - q.y, p.x - q.x) - q.theta))
            valid = q.valid & p.valid
            detected = np.isin(frames, meas.t[sel & (meas.subject == o)])
            inside = valid & (bearing <= half_width_rad)
            pairs += int(inside.sum())
            seen += int((inside & detected).sum())
            outside += int((valid & ~inside & detected).sum())
    if not pairs:
        raise window.too_little(
            f"no camera frame with another robot in view (±{half_width_rad:g} rad) to fit the "
            "detection probability on"
        )
    return InViewDetectionFit(
        calibration_window=window,
        half_width_rad=float(half_width_rad),
        p_detect=float(np.clip(seen / pairs, *P_DETECT_LIMITS)),
        pairs_in_view=pairs,
        detected_in_view=seen,
        detected_outside=outside,
    )


@dataclass(frozen=True)
class FieldOfViewFit:
    """Half-width (rad) of the camera's field of view: the widest ``|bearing|`` in the window."""

    calibration_window: CalibrationWindow
    half_width_rad: float
    n_bearings: int

    def to_dict(self) -> dict[str, object]:
        """JSON-ready record (the window as ``calibration_window``)."""
        return {**asdict(self), "calibration_window": self.calibration_window.to_dict()}


def fit_field_of_view(ds: MrclamDataset, window: CalibrationWindow) -> FieldOfViewFit:
    """The widest ``|wrap(bearing)|`` of any detection in ``window`` (DataError when there is
    no bearing or the widest is 0)."""
    bearings = []
    for s in ds.robot_ids:
        m = ds.robot(s).measurements
        bearings.append(np.abs(wrap_angle(m.bearing[window.contains(m.t)])))
    widest = max((float(b.max()) for b in bearings if b.size), default=0.0)
    if not 0.0 < widest <= np.pi:
        raise window.too_little(f"no usable camera bearings (widest {widest})")
    return FieldOfViewFit(
        calibration_window=window,
        half_width_rad=widest,
        n_bearings=int(sum(b.size for b in bearings)),
    )


def landmark_wait_s(ds: MrclamDataset, window: CalibrationWindow) -> float:
    """Expected wait from a random instant in ``window`` to a robot's next landmark detection,
    ``Σg²/(2Σg)`` over the gaps ``g`` between its landmark detections (the window's ends
    included) pooled over robots: the horizon odometry must bridge (1 s without any gap)."""
    t_lo, t_hi = window.start_s, window.end_s
    num = den = 0.0
    lm = set(int(s) for s in ds.landmarks.subject)
    for rid in ds.robot_ids:
        m = ds.robot(rid).measurements
        t = np.unique(m.t[np.isin(m.subject, list(lm)) & window.contains(m.t)])
        g = np.diff(np.concatenate([[t_lo], t, [t_hi]]))
        num += float(np.sum(g**2))
        den += float(np.sum(g))
    return num / (2.0 * den) if den > 0 else 1.0
