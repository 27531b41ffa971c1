"""Multi-rate switching EKF of a follower UGV (seed 003, Section 3.1 and Algorithm 1).

Follower ``R_i`` estimates ``x = [r_x, r_y, θ_i, θ_0]`` (:mod:`relloc.models.airground`; the
frame ``airground_follower`` of :mod:`relloc.pipeline.frames`) and implements the estimator
contract (:mod:`relloc.core.contract`):

- :meth:`SwitchingEkf.advance` predicts with Eq. 3 from both robots' commands — its own and the
  leader's ``(v, 0, 0, ω)`` rows of the held odometry, ``u = [v_i, ω_i, v_0, ω_0]``;
- :meth:`SwitchingEkf.measure` builds the tick's :class:`TickInputs` from the batch — the
  ``range`` rows between UGVs (its own range to the leader, the leader's and its own ranges to
  the other followers) and the drones' ``pair_sighting`` rows of pairs {R_0, R_j} — and picks
  the measurement model of Eq. 4 from the set ``S`` of detected pairs the drones broadcast:

  - ``sw = 1`` — ``{R_0, R_i} ∈ S``: ``[d, φ, θ_i, θ_0]``;
  - ``sw = 2`` — ``S ≠ ∅`` but not its own pair: ``[d, φ̄, θ_0]`` with φ̄ from the triangle of
    Fig. 3 (:func:`relloc.geometry.triangle_bearing`), using the detected pair whose triangle is
    best conditioned (largest ``sin α_0``);
  - ``sw = 3`` — ``S = ∅``: ``[d]``.

  A drone broadcasts ``S`` with every camera frame, so a pair stays in ``S`` for one frame
  period after its sighting (:attr:`SwitchingEkfSettings.sighting_hold`); a frame that does not
  see it again drops it;
- :meth:`SwitchingEkf.beliefs` gives the belief of the leader with the mode ``sw`` in force in
  its ``info``; :meth:`SwitchingEkf.take_updates` one record per block update (NIS and its
  dof, conditioning of ``R`` and ``S``); :meth:`SwitchingEkf.take_counts` the blocks applied
  and gated out per kind, the triangle refusals and the rows it could not use.

Multi-rate: the filter ticks faster than the UWB and the camera; a component enters only when a
fresh reading arrived this tick (a tick may carry nothing and is a pure prediction).

Update blocks. The range noise is independent of the camera's, so ``sw = 1`` is applied as two
sequential blocks ``[d]`` and ``[φ, θ_i, θ_0]`` (exact for block-diagonal R). In ``sw = 2`` the
derived bearing φ̄ depends on ``d_0i`` itself (and on ``d_0j``, ``d_ij``, φ_j), so ``[d, φ̄]`` is one
block whose covariance is propagated exactly, ``R = J diag(σ_d², σ_φ², σ_d², σ_d²) Jᵀ`` with ``J``
the Jacobian of ``(d_0i, φ̄)`` w.r.t. ``(d_0i, φ_j, d_0j, d_ij)``; θ_0 is a second block. If the
triangle is refused (near-collinear, inconsistent ranges) the block falls back to ``[d]`` and the
refusal is counted.

Outliers. UWB ranges have a heavy positive tail (:mod:`relloc.models.uwb_noise`). Each block
is χ²-gated: it is applied only if its NIS ``νᵀS⁻¹ν`` is below the ``gate_probability``
quantile of χ²(m); rejections are counted per block kind. Angle residuals are wrapped. Gate and
update are :func:`relloc.core.kalman.gated_update`: ``S`` and the NIS first, then the Joseph-form
update only for an accepted block.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from relloc.core.angles import wrap_angle
from relloc.core.checks import number, positive, probability
from relloc.core.contract import Belief, HeldOdometry, Silent, UpdateRecord
from relloc.core.events import TIME_TOL, elapsed
from relloc.core.gaussian import Gaussian
from relloc.core.kalman import gated_update, prepare_gates
from relloc.core.linalg import condition_log10
from relloc.core.recording import Measurements, kind_code
from relloc.errors import ConfigError, DataError
from relloc.geometry.triangle import TriangleBearing, triangle_bearing
from relloc.models.airground import (
    STATE_DIM,
    TH_0,
    TH_I,
    Mode,
    bearing_h,
    heading_h,
    process_noise,
    range_h,
    relative_step,
)

Array = NDArray[np.float64]
#: Block kinds counted by the filter, with their measurement dimension.
BLOCK_DIMS = {"range": 1, "camera": 3, "triangle": 2, "leader_heading": 1}
BLOCKS = tuple(BLOCK_DIMS)
#: Name of the estimator (``Estimates.estimator``) and the frame of its beliefs.
NAME = "switching_ekf"
FRAME = "airground_follower"


@dataclass(frozen=True, kw_only=True)
class SwitchingEkfSettings:
    """Noise levels the filter assumes, calibration, gate. Lengths in m, angles in rad.

    ``sighting_hold`` (s): how long a pair sighting keeps its pair in the broadcast set ``S`` —
    the drones' camera frame period (a frame that does not see the pair again drops it).
    """

    sigma_v: float = 0.02
    sigma_w: float = 0.04
    range_sigma: float = 0.08
    range_bias: float = 0.0
    bearing_sigma: float = 0.03
    heading_sigma: float = 0.03
    gate_probability: float | None = 0.999
    min_sin: float = 0.2
    sighting_hold: float = 0.1

    def __post_init__(self) -> None:
        for name in (
            "sigma_v",
            "sigma_w",
            "range_sigma",
            "bearing_sigma",
            "heading_sigma",
            "sighting_hold",
        ):
            positive(getattr(self, name), f"SwitchingEkfSettings.{name}")
        number(self.range_bias, "SwitchingEkfSettings.range_bias")
        if self.gate_probability is not None:
            probability(self.gate_probability, "SwitchingEkfSettings.gate_probability")
        probability(self.min_sin, "SwitchingEkfSettings.min_sin")


@dataclass(frozen=True, kw_only=True)
class PairSighting:
    """A drone's broadcast for one detected pair {R_0, R_j} (a ``pair_sighting`` row): bearing
    φ_j of ``p_0 − p_j`` in F_G and the headings θ_j, θ_0 it read from the patterns; ``follower``
    is R_j's robot index."""

    follower: int
    bearing: float
    heading_follower: float
    heading_leader: float


@dataclass(frozen=True, kw_only=True)
class TickInputs:
    """Everything follower ``i`` received in one filter tick, taken from the batch.

    ``detected``: the followers j (robot indices) whose pair {R_0, R_j} is in the drones' broadcast
    set S (held between camera frames; it sets sw); ``range_0i``: own fresh raw UWB range to the
    leader (None if none this tick); ``ranges_0j[j]`` / ``ranges_ij[j]``: fresh raw ranges
    leader–R_j and R_i–R_j of the team; ``sightings``: the pair readings of a camera frame taken
    this tick (empty between frames), in the order of the batch.
    """

    detected: tuple[int, ...] = ()
    range_0i: float | None = None
    ranges_0j: Mapping[int, float] = field(default_factory=dict)
    ranges_ij: Mapping[int, float] = field(default_factory=dict)
    sightings: tuple[PairSighting, ...] = ()


def select_mode(follower: int, detected: tuple[int, ...]) -> Mode:
    """Eq. 4 switching rule from the broadcast set S (given as the detected followers' ids)."""
    if follower in detected:
        return Mode.PAIR_SEEN
    if detected:
        return Mode.OTHER_PAIR_SEEN
    return Mode.NONE_SEEN


def predict(belief: Gaussian, u: Array, dt: float, settings: SwitchingEkfSettings) -> Gaussian:
    """EKF prediction with Eq. 3: ``x⁻ = f(x, u)``, ``P⁻ = F P Fᵀ + G Σ_u Gᵀ``."""
    F, Q = process_noise(belief.mean, u, dt, settings.sigma_v, settings.sigma_w)
    P = F @ belief.cov @ F.T + Q
    return Gaussian(relative_step(belief.mean, u, dt), 0.5 * (P + P.T))


@dataclass(frozen=True)
class BlockResult:
    """One gated block update: the belief after it, its NIS and whether it was applied."""

    belief: Gaussian
    nis: float
    dim: int
    accepted: bool


def block_update(
    belief: Gaussian,
    z: Array,
    h: Array,
    H: Array,
    R: Array,
    is_angle: tuple[bool, ...],
    gate_probability: float | None,
    *,
    where: str = "",
) -> BlockResult:
    """χ²-gated Joseph-form update of one block (residual ``z − h``, angles wrapped)."""
    residual = np.asarray(z, dtype=float) - np.asarray(h, dtype=float)
    for k, ang in enumerate(is_angle):
        if ang:
            residual[k] = float(wrap_angle(residual[k]))
    mean, cov, innov, accepted = gated_update(
        belief.mean, belief.cov, residual, H, R, gate_probability, where=where
    )
    after = Gaussian(mean, cov) if accepted else belief
    return BlockResult(after, float(innov.nis), len(z), accepted)


@dataclass
class BlockDiagnostics:
    """What the estimates record has no column for: the NIS of every block summed per block
    kind (applied or gated out; the counts say how many) and the first few reasons a triangle
    was refused."""

    nis_sum: dict[str, float] = field(default_factory=lambda: dict.fromkeys(BLOCKS, 0.0))
    refusal_examples: list[str] = field(default_factory=list)


#: How many triangle refusals keep their reason in :attr:`BlockDiagnostics.refusal_examples`.
MAX_REFUSAL_EXAMPLES = 5


class SwitchingEkf(Silent):
    """Follower ``owner``'s switching EKF of the leader (module docstring).

    ``robots``: the team's robot names, indexed as in the measurement rows; ``prior``: the
    belief at ``t0``; ``sides[name]``: on which side (±1) of the line R_0R_j the follower sits
    for each other follower R_j (from the formation layout; distances cannot tell).
    """

    name = NAME

    def __init__(
        self,
        *,
        robots: Sequence[str],
        owner: str,
        leader: str,
        prior: Gaussian,
        settings: SwitchingEkfSettings,
        sides: Mapping[str, int],
        t0: float = 0.0,
    ) -> None:
        names = tuple(robots)
        for role, robot in (("owner", owner), ("leader", leader), *(("sides", r) for r in sides)):
            if robot not in names:
                raise ConfigError(f"SwitchingEkf.{role}: unknown robot {robot!r}; team: {names}")
        if owner == leader:
            raise ConfigError(f"SwitchingEkf: {owner} cannot follow itself")
        if prior.mean.shape != (STATE_DIM,):
            raise DataError(f"SwitchingEkf {owner}: prior mean must have shape (4,)")
        for robot, side in sides.items():
            if side not in (1, -1):
                raise ConfigError(f"SwitchingEkf.sides[{robot!r}]: must be +1 or -1, got {side}")
        if not math.isfinite(t0):
            raise ConfigError(f"SwitchingEkf.t0: not finite ({t0})")
        self.owner = owner
        self.leader = leader
        self.settings = settings
        self.belief = prior
        self.diagnostics = BlockDiagnostics()
        self._names = names
        self._me = names.index(owner)
        self._leader = names.index(leader)
        self._sides = {names.index(r): side for r, side in sides.items()}
        self._t0 = float(t0)
        self._t = float(t0)
        self._last_sighting: dict[int, float] = {}
        self._updates: list[UpdateRecord] = []
        self._counts: dict[str, int] = {}
        # the gates' χ² quantiles of every block size, when the filter is built
        prepare_gates(BLOCK_DIMS.values(), settings.gate_probability)

    # ------------------------------------------------------------------ the estimator contract

    def advance(self, t: float, odometry: HeldOdometry) -> None:
        """Predict from the previous event to ``t`` with ``u = [v_i, ω_i, v_0, ω_0]``."""
        dt = elapsed(self._t, t, f"SwitchingEkf {self.owner}")
        if dt > 0.0:
            v = np.asarray(odometry.velocity, dtype=float)
            if v.shape != (len(self._names), 4):
                raise DataError(
                    f"SwitchingEkf {self.owner} at t={t:.3f}s: odometry of {v.shape[0]} robots "
                    f"for a team of {len(self._names)}"
                )
            u = v[[self._me, self._me, self._leader, self._leader], [0, 3, 0, 3]]
            if not np.all(np.isfinite(u)):
                raise DataError(f"SwitchingEkf {self.owner} at t={t:.3f}s: bad input u={u}")
            self.belief = predict(self.belief, u, dt, self.settings)
            self._t = float(t)

    def measure(self, batch: Measurements) -> None:
        """Update with the readings of the current tick (module docstring)."""
        self._update(self._tick_inputs(batch))

    def beliefs(self) -> list[Belief]:
        """The belief of the leader, with the mode ``sw`` in force in ``info``."""
        return [
            Belief(
                subject=self.leader,
                frame=FRAME,
                mean=self.belief.mean,
                cov=self.belief.cov,
                age=self._t - self._t0,
                info={"sw": float(self.mode())},
            )
        ]

    def take_updates(self) -> list[UpdateRecord]:
        out, self._updates = self._updates, []
        return out

    def take_counts(self) -> dict[str, int]:
        """Blocks applied / gated out per kind (``range_applied``, ``camera_rejected``, …),
        ``triangle_refusals`` and ``rows_ignored``, since the previous call."""
        out, self._counts = self._counts, {}
        return out

    # ------------------------------------------------------------------ the filter

    def detected(self) -> tuple[int, ...]:
        """The broadcast set S now: the followers whose pair was sighted within the hold."""
        hold = self.settings.sighting_hold - TIME_TOL
        return tuple(sorted(j for j, s in self._last_sighting.items() if self._t - s < hold))

    def mode(self) -> Mode:
        """The mode sw in force now (Eq. 4 from the broadcast set S)."""
        return select_mode(self._me, self.detected())

    def _count(self, key: str) -> None:
        self._counts[key] = self._counts.get(key, 0) + 1

    def _tick_inputs(self, batch: Measurements) -> TickInputs:
        """The tick's inputs from the rows of the batch (each sighting also refreshes its pair
        in the held set S); rows it cannot use are counted ``rows_ignored``, among them every
        range of a pair after the first of the tick (either direction: the pair is unordered)."""
        me, leader = self._me, self._leader
        ranges: dict[tuple[int, int], float] = {}
        sightings = []
        for k in range(batch.size):
            kind, a, b = int(batch.kind[k]), int(batch.observer[k]), int(batch.target[k])
            pair = (min(a, b), max(a, b))
            if kind == _RANGE and b >= 0 and (me in pair or leader in pair) and pair not in ranges:
                ranges[pair] = float(batch.value[k, 0])
            elif kind == _PAIR_SIGHTING and b != leader:
                bearing, heading_follower, heading_leader = (float(v) for v in batch.value[k])
                sightings.append(
                    PairSighting(
                        follower=b,
                        bearing=bearing,
                        heading_follower=heading_follower,
                        heading_leader=heading_leader,
                    )
                )
                self._last_sighting[b] = self._t
            else:
                self._count("rows_ignored")

        def ranges_from(hub: int) -> dict[int, float]:
            """Ranges hub–R_j for every robot j other than this follower and the leader."""
            out = {}
            for (a, b), d in ranges.items():
                j = b if a == hub else a if b == hub else None
                if j is not None and j not in (me, leader):
                    out[j] = d
            return out

        return TickInputs(
            detected=self.detected(),
            range_0i=ranges.get((min(me, leader), max(me, leader))),
            ranges_0j=ranges_from(leader),
            ranges_ij=ranges_from(me),
            sightings=tuple(sightings),
        )

    def _update(self, inputs: TickInputs) -> None:
        """Pick sw from the broadcast set S and update with the tick's fresh readings."""
        s = self.settings
        mode = select_mode(self._me, inputs.detected)
        d = None if inputs.range_0i is None else inputs.range_0i - s.range_bias
        own = [p for p in inputs.sightings if p.follower == self._me]
        others = [p for p in inputs.sightings if p.follower != self._me]
        if mode is Mode.PAIR_SEEN:
            if d is not None:
                self._range_block(d)
            if own:
                x = self.belief.mean
                parts = [bearing_h(x), heading_h(x, TH_I), heading_h(x, TH_0)]
                z = np.array([own[0].bearing, own[0].heading_follower, own[0].heading_leader])
                R = np.diag([s.bearing_sigma**2, s.heading_sigma**2, s.heading_sigma**2])
                h = np.array([p[0] for p in parts])
                H = np.vstack([p[1] for p in parts])
                self._apply("camera", z, h, H, R, (True, True, True))
        elif mode is Mode.OTHER_PAIR_SEEN:
            if d is not None and others:
                self._update_other_pair(inputs, others, d)
            elif d is not None:
                self._range_block(d)
            if others:
                th0, H0 = heading_h(self.belief.mean, TH_0)
                R = np.array([[s.heading_sigma**2]])
                z = np.array([others[0].heading_leader])
                self._apply("leader_heading", z, np.array([th0]), H0, R, (True,))
        elif d is not None:
            self._range_block(d)

    def _apply(
        self, kind: str, z: Array, h: Array, H: Array, R: Array, angles: tuple[bool, ...]
    ) -> None:
        """One gated block update, recorded (NIS, dof, conditioning of R and S) and counted."""
        prior = self.belief
        res = block_update(
            prior,
            z,
            h,
            H,
            R,
            angles,
            self.settings.gate_probability,
            where=f"{self.owner} {kind} update at t={self._t:.3f}s",
        )
        self.belief = res.belief
        self._updates.append(
            UpdateRecord(
                t=self._t,
                subject=self.leader,
                nis=res.nis,
                dof=res.dim,
                cond_r=condition_log10(R),
                cond_s=condition_log10(H @ prior.cov @ H.T + R),
                age=self._t - self._t0,
            )
        )
        self.diagnostics.nis_sum[kind] += res.nis
        self._count(f"{kind}_{'applied' if res.accepted else 'rejected'}")

    def _range_block(self, d: float) -> None:
        dh, Hd = range_h(self.belief.mean)
        R = np.array([[self.settings.range_sigma**2]])
        self._apply("range", np.array([d]), np.array([dh]), Hd, R, (False,))

    def _update_other_pair(self, inputs: TickInputs, others: list[PairSighting], d: float) -> None:
        """sw = 2: joint ``[d_0i, φ̄]`` block from the best-conditioned triangle (or ``[d]``)."""
        s = self.settings
        best: TriangleBearing | None = None
        reasons = []
        for sighting in others:
            j = sighting.follower
            name = self._names[j]
            if j not in inputs.ranges_0j or j not in inputs.ranges_ij or j not in self._sides:
                reasons.append(f"{name}: ranges to {name} not fresh")
                continue
            tri = triangle_bearing(
                sighting.bearing,
                inputs.ranges_0j[j] - s.range_bias,
                d,
                inputs.ranges_ij[j] - s.range_bias,
                self._sides[j],
                min_sin=s.min_sin,
            )
            if not tri.ok:
                reasons.append(f"{name}: {tri.reason}")
                continue
            if best is None or math.sin(tri.interior_angle) > math.sin(best.interior_angle):
                best = tri
        if best is None or best.bearing is None:
            self._count("triangle_refusals")
            examples = self.diagnostics.refusal_examples
            if len(examples) < MAX_REFUSAL_EXAMPLES:
                examples.append(f"t={self._t:.2f}s: " + "; ".join(reasons))
            self._range_block(d)
            return
        g_phi, g_a, g_b, g_c = best.d_bearing  # ∂φ̄/∂(φ_j, d_0j, d_0i, d_ij)
        # raw w = (d_0i, φ_j, d_0j, d_ij); y = (d_0i, φ̄)
        J = np.array([[1.0, 0.0, 0.0, 0.0], [g_b, g_phi, g_a, g_c]])
        W = np.diag([s.range_sigma**2, s.bearing_sigma**2, s.range_sigma**2, s.range_sigma**2])
        R = J @ W @ J.T
        x = self.belief.mean
        dh, Hd = range_h(x)
        ph, Hp = bearing_h(x)
        self._apply(
            "triangle",
            np.array([d, best.bearing]),
            np.array([dh, ph]),
            np.vstack([Hd, Hp]),
            R,
            (False, True),
        )


_RANGE = kind_code("range")
_PAIR_SIGHTING = kind_code("pair_sighting")
