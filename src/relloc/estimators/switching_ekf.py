"""Multi-rate switching EKF of a follower UGV (seed 003, Section 3.1 and Algorithm 1).

Follower ``R_i`` estimates ``x = [r_x, r_y, θ_i, θ_0]`` (:mod:`relloc.models.airground`). Every
filter tick it predicts with Eq. 3 from both robots' commands; then it picks the measurement
model of Eq. 4 from what the drones broadcast this tick (the set ``S`` of detected pairs):

- ``sw = 1`` — ``{R_0, R_i} ∈ S``: ``[d, φ, θ_i, θ_0]``;
- ``sw = 2`` — ``S ≠ ∅`` but not its own pair: ``[d, φ̄, θ_0]`` with φ̄ from the triangle of
  Fig. 3 (:func:`relloc.geometry.triangle_bearing`), using the detected pair whose triangle is
  best conditioned (largest ``sin α_0``);
- ``sw = 3`` — ``S = ∅``: ``[d]``.

Multi-rate: the filter ticks faster than the UWB and the camera; a component enters only when a
fresh reading arrived this tick (a tick may carry nothing and is a pure prediction).

Update blocks. The range noise is independent of the camera's, so ``sw = 1`` is applied as two
sequential blocks ``[d]`` and ``[φ, θ_i, θ_0]`` (exact for block-diagonal R). In ``sw = 2`` the
derived bearing φ̄ depends on ``d_0i`` itself (and on ``d_0j``, ``d_ij``, φ_j), so ``[d, φ̄]`` is one
block whose covariance is propagated exactly, ``R = J diag(σ_d², σ_φ², σ_d², σ_d²) Jᵀ`` with ``J``
the Jacobian of ``(d_0i, φ̄)`` w.r.t. ``(d_0i, φ_j, d_0j, d_ij)``; θ_0 is a second block. If the
triangle is refused (near-collinear, inconsistent ranges) the block falls back to ``[d]`` and the
refusal is counted.

Outliers. UWB ranges have a heavy positive tail (:mod:`relloc.datasets.uwb_noise`). Each block
is χ²-gated: it is applied only if its NIS ``νᵀS⁻¹ν`` is below the ``gate_probability``
quantile of χ²(m); rejections are counted per block kind. Angle residuals are wrapped. Gate and
update are :func:`relloc.core.kalman.gated_update`: ``S`` and the NIS first, then the Joseph-form
update only for an accepted block.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from relloc.core.angles import wrap_angle
from relloc.core.gaussian import Gaussian
from relloc.core.kalman import gated_update
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


@dataclass(frozen=True, kw_only=True)
class SwitchingEkfSettings:
    """Noise levels the filter assumes, calibration, gate. Lengths in m, angles in rad."""

    sigma_v: float = 0.02
    sigma_w: float = 0.04
    range_sigma: float = 0.08
    range_bias: float = 0.0
    bearing_sigma: float = 0.03
    heading_sigma: float = 0.03
    gate_probability: float | None = 0.999
    min_sin: float = 0.2

    def __post_init__(self) -> None:
        for name in ("sigma_v", "sigma_w", "range_sigma", "bearing_sigma", "heading_sigma"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0.0):
                raise ConfigError(f"SwitchingEkfSettings.{name}: must be > 0, got {value!r}")
        if not math.isfinite(self.range_bias):
            raise ConfigError(f"SwitchingEkfSettings.range_bias: not finite ({self.range_bias})")
        if self.gate_probability is not None and not 0.0 < self.gate_probability < 1.0:
            raise ConfigError(
                "SwitchingEkfSettings.gate_probability: must be in (0, 1) or None, "
                f"got {self.gate_probability!r}"
            )
        if not 0.0 < self.min_sin < 1.0:
            raise ConfigError(
                f"SwitchingEkfSettings.min_sin: must be in (0, 1), got {self.min_sin}"
            )


@dataclass(frozen=True, kw_only=True)
class PairSighting:
    """A drone's broadcast for one detected pair {R_0, R_j}: bearing φ_j of ``p_0 − p_j`` in F_G
    and the headings θ_j, θ_0 it read from the patterns."""

    follower: int
    bearing: float
    heading_follower: float
    heading_leader: float


@dataclass(frozen=True, kw_only=True)
class TickInputs:
    """Everything follower ``i`` receives in one filter tick.

    ``u = [v_i, ω_i, v_0, ω_0]``; ``detected``: the followers j whose pair {R_0, R_j} is in the
    drones' latest broadcast set S (held between camera frames; it sets sw); ``range_0i``: own
    fresh raw UWB range to the leader (None if none this tick); ``ranges_0j[j]`` /
    ``ranges_ij[j]``: fresh raw ranges leader–R_j and R_i–R_j broadcast by the team;
    ``sightings``: the pair readings of a camera frame taken this tick (empty between frames);
    ``sides[j]``: on which side of the line R_0R_j follower i sits (formation layout, ±1).
    """

    u: Array
    detected: tuple[int, ...] = ()
    range_0i: float | None = None
    ranges_0j: Mapping[int, float] = field(default_factory=dict)
    ranges_ij: Mapping[int, float] = field(default_factory=dict)
    sightings: tuple[PairSighting, ...] = ()
    sides: Mapping[int, int] = field(default_factory=dict)


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
class FilterCounters:
    """Per-follower bookkeeping: ticks per mode, accepted/rejected blocks, triangle refusals."""

    mode_ticks: dict[int, int] = field(default_factory=lambda: {1: 0, 2: 0, 3: 0})
    accepted: dict[str, int] = field(default_factory=lambda: dict.fromkeys(BLOCKS, 0))
    rejected: dict[str, int] = field(default_factory=lambda: dict.fromkeys(BLOCKS, 0))
    triangle_refusals: int = 0
    refusal_examples: list[str] = field(default_factory=list)
    nis: dict[str, list[float]] = field(default_factory=lambda: {b: [] for b in BLOCKS})


class SwitchingEkf:
    """Thin stateful wrapper: one follower's belief, its settings and its counters."""

    def __init__(self, follower: int, prior: Gaussian, settings: SwitchingEkfSettings) -> None:
        if follower < 1:
            raise ConfigError(f"SwitchingEkf.follower: follower ids start at 1, got {follower}")
        if prior.mean.shape != (STATE_DIM,):
            raise DataError(f"SwitchingEkf R_{follower}: prior mean must have shape (4,)")
        self.follower = follower
        self.belief = prior
        self.settings = settings
        self.counters = FilterCounters()

    def _apply(
        self, kind: str, z: Array, h: Array, H: Array, R: Array, angles: tuple[bool, ...], t: float
    ) -> None:
        res = block_update(
            self.belief,
            z,
            h,
            H,
            R,
            angles,
            self.settings.gate_probability,
            where=f"R_{self.follower} {kind} update at t={t:.3f}s",
        )
        self.belief = res.belief
        self.counters.nis[kind].append(res.nis)
        (self.counters.accepted if res.accepted else self.counters.rejected)[kind] += 1

    def _range_block(self, d: float, t: float) -> None:
        dh, Hd = range_h(self.belief.mean)
        R = np.array([[self.settings.range_sigma**2]])
        self._apply("range", np.array([d]), np.array([dh]), Hd, R, (False,), t)

    def tick(self, inputs: TickInputs, dt: float, t: float) -> Mode:
        """Predict over ``dt``, pick sw from the broadcast set S, update with fresh readings."""
        s = self.settings
        u = np.asarray(inputs.u, dtype=float)
        if u.shape != (4,) or not np.all(np.isfinite(u)):
            raise DataError(f"SwitchingEkf R_{self.follower} at t={t:.3f}s: bad input u={u}")
        self.belief = predict(self.belief, u, dt, s)
        mode = select_mode(self.follower, inputs.detected)
        self.counters.mode_ticks[int(mode)] += 1
        d = None if inputs.range_0i is None else inputs.range_0i - s.range_bias
        own = [p for p in inputs.sightings if p.follower == self.follower]
        others = [p for p in inputs.sightings if p.follower != self.follower]
        if mode is Mode.PAIR_SEEN:
            if d is not None:
                self._range_block(d, t)
            if own:
                x = self.belief.mean
                parts = [bearing_h(x), heading_h(x, TH_I), heading_h(x, TH_0)]
                z = np.array([own[0].bearing, own[0].heading_follower, own[0].heading_leader])
                R = np.diag([s.bearing_sigma**2, s.heading_sigma**2, s.heading_sigma**2])
                h = np.array([p[0] for p in parts])
                H = np.vstack([p[1] for p in parts])
                self._apply("camera", z, h, H, R, (True, True, True), t)
        elif mode is Mode.OTHER_PAIR_SEEN:
            if d is not None and others:
                self._update_other_pair(inputs, others, d, t)
            elif d is not None:
                self._range_block(d, t)
            if others:
                th0, H0 = heading_h(self.belief.mean, TH_0)
                R = np.array([[s.heading_sigma**2]])
                z = np.array([others[0].heading_leader])
                self._apply("leader_heading", z, np.array([th0]), H0, R, (True,), t)
        elif d is not None:
            self._range_block(d, t)
        return mode

    def _update_other_pair(
        self, inputs: TickInputs, others: list[PairSighting], d: float, t: float
    ) -> None:
        """sw = 2: joint ``[d_0i, φ̄]`` block from the best-conditioned triangle (or ``[d]``)."""
        s = self.settings
        best: TriangleBearing | None = None
        reasons = []
        for sighting in others:
            j = sighting.follower
            if j not in inputs.ranges_0j or j not in inputs.ranges_ij or j not in inputs.sides:
                reasons.append(f"R_{j}: ranges to R_{j} not fresh")
                continue
            tri = triangle_bearing(
                sighting.bearing,
                inputs.ranges_0j[j] - s.range_bias,
                d,
                inputs.ranges_ij[j] - s.range_bias,
                inputs.sides[j],
                min_sin=s.min_sin,
            )
            if not tri.ok:
                reasons.append(f"R_{j}: {tri.reason}")
                continue
            if best is None or math.sin(tri.interior_angle) > math.sin(best.interior_angle):
                best = tri
        if best is None or best.bearing is None:
            self.counters.triangle_refusals += 1
            if len(self.counters.refusal_examples) < 5:
                self.counters.refusal_examples.append(f"t={t:.2f}s: " + "; ".join(reasons))
            self._range_block(d, t)
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
            t,
        )
