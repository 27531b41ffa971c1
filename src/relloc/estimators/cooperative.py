"""Asynchronous cooperative-localization pipeline for a team of unicycles (seed 001).

A :class:`TeamRecording` holds each robot's odometry stream (commanded or measured ``v, ω`` at its
own time stamps), detections (bearing, optionally range, of another robot or of a known landmark,
each at its own time stamp) and optional GPS-like absolute pose fixes. :func:`run_team` replays it
through a joint filter (the EIF of :mod:`relloc.estimators.eif` or the EKF of
:mod:`relloc.estimators.joint_ekf`) and returns the estimate at requested output times with the
counts of what was used, rejected and ignored.

Odometry model (:class:`OdometryModel`)
---------------------------------------
Each command is held from its (latency-shifted) time stamp until the next one, at most
``max_hold_s``; after that the robot is assumed still, with the larger ``stale`` noise rates
(a robot whose odometry stops). Before the first command robots stand still. The input is
``u = (s_v v_cmd, s_ω ω_cmd)`` applied ``latency_s`` after it was commanded. The noise on the
true input is white with spectral densities (variance rates, SI units per second)

    q_v = q_v0 + k_v |v|,     q_ω = q_ω0 + k_ω |ω| + k_ωv |v|,

so the dead-reckoning variance grows with distance travelled and angle turned, independent of
the odometry rate. Over a step of length ``dt`` the covariance of the averaged input is
``diag(q_v, q_ω)/dt``.

Exact multi-step prediction
---------------------------
Between two measurement epochs each robot moves on its own inputs, so the joint transition is
block-diagonal. For robot ``i`` and steps ``k = 1 … K`` of the midpoint unicycle
(:mod:`relloc.models.unicycle`), ``F_k = I + a_k e₀e₂ᵀ + b_k e₁e₂ᵀ`` and the product of such
matrices only adds their ``a, b`` entries, so

    Φ_i = F_K ⋯ F_1 = I + (Σ a_k) e₀e₂ᵀ + (Σ b_k) e₁e₂ᵀ,
    Q_i = Σ_k Φ_{k+1:K} G_k Q_{u,k} G_kᵀ Φ_{k+1:K}ᵀ,

computed vectorised over the steps (suffix sums of ``a, b``). One joint prediction with these
blocks equals the K single-step predictions of seed 001 Eq. 5 exactly, which is what lets the
pipeline process every measurement at its own time stamp while paying the joint prediction only
once per measurement epoch.

Measurements
------------
Rows (:mod:`relloc.models.planar_measurement`) are built per epoch: bearing (always, if
``use_bearing``), range (if ``use_range``; corrected by a fitted bias
``b(η, ρ)`` that depends on bearing and range (:class:`SensorModel`) and optionally
thinned to one range per pair every ``range_min_interval_s``
because consecutive ranges have strongly correlated errors), and absolute pose rows. Each detection
or fix is gated as a whole with its normalised innovation squared against
``χ²_{dof}(p_gate)`` (:mod:`relloc.association.gating`) before the batch update.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Literal, Protocol

import numpy as np
from numpy.typing import NDArray

from relloc.association.gating import mahalanobis_batch
from relloc.core.gaussian import Gaussian
from relloc.core.kalman import chi2_threshold
from relloc.errors import ConfigError, DataError
from relloc.estimators.eif import ExtendedInformationFilter
from relloc.estimators.joint_ekf import JointEkf
from relloc.models.planar_measurement import (
    LinearisedRows,
    RowKind,
    ScalarRows,
    empty_rows,
    linearise_rows,
)
from relloc.models.unicycle import unicycle_jacobians, unicycle_step

Array = NDArray[np.float64]
IntArray = NDArray[np.int64]
BoolArray = NDArray[np.bool_]

_MIN_SEPARATION_M = 1e-3


# ----------------------------------------------------------------------------------------------
# Recording (the pipeline's input)
# ----------------------------------------------------------------------------------------------


def _vector(value: object, where: str, n: int | None = None) -> Array:
    arr = np.asarray(value, dtype=float).reshape(-1)
    if n is not None and arr.shape != (n,):
        raise DataError(f"{where}: expected {n} values, got {arr.shape[0]}")
    return arr


@dataclass(frozen=True)
class OdometryStream:
    """Odometry of one robot: strictly increasing ``t``, forward speed ``v`` and turn rate ``w``."""

    t: Array
    v: Array
    w: Array

    def __post_init__(self) -> None:
        t = _vector(self.t, "odometry.t")
        v = _vector(self.v, "odometry.v", t.size)
        w = _vector(self.w, "odometry.w", t.size)
        if not (np.isfinite(t).all() and np.isfinite(v).all() and np.isfinite(w).all()):
            raise DataError("odometry: non-finite time or velocity")
        if t.size > 1 and np.any(np.diff(t) <= 0):
            row = int(np.argmax(np.diff(t) <= 0)) + 1
            raise DataError(f"odometry.t: not strictly increasing at row {row}")
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "v", v)
        object.__setattr__(self, "w", w)


@dataclass(frozen=True)
class Detections:
    """Camera detections of the team, sorted by time.

    ``observer``: robot index; ``target_robot``: observed robot index or −1; ``landmark``:
    observed landmark index or −1 (exactly one of the two is ≥ 0); ``range``: NaN when the sensor
    gives no range; ``bearing`` in the observer's frame (rad).
    """

    t: Array
    observer: IntArray
    target_robot: IntArray
    landmark: IntArray
    range: Array
    bearing: Array

    def __post_init__(self) -> None:
        t = _vector(self.t, "detections.t")
        n = t.size
        for name in ("observer", "target_robot", "landmark"):
            arr = np.asarray(getattr(self, name)).reshape(-1)
            if arr.shape != (n,) or (n and not np.issubdtype(arr.dtype, np.integer)):
                raise DataError(f"detections.{name}: expected {n} integer indices")
            object.__setattr__(self, name, arr.astype(np.int64))
        rng = _vector(self.range, "detections.range", n)
        brg = _vector(self.bearing, "detections.bearing", n)
        if not (np.isfinite(t).all() and np.isfinite(brg).all()):
            raise DataError("detections: non-finite time or bearing")
        if n > 1 and np.any(np.diff(t) < 0):
            raise DataError(f"detections.t: not sorted at row {int(np.argmax(np.diff(t) < 0)) + 1}")
        if np.any((self.target_robot >= 0) == (self.landmark >= 0)):
            raise DataError("detections: each row must observe exactly one robot or landmark")
        if np.any(self.target_robot == self.observer):
            raise DataError("detections: a robot cannot detect itself")
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "range", rng)
        object.__setattr__(self, "bearing", brg)

    def __len__(self) -> int:
        return int(self.t.size)

    def select(self, keep: BoolArray) -> Detections:
        """The rows where ``keep`` is true."""
        return Detections(
            self.t[keep],
            self.observer[keep],
            self.target_robot[keep],
            self.landmark[keep],
            self.range[keep],
            self.bearing[keep],
        )


@dataclass(frozen=True)
class PoseFixes:
    """GPS-like absolute pose fixes ``pose (g, 3)`` of robot ``robot (g,)`` with noise ``sigma``."""

    t: Array
    robot: IntArray
    pose: Array
    sigma: Array

    def __post_init__(self) -> None:
        t = _vector(self.t, "fixes.t")
        pose = np.asarray(self.pose, dtype=float).reshape(t.size, 3)
        sigma = _vector(self.sigma, "fixes.sigma", 3)
        robot = np.asarray(self.robot).reshape(-1).astype(np.int64)
        if robot.shape != t.shape or not np.isfinite(pose).all() or np.any(sigma <= 0):
            raise DataError("fixes: bad robot indices, non-finite pose or σ ≤ 0")
        if t.size > 1 and np.any(np.diff(t) < 0):
            raise DataError("fixes.t: not sorted")
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "pose", pose)
        object.__setattr__(self, "sigma", sigma)
        object.__setattr__(self, "robot", robot)

    @staticmethod
    def none() -> PoseFixes:
        return PoseFixes(np.zeros(0), np.zeros(0, dtype=np.int64), np.zeros((0, 3)), np.ones(3))


@dataclass(frozen=True)
class TeamRecording:
    """Everything the pipeline consumes. Robots are indexed ``0 … n−1``.

    (The shared :class:`relloc.sim.log.Log` models 4-DOF inter-robot range/azimuth/elevation
    without landmarks or absolute fixes; this planar record adds both.)
    """

    odometry: tuple[OdometryStream, ...]
    detections: Detections
    landmarks_xy: Array
    fixes: PoseFixes = field(default_factory=PoseFixes.none)

    def __post_init__(self) -> None:
        n = len(self.odometry)
        if n == 0:
            raise DataError("TeamRecording: no robots")
        lm = np.asarray(self.landmarks_xy, dtype=float).reshape(-1, 2)
        object.__setattr__(self, "landmarks_xy", lm)
        d = self.detections
        if len(d) and (d.observer.min() < 0 or d.observer.max() >= n or d.target_robot.max() >= n):
            raise DataError(f"detections: robot index outside 0…{n - 1}")
        if len(d) and d.landmark.max() >= lm.shape[0]:
            raise DataError(f"detections: landmark index outside 0…{lm.shape[0] - 1}")
        if self.fixes.robot.size and (self.fixes.robot.min() < 0 or self.fixes.robot.max() >= n):
            raise DataError(f"fixes: robot index outside 0…{n - 1}")

    @property
    def n_robots(self) -> int:
        return len(self.odometry)


# ----------------------------------------------------------------------------------------------
# Settings
# ----------------------------------------------------------------------------------------------


def _check_nonneg(obj: object, names: Sequence[str]) -> None:
    for name in names:
        value = getattr(obj, name)
        if not (np.isfinite(value) and value >= 0):
            raise ConfigError(f"{type(obj).__name__}.{name} must be a finite number ≥ 0")


@dataclass(frozen=True, kw_only=True)
class OdometryModel:
    """How odometry turns into inputs and process noise (see the module docstring)."""

    q_v0: float
    q_w0: float
    k_v: float = 0.0
    k_w: float = 0.0
    k_wv: float = 0.0
    latency_s: float = 0.0
    scale_v: float = 1.0
    scale_w: float = 1.0
    max_hold_s: float = 1.0
    stale_q_v: float = 0.01
    stale_q_w: float = 0.01
    max_step_s: float = 0.1

    def __post_init__(self) -> None:
        _check_nonneg(
            self,
            (
                "q_v0",
                "q_w0",
                "k_v",
                "k_w",
                "k_wv",
                "latency_s",
                "max_hold_s",
                "stale_q_v",
                "stale_q_w",
            ),
        )
        for name in ("scale_v", "scale_w", "max_step_s"):
            if not (np.isfinite(getattr(self, name)) and getattr(self, name) > 0):
                raise ConfigError(f"OdometryModel.{name} must be a finite number > 0")
        if self.q_v0 + self.k_v <= 0 or self.q_w0 + self.k_w + self.k_wv <= 0:
            raise ConfigError("OdometryModel: q_v0/k_v and q_w0/k_w must not all be zero")

    @staticmethod
    def from_discrete(sigma_v: float, sigma_w: float, dt: float) -> OdometryModel:
        """Per-step white input noise ``σ`` at step ``dt`` (seed 001 ``Q_i``): ``q = σ² dt``."""
        if dt <= 0:
            raise ConfigError("OdometryModel.from_discrete: dt must be > 0")
        return OdometryModel(q_v0=sigma_v**2 * dt, q_w0=sigma_w**2 * dt, max_step_s=dt)


RANGE_BIAS_FEATURES = ("1", "η", "η²", "ρ", "ρη²")


def range_bias_features(bearing: Array, rng: Array) -> Array:
    """Regressors ``(1, η, η², ρ, ρ η²)`` of the range-bias model, shape ``(…, 5)``."""
    return np.stack([np.ones_like(bearing), bearing, bearing**2, rng, rng * bearing**2], axis=-1)


@dataclass(frozen=True, kw_only=True)
class SensorModel:
    """Noise and corrections of the camera rows.

    ``range_bias_coeffs``: ``c`` of the range bias ``b(η, ρ) = c · (1, η, η², ρ, ρη²)`` (fewer
    coefficients use a prefix of the features) subtracted from each measured range;
    ``sigma_range = √(σ_r0² + (k_r ρ)²)``; ``range_min_interval_s``: at most one range per
    (observer, target) pair within this interval (0 keeps every range).
    """

    sigma_bearing: float
    sigma_range0: float = 0.1
    sigma_range_rel: float = 0.0
    range_bias_coeffs: tuple[float, ...] = ()
    bearing_bias: float = 0.0
    range_min_interval_s: float = 0.0

    def __post_init__(self) -> None:
        _check_nonneg(self, ("sigma_range_rel", "range_min_interval_s"))
        for name in ("sigma_bearing", "sigma_range0"):
            if not (np.isfinite(getattr(self, name)) and getattr(self, name) > 0):
                raise ConfigError(f"SensorModel.{name} must be a finite number > 0")
        if not all(np.isfinite(c) for c in self.range_bias_coeffs) or not np.isfinite(
            self.bearing_bias
        ):
            raise ConfigError("SensorModel.range_bias_coeffs/bearing_bias must be finite")
        if len(self.range_bias_coeffs) > len(RANGE_BIAS_FEATURES):
            raise ConfigError(
                f"SensorModel.range_bias_coeffs: at most {len(RANGE_BIAS_FEATURES)} coefficients"
            )

    def range_bias(self, bearing: Array, rng: Array) -> Array:
        """``b(η, ρ)`` at the measured bearings and ranges."""
        c = np.asarray(self.range_bias_coeffs, dtype=float)
        if c.size == 0:
            return np.zeros_like(rng)
        return range_bias_features(bearing, rng)[..., : c.size] @ c


@dataclass(frozen=True, kw_only=True)
class PipelineSettings:
    """What the pipeline uses and how.

    ``anchors``: landmark indices whose detections are used (others are ignored and counted);
    ``use_robot_detections``: robot→robot rows; ``p_gate``: χ² gate probability (``None``: no
    gating); ``filter``: ``"eif"`` or ``"ekf"``.
    """

    odometry: OdometryModel
    sensor: SensorModel
    use_bearing: bool = True
    use_range: bool = False
    use_robot_detections: bool = True
    anchors: tuple[int, ...] = ()
    use_fixes: bool = False
    p_gate: float | None = 0.999
    filter: Literal["eif", "ekf"] = "eif"

    def __post_init__(self) -> None:
        if self.filter not in ("eif", "ekf"):
            raise ConfigError(f"PipelineSettings.filter must be 'eif' or 'ekf', got {self.filter}")
        if self.p_gate is not None and not 0.0 < self.p_gate < 1.0:
            raise ConfigError(f"PipelineSettings.p_gate must lie in (0, 1), got {self.p_gate}")
        if any(a < 0 for a in self.anchors):
            raise ConfigError("PipelineSettings.anchors must be landmark indices ≥ 0")

    @property
    def uses_measurements(self) -> bool:
        return self.use_fixes or (self.use_bearing or self.use_range)


# ----------------------------------------------------------------------------------------------
# Odometry → piecewise-constant input timeline → exact block prediction
# ----------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class InputTimeline:
    """Piecewise-constant inputs of one robot: segment ``k`` holds from ``start[k]`` to
    ``start[k+1]`` (the first starts at −∞, the last ends at +∞)."""

    start: Array
    v: Array
    w: Array
    q_v: Array
    q_w: Array
    stale: BoolArray

    @staticmethod
    def build(odo: OdometryStream, model: OdometryModel) -> InputTimeline:
        t = odo.t + model.latency_s
        v = model.scale_v * odo.v
        w = model.scale_w * odo.w
        k = t.size
        gaps = np.append(np.diff(t), np.inf)
        expire = gaps > model.max_hold_s
        n_seg = 1 + k + int(expire.sum())
        start = np.empty(n_seg)
        sv, sw = np.zeros(n_seg), np.zeros(n_seg)
        qv, qw = np.full(n_seg, model.q_v0), np.full(n_seg, model.q_w0)
        stale = np.zeros(n_seg, dtype=bool)
        start[0] = -np.inf
        # position of command j: 1 + j + (number of expiries before j)
        pos = 1 + np.arange(k) + np.concatenate(([0], np.cumsum(expire)[:-1])).astype(int)
        start[pos] = t
        sv[pos], sw[pos] = v, w
        qv[pos] = model.q_v0 + model.k_v * np.abs(v)
        qw[pos] = model.q_w0 + model.k_w * np.abs(w) + model.k_wv * np.abs(v)
        epos = pos[expire] + 1
        start[epos] = t[expire] + model.max_hold_s
        qv[epos], qw[epos] = model.stale_q_v, model.stale_q_w
        stale[epos] = True
        return InputTimeline(start, sv, sw, qv, qw, stale)

    def stale_seconds(self, t0: float, t1: float) -> float:
        """Time within ``[t0, t1]`` spent without a fresh command (after ``max_hold_s``)."""
        end = np.append(self.start[1:], np.inf)
        s, e = np.maximum(self.start, t0), np.minimum(end, t1)
        return float(np.sum(np.clip(e - s, 0, None)[self.stale]))


@dataclass(frozen=True)
class TeamTimeline:
    """All robots' input timelines merged on the union of their segment starts: ``(S,)`` starts
    and ``(S, n)`` inputs and noise rates, so a whole team advances in one vectorised step."""

    start: Array
    v: Array
    w: Array
    q_v: Array
    q_w: Array

    @staticmethod
    def merge(timelines: Sequence[InputTimeline]) -> TeamTimeline:
        start = np.unique(np.concatenate([tl.start for tl in timelines]))
        cols: list[list[Array]] = [[], [], [], []]
        for tl in timelines:
            k = np.searchsorted(tl.start, start, side="right") - 1
            for c, arr in zip(cols, (tl.v, tl.w, tl.q_v, tl.q_w), strict=True):
                c.append(arr[k])
        v, w, qv, qw = (np.stack(c, axis=1) for c in cols)
        return TeamTimeline(start, v, w, qv, qw)


@dataclass
class TeamPending:
    """Prediction not yet applied to the joint filter: poses ``(n,3)``, ``Φ`` and ``Q (n,3,3)``."""

    pose: Array
    F: Array
    Q: Array

    @staticmethod
    def at(pose: Array) -> TeamPending:
        n = pose.shape[0]
        return TeamPending(
            np.array(pose, dtype=float), np.tile(np.eye(3), (n, 1, 1)), np.zeros((n, 3, 3))
        )

    def reset(self, pose: Array) -> None:
        self.pose = np.array(pose, dtype=float)
        self.F[:] = np.eye(3)
        self.Q[:] = 0.0


def advance(
    pending: TeamPending, timeline: TeamTimeline, t0: float, t1: float, max_step: float
) -> None:
    """Move every robot of ``pending`` from ``t0`` to ``t1`` (exact block accumulation, module
    docstring), vectorised over steps and robots."""
    if t1 <= t0:
        return
    i0 = int(np.searchsorted(timeline.start, t0, side="right")) - 1
    i1 = int(np.searchsorted(timeline.start, t1, side="left"))
    end = np.append(timeline.start[i0 + 1 : i1], t1)
    begin = np.maximum(timeline.start[i0:i1], t0)
    dur = end - begin
    ok = np.flatnonzero(dur > 0) + i0
    dur = dur[dur > 0]
    n_sub = np.maximum(np.ceil(dur / max_step - 1e-9).astype(int), 1)
    seg = np.repeat(ok, n_sub)
    dt = np.repeat(dur / n_sub, n_sub)[:, None]
    v, w = timeline.v[seg], timeline.w[seg]
    qv, qw = timeline.q_v[seg], timeline.q_w[seg]
    # Midpoint unicycle steps written with increments (v dt, ω dt) over a unit step, so
    # G' = ∂x⁺/∂(v dt, ω dt) and the covariance of an increment's noise is diag(q_v dt, q_ω dt).
    incr = np.stack([v * dt, w * dt], axis=-1)  # (K, n, 2)
    theta = np.cumsum(incr[..., 1], axis=0)
    prev = np.zeros((*incr.shape[:2], 3))
    prev[..., 2] = pending.pose[:, 2] + np.concatenate(
        [np.zeros((1, theta.shape[1])), theta[:-1]], axis=0
    )
    step = unicycle_step(prev, incr, 1.0) - prev
    F, G = unicycle_jacobians(prev, incr, 1.0)
    a, b = F[..., 0, 2], F[..., 1, 2]
    # Φ_{k+1:K}: suffix sums of the (0,2), (1,2) entries.
    A = a.sum(axis=0) - np.cumsum(a, axis=0)
    B = b.sum(axis=0) - np.cumsum(b, axis=0)
    PhiG = G.copy()
    PhiG[..., 0, :] += A[..., None] * G[..., 2, :]
    PhiG[..., 1, :] += B[..., None] * G[..., 2, :]
    q = np.stack([qv * dt, qw * dt], axis=-1)
    Qseg = np.einsum("knai,kni,knbi->nab", PhiG, q, PhiG)
    F_seg = np.tile(np.eye(3), (pending.pose.shape[0], 1, 1))
    F_seg[:, 0, 2], F_seg[:, 1, 2] = a.sum(axis=0), b.sum(axis=0)
    pending.pose = pending.pose + step.sum(axis=0)
    pending.F = F_seg @ pending.F
    pending.Q = F_seg @ pending.Q @ np.swapaxes(F_seg, -1, -2) + Qseg


# ----------------------------------------------------------------------------------------------
# Rows and gating
# ----------------------------------------------------------------------------------------------


@dataclass
class Counts:
    """What happened to every detection and fix (reported in summaries)."""

    detections_used: int = 0
    fixes_used: int = 0
    rejected_gate: int = 0
    rejected_degenerate: int = 0
    ignored_not_anchor: int = 0
    ignored_robot_detection: int = 0
    ranges_thinned: int = 0
    epochs: int = 0
    stale_odometry_s: list[float] = field(default_factory=list)

    @property
    def used(self) -> int:
        return self.detections_used + self.fixes_used

    @property
    def rejected(self) -> int:
        return self.rejected_gate + self.rejected_degenerate

    def to_dict(self) -> dict[str, object]:
        return {
            "used": self.used,
            "rejected": self.rejected,
            "detections_used": self.detections_used,
            "fixes_used": self.fixes_used,
            "rejected_gate": self.rejected_gate,
            "rejected_degenerate": self.rejected_degenerate,
            "ignored_not_anchor": self.ignored_not_anchor,
            "ignored_robot_detection": self.ignored_robot_detection,
            "ranges_thinned": self.ranges_thinned,
            "epochs": self.epochs,
            "stale_odometry_s": list(self.stale_odometry_s),
        }


def detection_rows(
    det: Detections,
    rows_of_epoch: slice,
    landmarks_xy: Array,
    settings: PipelineSettings,
    group_offset: int,
    last_range: dict[tuple[int, int], float],
    counts: Counts,
) -> ScalarRows:
    """Scalar rows (bearing, range) of the detections ``det[rows_of_epoch]`` of one epoch, after
    the settings' choices of anchors, robot detections and range thinning (all counted)."""
    idx = np.arange(rows_of_epoch.start, rows_of_epoch.stop)
    landmark = det.landmark[idx]
    is_lm = landmark >= 0
    not_anchor = is_lm & ~np.isin(landmark, np.asarray(settings.anchors, dtype=np.int64))
    counts.ignored_not_anchor += int(not_anchor.sum())
    keep = ~not_anchor
    if not settings.use_robot_detections:
        counts.ignored_robot_detection += int((~is_lm).sum())
        keep &= is_lm
    idx, landmark, is_lm = idx[keep], landmark[keep], is_lm[keep]
    m = idx.size
    if m == 0:
        return empty_rows()
    observer, target = det.observer[idx], det.target_robot[idx]
    bearing_z = det.bearing[idx]
    groups = group_offset + np.arange(m)
    lm_xy = np.zeros((m, 2))
    lm_xy[is_lm] = landmarks_xy[landmark[is_lm]]
    parts: list[ScalarRows] = []
    if settings.use_bearing:
        parts.append(
            ScalarRows(
                kind=np.full(m, RowKind.BEARING, dtype=np.int64),
                observer=observer,
                target=target,
                landmark_xy=lm_xy,
                z=bearing_z - settings.sensor.bearing_bias,
                sigma=np.full(m, settings.sensor.sigma_bearing),
                group=groups,
            )
        )
    if settings.use_range:
        rng = det.range[idx]
        use = np.isfinite(rng)
        interval = settings.sensor.range_min_interval_s
        if interval > 0:
            t = det.t[idx]
            for r in np.flatnonzero(use):
                key = (int(observer[r]), int(target[r] if landmark[r] < 0 else -1 - landmark[r]))
                if t[r] - last_range.get(key, -np.inf) < interval:
                    use[r] = False
                    counts.ranges_thinned += 1
                else:
                    last_range[key] = float(t[r])
        sensor = settings.sensor
        r_use = rng[use]
        parts.append(
            ScalarRows(
                kind=np.full(int(use.sum()), RowKind.RANGE, dtype=np.int64),
                observer=observer[use],
                target=target[use],
                landmark_xy=lm_xy[use],
                z=r_use - sensor.range_bias(bearing_z[use], r_use),
                sigma=np.sqrt(sensor.sigma_range0**2 + (sensor.sigma_range_rel * r_use) ** 2),
                group=groups[use],
            )
        )
    return ScalarRows.concatenate(parts)


def fix_rows(fixes: PoseFixes, group_offset: int) -> ScalarRows:
    """Three rows (x, y, ψ) per absolute pose fix, one gating group per fix."""
    g = fixes.t.size
    kinds = np.array([RowKind.POSE_X, RowKind.POSE_Y, RowKind.POSE_HEADING], dtype=np.int64)
    return ScalarRows(
        kind=np.tile(kinds, g),
        observer=np.repeat(fixes.robot, 3),
        target=np.full(3 * g, -1, dtype=np.int64),
        landmark_xy=np.zeros((3 * g, 2)),
        z=fixes.pose.reshape(-1),
        sigma=np.tile(fixes.sigma, g),
        group=np.repeat(group_offset + np.arange(g), 3),
    )


def group_nis(lin: LinearisedRows, P: Array) -> tuple[IntArray, Array, IntArray]:
    """NIS of every gating group: ``(group ids, νᵀ S⁻¹ ν, dof)`` with ``S = H P Hᵀ + R``.

    Only the entries of ``S`` within a group are formed, from the 3 × 3 blocks of ``P`` that the
    rows' two Jacobian blocks touch.
    """
    n = P.shape[0] // 3
    order = np.argsort(lin.group, kind="stable")
    ids, start, dof = np.unique(lin.group[order], return_index=True, return_counts=True)
    width = int(dof.max())
    Pb = P.reshape(n, 3, n, 3).transpose(0, 2, 1, 3)
    idx = np.maximum(lin.block_index, 0)
    S = np.broadcast_to(np.eye(width), (ids.size, width, width)).copy()
    nu = np.zeros((ids.size, width))
    for a in range(width):
        ok_a = a < dof
        nu[ok_a, a] = lin.residual[order[start[ok_a] + a]]
        for b in range(width):
            ok = ok_a & (b < dof)
            ra, rb = order[start[ok] + a], order[start[ok] + b]
            blk = Pb[idx[ra][:, :, None], idx[rb][:, None, :]]  # (k, 2, 2, 3, 3)
            val = np.einsum("kpa,kpqab,kqb->k", lin.blocks[ra], blk, lin.blocks[rb])
            if a == b:
                val += lin.sigma[ra] ** 2
            S[ok, a, b] = val
    return ids, mahalanobis_batch(nu, S), dof


def gate(lin: LinearisedRows, P: Array, p_gate: float) -> tuple[BoolArray, IntArray]:
    """Rows inside the χ² gate, and the ids of the groups rejected."""
    ids, nis, dof = group_nis(lin, P)
    thresholds = np.array([chi2_threshold(int(d), p_gate) for d in dof])
    bad = ~(nis <= thresholds)
    rejected = ids[bad]
    return ~np.isin(lin.group, rejected), rejected


def _select_lin(lin: LinearisedRows, keep: BoolArray) -> LinearisedRows:
    return LinearisedRows(
        residual=lin.residual[keep],
        blocks=lin.blocks[keep],
        block_index=lin.block_index[keep],
        sigma=lin.sigma[keep],
        group=lin.group[keep],
    )


# ----------------------------------------------------------------------------------------------
# The replay
# ----------------------------------------------------------------------------------------------


class TeamFilter(Protocol):
    """What :func:`run_team` needs from a joint filter."""

    def mean(self) -> Array: ...

    def covariance(self) -> Array: ...

    def predict(self, mean_pred: Array, F_blocks: Array, Q_blocks: Array) -> None: ...

    def update(self, rows: LinearisedRows) -> None: ...


@dataclass(frozen=True)
class TeamRun:
    """Estimates at the output times: ``mean (T, n, 3)``, per-robot ``cov (T, n, 3, 3)``."""

    t: Array
    mean: Array
    cov: Array
    counts: Counts


def make_filter(prior: Gaussian, kind: str) -> TeamFilter:
    """The joint filter named by ``kind`` ("eif" or "ekf") started at ``prior``."""
    if kind == "eif":
        return ExtendedInformationFilter.from_prior(prior)
    return JointEkf(prior)


def _degenerate(rows: ScalarRows, X: Array) -> BoolArray:
    """Rows whose observer and (estimated) target coincide — bearing undefined."""
    rel = (rows.kind == RowKind.BEARING) | (rows.kind == RowKind.RANGE)
    tgt = np.where((rows.target >= 0)[:, None], X[np.maximum(rows.target, 0), :2], rows.landmark_xy)
    sep = np.linalg.norm(tgt - X[rows.observer, :2], axis=1)
    return rel & (sep < _MIN_SEPARATION_M)


def run_team(
    recording: TeamRecording,
    prior: Gaussian,
    t_start: float,
    output_times: Array,
    settings: PipelineSettings,
) -> TeamRun:
    """Replay ``recording`` from ``t_start`` (where ``prior`` holds) and report at ``output_times``.

    Every detection and fix is processed at its own time stamp; all those sharing a time stamp
    form one epoch (one joint prediction, one gated batch update).
    """
    n = recording.n_robots
    if prior.dim != 3 * n:
        raise ConfigError(f"prior has dimension {prior.dim}, the team needs {3 * n}")
    out_t = np.asarray(output_times, dtype=float).reshape(-1)
    if out_t.size and (np.any(np.diff(out_t) < 0) or out_t[0] < t_start):
        raise ConfigError("output_times must be sorted and ≥ t_start")
    t_end = float(out_t[-1]) if out_t.size else t_start
    det = recording.detections
    fixes = recording.fixes
    in_span = (det.t > t_start) & (det.t <= t_end)
    det = det.select(in_span)
    if not settings.uses_measurements:
        det = det.select(np.zeros(len(det), dtype=bool))
    fix_ok = (fixes.t > t_start) & (fixes.t <= t_end) & settings.use_fixes
    fixes = PoseFixes(fixes.t[fix_ok], fixes.robot[fix_ok], fixes.pose[fix_ok], fixes.sigma)
    epochs = np.unique(np.concatenate([det.t, fixes.t, out_t]))
    det_lo = np.searchsorted(det.t, epochs, side="left")
    det_hi = np.searchsorted(det.t, epochs, side="right")
    fix_lo = np.searchsorted(fixes.t, epochs, side="left")
    fix_hi = np.searchsorted(fixes.t, epochs, side="right")
    is_out = np.isin(epochs, out_t)

    timelines = [InputTimeline.build(o, settings.odometry) for o in recording.odometry]
    team_timeline = TeamTimeline.merge(timelines)
    filt = make_filter(prior, settings.filter)
    pending = TeamPending.at(filt.mean())
    counts = Counts()
    last_range: dict[tuple[int, int], float] = {}
    means = np.zeros((out_t.size, n, 3))
    covs = np.zeros((out_t.size, n, 3, 3))
    out_index = 0
    t_prev = t_start
    group_offset = 0
    diag = np.arange(n)
    for e, t in enumerate(epochs):
        advance(pending, team_timeline, t_prev, float(t), settings.odometry.max_step_s)
        t_prev = float(t)
        parts = []
        if det_hi[e] > det_lo[e]:
            sl = slice(int(det_lo[e]), int(det_hi[e]))
            parts.append(
                detection_rows(
                    det, sl, recording.landmarks_xy, settings, group_offset, last_range, counts
                )
            )
            group_offset += sl.stop - sl.start
        if fix_hi[e] > fix_lo[e]:
            sl = slice(int(fix_lo[e]), int(fix_hi[e]))
            epoch_fix = PoseFixes(fixes.t[sl], fixes.robot[sl], fixes.pose[sl], fixes.sigma)
            parts.append(fix_rows(epoch_fix, group_offset))
            group_offset += epoch_fix.t.size
        rows = ScalarRows.concatenate(parts) if len(parts) > 1 else (parts or [empty_rows()])[0]
        if rows.size:
            counts.epochs += 1
            filt.predict(pending.pose, pending.F, pending.Q)
            X = filt.mean()
            degenerate = _degenerate(rows, X)
            if degenerate.any():
                counts.rejected_degenerate += int(np.unique(rows.group[degenerate]).size)
                rows = rows.select(~np.isin(rows.group, rows.group[degenerate]))
            lin = linearise_rows(X, rows)
            if settings.p_gate is not None and rows.size:
                keep, rejected = gate(lin, filt.covariance(), settings.p_gate)
                counts.rejected_gate += int(rejected.size)
                lin = _select_lin(lin, keep)
                rows = rows.select(keep)
            n_fixes = int((rows.kind == RowKind.POSE_X).sum())
            counts.fixes_used += n_fixes
            counts.detections_used += int(np.unique(rows.group).size) - n_fixes
            filt.update(lin)
            pending.reset(filt.mean())
        if is_out[e]:
            Pb = filt.covariance().reshape(n, 3, n, 3)[diag, :, diag, :]
            covs[out_index] = pending.F @ Pb @ np.swapaxes(pending.F, -1, -2) + pending.Q
            means[out_index] = pending.pose
            out_index += 1
    counts.stale_odometry_s = [tl.stale_seconds(t_start, t_end) for tl in timelines]
    if not (np.isfinite(means).all() and np.isfinite(covs).all()):
        raise DataError("cooperative pipeline produced non-finite estimates")
    return TeamRun(t=out_t, mean=means, cov=covs, counts=counts)
