"""Distributed multi-hypothesis relative localization: one fuser per sensing robot (seed 002).

A sensing robot ``i`` runs a fuser ``FUS^(i)`` holding one Gaussian-sum filter ``GSF^(i,j)``
per teammate ``j``; each mixture component is a *track* with mean ``m_h``, covariance
``P_h``, weight ``w_h``, its last association and its ancestry (for N-scan pruning). The state
is ``RelPose4 = (x, y, z, φ)`` of ``j`` in ``i``'s body frame. Seed 002's process model (Eq. 5)
is the same 4-DOF relative kinematics as seed 000 Eq. 1 (``θ̇ = ω_j − ω_i``, ``ż = v_zj − v_zi``),
so the prediction is :func:`relloc.estimators.relative.predict_arrays`, applied to all tracks
of all teammates in one batched call; the Kalman update is
:func:`relloc.core.kalman.kalman_update` (Joseph form).

Measurements (seed 002 Eq. 6; the paper names azimuth α and elevation β, ``relloc.models``
names them θ and α), processed **sensor by sensor** (gate → form → update), so that clutter on
one sensor does not discard the others:

1. height difference ``h = z + ν_h`` from the robots' absolute height references
   (known correspondence, ``H = [0, 0, 1, 0]``);
2. range ``r = ‖p‖ + ν_r`` (known correspondence);
3. bearings ``(α, β)`` of *unknown* correspondence: every bearing the robot sees (teammates
   and clutter) is a candidate for every teammate (``association.hypotheses``).

Known-correspondence sensors do not branch. Every track's weight is multiplied by the
predictive density of the measurement, with a small outlier probability ``ε``
(``known_outlier_probability``) spread uniformly over the sensor's span ``V_z``
(``max_range`` for a range, ``2·max_range`` for a height difference)::

    w_h ← w_h · ((1 − ε) N(z; ẑ_h, S_h) + ε / V_z),

and the track is Kalman-updated when the measurement is more likely valid than an outlier,
``(1 − ε) N(z; ẑ_h, S_h) ≥ ε / V_z`` (about a 4σ gate at the paper's noise). The weights are
normalised only at the end of the scan, so these densities compete with those of the new tracks
born from the bearings, which explain the same range and height with the uniform-prior
densities of :func:`relloc.association.hypotheses.birth_tracks` (``1/V_r`` and
``N(h; r sin β, P₃₃)``): a converged track is not displaced by a newborn one because one
measurement was a 2–3σ draw, while a track whose range or height has drifted away is (this is
what re-finds a kidnapped robot).

For the bearings the density ``κ`` of measurements that are not teammate ``j`` is evaluated per
bearing from the fuser's other filters (clutter plus ``P_D`` times their predicted bearing
densities, :meth:`GaussianSumFuser._false_density`): the filters of one fuser are independent
mixtures as in the paper, but a bearing that teammate ``k``'s tracks explain is weak evidence
for ``j``. New tracks are born only from bearings outside a wide exclusion gate of ``j``'s
tracks (``GateSettings.p_birth_exclusion``); each is Eq. 13's Gaussian with its unknown yaw
split into ``formation.birth_yaw_components`` components (8 by default, yaw ``2πk/8``,
σ = π/8), so that no update is linearised about a yaw far from the truth. The scan's detection
probability is ``formation.p_detect`` for every teammate, or, with
``ranges_mark_detections`` (one detector gives range and bearing, like a camera reading
barcodes), 1 for the teammates with a range in the scan and 0 for the others. Between the
two, ``range_in_view`` keeps the sensors separate but gives the range sensor the bearing
sensor's field of view: whether a teammate was ranged then weighs its tracks by where they
put it (inside or outside the view), not which bearing is its.
:meth:`GaussianSumFuser.decide` gives, on top, a one-to-one bearing-to-teammate decision
(``linear_sum_assignment``) for reporting.

After the direct scan each filter is normalised and reduced (``association.mixture_reduction``
and ``association.nscan``): prune by weight, N-scan prune track families, merge by Mahalanobis
distance (moment preserving), and cap the number of components.

Communication (Eq. 8): :meth:`GaussianSumFuser.broadcast` publishes every filter as an
:class:`~relloc.fusion.messages.EquivalentMeasurement` holding the tracks and their
previous-broadcast priors propagated to now. :meth:`GaussianSumFuser.fuse` takes a teammate's
message: ``j``'s belief of ``i`` (mutual, inverted with ⊖, Eq. 9) or ``l``'s belief of another
teammate (indirect, registered through this fuser's own belief of ``l`` with ⊕, Eq. 11), and
fuses it track by track with the de-correlation of Eqs. 10/12 (or covariance intersection).
Pairs inside the χ² gate of ``P_h + P_h'`` are fused, scored ``w_h' N(Δ; 0, P_h + P_h')``
(Eq. 10); a local track with no partner is scored ``(1 − P_G) N_γ``; a received track that
falls in no local gate is born with weight ``P_B w_h' N_γ`` if it explains the receiver's own
height and range of that instant. Unlike Eq. 10, the scores only share each local track's
weight ``w_h`` among its outcomes (the two fusers' weights rest on common information that the
weights, unlike the states, carry no prior to remove; :meth:`GaussianSumFuser._fuse_tracks`
derives it). The same increment is also
fused into the local track's broadcast prior, so that a later broadcast forwards only this
robot's own direct information (what was fused from others is never sent back to them).
Two sharing policies may restrict this (``GaussianSumSettings``): ``share_confirmed_only``
broadcasts only the filters whose dominant track is confirmed (an unresolved mixture of yaw
hypotheses is kept at home), and ``indirect_fusion=False`` fuses only the mutual messages (a
belief of a third robot registered through an uncertain belief of its sender is not used);
:data:`SHARING_POLICIES` names the combinations in use (``"all"``: seed 002's;
``"mutual-confirmed"``: both restrictions), :meth:`GaussianSumSettings.with_sharing_policy`
applies one.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field, fields, replace
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.special import ndtr

from relloc.association.assignment import assign
from relloc.association.gating import GateSettings, mahalanobis_batch, modified_gate_covariance
from relloc.association.hypotheses import FormationSettings, birth_tracks, formation_weights
from relloc.association.mixture_reduction import (
    align_angles,
    cap_mask,
    heaviest_mask,
    merge_groups,
    merge_moments,
    prune_mask,
)
from relloc.association.nscan import branch, family_keep_mask, new_history
from relloc.core.angles import wrap_angle
from relloc.core.checks import count, number, positive
from relloc.core.gaussian import Gaussian, GaussianMixture
from relloc.core.kalman import chi2_threshold, kalman_update, prepare_gates
from relloc.errors import ConfigError, DataError
from relloc.estimators.relative import predict_arrays
from relloc.fusion.covariance_intersection import covariance_intersection
from relloc.fusion.decorrelation import decorrelated_fusion, pose_difference
from relloc.fusion.messages import EquivalentMeasurement
from relloc.fusion.pose_beliefs import compose_beliefs, invert_beliefs, register_prior
from relloc.models.measurement import range_bearing, range_bearing_jacobian
from relloc.models.motion import VelocityNoise

Array = NDArray[np.float64]
IntArray = NDArray[np.int64]
FusionMode = Literal["decorrelated", "ci"]
FUSION_MODES: tuple[str, ...] = ("decorrelated", "ci")

_YAW = 3
_H_HEIGHT = np.array([[0.0, 0.0, 1.0, 0.0]])
#: Smallest horizontal distance ``ρ`` (m) at which a track is linearised (:func:`_jacobian`).
RHO_FLOOR = 1e-6
#: Floor on ``expected_clutter`` (bearings per scan) in the clutter density ``κ``: with none
#: modelled, ``κ`` would be 0 and an unexplained bearing's ``log κ`` / ``1/κ`` infinite.
MIN_EXPECTED_CLUTTER = 1e-3


@dataclass(frozen=True, kw_only=True)
class GaussianSumSettings:
    """Everything a fuser needs (units: m, rad, s).

    Attributes:
        velocity_noise: body-velocity noise of observer and teammates (process noise).
        sigma_height, sigma_range: noise of the height difference and of the range (m).
        sigma_azimuth, sigma_elevation: bearing noise (rad).
        use_elevation: bearings are (azimuth, elevation); ``False`` for azimuth-only sensors
            (planar robots), where births place the teammate at the height reference.
        expected_clutter: expected number of clutter bearings per scan (Poisson mean λV);
            the clutter density ``κ`` uses at least :data:`MIN_EXPECTED_CLUTTER` (10⁻³), so
            a bearing no track explains never has density 0 (``1/κ``, ``log κ`` finite).
        formation: P_D, P_G, P_B and the Eq. 13 birth covariance.
        gate: gate probability and the modified gate for uniform-yaw tracks.
        prune_weight: tracks below this normalised weight are deleted.
        merge_threshold: squared Mahalanobis distance below which tracks are merged (3: the
            yaw components of a new track, 2σ apart, stay separate).
        nscan_depth, nscan_weight: N of the N-scan pruning and the family-weight threshold.
        max_components: cap on the tracks of one filter.
        fusion: ``"decorrelated"`` (Eqs. 10/12) or ``"ci"`` (covariance intersection).
        registration_weight: tracks of this fuser's belief of ``l`` below this weight are not
            used to register ``l``'s messages (indirect fusion).
        confirm_weight, confirm_position_sigma, confirm_yaw_sigma: a filter's dominant track is
            *confirmed* when its weight and its position / yaw standard deviations pass these.
        ranges_mark_detections: the range and the bearing come from one detector (a camera
            reading a barcode's range and bearing): a teammate with a range in a scan has its
            bearing in the set (``P_D = 1`` for that scan) and one without has none
            (``P_D = 0``); ``False``: separate sensors, ``P_D = formation.p_detect``.
        field_of_view: half-width (rad) of the bearing sensor's azimuth field of view, or
            ``None`` (the sensor sees all around). With it, ``formation.p_detect`` is the
            detection probability of a teammate *inside* the field of view, and a track's
            ``P_D`` is that times the probability that its predicted azimuth lies inside
            ``±field_of_view`` (module docstring), and the bearing space spans
            ``±field_of_view`` (:attr:`bearing_volume`); separate sensors only.
        range_in_view: the range sensor shares the bearing sensor's field of view (a
            camera's barcode ranges): it ranges a teammate with probability
            ``formation.p_detect`` inside ``±field_of_view`` and never outside, so a range of
            ``j`` multiplies each of ``j``'s tracks by its in-view probability and a scan
            without one by ``1 − P_D`` of the track (:meth:`GaussianSumFuser.update_known`);
            ``False``: the range sensor sees all around (seed 002's ranging). Needs
            ``field_of_view``.
        known_outlier_probability: probability ``ε`` that a range or height is an outlier
            (uniform over the sensor's span; module docstring).
        max_range, max_position_sigma: tracks farther than ``max_range`` (m) or with a position
            standard deviation ``√tr P_xyz`` above ``max_position_sigma`` (m) carry no usable
            information (a teammate unseen for long) and are deleted; the filter then waits
            for new measurements to give birth to tracks again.
        share_confirmed_only: a broadcast carries only the filters whose dominant track is
            confirmed (the others keep their broadcast priors, so what they learn is sent once
            they are confirmed); ``False``: every filter, as seed 002.
        indirect_fusion: fuse teammates' beliefs of third robots (Eqs. 11–12); ``False``:
            mutual fusion only (Eqs. 9–10), indirect messages are skipped.
    """

    velocity_noise: VelocityNoise
    sigma_height: float
    sigma_range: float
    sigma_azimuth: float
    sigma_elevation: float
    use_elevation: bool = True
    expected_clutter: float = 0.0
    formation: FormationSettings = field(default_factory=FormationSettings)
    gate: GateSettings = field(default_factory=GateSettings)
    prune_weight: float = 1e-3
    merge_threshold: float = 3.0
    nscan_depth: int = 3
    nscan_weight: float = 1e-3
    max_components: int = 32
    fusion: FusionMode = "decorrelated"
    registration_weight: float = 0.2
    confirm_weight: float = 0.8
    confirm_position_sigma: float = 0.3
    confirm_yaw_sigma: float = 0.35
    ranges_mark_detections: bool = False
    field_of_view: float | None = None
    range_in_view: bool = False
    known_outlier_probability: float = 0.01
    max_range: float = 20.0
    max_position_sigma: float = 5.0
    share_confirmed_only: bool = False
    indirect_fusion: bool = True

    def __post_init__(self) -> None:
        if not isinstance(self.velocity_noise, VelocityNoise):
            raise ConfigError("GaussianSumSettings.velocity_noise must be a VelocityNoise")
        for name in (
            "sigma_height",
            "sigma_range",
            "sigma_azimuth",
            "sigma_elevation",
            "confirm_position_sigma",
            "confirm_yaw_sigma",
            "max_range",
            "max_position_sigma",
        ):
            positive(getattr(self, name), f"GaussianSumSettings.{name}")
        for name in ("expected_clutter", "merge_threshold"):
            number(getattr(self, name), f"GaussianSumSettings.{name}", low=0.0)
        for name in (
            "prune_weight",
            "nscan_weight",
            "registration_weight",
            "confirm_weight",
            "known_outlier_probability",
        ):
            value = number(getattr(self, name), f"GaussianSumSettings.{name}", low=0.0, high=1.0)
            if value == 1.0:
                raise ConfigError(f"GaussianSumSettings.{name} must lie in [0, 1): {value}")
        count(self.nscan_depth, "GaussianSumSettings.nscan_depth")
        count(self.max_components, "GaussianSumSettings.max_components")
        for name in (
            "ranges_mark_detections",
            "range_in_view",
            "share_confirmed_only",
            "indirect_fusion",
        ):
            if not isinstance(getattr(self, name), bool):
                raise ConfigError(
                    f"GaussianSumSettings.{name} must be a bool: {getattr(self, name)!r}"
                )
        if self.field_of_view is not None:
            if not (np.isfinite(self.field_of_view) and 0.0 < self.field_of_view <= np.pi):
                raise ConfigError(
                    f"GaussianSumSettings.field_of_view must lie in (0, π]: {self.field_of_view}"
                )
            if self.ranges_mark_detections:
                raise ConfigError(
                    "GaussianSumSettings: field_of_view is a separate-sensor model; it cannot "
                    "be combined with ranges_mark_detections"
                )
        if self.range_in_view and self.field_of_view is None:
            raise ConfigError("GaussianSumSettings.range_in_view needs a field_of_view")
        if self.fusion not in FUSION_MODES:
            raise ConfigError(f"GaussianSumSettings.fusion: one of {FUSION_MODES}: {self.fusion}")

    @property
    def bearing_rows(self) -> list[int]:
        """Rows of ``relloc.models.measurement.range_bearing`` that the bearing sensor gives."""
        return [1, 2] if self.use_elevation else [1]

    @property
    def bearing_noise(self) -> Array:
        """Bearing noise covariance ``R_b``."""
        sig = (
            [self.sigma_azimuth, self.sigma_elevation]
            if self.use_elevation
            else [self.sigma_azimuth]
        )
        return np.diag(np.square(sig))

    def known_span(self, kind: Literal["height", "range"]) -> float:
        """Span ``V_z`` (m) of a known-correspondence sensor: ``[0, max_range]`` for a range,
        ``[−max_range, max_range]`` for a height difference."""
        return self.max_range if kind == "range" else 2.0 * self.max_range

    @property
    def bearing_volume(self) -> float:
        """Volume of the bearing space: 2π·π (azimuth × elevation) or 2π (azimuth only); with
        a field of view ``f`` the azimuth spans ``2f`` (no bearing comes from outside it, so
        clutter and a teammate of unknown place are uniform over ``±f``)."""
        azimuth = 2.0 * np.pi if self.field_of_view is None else 2.0 * self.field_of_view
        return azimuth * (np.pi if self.use_elevation else 1.0)

    def with_sharing_policy(self, name: str) -> GaussianSumSettings:
        """These settings with the named sharing policy of :data:`SHARING_POLICIES`."""
        if name not in SHARING_POLICIES:
            raise ConfigError(f"sharing policy {name!r}: one of {', '.join(SHARING_POLICIES)}")
        confirmed_only, indirect = SHARING_POLICIES[name]
        return replace(self, share_confirmed_only=confirmed_only, indirect_fusion=indirect)


#: Named sharing policies → their ``(share_confirmed_only, indirect_fusion)`` of
#: :class:`GaussianSumSettings`: ``"all"`` is seed 002's (every filter broadcast, mutual and
#: indirect messages fused); ``"mutual-confirmed"`` broadcasts only confirmed filters and fuses
#: only mutual messages.
SHARING_POLICIES: dict[str, tuple[bool, bool]] = {
    "all": (False, True),
    "mutual-confirmed": (True, False),
}


@dataclass(frozen=True, kw_only=True)
class Tracks(GaussianMixture):
    """The tracks of all filters of one fuser: a :class:`~relloc.core.gaussian.GaussianMixture`
    in the flat layout whose ``groups[k]`` is the local index of the teammate whose filter holds
    track ``k``, with three more arrays per track.

    ``prior_means``/``prior_covs`` are the track at the previous broadcast, propagated (Eq. 8);
    ``history`` its ancestry (:mod:`relloc.association.nscan`); ``assoc[k]`` the index of the
    bearing the track was last updated with (−1: none).

    Only the fuser builds tracks, from arrays it has checked, a dozen times per scan (sub-sets,
    concatenations, updates), so construction skips the checks of
    :class:`~relloc.core.gaussian.GaussianMixture` (a few microseconds each, several per cent of
    a one-teammate scan of under a millisecond).
    """

    groups: IntArray
    prior_means: Array
    prior_covs: Array
    history: IntArray
    assoc: IntArray

    def __post_init__(self) -> None:
        """No checks (class docstring)."""

    @staticmethod
    def empty(depth: int) -> Tracks:
        """No tracks."""
        return Tracks(
            groups=np.zeros(0, dtype=np.int64),
            means=np.zeros((0, 4)),
            covs=np.zeros((0, 4, 4)),
            prior_means=np.zeros((0, 4)),
            prior_covs=np.zeros((0, 4, 4)),
            weights=np.zeros(0),
            history=np.zeros((0, depth + 1), dtype=np.int64),
            assoc=np.zeros(0, dtype=np.int64),
        )

    def take(self, idx: ArrayLike) -> Tracks:
        """Sub-set (or repetition) of tracks by index."""
        i = np.asarray(idx, dtype=np.int64)
        return Tracks(**{name: array[i] for name, array in vars(self).items()})

    def with_arrays(self, **changes: NDArray[Any]) -> Tracks:
        """These tracks with some arrays replaced (``dataclasses.replace`` without its per-call
        look-up of the fields; the fuser does this several times per scan)."""
        return Tracks(**{**vars(self), **changes})

    @staticmethod
    def concat(parts: Sequence[Tracks]) -> Tracks:
        """Tracks of all parts, in order."""
        return Tracks(
            **{name: np.concatenate([getattr(p, name) for p in parts]) for name in _TRACK_FIELDS}
        )


_TRACK_FIELDS = tuple(f.name for f in fields(Tracks))


@dataclass(frozen=True)
class TrackSummary:
    """The dominant track of one filter: belief, weight, size of the mixture, confirmation."""

    belief: Gaussian
    weight: float
    components: int
    confirmed: bool
    assoc: int


def predict_fusers(
    fusers: Sequence[GaussianSumFuser],
    u_self: Sequence[ArrayLike],
    u_team: Sequence[ArrayLike],
    dt: float,
) -> None:
    """Predict the tracks of several fusers in one batched call of ``relative.predict_arrays``.

    ``u_self[n]`` and ``u_team[n]`` are the inputs of ``fusers[n]`` (see
    :meth:`GaussianSumFuser.predict`). Identical to predicting each fuser on its own.
    """
    inputs = [f._predict_inputs(a, b, dt) for f, a, b in zip(fusers, u_self, u_team, strict=True)]
    sizes = [x[0].shape[0] for x in inputs]
    if sum(sizes) == 0:
        return
    m, P = predict_arrays(
        np.concatenate([x[0] for x in inputs]),
        np.concatenate([x[1] for x in inputs]),
        np.concatenate([x[2] for x in inputs]),
        np.concatenate([x[3] for x in inputs]),
        dt,
        fusers[0].settings.velocity_noise,
        where=f"fusers {[f.robot for f in fusers]} t={fusers[0].time:.3f}",
    )
    start = 0
    for f, size in zip(fusers, sizes, strict=True):
        f._set_predicted(m[start : start + size], P[start : start + size])
        start += size


def _jacobian(means: Array) -> Array:
    """``range_bearing_jacobian`` of tracks ``means (K, 4)``, linearised at ``ρ ≥ ρ_min``.

    ``∂θ/∂p = [−y, x, 0]/ρ²`` and ``∂α/∂p`` carry ``1/ρ`` (``ρ = √(x² + y²)``), and ``∂r/∂p =
    p/r``: the Jacobian is undefined on the vertical axis through the observer (``ρ = 0``: a
    teammate straight above, or a track at the observer, ``r = 0``) and overflows next to it, and
    its NaN or ∞ would poison the innovation covariance, the likelihoods and through the clutter
    density ``κ`` every filter's weights. A track with ``ρ < ρ_min`` (:data:`RHO_FLOOR`,
    10⁻⁶ m) is therefore linearised at its position moved horizontally out to ``ρ_min`` along
    its own azimuth (along +x at ``ρ = 0``, where the predicted azimuth ``atan2(0, 0) = 0``
    points too), so ``‖∂θ/∂p‖ ≤ 1/ρ_min`` and ``r ≥ ρ_min``. Then ``S = H P Hᵀ + R`` is finite and
    factorisable and, being huge, makes the bearing almost uninformative for such a track: the
    limit of the exact model, in which the azimuth of a point on the axis is undefined. ``ρ_min``
    lies far below any robot's size or sensor noise; every track with ``ρ ≥ ρ_min`` is
    linearised exactly where it is.
    """
    x, y = means[:, 0], means[:, 1]
    low = x * x + y * y < RHO_FLOOR**2
    if not low.any():
        return range_bearing_jacobian(means)
    point = np.array(means, dtype=float, copy=True)
    azimuth = np.arctan2(point[low, 1], point[low, 0])
    point[low, 0] = RHO_FLOOR * np.cos(azimuth)
    point[low, 1] = RHO_FLOOR * np.sin(azimuth)
    return range_bearing_jacobian(point)


def _gaussian_density(nu: Array, S: Array) -> Array:
    """``N(ν; 0, S)`` for stacks ``ν (..., n)``, ``S (..., n, n)``."""
    n = nu.shape[-1]
    d2 = mahalanobis_batch(nu, S)
    return np.exp(-0.5 * d2) / np.sqrt(np.linalg.det(S) * (2.0 * np.pi) ** n)


def _edge_density(S: Array, gamma: float) -> Array:
    """Likelihood on the gate boundary ``e^{−γ/2}/√det(2πS)`` for stacks ``S (..., n, n)``."""
    n = S.shape[-1]
    return np.exp(-0.5 * gamma) / np.sqrt(np.linalg.det(S) * (2.0 * np.pi) ** n)


class GaussianSumFuser:
    """``FUS^(i)``: the Gaussian-sum filters of robot ``robot`` for each of its ``teammates``."""

    def __init__(self, robot: int, teammates: Sequence[int], settings: GaussianSumSettings) -> None:
        team = [int(t) for t in teammates]
        if robot in team or len(set(team)) != len(team) or not team:
            raise ConfigError(
                f"GaussianSumFuser({robot}): teammates must be distinct, non-empty and exclude "
                f"the robot itself: {team}"
            )
        self.robot = int(robot)
        self.teammates = tuple(team)
        self.settings = settings
        # the gates' χ² quantiles, when the fuser is built: a bearing block (gate and birth
        # exclusion) and a 4-state track pair (the fusion's pairing gate)
        gate = settings.gate
        prepare_gates([len(settings.bearing_rows)], gate.p_gate, gate.p_birth_exclusion)
        prepare_gates([4], gate.p_gate)
        self._index = {t: k for k, t in enumerate(team)}
        self.tracks = Tracks.empty(settings.nscan_depth)
        self._next_id = 0
        self.time = 0.0
        #: horizontal speed of each teammate at the last prediction (for the modified gate)
        self._speed = np.zeros(len(team))
        #: per teammate, the bearing index the last :meth:`decide` gave it (−1: none)
        self.last_decision = np.full(len(team), -1, dtype=np.int64)
        #: the last direct scan: its time and, per teammate, its height and range (NaN: none)
        self._scan_time = float("nan")
        self._scan_known: dict[str, Array] = {}

    # ------------------------------------------------------------------ bookkeeping helpers

    def _ids(self, n: int) -> IntArray:
        ids = np.arange(self._next_id, self._next_id + n, dtype=np.int64)
        self._next_id += n
        return ids

    def teammate_index(self, robot: int) -> int:
        """Local filter index of teammate ``robot`` (DataError if unknown)."""
        try:
            return self._index[int(robot)]
        except KeyError as exc:
            raise DataError(
                f"fuser {self.robot}: robot {robot} is not a teammate {self.teammates}"
            ) from exc

    def _normalise(self) -> None:
        t = self.tracks
        if t.size == 0:
            return
        self.tracks = t.with_arrays(weights=t.normalised_weights())

    def _per_teammate(self, values: ArrayLike, what: str) -> Array:
        arr = np.asarray(values, dtype=float).reshape(-1)
        if arr.size != len(self.teammates):
            raise DataError(
                f"fuser {self.robot}: {what} needs one value per teammate "
                f"({len(self.teammates)}), got {arr.size}"
            )
        if np.isinf(arr).any():
            raise DataError(f"fuser {self.robot}: {what} contains inf (use NaN for missing)")
        return arr

    def _bearing_detection(self, ranges: Array) -> Array:
        """``P_D`` of the bearing set for each teammate in this scan (see the settings)."""
        st = self.settings
        if st.ranges_mark_detections:
            return np.where(np.isfinite(ranges), 1.0, 0.0)
        return np.full(len(self.teammates), st.formation.p_detect)

    def _track_detection(self, p_det: Array) -> Array:
        """``P_D`` of every track: its teammate's ``p_det``, times, with a field of view, the
        probability ``Φ((f − α̂)/σ) − Φ((−f − α̂)/σ)`` that the azimuth lies inside ``±f``
        (``α̂`` the predicted azimuth, ``σ²`` its innovation variance)."""
        st = self.settings
        t = self.tracks
        p = p_det[t.groups]
        if st.field_of_view is None or t.size == 0:
            return p
        azimuth = range_bearing(t.means)[:, 1]
        H = _jacobian(t.means)[:, 1:2, :]
        var = (H @ t.covs @ np.swapaxes(H, -1, -2))[:, 0, 0] + st.sigma_azimuth**2
        sd = np.sqrt(var)
        fov = st.field_of_view
        return p * (ndtr((fov - azimuth) / sd) - ndtr((-fov - azimuth) / sd))

    # ------------------------------------------------------------------ prediction

    def predict(self, u_self: ArrayLike, u_team: ArrayLike, dt: float) -> None:
        """Propagate every track (and its broadcast prior) by ``dt`` (seed 002 §II-D.1).

        ``u_self`` (4,) is this robot's body velocity, ``u_team`` (n_teammates, 4) the
        teammates' (communicated with known correspondence).
        """
        predict_fusers([self], [u_self], [u_team], dt)

    def _predict_inputs(
        self, u_self: ArrayLike, u_team: ArrayLike, dt: float
    ) -> tuple[Array, Array, Array, Array]:
        """Stacked (tracks, priors), their inputs, for one batched prediction."""
        u_self = np.asarray(u_self, dtype=float).reshape(4)
        u_team = np.asarray(u_team, dtype=float).reshape(len(self.teammates), 4)
        if not (np.isfinite(u_self).all() and np.isfinite(u_team).all()):
            raise DataError(f"fuser {self.robot} at t={self.time:.3f}: non-finite velocity")
        if not (np.isfinite(dt) and dt >= 0.0):
            raise DataError(f"fuser {self.robot} at t={self.time:.3f}: bad time step {dt}")
        self.time += float(dt)
        self._speed = np.hypot(u_team[:, 0], u_team[:, 1])
        t = self.tracks
        means = np.concatenate([t.means, t.prior_means])
        covs = np.concatenate([t.covs, t.prior_covs])
        u_c = np.concatenate([u_team[t.groups], u_team[t.groups]])
        u_l = np.broadcast_to(u_self, u_c.shape)
        return means, covs, u_l, u_c

    def _set_predicted(self, m: Array, P: Array) -> None:
        k = self.tracks.size
        self.tracks = self.tracks.with_arrays(
            means=m[:k], prior_means=m[k:], covs=P[:k], prior_covs=P[k:]
        )

    # ------------------------------------------------------------------ direct fusion

    def update_known(self, kind: Literal["height", "range"], values: ArrayLike) -> None:
        """Update with a known-correspondence sensor (``values`` per teammate, NaN = none).

        Weights are multiplied by the outlier-robust predictive density (module docstring) and
        left unnormalised (see :meth:`direct_scan`; :meth:`reduce` normalises). With
        ``range_in_view`` a range scan first weighs every track by whether its teammate was
        ranged (:meth:`_range_detection`).
        """
        vals = self._per_teammate(values, kind)
        t = self.tracks
        if t.size == 0:
            return
        if kind == "range" and self.settings.range_in_view:
            t = t.with_arrays(weights=t.weights * self._range_detection(np.isfinite(vals)))
            self.tracks = t
        z = vals[t.groups]
        sel = np.flatnonzero(np.isfinite(z))
        if sel.size == 0:
            return
        mean, cov = t.means[sel], t.covs[sel]
        nu, H, R, valid, outlier = self._known_density(kind, z[sel], mean, cov)
        inside = valid >= outlier
        new_m, new_P, _ = kalman_update(
            mean, cov, nu, H, R, where=f"fuser {self.robot} {kind} t={self.time:.3f}"
        )
        means, covs, weights = t.means.copy(), t.covs.copy(), t.weights.copy()
        means[sel] = np.where(inside[:, None], new_m, mean)
        covs[sel] = np.where(inside[:, None, None], new_P, cov)
        weights[sel] = t.weights[sel] * (valid + outlier)
        self.tracks = t.with_arrays(means=means, covs=covs, weights=weights)

    def _range_detection(self, ranged: NDArray[np.bool_]) -> Array:
        """The likelihood of a scan's range detections (``ranged`` per teammate) for every
        track, up to a factor common to each teammate's filter.

        With the range sensor seeing only inside ``±f`` (``range_in_view``) and ranging a
        teammate there with probability ``P_D``, a track whose azimuth lies inside with
        probability ``p_in`` (:meth:`_track_detection`) explains a range with ``P_D·p_in``
        and its absence with ``1 − P_D·p_in``. The common ``P_D`` of the first is dropped:
        the births of the same scan, at a measured bearing, are inside by construction and
        carry it too. A track out of view therefore loses its weight when its teammate is
        ranged, and one in view when it is not."""
        st = self.settings
        p_in = self._track_detection(np.ones(len(self.teammates)))
        ranged_track = ranged[self.tracks.groups]
        return np.where(ranged_track, p_in, 1.0 - st.formation.p_detect * p_in)

    def _known_density(
        self, kind: Literal["height", "range"], z: Array, mean: Array, cov: Array
    ) -> tuple[Array, Array, Array, Array, float]:
        """Innovation ``ν``, Jacobian ``H``, noise ``R`` of a known-correspondence reading ``z``
        (one per track ``mean, cov``), the valid density ``(1 − ε) N(ν; 0, S)`` and the outlier
        density ``ε / V_z`` (module docstring)."""
        n = mean.shape[0]
        if kind == "height":
            H = np.broadcast_to(_H_HEIGHT, (n, 1, 4))
            pred = mean[:, 2:3]
            var = self.settings.sigma_height**2
        elif kind == "range":
            H = _jacobian(mean)[:, :1, :]
            pred = range_bearing(mean)[:, :1]
            var = self.settings.sigma_range**2
        else:
            raise ConfigError(f"update_known: kind must be 'height' or 'range', got {kind!r}")
        R = np.full((n, 1, 1), var)
        nu = z[:, None] - pred
        S = H @ cov @ np.swapaxes(H, -1, -2) + R
        eps = self.settings.known_outlier_probability
        valid = (1.0 - eps) * _gaussian_density(nu, S)
        return nu, H, R, valid, eps / self.settings.known_span(kind)

    def update_bearings(self, bearings: ArrayLike, ranges: ArrayLike, heights: ArrayLike) -> None:
        """Gate, form and update with a bearing set of unknown correspondence.

        ``bearings`` (m, 2) or (m, 1) (azimuth[, elevation]); ``ranges`` and ``heights`` per
        teammate (NaN: not measured this scan) are used to initialise new tracks (Eq. 13).
        """
        st = self.settings
        nb = len(st.bearing_rows)
        Z = np.asarray(bearings, dtype=float).reshape(-1, nb)
        if not np.isfinite(Z).all():
            raise DataError(f"fuser {self.robot} t={self.time:.3f}: non-finite bearing")
        r = self._per_teammate(ranges, "ranges")
        h = self._per_teammate(heights, "heights")
        p_det = self._bearing_detection(r)
        m = Z.shape[0]
        t = self.tracks
        k = t.size
        gated = np.zeros((k, m), dtype=bool)
        near = np.zeros((k, m), dtype=bool)
        parts: list[Tracks] = []
        if k and m:
            hz = range_bearing(t.means)[:, st.bearing_rows]
            H = _jacobian(t.means)[:, st.bearing_rows, :]
            R = st.bearing_noise
            S = H @ t.covs @ np.swapaxes(H, -1, -2) + R
            nu = Z[None, :, :] - hz[:, None, :]
            nu[..., 0] = wrap_angle(nu[..., 0])
            S_gate = modified_gate_covariance(
                S, H, t.covs[:, _YAW, _YAW], self._speed[t.groups], st.gate
            )
            d2 = mahalanobis_batch(nu, S_gate[:, None, :, :])
            gated = d2 <= chi2_threshold(nb, st.gate.p_gate)
            near = d2 <= chi2_threshold(nb, st.gate.p_birth_exclusion)
            lik = _gaussian_density(nu, np.broadcast_to(S[:, None], (k, m, nb, nb)))
            p_track = self._track_detection(p_det)
            kappa = self._false_density(lik, m, p_det, p_track)
            w_fa, w_det = formation_weights(
                t.weights, lik, gated, st.formation, kappa[t.groups], p_detect=p_track
            )
            fa = t.with_arrays(
                weights=w_fa,
                assoc=np.full(k, -1, dtype=np.int64),
                history=branch(t.history, np.arange(k), self._ids(k)),
            )
            parts.append(fa)
            hi, ri = np.nonzero(gated)
            if hi.size:
                new_m, new_P, _ = kalman_update(
                    t.means[hi],
                    t.covs[hi],
                    nu[hi, ri],
                    H[hi],
                    np.broadcast_to(R, (hi.size, nb, nb)),
                    where=f"fuser {self.robot} bearings t={self.time:.3f}",
                )
                det = Tracks(
                    groups=t.groups[hi],
                    means=new_m,
                    covs=new_P,
                    prior_means=t.prior_means[hi],
                    prior_covs=t.prior_covs[hi],
                    weights=w_det[hi, ri],
                    history=branch(t.history, hi, self._ids(hi.size)),
                    assoc=ri.astype(np.int64),
                )
                parts.append(det)
        elif k:
            # no bearing at all: every track is a false-alarm branch with the factor
            # (1 − P_D P_G); without a field of view it is the same for all tracks of a
            # filter and normalisation cancels it, so only the associations change
            weights = t.weights
            if st.field_of_view is not None:
                weights = weights * (1.0 - self._track_detection(p_det) * st.formation.p_gate)
            self.tracks = t.with_arrays(weights=weights, assoc=np.full(k, -1, dtype=np.int64))
            return
        if m:
            if not k:
                kappa = self._false_density(np.zeros((0, m)), m, p_det)
            parts.extend(self._births(Z, r, h, near, kappa, p_det))
        if parts:
            self.tracks = Tracks.concat(parts)

    def _false_density(
        self, lik: Array, m: int, p_det: Array, p_track: Array | None = None
    ) -> Array:
        """``κ[j, b]``: density at bearing ``b`` of everything that is not teammate ``j``.

        Clutter (``expected_clutter/V``) plus ``P_D`` (``p_det``, per teammate) times the
        predicted bearing density of every other teammate: the mixture
        ``Σ_h w_h N(z_b; ẑ_h, S_h)`` of its filter when it has tracks, uniform ``1/V`` while it
        has none. A bearing that another teammate's tracks explain is therefore weak evidence
        for ``j`` (no ghost track of ``j`` can feed on it). With a field of view each track's
        density is weighted by its own ``P_D`` (``p_track``, :meth:`_track_detection`).
        """
        st = self.settings
        n_team = len(self.teammates)
        t = self.tracks
        dens = np.zeros((n_team, m))
        tracked = np.zeros(n_team, dtype=bool)
        if st.field_of_view is not None and p_track is not None and t.size:
            w = t.normalised_weights()
            np.add.at(dens, t.groups, (w * p_track)[:, None] * lik)
            tracked[t.groups] = True
            dens[~tracked] = p_det[~tracked, None] / st.bearing_volume
        else:
            if t.size:
                w = t.normalised_weights()
                np.add.at(dens, t.groups, w[:, None] * lik)
                tracked[t.groups] = True
            dens[~tracked] = 1.0 / st.bearing_volume
            dens *= p_det[:, None]
        others = dens.sum(axis=0)[None, :] - dens
        clutter = max(st.expected_clutter, MIN_EXPECTED_CLUTTER) / st.bearing_volume
        return clutter + others

    def _births(
        self, Z: Array, r: Array, h: Array, near: NDArray[np.bool_], kappa: Array, p_det: Array
    ) -> list[Tracks]:
        """New tracks (Eq. 13) from bearings outside the birth-exclusion gate of every track
        of each teammate's filter."""
        st = self.settings
        t = self.tracks
        n_team = len(self.teammates)
        # hit[j, b]: bearing b lies in the gate of some track of teammate j
        hit = np.zeros((n_team, Z.shape[0]), dtype=bool)
        if t.size:
            np.logical_or.at(hit, t.groups, near)
        usable = np.isfinite(r) & (r > 0.0) & np.isfinite(h) & (p_det > 0.0)
        jj, bb = np.nonzero(~hit & usable[:, None])
        if jj.size == 0:
            return []
        beta = Z[bb, 1] if st.use_elevation else np.arcsin(np.clip(h[jj] / r[jj], -1.0, 1.0))
        means, covs, w = birth_tracks(
            r[jj],
            Z[bb, 0],
            beta,
            h[jj],
            st.formation,
            volume=st.bearing_volume,
            range_volume=st.known_span("range"),
            false_density=kappa[jj, bb],
            p_detect=p_det[jj],
        )
        K = st.formation.birth_yaw_components
        jj, bb = np.repeat(jj, K), np.repeat(bb, K)
        ids = self._ids(jj.size)
        return [
            Tracks(
                groups=jj.astype(np.int64),
                means=means,
                covs=covs,
                prior_means=means.copy(),
                prior_covs=covs.copy(),
                weights=w,
                history=new_history(ids, st.nscan_depth),
                assoc=bb.astype(np.int64),
            )
        ]

    def decide(self, bearings: ArrayLike, ranges: ArrayLike | None = None) -> IntArray:
        """Joint (global-nearest-neighbour) decision: which bearing is which teammate.

        The filters weigh every association separately; this one-to-one decision uses the
        dominant track of every filter *before* the update: cost
        ``−log(P_D N(z_b; ẑ_j, S_j)/κ)`` inside the gate (κ: clutter density), ``−log(1 − P_D P_G)``
        for no bearing, solved by :func:`relloc.association.assignment.assign`. ``ranges`` (per
        teammate) give the scan's ``P_D`` when ``ranges_mark_detections``. Returns, per
        teammate, the bearing index or −1.
        """
        st = self.settings
        nb = len(st.bearing_rows)
        Z = np.asarray(bearings, dtype=float).reshape(-1, nb)
        n_team = len(self.teammates)
        p_det = self._bearing_detection(
            np.zeros(n_team) if ranges is None else self._per_teammate(ranges, "ranges")
        )
        t = self.tracks
        cost = np.full((n_team, Z.shape[0]), np.inf)
        if t.size and Z.shape[0]:
            dom = np.flatnonzero(heaviest_mask(t.weights, t.groups))
            mean, cov = t.means[dom], t.covs[dom]
            H = _jacobian(mean)[:, st.bearing_rows, :]
            S = H @ cov @ np.swapaxes(H, -1, -2) + st.bearing_noise
            nu = Z[None, :, :] - range_bearing(mean)[:, st.bearing_rows][:, None, :]
            nu[..., 0] = wrap_angle(nu[..., 0])
            d2 = mahalanobis_batch(nu, S[:, None, :, :])
            kappa = max(st.expected_clutter, MIN_EXPECTED_CLUTTER) / st.bearing_volume
            c = 0.5 * d2 + 0.5 * np.log(np.linalg.det(2.0 * np.pi * S))[:, None]
            owner_pd = self._track_detection(p_det)[dom]
            p_det = p_det.copy()
            p_det[t.groups[dom]] = owner_pd
            with np.errstate(divide="ignore"):
                c += np.log(kappa) - np.log(owner_pd)[:, None]
            inside = (d2 <= chi2_threshold(nb, st.gate.p_gate)) & (owner_pd > 0.0)[:, None]
            cost[t.groups[dom]] = np.where(inside, c, np.inf)
        miss = -np.log(1.0 - p_det * st.formation.p_gate)
        return assign(cost, miss)

    def direct_scan(self, heights: ArrayLike, ranges: ArrayLike, bearings: ArrayLike) -> None:
        """One direct-fusion scan: height, range, then bearings, then reduction.

        The weights are left unnormalised between the sensors and normalised by the reduction.
        The joint decision of :meth:`decide` (on the predicted tracks) is kept in
        ``last_decision``.
        """
        self.last_decision = self.decide(bearings, ranges)
        self._scan_time = self.time
        self._scan_known = {
            "height": self._per_teammate(heights, "height"),
            "range": self._per_teammate(ranges, "range"),
        }
        self.update_known("height", heights)
        self.update_known("range", ranges)
        self.update_bearings(bearings, ranges, heights)
        self.reduce()

    # ------------------------------------------------------------------ reduction

    def reduce(self) -> None:
        """Delete unusable tracks (too far, too uncertain, or of a filter whose weights all
        underflowed to 0), prune, N-scan prune, merge and cap every filter (§II-D.5)."""
        st = self.settings
        t = self.tracks
        if t.size == 0:
            return
        usable = (np.linalg.norm(t.means[:, :3], axis=1) <= st.max_range) & (
            np.trace(t.covs[:, :3, :3], axis1=1, axis2=2) <= st.max_position_sigma**2
        )
        # a filter whose every track has weight 0 (each density it was given underflowed) says
        # nothing about where its teammate is: it is emptied and waits for new births
        total = np.bincount(t.groups, weights=t.weights, minlength=len(self.teammates))
        usable &= total[t.groups] > 0.0
        t = t.take(np.flatnonzero(usable))
        self.tracks = t
        if t.size == 0:
            return
        self._normalise()
        t = self.tracks
        keep = prune_mask(t.weights, st.prune_weight, t.groups)
        t = t.take(np.flatnonzero(keep))
        t = t.take(
            np.flatnonzero(family_keep_mask(t.history, t.weights, st.nscan_weight, t.groups))
        )
        if t.size > 1:
            t = self._merge(
                t.take(np.flatnonzero(cap_mask(t.weights, 4 * st.max_components, t.groups)))
            )
            t = t.take(np.flatnonzero(cap_mask(t.weights, st.max_components, t.groups)))
        self.tracks = t
        self._normalise()

    def _merge(self, sub: Tracks) -> Tracks:
        """Moment-preserving Mahalanobis merging within each filter (priors merged alike)."""
        clusters = merge_groups(
            sub.means,
            sub.covs,
            sub.weights,
            self.settings.merge_threshold,
            angle_index=_YAW,
            groups=sub.groups,
        )
        if len(clusters) == sub.size:
            return sub
        out = sub.take([g[0] for g in clusters])
        for n, g in enumerate(clusters):
            if g.size == 1:
                continue
            out.means[n], out.covs[n], out.weights[n] = merge_moments(
                sub.means, sub.covs, sub.weights, g, angle_index=_YAW
            )
            out.prior_means[n], out.prior_covs[n], _ = merge_moments(
                sub.prior_means, sub.prior_covs, sub.weights, g, angle_index=_YAW
            )
        return out

    # ------------------------------------------------------------------ queries

    def mixture(self, robot: int) -> GaussianMixture | None:
        """``GSF^(i,robot)`` as a :class:`GaussianMixture` (``None`` while it has no track)."""
        j = self.teammate_index(robot)
        sel = np.flatnonzero(self.tracks.groups == j)
        if sel.size == 0:
            return None
        t = self.tracks
        return GaussianMixture(means=t.means[sel], covs=t.covs[sel], weights=t.weights[sel])

    def summary(self, robot: int) -> TrackSummary | None:
        """The dominant track of ``GSF^(i,robot)`` and whether it is confirmed."""
        j = self.teammate_index(robot)
        sel = np.flatnonzero(self.tracks.groups == j)
        if sel.size == 0:
            return None
        t = self.tracks
        best = self._dominant(sel)
        return TrackSummary(
            belief=Gaussian(mean=t.means[best], cov=t.covs[best]),
            weight=float(t.weights[best]),
            components=int(sel.size),
            confirmed=self._confirmed(best),
            assoc=int(t.assoc[best]),
        )

    def _dominant(self, sel: IntArray) -> int:
        """The heaviest of the tracks ``sel`` (one filter's, not empty)."""
        return int(sel[np.argmax(self.tracks.weights[sel])])

    def _confirmed(self, track: int) -> bool:
        """Whether ``track`` passes the confirmation thresholds (weight, position and yaw
        standard deviations) of :class:`GaussianSumSettings`."""
        st = self.settings
        P = self.tracks.covs[track]
        return bool(
            self.tracks.weights[track] >= st.confirm_weight
            and np.sqrt(np.trace(P[:3, :3])) <= st.confirm_position_sigma
            and np.sqrt(P[_YAW, _YAW]) <= st.confirm_yaw_sigma
        )

    # ------------------------------------------------------------------ communication

    def broadcast(self) -> list[EquivalentMeasurement]:
        """Equivalent measurements of every filter (Eq. 8), or with ``share_confirmed_only``
        of every filter whose dominant track is confirmed; resets the broadcast priors of the
        filters sent."""
        t = self.tracks
        out = []
        sent = np.zeros(t.size, dtype=bool)
        for j, robot in enumerate(self.teammates):
            sel = np.flatnonzero(t.groups == j)
            if sel.size == 0:
                continue
            if self.settings.share_confirmed_only and not self._confirmed(self._dominant(sel)):
                continue
            sent[sel] = True
            out.append(
                EquivalentMeasurement(
                    sender=self.robot,
                    subject=robot,
                    time=self.time,
                    means=t.means[sel],
                    covs=t.covs[sel],
                    prior_means=t.prior_means[sel],
                    prior_covs=t.prior_covs[sel],
                    weights=t.weights[sel],
                )
            )
        self.tracks = t.with_arrays(
            prior_means=np.where(sent[:, None], t.means, t.prior_means),
            prior_covs=np.where(sent[:, None, None], t.covs, t.prior_covs),
        )
        return out

    def fuse(self, msg: EquivalentMeasurement) -> str:
        """Fuse a teammate's message; returns ``"mutual"``, ``"indirect"`` or ``"skipped"``.

        Mutual (Eq. 9–10): ``msg`` is ``j``'s belief of this robot, inverted with ⊖.
        Indirect (Eq. 11–12): ``msg`` is ``l``'s belief of a teammate ``j``, composed with this
        fuser's tracks of ``l`` (those above ``registration_weight``, weight ``w'_{il} w_{lj}``).
        A message about a robot this fuser does not track, from a sender it has no track of
        yet, or an indirect one without ``indirect_fusion``, is skipped.
        """
        if msg.sender == self.robot:
            raise DataError(f"fuser {self.robot}: received its own message")
        if msg.subject == self.robot:
            j = self.teammate_index(msg.sender)
            means, covs = invert_beliefs(msg.means, msg.covs)
            pmeans, pcovs = invert_beliefs(msg.prior_means, msg.prior_covs)
            self._fuse_tracks(j, means, covs, pmeans, pcovs, msg.weights)
            return "mutual"
        if (
            not self.settings.indirect_fusion
            or msg.subject not in self._index
            or msg.sender not in self._index
        ):
            return "skipped"
        j = self._index[msg.subject]
        l_idx = self._index[msg.sender]
        t = self.tracks
        reg = np.flatnonzero((t.groups == l_idx) & (t.weights >= self.settings.registration_weight))
        if reg.size == 0:
            return "skipped"
        parts_m, parts_P, parts_pm, parts_pP, parts_w = [], [], [], [], []
        for k in reg:
            m, P, from_a = compose_beliefs(t.means[k], t.covs[k], msg.means, msg.covs)
            pm, pP = register_prior(t.means[k], msg.prior_means, msg.prior_covs, from_a)
            parts_m.append(m)
            parts_P.append(P)
            parts_pm.append(pm)
            parts_pP.append(pP)
            parts_w.append(t.weights[k] * msg.weights)
        self._fuse_tracks(
            j,
            np.concatenate(parts_m),
            np.concatenate(parts_P),
            np.concatenate(parts_pm),
            np.concatenate(parts_pP),
            np.concatenate(parts_w),
        )
        return "indirect"

    def _fuse_tracks(
        self,
        j: int,
        means: Array,
        covs: Array,
        prior_means: Array,
        prior_covs: Array,
        weights: Array,
    ) -> None:
        """Gate, form, fuse and reduce received tracks into ``GSF^(i,j)``.

        A received track ``b`` (``w'_b``, ``N(x_b, P_b)``) and a local track ``h`` (``w_h``,
        ``N(x_h, P_h)``) pair when ``d²(x_b − x_h; P_h + P_b) ≤ γ`` (``P_G``); their states are
        fused with the de-correlation of Eq. 10. Eq. 10's formation scores the pair by
        ``λ_hb = w'_b N(x_b − x_h; 0, P_h + P_b)``, the local track left unpaired by
        ``λ_h0 = (1 − P_G) N_γ(P_h + Σ_b w'_b P_b)``, and a received track in no gate is born
        with ``β_b = P_B w'_b N_γ(P_b)`` (if :meth:`_scan_admits` it).

        Eq. 10 multiplies ``w_h`` by ``λ``, i.e. takes the sender's weights as evidence
        independent of the receiver's. They are not: every fuser predicts ``j`` with the same
        communicated odometry ``u_j`` (Eq. 5), from which the relative motion — the evidence
        that tells heading hypotheses apart — is computed, and both hold what they exchanged
        before. Eq. 10 removes that shared part from the states (the broadcast prior), but the
        weights carry no broadcast prior (Eq. 8) to remove it with, so the product counts it
        again every fusion period: a hypothesis the receiver's own scans still support but
        the sender has dropped is cut by ``λ_h0 / λ_hb`` each period and pruned, and two fusers
        leaning to the same wrong heading (after a kidnap) lock each other onto it. Here a
        message only redistributes each local hypothesis's weight among its outcomes,

            w_hk = w_h λ_hk / Σ_k' λ_hk'     (k = 0 or a gated b),

        so the states fuse as in Eq. 10 while which local hypothesis is right is left to the
        direct scans (Eq. 7); a birth keeps its share ``β_b / (Σ_h w_h Σ_k λ_hk + Σ_b β_b)`` of
        Eq. 10's whole mixture. With one local track the result equals Eq. 10's.
        """
        st = self.settings
        t = self.tracks
        mine = np.flatnonzero(t.groups == j)
        others = t.take(np.flatnonzero(t.groups != j))
        gamma = chi2_threshold(4, st.gate.p_gate)
        local = t.take(mine)
        n_loc, n_rx = local.size, weights.size
        parts: list[Tracks] = [others]
        gated = np.zeros((n_loc, n_rx), dtype=bool)
        if n_loc:
            rx_aligned = align_angles(
                np.broadcast_to(means[None], (n_loc, n_rx, 4)), local.means[:, None, :], _YAW
            )
            diff = rx_aligned - local.means[:, None, :]
            S = local.covs[:, None] + covs[None, :]
            d2 = mahalanobis_batch(diff, S)
            gated = d2 <= gamma
            dens = _gaussian_density(diff, S)
            S_mean = local.covs + np.einsum("k,kij->ij", weights, covs)[None]
            unpaired = (1.0 - st.gate.p_gate) * _edge_density(S_mean, gamma)
            paired = np.where(gated, weights[None, :] * dens, 0.0)
            evidence = unpaired + paired.sum(axis=1)  # Σ_k λ_hk
            share = 1.0 / evidence
            keep = local.with_arrays(
                weights=local.weights * unpaired * share,
                history=branch(local.history, np.arange(n_loc), self._ids(n_loc)),
            )
            parts.append(keep)
            hi, ri = np.nonzero(gated)
            if hi.size:
                fused = local.take(hi)
                for n, (a, b) in enumerate(zip(hi, ri, strict=True)):
                    fused.means[n], fused.covs[n] = self._fuse_pair(
                        local.means[a],
                        local.covs[a],
                        means[b],
                        covs[b],
                        prior_means[b],
                        prior_covs[b],
                    )
                    fused.prior_means[n], fused.prior_covs[n] = self._fuse_pair(
                        local.prior_means[a],
                        local.prior_covs[a],
                        means[b],
                        covs[b],
                        prior_means[b],
                        prior_covs[b],
                    )
                fused = fused.with_arrays(
                    weights=local.weights[hi] * paired[hi, ri] * share[hi],
                    history=branch(local.history, hi, self._ids(hi.size)),
                )
                parts.append(fused)
        free = np.flatnonzero(~gated.any(axis=0)) if n_loc else np.arange(n_rx)
        free = free[self._scan_admits(j, means[free], covs[free])]
        if free.size:
            born = st.formation.p_birth * weights[free] * _edge_density(covs[free], gamma)
            if n_loc:
                # on the scale where the local part sums to Σ_h w_h = 1
                born = born / np.sum(local.weights * evidence)
            ids = self._ids(free.size)
            parts.append(
                Tracks(
                    groups=np.full(free.size, j, dtype=np.int64),
                    means=means[free].copy(),
                    covs=covs[free].copy(),
                    prior_means=means[free].copy(),
                    prior_covs=covs[free].copy(),
                    weights=born,
                    history=new_history(ids, st.nscan_depth),
                    assoc=np.full(free.size, -1, dtype=np.int64),
                )
            )
        self.tracks = Tracks.concat(parts)
        self._normalise()
        self.reduce()

    def _scan_admits(self, j: int, means: Array, covs: Array) -> NDArray[np.bool_]:
        """Which received tracks of ``GSF^(i,j)`` this fuser's own direct scan of the same
        instant admits (all when the tracks were predicted since the scan, or it read no
        height nor range of ``j``).

        A received track in no local gate is a hypothesis this fuser does not hold. It is born
        only if it explains the height and range this fuser itself measured of ``j`` at this
        instant: more likely valid than an outlier, ``(1 − ε) N(z; ẑ, H P Hᵀ + R) ≥ ε / V_z``,
        the test :meth:`update_known` applies before updating a track. The sender's track is a
        posterior (Eq. 8) that may rest on readings that are out of date — a teammate that has
        not yet seen a jump of ``j`` still broadcasts its old, confident track — while the
        receiver's reading is current; Eq. 13 likewise weighs a direct birth by the reading
        (height) not used to form it. Without the test such a track, its covariance ``P``
        small, is born with the weight ``P_B w' N_γ(P)`` of a tight Gaussian at its gate edge
        and, normalised, displaces the receiver's re-found tracks before its next scan can
        refute it.
        """
        ok = np.ones(means.shape[0], dtype=bool)
        if self.time != self._scan_time or means.shape[0] == 0:
            return ok
        for kind in ("height", "range"):
            z = self._scan_known[kind][j]
            if np.isfinite(z):
                _, _, _, valid, outlier = self._known_density(
                    kind, np.full(means.shape[0], z), means, covs
                )
                ok &= valid >= outlier
        return ok

    def _fuse_pair(
        self,
        x: Array,
        P: Array,
        x_post: Array,
        P_post: Array,
        x_prior: Array,
        P_prior: Array,
    ) -> tuple[Array, Array]:
        if self.settings.fusion == "ci":
            x_rx = x + pose_difference(x_post, x, _YAW)
            fused_x, fused_P, _ = covariance_intersection(x, P, x_rx, P_post)
            return fused_x, fused_P
        return decorrelated_fusion(x, P, x_post, P_post, x_prior, P_prior, angle_index=_YAW)
