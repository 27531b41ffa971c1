"""Asynchronous cooperative localization of a team of unicycles (seed 001).

:class:`CooperativeEstimator` is the centralised joint filter of the whole team — the EIF of
:mod:`relloc.estimators.eif` or the covariance-form EKF of :mod:`relloc.estimators.joint_ekf` —
behind the estimator contract of :mod:`relloc.core.contract` (owner ``"team"``), so
:func:`relloc.pipeline.replay.replay` drives it over any :class:`~relloc.core.recording.Recording`
of planar robots:

- odometry ``(v, 0, 0, ω)`` per robot (a unicycle; lateral or vertical velocity is an error);
- detections: rows of kind ``"range_bearing"`` (range and bearing) or ``"bearing"`` of another
  robot (``target``) or of a known landmark (``landmark``, its world position in
  :attr:`Recording.landmarks`), every one processed at its own time stamp;
- GPS-like absolute pose fixes: rows of kind ``"pose"`` ``(x, y, ψ)`` with their stated ``σ``.

Rows it has no model for (other kinds, detections of unknown correspondence) and rows its
settings leave unused are counted (:class:`Counts`). Its beliefs are every robot's marginal
``(x, y, ψ)`` in the frame ``world_pose2``; its update records are one NIS per detection or fix.

Odometry model (:class:`OdometryModel`)
---------------------------------------
Each command is held from its time stamp until the next one, at most ``max_hold_s``; after that
the robot is assumed still, with the larger ``stale`` noise rates (a robot whose odometry
stops). Before the first command robots stand still. The noise on the input is white with
spectral densities (variance rates, SI units per second)

    q_v = q_v0 + k_v |v|,     q_ω = q_ω0 + k_ω |ω| + k_ωv |v|,

so the dead-reckoning variance grows with distance travelled and angle turned, independent of
the odometry rate. Over a step of length ``dt`` the covariance of the averaged input is
``diag(q_v, q_ω)/dt``. A calibrated latency ``τ`` (the commands lead the motion) and scale
factors are properties of the data, not of the filter: they are applied to the recording before
the replay (each command re-stamped ``t + τ`` and scaled), because the filter learns a command
only once the loop holds it.

A robot whose odometry stops *while the robot may still be moving* — a teammate whose process
died while its wheels kept turning (robot processes, :mod:`relloc.runtime.handoff`) — is not
still: all the filter knows is that it moves at most at the platform's speed ``V`` and turns at
most at ``Ω``. With ``lost_speed = V > 0`` (default 0: off) such a robot is *lost* once its
command expires: still, as above (mean zero: the last command may have been kept, stopped or
reversed, and the centre of the disc it can reach errs least in the worst case, while holding
the last velocity errs by up to ``2 V a``), and its position gets the isotropic variance
``(V a)²`` per axis at age ``a`` since the expiry — the reach as one standard deviation
(conservative: a uniform disc of that radius has a quarter of it), growing with the square of
the age like a displacement, not linearly like white input noise, which would claim the robot
has barely moved and make the filter reject every reading of it when it is back; its heading
gets ``min((Ω a)², π²/3)`` (``π²/3``: a heading uniform on the circle). The variance is added
to the robot's block of the prediction's ``Q``: a still robot's ``Φ_i`` leaves the position
block unchanged, so the position part is exact; the heading part misses its coupling into
position over the one step in which a fresh command ends the loss (small next to ``(V a)²``).

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
filter process every measurement at its own time stamp while paying the joint prediction only
once per measurement epoch. :meth:`CooperativeEstimator.advance` only collects the commands the
loop holds; the steps are laid out and accumulated (:func:`command_timeline`,
:func:`accumulate_prediction`) when a measurement epoch or a belief needs the state — the
segments between command changes (every robot's, the team advances in one vectorised step) are
cut at those epochs and at most ``max_step_s`` long.

Linearisation
-------------
``CooperativeSettings.linearisation = "latest"`` is the standard filter (seed 001): every
Jacobian at the latest estimate. Without enough anchors that filter is inconsistent: it gains
information along the unobservable global rotation. ``"first_estimates"`` evaluates every
Jacobian at the first estimate of the state it differentiates (FEJ, Huang et al. 2008–2010),
which keeps the unobservable subspace of the linearised team equal to the nonlinear one; the
derivation is in :mod:`relloc.estimators.first_estimates`. ``"observability_constrained"``
(OC-EKF/EIF, Huang et al. 2010–2011) linearises at the latest estimate and changes the
Jacobians least so that they keep that subspace (:mod:`relloc.estimators.observability_constrained`;
its transition is dense, coupling the robots).

Measurements
------------
Rows (:mod:`relloc.models.planar_measurement`) are built per epoch: bearing (always, if
``use_bearing``), range (if ``use_range``; corrected by a fitted bias
``b(η, ρ)`` that depends on bearing and range (:class:`SensorModel`) and optionally
thinned to one range per pair every ``range_min_interval_s``
because consecutive ranges have strongly correlated errors), and absolute pose rows. Each detection
or fix is gated as a whole with its normalised innovation squared against
``χ²_{dof}(p_gate)`` (:mod:`relloc.association.gating`) before the batch update. The NIS of every
detection or fix used is recorded (:meth:`CooperativeEstimator.take_updates`), with the
conditioning ``log10(λmax/λmin)`` of its ``R`` (diagonal) and of its ``S`` (at most 3 × 3).
The gate's quantiles of every group size (:data:`GATE_DOFS`) are computed when the estimator is
built (:func:`relloc.core.kalman.prepare_gates`), not in its first update.
"""

from __future__ import annotations

import copy
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from typing import Literal, Protocol

import numpy as np
from numpy.typing import NDArray

from relloc.association.gating import mahalanobis_batch
from relloc.core.checks import count, number, positive, probability
from relloc.core.contract import BeliefStack, HeldOdometry, Silent, UpdateRecord
from relloc.core.events import TIME_TOL, elapsed
from relloc.core.gaussian import Gaussian
from relloc.core.kalman import chi2_threshold, prepare_gates
from relloc.core.recording import NO_TARGET, Measurements, kind_code
from relloc.errors import ConfigError, DataError, ModelError
from relloc.estimators.eif import ExtendedInformationFilter
from relloc.estimators.first_estimates import first_estimates_transition
from relloc.estimators.joint_ekf import JointEkf, propagate_team_covariance
from relloc.estimators.observability_constrained import (
    constrained_rows,
    constrained_transition,
    unobservable_directions,
)
from relloc.estimators.second_order import second_order_rows
from relloc.models.planar_measurement import (
    RANGE_BIAS_FEATURES,
    LinearisedRows,
    RowKind,
    ScalarRows,
    empty_rows,
    linearise_rows,
    range_bias_features,
)
from relloc.models.unicycle import unicycle_jacobians, unicycle_step

Array = NDArray[np.float64]
IntArray = NDArray[np.int64]
BoolArray = NDArray[np.bool_]

_MIN_SEPARATION_M = 1e-3
HEADING_UNKNOWN = np.pi**2 / 3
"""Variance of a heading uniform on the circle (rad²): a lost robot's heading is no less known."""
RANGE_BEARING = kind_code("range_bearing")
BEARING = kind_code("bearing")
POSE = kind_code("pose")
#: The frame of the beliefs: every robot's ``(x, y, ψ)`` in the world frame.
FRAME = "world_pose2"
Linearisation = Literal["latest", "first_estimates", "observability_constrained"]
LINEARISATIONS: tuple[Linearisation, ...] = (
    "latest",
    "first_estimates",
    "observability_constrained",
)


# ----------------------------------------------------------------------------------------------
# Settings
# ----------------------------------------------------------------------------------------------


def _check_nonneg(obj: object, names: Sequence[str]) -> None:
    for name in names:
        number(getattr(obj, name), f"{type(obj).__name__}.{name}", low=0.0)


@dataclass(frozen=True, kw_only=True)
class OdometryModel:
    """How odometry turns into inputs and process noise (see the module docstring)."""

    q_v0: float
    q_w0: float
    k_v: float = 0.0
    k_w: float = 0.0
    k_wv: float = 0.0
    max_hold_s: float = 1.0
    stale_q_v: float = 0.01
    stale_q_w: float = 0.01
    max_step_s: float = 0.1
    lost_speed: float = 0.0
    lost_turn_rate: float = 0.0

    def __post_init__(self) -> None:
        _check_nonneg(
            self,
            (
                "q_v0",
                "q_w0",
                "k_v",
                "k_w",
                "k_wv",
                "max_hold_s",
                "stale_q_v",
                "stale_q_w",
                "lost_speed",
                "lost_turn_rate",
            ),
        )
        positive(self.max_step_s, "OdometryModel.max_step_s")
        if self.q_v0 + self.k_v <= 0 or self.q_w0 + self.k_w + self.k_wv <= 0:
            raise ConfigError("OdometryModel: q_v0/k_v and q_w0/k_w must not all be zero")

    @staticmethod
    def from_discrete(sigma_v: float, sigma_w: float, dt: float) -> OdometryModel:
        """Per-step white input noise ``σ`` at step ``dt`` (seed 001 ``Q_i``): ``q = σ² dt``."""
        if dt <= 0:
            raise ConfigError("OdometryModel.from_discrete: dt must be > 0")
        return OdometryModel(q_v0=sigma_v**2 * dt, q_w0=sigma_w**2 * dt, max_step_s=dt)

    def lost_variance(self, age: Array) -> tuple[Array, Array]:
        """Variance of a lost robot's position (per axis, m²) and heading (rad²) ``age``
        seconds after its command expired: ``(V a)²`` and ``min((Ω a)², π²/3)``
        (:data:`lost_speed` ``V``, :data:`lost_turn_rate` ``Ω``; module docstring)."""
        a = np.maximum(age, 0.0)
        return (self.lost_speed * a) ** 2, np.minimum(
            (self.lost_turn_rate * a) ** 2, HEADING_UNKNOWN
        )

    def rates(self, v: Array, w: Array) -> tuple[Array, Array]:
        """Variance rates ``(q_v, q_ω)`` of fresh commands ``(v, ω)``."""
        return self.q_v0 + self.k_v * np.abs(v), self.q_w0 + self.k_w * np.abs(
            w
        ) + self.k_wv * np.abs(v)


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
            positive(getattr(self, name), f"SensorModel.{name}")
        number(self.bearing_bias, "SensorModel.bearing_bias")
        if not isinstance(self.range_bias_coeffs, (tuple, list)):
            raise ConfigError(
                f"SensorModel.range_bias_coeffs: expected a tuple, got {self.range_bias_coeffs!r}"
            )
        for c in self.range_bias_coeffs:
            number(c, "SensorModel.range_bias_coeffs")
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
class CooperativeSettings:
    """What the filter uses and how.

    ``anchors``: landmark indices whose detections are used (others are ignored and counted);
    ``use_robot_detections``: robot→robot rows; ``use_fixes``: absolute pose rows; ``p_gate``:
    χ² gate probability (``None``: no gating); ``filter``: ``"eif"`` or ``"ekf"``;
    ``linearisation``: ``"latest"`` (the standard filter: every Jacobian at the latest estimate)
    or ``"first_estimates"`` (FEJ, :mod:`relloc.estimators.first_estimates`: the linearised team
    keeps the unobservable global translation/rotation unobservable) or
    ``"observability_constrained"`` (OC, :mod:`relloc.estimators.observability_constrained`: the
    latest-estimate Jacobians changed least to keep that subspace); ``second_order``: bearing
    and range rows carry their second-order mean and variance under the prior
    (:mod:`relloc.estimators.second_order`: a row whose linearisation fails over the prior's
    spread is de-weighted by that much).
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
    linearisation: Linearisation = "latest"
    second_order: bool = False

    def __post_init__(self) -> None:
        if not isinstance(self.odometry, OdometryModel) or not isinstance(self.sensor, SensorModel):
            raise ConfigError(
                "CooperativeSettings: odometry must be an OdometryModel, sensor a SensorModel"
            )
        if not isinstance(self.anchors, tuple):
            raise ConfigError(
                f"CooperativeSettings.anchors: expected a tuple, got {self.anchors!r}"
            )
        for a in self.anchors:
            count(a, "CooperativeSettings.anchors", low=0)
        if self.filter not in ("eif", "ekf"):
            raise ConfigError(
                f"CooperativeSettings.filter must be 'eif' or 'ekf', got {self.filter}"
            )
        if self.linearisation not in LINEARISATIONS:
            raise ConfigError(
                f"CooperativeSettings.linearisation must be one of {', '.join(LINEARISATIONS)}, "
                f"got {self.linearisation}"
            )
        if self.p_gate is not None:
            probability(self.p_gate, "CooperativeSettings.p_gate")

    @property
    def uses_detections(self) -> bool:
        """Whether detections are looked at (each then opens a measurement epoch)."""
        return self.use_fixes or (self.use_bearing or self.use_range)


# ----------------------------------------------------------------------------------------------
# Held commands → piecewise-constant input timeline → exact block prediction
# ----------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class HeldCommands:
    """What the loop held over ``K`` consecutive event intervals ``(begin[k], end[k]]``: each
    robot's command ``(v, w)`` (``(K, n)``) and its time stamp ``stamp`` (NaN before the
    robot's first report); ``in_force`` ``(n,)`` is the stamp of the command held before them.
    A command takes effect at its stamp."""

    begin: Array
    end: Array
    stamp: Array
    v: Array
    w: Array
    in_force: Array


@dataclass(frozen=True)
class TeamTimeline:
    """Every robot's inputs on the union of all robots' segment starts: segment ``k`` holds from
    ``start[k]`` to ``start[k+1]`` (the last to +∞), with ``(S, n)`` inputs and noise rates, so a
    whole team advances in one vectorised step."""

    start: Array
    v: Array
    w: Array
    q_v: Array
    q_w: Array


@dataclass(frozen=True)
class StaleIntervals:
    """Intervals ``[start, end)`` during which ``robot`` had no fresh command (``end`` may be
    +∞)."""

    robot: IntArray
    start: Array
    end: Array

    @staticmethod
    def concatenate(parts: Sequence[StaleIntervals]) -> StaleIntervals:
        return StaleIntervals(
            robot=np.concatenate([p.robot for p in parts]),
            start=np.concatenate([p.start for p in parts]),
            end=np.concatenate([p.end for p in parts]),
        )

    def seconds(self, n: int, t0: float, t1: float) -> list[float]:
        """Per robot, the time within ``[t0, t1]`` spent without a fresh command."""
        overlap = np.clip(np.minimum(self.end, t1) - np.maximum(self.start, t0), 0, None)
        return [float(np.sum(overlap[self.robot == i])) for i in range(n)]


NO_STALE = StaleIntervals(np.zeros(0, dtype=np.int64), np.zeros(0), np.zeros(0))


def command_timeline(
    held: HeldCommands, model: OdometryModel
) -> tuple[TeamTimeline, StaleIntervals]:
    """The team's input timeline over the held intervals, and the stale intervals it closes.

    Each command holds from its stamp until the next one, at most ``max_hold_s`` (then the
    robot is still, at the stale noise rates); a robot that has not reported yet is still at
    the rates ``(q_v0, q_ω0)``. Segments start at the first interval's begin, at every command
    that appears later and at every expiry inside the intervals (a command's successor comes at
    an event, so it expires inside the interval that holds it, or before, or after); every
    robot's input over a segment is the one in force at its start. A stale interval is closed
    by the command after it.
    """
    hold = model.max_hold_s
    before = np.concatenate([held.in_force[None], held.stamp[:-1]])
    fresh = ~np.isnan(held.stamp) & (held.stamp != before)  # (K, n): a new command
    expiry = held.stamp + hold
    inside = (expiry >= held.begin[:, None]) & (expiry < held.end[:, None])
    later = fresh & (held.stamp > held.begin[0])
    # at each segment start: the interval holding it, each robot's command there, and whether
    # the robot has none yet or its command has expired
    if later.any() or inside.any():
        start = np.unique(np.concatenate([held.begin[:1], held.stamp[later], expiry[inside]]))
        k = np.searchsorted(held.end, start, side="right")
    else:  # one segment (nothing changes inside the intervals)
        start, k = held.begin[:1], np.zeros(1, dtype=np.int64)
    none = np.isnan(held.stamp[k])
    still = none | (start[:, None] >= expiry[k])
    v, w = held.v[k], held.w[k]
    q_v, q_w = model.rates(v, w)
    q_v[still], q_w[still] = model.stale_q_v, model.stale_q_w
    q_v[none], q_w[none] = model.q_v0, model.q_w0
    timeline = TeamTimeline(
        start=start, v=np.where(still, 0.0, v), w=np.where(still, 0.0, w), q_v=q_v, q_w=q_w
    )
    closed = fresh & (before + hold < held.stamp)
    if not closed.any():
        return timeline, NO_STALE
    k_closed, robot = np.nonzero(closed)
    stale = StaleIntervals(
        robot=robot,
        start=before[k_closed, robot] + hold,
        end=held.stamp[k_closed, robot],
    )
    return timeline, stale


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


def accumulate_prediction(
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
    # a segment where the whole team stands still is one exact step (F = I, G constant), so
    # a long gap after every command expired costs one step, not one per max_step
    moving = np.any((timeline.v[ok] != 0) | (timeline.w[ok] != 0), axis=1)
    n_sub = np.where(moving, np.maximum(np.ceil(dur / max_step - 1e-9), 1), 1).astype(np.int64)
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
    a_sum, b_sum = a.sum(axis=0), b.sum(axis=0)
    A = a_sum - np.cumsum(a, axis=0)
    B = b_sum - np.cumsum(b, axis=0)
    PhiG = G.copy()
    PhiG[..., 0, :] += A[..., None] * G[..., 2, :]
    PhiG[..., 1, :] += B[..., None] * G[..., 2, :]
    q = np.stack([qv * dt, qw * dt], axis=-1)
    Qseg = np.einsum("knai,kni,knbi->nab", PhiG, q, PhiG)
    F_seg = np.broadcast_to(np.eye(3), (pending.pose.shape[0], 3, 3)).copy()
    F_seg[:, 0, 2], F_seg[:, 1, 2] = a_sum, b_sum
    pending.pose = pending.pose + step.sum(axis=0)
    pending.F = F_seg @ pending.F
    pending.Q = F_seg @ pending.Q @ np.swapaxes(F_seg, -1, -2) + Qseg


# ----------------------------------------------------------------------------------------------
# Rows and gating
# ----------------------------------------------------------------------------------------------


@dataclass
class Counts:
    """What happened to every detection and fix (reported in summaries).

    ``ignored_unused``: rows of a kind the settings leave unused (fixes without ``use_fixes``,
    every detection when neither bearing, range nor fixes are used); ``ignored_unmodelled``:
    rows the filter has no model for (other kinds, detections of unknown correspondence).
    """

    detections_used: int = 0
    fixes_used: int = 0
    rejected_gate: int = 0
    rejected_degenerate: int = 0
    ignored_not_anchor: int = 0
    ignored_robot_detection: int = 0
    ignored_unused: int = 0
    ignored_unmodelled: int = 0
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
            "ignored_unused": self.ignored_unused,
            "ignored_unmodelled": self.ignored_unmodelled,
            "ranges_thinned": self.ranges_thinned,
            "epochs": self.epochs,
            "stale_odometry_s": list(self.stale_odometry_s),
        }


def detection_rows(
    batch: Measurements,
    idx: IntArray,
    landmarks_xy: Array,
    settings: CooperativeSettings,
    group_offset: int,
    last_range: dict[tuple[int, int], float],
    counts: Counts,
) -> ScalarRows:
    """Scalar rows (bearing, range) of the detections ``batch[idx]`` of one epoch, after the
    settings' choices of anchors, robot detections and range thinning (all counted)."""
    assert batch.landmark is not None
    landmark = batch.landmark[idx]
    is_lm = landmark >= 0
    anchor = (landmark[:, None] == np.asarray(settings.anchors, dtype=np.int64)).any(axis=1)
    not_anchor = is_lm & ~anchor
    counts.ignored_not_anchor += int(np.count_nonzero(not_anchor))
    keep = ~not_anchor
    if not settings.use_robot_detections:
        counts.ignored_robot_detection += int((~is_lm).sum())
        keep &= is_lm
    idx, landmark, is_lm = idx[keep], landmark[keep], is_lm[keep]
    m = idx.size
    if m == 0:
        return empty_rows()
    groups = group_offset + np.arange(m)
    observer, target = batch.observer[idx], batch.target[idx]
    has_range = batch.kind[idx] == RANGE_BEARING
    value = batch.value[idx]
    bearing_z = np.where(has_range, value[:, 1], value[:, 0])
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
        rng = np.where(has_range, value[:, 0], np.nan)
        use = has_range.copy()
        interval = settings.sensor.range_min_interval_s
        if interval > 0:
            t = batch.t[idx]
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
    return ScalarRows.concatenate(parts) if len(parts) > 1 else parts[0]


def fix_rows(batch: Measurements, idx: IntArray, group_offset: int) -> ScalarRows:
    """Three rows (x, y, ψ) per absolute pose fix ``batch[idx]``, one gating group per fix."""
    g = idx.size
    sigma = batch.sigma[idx, :3]
    if not np.isfinite(sigma).all():
        row = int(idx[np.argwhere(~np.isfinite(sigma))[0][0]])
        raise DataError(f"pose fix at t={batch.t[row]:.6g} states no σ (needed for its noise)")
    kinds = np.array([RowKind.POSE_X, RowKind.POSE_Y, RowKind.POSE_HEADING], dtype=np.int64)
    return ScalarRows(
        kind=np.tile(kinds, g),
        observer=np.repeat(batch.observer[idx], 3),
        target=np.full(3 * g, -1, dtype=np.int64),
        landmark_xy=np.zeros((3 * g, 2)),
        z=batch.value[idx, :3].reshape(-1),
        sigma=sigma.reshape(-1),
        group=np.repeat(group_offset + np.arange(g), 3),
    )


@dataclass(frozen=True)
class GroupInnovations:
    """Per gating group (a detection or fix) of one epoch, in ``ids`` order: the NIS
    ``νᵀ S⁻¹ ν`` with ``dof`` rows, the observer (the robot whose reading it is), and the
    innovation covariance ``S`` (padded with the identity to the widest group); ``rows``
    ``(groups, width)`` index each group's rows (−1 beyond its ``dof``), ``sigma`` their noise."""

    ids: IntArray
    nis: Array
    dof: IntArray
    observer: IntArray
    S: Array
    rows: IntArray
    sigma: Array

    def conditioning(self) -> tuple[Array, Array]:
        """``log10(λmax/λmin)`` of every group's ``R`` (diagonal) and ``S``."""
        cond_r, cond_s = np.zeros(self.ids.size), np.zeros(self.ids.size)
        for d in np.unique(self.dof[self.dof > 1]):
            sel = self.dof == d
            var = self.sigma[self.rows[sel, :d]] ** 2
            cond_r[sel] = np.log10(var.max(axis=1) / var.min(axis=1))
            eig = np.linalg.eigvalsh(self.S[sel, :d, :d])
            cond_s[sel] = np.log10(eig[:, -1] / eig[:, 0])
        return cond_r, cond_s


def group_innovations(lin: LinearisedRows, P: Array) -> GroupInnovations:
    """NIS of every gating group, with ``S = H P Hᵀ + R``.

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
    rows = np.full((ids.size, width), -1, dtype=np.int64)
    for a in range(width):
        ok_a = a < dof
        rows[ok_a, a] = order[start[ok_a] + a]
        nu[ok_a, a] = lin.residual[rows[ok_a, a]]
        for b in range(width):
            ok = ok_a & (b < dof)
            ra, rb = order[start[ok] + a], order[start[ok] + b]
            blk = Pb[idx[ra][:, :, None], idx[rb][:, None, :]]  # (k, 2, 2, 3, 3)
            val = np.einsum("kpa,kpqab,kqb->k", lin.blocks[ra], blk, lin.blocks[rb])
            if a == b:
                val += lin.sigma[ra] ** 2
            S[ok, a, b] = val
    return GroupInnovations(
        ids=ids,
        nis=mahalanobis_batch(nu, S),
        dof=dof,
        observer=lin.block_index[order[start], 0],
        S=S,
        rows=rows,
        sigma=lin.sigma,
    )


GATE_DOFS = (1, 2, 3)
"""Rows of a gating group: a bearing (1), a bearing with its range (2), a pose fix (3)."""


def outside_gate(groups: GroupInnovations, p_gate: float) -> BoolArray:
    """Groups whose NIS exceeds ``χ²_{dof}(p_gate)``."""
    dofs, which = np.unique(groups.dof, return_inverse=True)
    thresholds = np.array([chi2_threshold(int(d), p_gate) for d in dofs])[which]
    return ~(groups.nis <= thresholds)


def _select_lin(lin: LinearisedRows, keep: BoolArray) -> LinearisedRows:
    return LinearisedRows(
        residual=lin.residual[keep],
        blocks=lin.blocks[keep],
        block_index=lin.block_index[keep],
        sigma=lin.sigma[keep],
        group=lin.group[keep],
    )


def _degenerate(rows: ScalarRows, X: Array) -> BoolArray:
    """Rows whose observer and (estimated) target coincide — bearing undefined."""
    rel = (rows.kind == RowKind.BEARING) | (rows.kind == RowKind.RANGE)
    tgt = np.where((rows.target >= 0)[:, None], X[np.maximum(rows.target, 0), :2], rows.landmark_xy)
    sep = np.linalg.norm(tgt - X[rows.observer, :2], axis=1)
    return rel & (sep < _MIN_SEPARATION_M)


# ----------------------------------------------------------------------------------------------
# The estimator
# ----------------------------------------------------------------------------------------------


class TeamFilter(Protocol):
    """What :class:`CooperativeEstimator` needs from a joint filter."""

    def mean(self) -> Array: ...

    def covariance(self) -> Array: ...

    def predict(self, mean_pred: Array, F_blocks: Array, Q_blocks: Array) -> None: ...

    def update(self, rows: LinearisedRows) -> None: ...


def make_filter(prior: Gaussian, kind: str) -> TeamFilter:
    """The joint filter named by ``kind`` ("eif" or "ekf") started at ``prior``."""
    if kind == "eif":
        return ExtendedInformationFilter.from_prior(prior)
    return JointEkf(prior)


class CooperativeEstimator(Silent):
    """The team's joint filter behind the estimator contract (module docstring).

    ``robots`` name the team's robots in the recording's order; ``prior`` ``(3n,)`` holds at the
    first :meth:`advance`; ``landmarks (L, 2 or 3)`` are the world positions the detections'
    ``landmark`` indices refer to (:attr:`Recording.landmarks`). ``record_updates=False`` skips
    the per-detection update records (a few µs each: worth skipping where nobody reads them).
    ``joint_times``: when beliefs are read at one of these times, the joint belief of the team
    (:meth:`team_belief`) is kept too, in :attr:`joint_beliefs` as ``(t, N(X̂, P))`` — for a
    test of the whole team's error that the robots' marginals cannot give.

    Every batch is one epoch at the current time: the prediction pending since the previous
    epoch is applied, then every detection and fix of the batch is gated and used in one update
    (a batch with nothing the settings use leaves the prediction pending). Beliefs are read
    after applying the pending prediction too, so the unicycle steps are cut at every epoch and
    every record time.
    Robots' commands come from the held odometry at each :meth:`advance`; a command takes effect
    at its time stamp (the loop delivers each one at the first event after it).
    """

    owner = "team"
    planar_unicycles = True
    """Odometry with lateral or vertical velocity is an error here (a robot node refuses such
    a teammate's message: :meth:`relloc.runtime.estimation.WindowDriver.refuses_odometry`)."""

    def __init__(
        self,
        robots: Sequence[str],
        prior: Gaussian,
        settings: CooperativeSettings,
        landmarks: Array | None = None,
        *,
        record_updates: bool = True,
        joint_times: Sequence[float] | Array = (),
    ) -> None:
        self.robots = tuple(str(r) for r in robots)
        n = len(self.robots)
        if n == 0:
            raise ConfigError("CooperativeEstimator: no robots")
        if prior.dim != 3 * n:
            raise ConfigError(f"prior has dimension {prior.dim}, the team needs {3 * n}")
        lm = np.zeros((0, 2)) if landmarks is None else np.asarray(landmarks, dtype=float)
        if lm.ndim != 2 or lm.shape[1] not in (2, 3) or not np.isfinite(lm).all():
            raise ConfigError(f"landmarks: expected finite (L, 2) or (L, 3), got {lm.shape}")
        self.name: str = settings.filter
        self.settings = settings
        prepare_gates(GATE_DOFS, settings.p_gate)
        self._landmarks = lm[:, :2]
        # the known landmarks the constrained Jacobians need (those the detections may use)
        self._anchors_xy = self._landmarks[[a for a in settings.anchors if a < lm.shape[0]]]
        self._filter = make_filter(prior, settings.filter)
        self._pending = TeamPending.at(self._filter.mean())
        # the team mean before the last epoch's update (the first estimate of that instant)
        self._first = self._filter.mean().copy()
        self._t_epoch = np.nan
        self._counts = Counts()
        self._last_range: dict[tuple[int, int], float] = {}
        self._group_offset = 0
        self._record_updates = record_updates
        self._updates: list[UpdateRecord] = []
        self._joint_times = np.asarray(joint_times, dtype=float).reshape(-1)
        self.joint_beliefs: list[tuple[float, Gaussian]] = []
        self._t_start = np.nan
        self._t = np.nan
        self._t_applied = np.nan
        # the stamp of each robot's command at the last applied time; the loop's holds since
        self._in_force = np.full(n, np.nan)
        self._held: list[HeldOdometry] = []
        self._held_t: list[float] = []
        self._stale: list[StaleIntervals] = []

    @property
    def n_robots(self) -> int:
        return len(self.robots)

    @property
    def follows_lost_robots(self) -> bool:
        """Whether a robot whose odometry stopped is followed with the lost model (module
        docstring): the others' detections of it are then worth fusing."""
        return self.settings.odometry.lost_speed > 0

    # -- the contract ----------------------------------------------------------------------

    def advance(self, t: float, odometry: HeldOdometry) -> None:
        """Note the commands held over ``(previous event, t]``; the steps are taken lazily."""
        dt = elapsed(None if np.isnan(self._t) else self._t, t, "CooperativeEstimator.advance")
        t = float(t)
        if dt is None:
            self._t_start = self._t = self._t_applied = t
            return
        if dt > 0:
            self._held.append(odometry)
            self._held_t.append(t)
            self._t = t

    def measure(self, batch: Measurements) -> None:
        """One epoch with the detections and fixes of ``batch`` (the rest is counted)."""
        if batch.size == 0:
            return
        if np.isnan(self._t):
            raise ConfigError("CooperativeEstimator.measure before the first advance")
        self._check_indices(batch)
        assert batch.landmark is not None
        s = self.settings
        kind = batch.kind
        detection = (kind == RANGE_BEARING) | (kind == BEARING)
        known = detection & ((batch.target != NO_TARGET) | (batch.landmark != NO_TARGET))
        fix = kind == POSE
        c = self._counts
        c.ignored_unmodelled += batch.size - int(np.count_nonzero(known | fix))
        det_idx = np.flatnonzero(known) if s.uses_detections else np.zeros(0, dtype=np.int64)
        fix_idx = np.flatnonzero(fix) if s.use_fixes else np.zeros(0, dtype=np.int64)
        c.ignored_unused += (
            int(np.count_nonzero(known)) - det_idx.size + int(np.count_nonzero(fix)) - fix_idx.size
        )
        if det_idx.size == 0 and fix_idx.size == 0:
            return
        self._apply_motion()
        parts = []
        if det_idx.size:
            parts.append(
                detection_rows(
                    batch, det_idx, self._landmarks, s, self._group_offset, self._last_range, c
                )
            )
            self._group_offset += det_idx.size
        if fix_idx.size:
            parts.append(fix_rows(batch, fix_idx, self._group_offset))
            self._group_offset += fix_idx.size
        rows = ScalarRows.concatenate(parts) if len(parts) > 1 else parts[0]
        if rows.size:
            self._update(rows)

    def beliefs(self) -> BeliefStack:
        """Every robot's marginal ``(x, y, ψ)`` now, stacked: the pending prediction applied to
        its block, ``Φ_i P_ii Φ_iᵀ + Q_i``."""
        if not np.isnan(self._t):
            self._apply_motion()
        n = self.n_robots
        diag = np.arange(n)
        p = self._pending
        F = self._transition()
        if F.ndim == 2:  # dense (observability-constrained): the joint propagation's marginals
            P = propagate_team_covariance(self._filter.covariance(), F, p.Q)
            cov = P.reshape(n, 3, n, 3)[diag, :, diag, :]
        else:
            Pb = self._filter.covariance().reshape(n, 3, n, 3)[diag, :, diag, :]
            cov = F @ Pb @ np.swapaxes(F, -1, -2) + p.Q
        if not np.isfinite(cov.sum() + p.pose.sum()):
            raise ModelError("cooperative filter produced non-finite estimates")
        age = 0.0 if np.isnan(self._t) else self._t - self._t_start
        if self._joint_due():
            self.joint_beliefs.append(self.team_belief())
        return BeliefStack(self.robots, FRAME, p.pose, cov, age)

    def _joint_due(self) -> bool:
        """Whether now is one of ``joint_times`` whose joint belief is not kept yet."""
        if not self._joint_times.size or np.isnan(self._t):
            return False
        if self.joint_beliefs and self.joint_beliefs[-1][0] == self._t:
            return False
        return bool(np.any(np.abs(self._joint_times - self._t) <= TIME_TOL))

    def take_updates(self) -> list[UpdateRecord]:
        out, self._updates = self._updates, []
        return out

    @property
    def counts(self) -> Counts:
        """What happened to every row so far, with each robot's time without fresh odometry
        (``stale_odometry_s``) between the first and the latest event."""
        if np.isnan(self._t):
            return replace(self._counts, stale_odometry_s=[])
        hold = self.settings.odometry.max_hold_s
        parts = list(self._stale)
        last = self._in_force
        if self._held:
            held = self._held_commands()
            parts.append(command_timeline(held, self.settings.odometry)[1])
            last = held.stamp[-1]
        robot = np.flatnonzero(~np.isnan(last))
        parts.append(StaleIntervals(robot, last[robot] + hold, np.full(robot.size, np.inf)))
        seconds = StaleIntervals.concatenate(parts).seconds(self.n_robots, self._t_start, self._t)
        return replace(self._counts, stale_odometry_s=seconds)

    # -- a restarted agent rejoins the team's estimate ------------------------------------

    def team_belief(self) -> tuple[float, Gaussian]:
        """The joint belief of the whole team at the latest event time ``t``: ``N(X̂, P)`` of
        dimension ``3n`` with the pending prediction applied (``X̂`` the propagated poses,
        ``P = Φ P Φᵀ + Q``). It is computed on a copy, so this filter's arithmetic is untouched
        (applying the motion here would cut its unicycle steps at ``t``)."""
        if np.isnan(self._t):
            raise ModelError("CooperativeEstimator.team_belief before the first advance")
        probe = copy.deepcopy(self)
        probe._apply_motion()
        p = probe._pending
        P = propagate_team_covariance(probe._filter.covariance(), probe._transition(), p.Q)
        return probe._t, Gaussian(p.pose.reshape(-1), P)

    def resumed(self, t: float, belief: Gaussian) -> CooperativeEstimator:
        """A filter of these settings that starts at ``t`` from ``belief`` (a teammate's
        :meth:`team_belief`). It continues as the teammate's filter would: ``X̂, P`` are what
        that filter's next prediction starts from, the information form is ``P⁻¹`` again (the
        same up to round-off). Row counts start from zero; with first-estimates or
        observability-constrained Jacobians the first estimate is ``X̂`` (an approximation:
        the teammate's is that of its last epoch)."""
        if belief.dim != 3 * self.n_robots:
            raise ConfigError(
                f"resumed: belief of dimension {belief.dim}, the team needs {3 * self.n_robots}"
            )
        out = CooperativeEstimator(
            self.robots,
            belief,
            self.settings,
            self._landmarks,
            record_updates=self._record_updates,
        )
        out.advance(t, HeldOdometry.still(self.n_robots))
        return out

    # -- internals -------------------------------------------------------------------------

    def _check_indices(self, batch: Measurements) -> None:
        assert batch.landmark is not None
        for name, ids, limit in (
            ("observer", batch.observer, self.n_robots),
            ("target", batch.target, self.n_robots),
            ("landmark", batch.landmark, self._landmarks.shape[0]),
        ):
            if ids.max() >= limit:
                row = int(np.argmax(ids >= limit))
                raise DataError(
                    f"measurements at t={batch.t[row]:.6g}: {name} {int(ids[row])} is not among "
                    f"the filter's {limit}"
                )

    def _held_commands(self) -> HeldCommands:
        """What the loop held since the last applied time."""
        stamp = np.array([h.stamp for h in self._held])
        velocity = np.array([h.velocity for h in self._held])
        if velocity[..., 1:3].any():
            k, i = np.argwhere(velocity[..., 1:3] != 0)[0][:2]
            raise DataError(
                f"odometry of {self.robots[i]} at t={self._held_t[k]:.6g} has lateral or vertical "
                "velocity; the cooperative filter models unicycles (v, 0, 0, ω)"
            )
        end = np.array(self._held_t)
        return HeldCommands(
            begin=np.concatenate([[self._t_applied], end[:-1]]),
            end=end,
            stamp=stamp,
            v=velocity[..., 0],
            w=velocity[..., 3],
            in_force=self._in_force,
        )

    def _apply_motion(self) -> None:
        """Bring the pending prediction from the last applied time up to now."""
        if not self._held:
            return
        held = self._held_commands()
        timeline, stale = command_timeline(held, self.settings.odometry)
        accumulate_prediction(
            self._pending, timeline, self._t_applied, self._t, self.settings.odometry.max_step_s
        )
        if stale.robot.size:
            self._stale.append(stale)
        if self.settings.odometry.lost_speed > 0:
            self._add_lost_noise(held)
        self._in_force = held.stamp[-1]
        self._held.clear()
        self._held_t.clear()
        self._t_applied = self._t

    def _add_lost_noise(self, held: HeldCommands) -> None:
        """The variance of lost robots (module docstring) over the held intervals: per
        interval ``(b_k, e_k]`` and robot, the growth of :meth:`OdometryModel.lost_variance`
        between ``max(b_k, expiry)`` and ``e_k`` (the age counted from the expiry of the
        command held over it)."""
        model = self.settings.odometry
        expiry = held.stamp + model.max_hold_s  # (K, n); NaN: no command yet (not lost)
        lo = np.maximum(held.begin[:, None], expiry)
        hi = np.maximum(held.end[:, None], lo)
        ok = ~np.isnan(expiry)
        pos_hi, yaw_hi = model.lost_variance(np.where(ok, hi - expiry, 0.0))
        pos_lo, yaw_lo = model.lost_variance(np.where(ok, lo - expiry, 0.0))
        d_pos = (pos_hi - pos_lo).sum(axis=0)
        d_yaw = (yaw_hi - yaw_lo).sum(axis=0)
        Q = self._pending.Q
        Q[:, 0, 0] += d_pos
        Q[:, 1, 1] += d_pos
        Q[:, 2, 2] += d_yaw

    def _transition(self) -> Array:
        """The pending prediction's per-robot ``Φ_i (n, 3, 3)``: the accumulated one, or with
        ``first_estimates`` the one from the last epoch's first estimates; with
        ``observability_constrained`` the dense ``Φ* (3n, 3n)`` closest to the accumulated one
        that carries the unobservable directions from the last epoch's first estimates to the
        propagated poses. Each is the identity while no time has passed since that epoch."""
        p = self._pending
        lin = self.settings.linearisation
        if lin == "latest" or self._t_applied == self._t_epoch:
            return p.F
        if lin == "first_estimates":
            return first_estimates_transition(p.pose, self._first)
        return constrained_transition(
            p.F, self._unobservable(self._first), self._unobservable(p.pose)
        )

    def _unobservable(self, X: Array) -> Array:
        """The team's unobservable directions ``N (3n, d)`` at ``X`` under these settings."""
        return unobservable_directions(X, self._anchors_xy, self.settings.use_fixes)

    def _linearise(self, X: Array, rows: ScalarRows) -> LinearisedRows:
        """Residuals at the latest mean ``X``; with ``first_estimates`` the Jacobian blocks at
        the first estimate of this instant, with ``observability_constrained`` the blocks at
        ``X`` projected off the unobservable directions at that first estimate (either the same
        as the plain blocks unless an epoch at this instant was already applied)."""
        lin = linearise_rows(X, rows)
        if self.settings.linearisation == "latest" or np.array_equal(self._first, X):
            return lin
        if self.settings.linearisation == "first_estimates":
            return replace(lin, blocks=linearise_rows(self._first, rows).blocks)
        return constrained_rows(lin, self._unobservable(self._first))

    def _update(self, rows: ScalarRows) -> None:
        """Predict to now and update with the rows of one epoch (gated per detection / fix)."""
        c, s = self._counts, self.settings
        c.epochs += 1
        filt = self._filter
        filt.predict(self._pending.pose, self._transition(), self._pending.Q)
        X = filt.mean()
        if self._t != self._t_epoch:
            self._first, self._t_epoch = X.copy(), self._t
        degenerate = _degenerate(rows, X)
        if degenerate.any():
            c.rejected_degenerate += int(np.unique(rows.group[degenerate]).size)
            rows = rows.select(~np.isin(rows.group, rows.group[degenerate]))
        lin = self._linearise(X, rows)
        if s.second_order:
            lin = second_order_rows(lin, rows, X, filt.covariance())
        used = 0
        if rows.size:
            groups = group_innovations(lin, filt.covariance())
            rejected = outside_gate(groups, s.p_gate) if s.p_gate is not None else None
            used = groups.ids.size
            if rejected is not None and rejected.any():
                c.rejected_gate += int(rejected.sum())
                used -= int(rejected.sum())
                keep = ~np.isin(lin.group, groups.ids[rejected])
                lin = _select_lin(lin, keep)
                rows = rows.select(keep)
            if self._record_updates:
                self._record(groups, rejected)
        n_fixes = int((rows.kind == RowKind.POSE_X).sum())
        c.fixes_used += n_fixes
        c.detections_used += used - n_fixes
        filt.update(lin)
        self._pending.reset(filt.mean())

    def _record(self, groups: GroupInnovations, rejected: BoolArray | None) -> None:
        """One update record per detection or fix used (the observer's name as subject)."""
        used = np.ones(groups.ids.size, dtype=bool) if rejected is None else ~rejected
        cond_r, cond_s = groups.conditioning()
        t, age = self._t, self._t - self._t_start
        columns = zip(
            groups.observer[used].tolist(),
            groups.nis[used].tolist(),
            groups.dof[used].tolist(),
            cond_r[used].tolist(),
            cond_s[used].tolist(),
            strict=True,
        )
        self._updates.extend(
            UpdateRecord(t, self.robots[o], nis, dof, c_r, c_s, age)
            for o, nis, dof, c_r, c_s in columns
        )
