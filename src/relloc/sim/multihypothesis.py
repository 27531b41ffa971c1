"""Seed-002 scenario: two leaders and three pods with unknown bearing correspondence.

De Silva, Mann & Gosine §III: a group of two *leaders* (the sensing robots, here ground robots
at z = 0) and three *pods* (aerial robots hovering at different heights) moves along a common
path. Each leader measures, at the direct-fusion rate (paper: 10 Hz),

* the height difference ``h = z_j − z_i`` of every teammate from absolute height references
  (known correspondence, always available);
* the range ``r`` to every teammate (known correspondence), detected with probability ``P_D``
  (its Gaussian noise truncated to keep ``0 < r ≤ MAX_SENSOR_RANGE_M``: redrawn, which only
  matters when a teammate is closer than a few σ_r);
* a *set* of bearings ``(α, β)`` with unknown correspondence: each teammate within
  ``max_range`` is seen with probability ``P_D``, plus Poisson clutter uniform over the
  measurement space; the set is shuffled.

Units of the paper's settings (as read here). Measurement variances
``[ν_α, ν_β, ν_h, ν_r] = [0.0036 rad², 0.0036 rad², 5 mm², 8 mm²]`` are taken literally:
σ_α = σ_β = 0.06 rad, σ_h = √5 mm ≈ 2.2 mm, σ_r = √8 mm ≈ 2.8 mm. The clutter *spatial density*
λ = 10⁻⁷ is read per unit volume of the relative-measurement space ``(α, β, r)`` in the units
the paper states its noise in (rad × rad × mm): ``V = 2π · π · r_max[mm]``, so the expected
number of clutter bearings per scan is ``λV`` (≈ 0.02 at λ = 10⁻⁷ and r_max = 10 m; the
λ × 100 setting gives ≈ 2 and λ × 1000 ≈ 20 false bearings per scan, against 4 true ones).
The clutter's range coordinate is not observed (ranges have known correspondence), so a
clutter point contributes a false bearing only. The stochastic model's velocity variance
(0.05 (m/s)², 0.01 (rad/s)²) is the noise on every measured body velocity (v_x, v_y, v_z; ω_z)
of every robot at the filter rate; the filter uses the same values as its process noise.

The path (Fig. 4 of the paper is not given numerically): the group drives a wide arc (0.3 m/s,
0.04 rad/s) and every robot adds its own zero-mean speed and turn-rate oscillations (so the
relative poses keep changing, which makes the relative yaw observable), pods also oscillate in
height. A *kidnap* moves one robot's true pose by a fixed offset at a given time.

Beyond the paper, ``DeSilvaScenario.sensing`` may make any robots scan (``(0, 1, 2, 3, 4)``:
every robot senses, so every pair has mutual sightings): a pod's scan is the same sensor model
at its own height. The platforms stay as above (leaders ground, pods aerial) whoever senses.

:func:`simulate` gives a :class:`~relloc.core.recording.Recording`: every robot's measured body
velocities on the filter grid (odometry), the leaders' scans as measurement rows at the scan
times — ``"height"`` and ``"range"`` rows of a known teammate (``target``) and
``"bearing_elevation"`` rows of unknown correspondence (``target`` ``NO_TARGET``, in the shuffled
order of the set; ``origin`` the robot that produced the bearing or ``CLUTTER``, for scoring
only) — and the true poses on the filter grid.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from relloc.core import checks
from relloc.core.angles import wrap_angle
from relloc.core.limits import (
    MAX_ABS_POSITION_M,
    MAX_SENSOR_RANGE_M,
    MAX_SPEED_M_S,
    MAX_YAW_RATE_RAD_S,
)
from relloc.core.poses import compose, relative
from relloc.core.recording import (
    CLUTTER,
    GroundTruth,
    Measurements,
    Odometry,
    Recording,
    measurement_rows,
)
from relloc.errors import ConfigError
from relloc.sim.scenario import MAX_MEASUREMENTS, MAX_SIMULATED_STEPS

Array = NDArray[np.float64]

#: Robot names in index order: leaders first (the sensing robots), then pods.
ROBOT_NAMES: tuple[str, ...] = ("L1", "L2", "P1", "P2", "P3")
#: Formation offsets (x, y, z) of each robot in the group frame (m).
_OFFSET = np.array(
    [
        [0.0, 0.0, 0.0],
        [-2.0, 2.5, 0.0],
        [2.0, 1.5, 1.0],
        [1.5, -2.0, 1.5],
        [-1.5, -2.5, 2.0],
    ]
)
#: Per-robot oscillation of the offset: amplitudes (x, y, z) in m, periods (x, y, z) in s,
#: yaw-oscillation amplitude (rad, pods only) and period (s), phase (rad).
_OSC = np.array(
    [
        [0.6, 0.8, 0.0, 23.0, 17.0, 10.0, 0.0, 10.0, 0.0],
        [0.7, 0.6, 0.0, 19.0, 21.0, 10.0, 0.0, 10.0, 1.3],
        [0.8, 0.9, 0.3, 17.0, 13.0, 9.0, 0.8, 11.0, 2.1],
        [0.9, 0.7, 0.4, 15.0, 19.0, 11.0, 0.9, 9.0, 3.7],
        [0.7, 1.0, 0.3, 21.0, 14.0, 8.0, 1.0, 12.0, 5.0],
    ]
)
#: Robots whose heading follows their direction of travel (ground robots, v_y = 0).
_NONHOLONOMIC = (0, 1)


@dataclass(frozen=True, kw_only=True)
class DeSilvaScenario:
    """Settings of the seed-002 simulation (defaults: the paper's values, units above).

    ``kidnap``: ``(robot index, time s, dx m, dy m, dψ rad)`` or ``None``. ``sensing``: the
    indices of the robots that scan (ascending; the paper's: the two leaders).

    Validation (ConfigError naming the field): rates, variances and ``duration`` finite and
    > 0, with at least one filter step (``round(duration · filter_rate) ≥ 1``); ``max_range``
    and σ_h, σ_r ≤ ``MAX_SENSOR_RANGE_M``, σ_α, σ_β ≤ π (a wider angle noise carries no
    information); ``0 ≤ group_speed ≤ MAX_SPEED_M_S`` and
    ``|group_turn_rate| ≤ MAX_YAW_RATE_RAD_S`` (0: a straight path); indices integers; the
    kidnap's time inside the run and at most its last filter step, its offsets finite
    (``|dx|, |dy| ≤ MAX_ABS_POSITION_M``, ``|dψ| ≤ 2π``). So that no
    setting asks for unbounded work, the five robots' filter steps stay within
    :data:`~relloc.sim.scenario.MAX_SIMULATED_STEPS` and the expected clutter bearings of the
    whole run within :data:`~relloc.sim.scenario.MAX_MEASUREMENTS`.
    """

    duration: float = 60.0
    filter_rate: float = 20.0
    direct_rate: float = 10.0
    velocity_variance: float = 0.05
    angular_variance: float = 0.01
    var_azimuth: float = 0.0036
    var_elevation: float = 0.0036
    var_height_mm2: float = 5.0
    var_range_mm2: float = 8.0
    p_detect: float = 0.95
    clutter_density: float = 1e-7
    max_range: float = 10.0
    group_speed: float = 0.3
    group_turn_rate: float = 0.04
    kidnap: tuple[int, float, float, float, float] | None = None
    sensing: tuple[int, ...] = (0, 1)

    def __post_init__(self) -> None:
        angle_var, length_var_mm2 = math.pi**2, (MAX_SENSOR_RANGE_M * 1e3) ** 2
        for name, high in (
            ("duration", math.inf),
            ("filter_rate", math.inf),
            ("direct_rate", math.inf),
            ("velocity_variance", math.inf),
            ("angular_variance", math.inf),
            ("var_azimuth", angle_var),
            ("var_elevation", angle_var),
            ("var_height_mm2", length_var_mm2),
            ("var_range_mm2", length_var_mm2),
            ("max_range", MAX_SENSOR_RANGE_M),
        ):
            checks.number(
                getattr(self, name), f"DeSilvaScenario.{name}", low=0.0, open_low=True, high=high
            )
        checks.number(self.p_detect, "DeSilvaScenario.p_detect", low=0.0, high=1.0, open_low=True)
        checks.number(self.clutter_density, "DeSilvaScenario.clutter_density", low=0.0)
        checks.number(self.group_speed, "DeSilvaScenario.group_speed", low=0.0, high=MAX_SPEED_M_S)
        checks.number(
            self.group_turn_rate,
            "DeSilvaScenario.group_turn_rate",
            low=-MAX_YAW_RATE_RAD_S,
            high=MAX_YAW_RATE_RAD_S,
        )
        ratio = self.filter_rate / self.direct_rate
        if (
            self.direct_rate > self.filter_rate
            or not math.isfinite(ratio)
            or abs(ratio - round(ratio)) > 1e-9
        ):
            raise ConfigError(
                "DeSilvaScenario.direct_rate must divide filter_rate "
                f"({self.direct_rate} vs {self.filter_rate})"
            )
        sensing = checks.sequence(self.sensing, "DeSilvaScenario.sensing", "robot indices")
        for k, i in enumerate(sensing):
            checks.count(i, f"DeSilvaScenario.sensing[{k}]", low=0)
        if (
            not self.sensing
            or list(self.sensing) != sorted(set(self.sensing))
            or not 0 <= self.sensing[0] <= self.sensing[-1] < len(ROBOT_NAMES)
        ):
            raise ConfigError(
                "DeSilvaScenario.sensing must be distinct ascending robot indices in "
                f"[0, {len(ROBOT_NAMES)}), got {self.sensing}"
            )
        if self.kidnap is not None:
            self._check_kidnap(self.kidnap)
        self._check_work()

    def _check_kidnap(self, kidnap: object) -> None:
        """``(robot, time, dx, dy, dψ)``: a robot index, a time inside the run, finite offsets."""
        where = "DeSilvaScenario.kidnap"
        kidnap = checks.sequence(kidnap, where, "(robot, time, dx, dy, dψ)", length=5)
        if checks.count(kidnap[0], f"{where}[0] (robot)", low=0) >= len(ROBOT_NAMES):
            raise ConfigError(
                f"{where}[0] (robot): no robot {kidnap[0]} (0 to {len(ROBOT_NAMES) - 1})"
            )
        when = checks.number(
            kidnap[1],
            f"{where}[1] (time)",
            low=0.0,
            high=self.duration,
            open_low=True,
            open_high=True,
        )
        last = round(self.duration * self.filter_rate) / self.filter_rate
        if when > last:
            raise ConfigError(
                f"{where}[1] (time): {when:g} s is after the last filter step, {last:g} s "
                f"(round(duration · filter_rate) / filter_rate), so no pose would be moved"
            )
        for k, (name, bound) in enumerate(
            (("dx", MAX_ABS_POSITION_M), ("dy", MAX_ABS_POSITION_M), ("dψ", 2.0 * math.pi)),
            start=2,
        ):
            checks.number(kidnap[k], f"{where}[{k}] ({name})", low=-bound, high=bound)

    def _check_work(self) -> None:
        """At least one filter step; bounded robot-steps and clutter (class docstring)."""
        steps = self.duration * self.filter_rate
        if len(ROBOT_NAMES) * steps > MAX_SIMULATED_STEPS:
            raise ConfigError(
                f"DeSilvaScenario.duration × filter_rate: {len(ROBOT_NAMES)} robots × "
                f"{steps:.6g} steps; the limit is {MAX_SIMULATED_STEPS:.0e} (MAX_SIMULATED_STEPS)"
            )
        if round(steps) < 1:
            raise ConfigError(
                f"DeSilvaScenario.duration: shorter than one filter step ({self.duration:g} s at "
                f"filter_rate = {self.filter_rate:g} Hz)"
            )
        clutter = self.expected_clutter * self.duration * self.direct_rate * len(self.sensing)
        if clutter > MAX_MEASUREMENTS:
            raise ConfigError(
                f"DeSilvaScenario.clutter_density: {clutter:.3g} expected clutter bearings over "
                f"the run; the limit is {MAX_MEASUREMENTS:.0e} (MAX_MEASUREMENTS)"
            )

    @property
    def sigma_height(self) -> float:
        """σ_h in metres."""
        return float(np.sqrt(self.var_height_mm2) * 1e-3)

    @property
    def sigma_range(self) -> float:
        """σ_r in metres."""
        return float(np.sqrt(self.var_range_mm2) * 1e-3)

    @property
    def expected_clutter(self) -> float:
        """Poisson mean ``λV`` of clutter bearings per scan, ``V = 2π·π·r_max[mm]``."""
        return float(self.clutter_density * 2.0 * np.pi * np.pi * self.max_range * 1e3)

    @property
    def velocity_sigmas(self) -> tuple[float, float, float, float]:
        """``(σ_vx, σ_vy, σ_vz, σ_ω)`` of every robot's measured body velocity."""
        sv = float(np.sqrt(self.velocity_variance))
        return (sv, sv, sv, float(np.sqrt(self.angular_variance)))


def path_poses(scenario: DeSilvaScenario, times: Array) -> Array:
    """World poses ``(T, 5, 4)`` of the group path (module docstring).

    The group frame moves on an arc (speed ``group_speed``, turn rate ``group_turn_rate``);
    each robot sits at its oscillating offset in that frame. Ground robots head along their
    velocity; pods (holonomic) yaw with the group plus their own oscillation. A turn rate of
    zero, or one so small that the arc's radius ``v / ω`` overflows, gives the arc's limit: a
    straight path along x.
    """
    t = times[:, None]
    v, w = scenario.group_speed, scenario.group_turn_rate
    psi_g = w * t
    if w == 0.0 or not math.isfinite(v / w):
        cx, cy = v * t, np.zeros_like(t)
    else:
        radius = v / w
        cx, cy = radius * np.sin(psi_g), radius * (1.0 - np.cos(psi_g))
    osc = _OSC
    q = _OFFSET[None] + osc[None, :, 0:3] * np.sin(
        2.0 * np.pi * t[..., None] / osc[None, :, 3:6] + osc[None, :, 8:9]
    )
    c, s = np.cos(psi_g), np.sin(psi_g)
    x = cx + c * q[..., 0] - s * q[..., 1]
    y = cy + s * q[..., 0] + c * q[..., 1]
    yaw = psi_g + osc[:, 6] * np.sin(2.0 * np.pi * t / osc[:, 7] + osc[:, 8])
    for k in _NONHOLONOMIC:
        heading = np.arctan2(np.gradient(y[:, k], times), np.gradient(x[:, k], times))
        yaw[:, k] = np.unwrap(heading)
    return np.stack([x, y, q[..., 2], yaw], axis=-1)


def zoh_velocities(poses: Array, dt: float) -> Array:
    """Body velocities held over each step that carry ``poses[k]`` exactly to ``poses[k+1]``.

    Inverts the exact zero-order-hold step of :func:`relloc.models.motion.relative_step`:
    ``ω = Δψ/dt``, ``v_xy = R(ψ + Δψ/2)ᵀ Δp / (dt sinc(Δψ/2))``, ``v_z = Δz/dt``. The last row
    repeats the previous one.
    """
    d = np.diff(poses, axis=0)
    half = 0.5 * d[..., 3]
    sinc = np.where(np.abs(half) < 1e-9, 1.0, np.sin(half) / np.where(half == 0.0, 1.0, half))
    mid = poses[:-1, :, 3] + half
    c, s = np.cos(mid), np.sin(mid)
    vx = (c * d[..., 0] + s * d[..., 1]) / (dt * sinc)
    vy = (-s * d[..., 0] + c * d[..., 1]) / (dt * sinc)
    u = np.stack([vx, vy, d[..., 2] / dt, d[..., 3] / dt], axis=-1)
    return np.concatenate([u, u[-1:]], axis=0)


def simulate(scenario: DeSilvaScenario, rng: np.random.Generator) -> Recording:
    """Simulate one run: truth, noisy velocities and the sensing robots' direct scans."""
    dt = 1.0 / scenario.filter_rate
    n_steps = round(scenario.duration * scenario.filter_rate) + 1
    times: Array = np.arange(n_steps, dtype=np.float64) * dt
    truth = path_poses(scenario, times)
    u_true = zoh_velocities(truth, dt)
    if scenario.kidnap is not None:
        truth = _kidnap(truth, times, scenario.kidnap)
    sigmas = np.array(scenario.velocity_sigmas)
    u_meas = u_true + rng.normal(size=u_true.shape) * sigmas
    every = round(scenario.filter_rate / scenario.direct_rate)
    rows = _Rows()
    for k in range(every, n_steps, every):
        for i in scenario.sensing:
            _scan(scenario, truth[k], i, float(times[k]), rng, rows)
    robots = range(len(ROBOT_NAMES))
    return Recording(
        robots=ROBOT_NAMES,
        platforms=tuple("ground" if j in _NONHOLONOMIC else "aerial" for j in robots),
        odometry=tuple(Odometry(t=times, velocity=u_meas[:, j], sigma=sigmas) for j in robots),
        measurements=rows.table(scenario),
        truth=tuple(GroundTruth(t=times, pose=truth[:, j]) for j in robots),
        source="sim.multihypothesis",
        meta={"sensing": scenario.sensing},
    )


def _kidnap(truth: Array, times: Array, kidnap: tuple[int, float, float, float, float]) -> Array:
    """Move robot ``kidnap[0]`` at ``kidnap[1]`` by ``(dx, dy, dψ)``; it then keeps moving
    rigidly as before (same body velocities): ``pose(t) = (b₀ + δ) ⊕ (⊖b₀ ⊕ b(t))``."""
    robot, when, dx, dy, dpsi = kidnap
    out = np.array(truth, copy=True)
    after = np.flatnonzero(times >= when)
    base0 = truth[after[0], int(robot)]
    moved0 = base0 + np.array([dx, dy, 0.0, dpsi])
    for k in after:
        motion, _, _ = relative(base0, truth[k, int(robot)])
        out[k, int(robot)], _, _ = compose(moved0, motion)
    return out


@dataclass
class _Rows:
    """The leaders' readings as columns: ``(t, observer, target, value)`` of the heights and
    the ranges, ``(t, observer, origin, azimuth, elevation)`` of the bearings."""

    height: list[tuple[float, int, int, float]] = field(default_factory=list)
    range: list[tuple[float, int, int, float]] = field(default_factory=list)
    bearing: list[tuple[float, int, int, float, float]] = field(default_factory=list)

    def table(self, scenario: DeSilvaScenario) -> Measurements:
        """One measurement table (sorted by time; a scan's bearings keep their order)."""
        sa, se = np.sqrt(scenario.var_azimuth), np.sqrt(scenario.var_elevation)
        parts = []
        for kind, rows, sigma in (
            ("height", self.height, [scenario.sigma_height]),
            ("range", self.range, [scenario.sigma_range]),
        ):
            col = np.array(rows, dtype=float).reshape(-1, 4)
            parts.append(
                measurement_rows(
                    kind,
                    t=col[:, 0],
                    observer=col[:, 1].astype(np.int64),
                    target=col[:, 2].astype(np.int64),
                    value=col[:, 3],
                    sigma=np.array(sigma),
                )
            )
        col = np.array(self.bearing, dtype=float).reshape(-1, 5)
        parts.append(
            measurement_rows(
                "bearing_elevation",
                t=col[:, 0],
                observer=col[:, 1].astype(np.int64),
                value=col[:, 3:5],
                sigma=np.array([sa, se]),
                origin=col[:, 2].astype(np.int64),
            )
        )
        return Measurements.concatenate(parts)


def _scan(
    scenario: DeSilvaScenario,
    poses: Array,
    i: int,
    time: float,
    rng: np.random.Generator,
    rows: _Rows,
) -> None:
    """Append leader ``i``'s scan at ``time`` to ``rows``: heights and ranges of every teammate
    (known correspondence) and the shuffled set of bearings of unknown correspondence."""
    bearings: list[tuple[float, float]] = []
    origins: list[int] = []
    sa, se = np.sqrt(scenario.var_azimuth), np.sqrt(scenario.var_elevation)
    for j in range(poses.shape[0]):
        if j == i:
            continue
        rel, _, _ = relative(poses[i], poses[j])
        rows.height.append((time, i, j, float(rel[2] + scenario.sigma_height * rng.normal())))
        r = float(np.linalg.norm(rel[:3]))
        if r > scenario.max_range:
            continue
        if rng.random() < scenario.p_detect:
            noisy = r + scenario.sigma_range * rng.normal()
            while not 0.0 < noisy <= MAX_SENSOR_RANGE_M:  # truncated noise (module docstring)
                noisy = r + scenario.sigma_range * rng.normal()
            rows.range.append((time, i, j, noisy))
        if rng.random() < scenario.p_detect:
            az = np.arctan2(rel[1], rel[0]) + sa * rng.normal()
            el = np.arctan2(rel[2], np.hypot(rel[0], rel[1])) + se * rng.normal()
            bearings.append((float(wrap_angle(az)), float(el)))
            origins.append(j)
    n_clutter = rng.poisson(scenario.expected_clutter)
    for _ in range(n_clutter):
        bearings.append((rng.uniform(-np.pi, np.pi), rng.uniform(-0.5 * np.pi, 0.5 * np.pi)))
        origins.append(CLUTTER)
    for k in rng.permutation(len(bearings)):
        rows.bearing.append((time, i, origins[k], *bearings[k]))
