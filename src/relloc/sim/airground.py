"""Closed-loop simulator of the air-ground team of seed 003 (leader, N followers, M drones).

:func:`simulate_airground` is given the followers' estimators (one per follower, each built by
the caller's factory and driven through the estimator contract of
:mod:`relloc.core.contract`) and their controller. Per tick ``k`` (period ``dt``, the
filters' 20 Hz of the paper) it

1. **Commands.** The leader follows its path (constant arc, or an S-shaped curve with
   ``ω_0(t) = ω̄ sin(2πt/T)``). Followers are either externally commanded to move rigidly with
   the leader on the arc (``control="external"``) or commanded by the controller from *their
   own estimates* (``control="formation"``, e.g.
   :class:`relloc.control.formation.FormationController`).
2. **Motion.** Every UGV moves with its commands perturbed by white velocity noise (slip,
   actuation), :func:`relloc.models.unicycle.unicycle_step`. Each drone flies at a constant
   heading (ψ̄ = 0, the x-axis of F_G) with :func:`relloc.models.airground.drone_step` toward
   its commanded midpoint; its altitude wanders around the set altitude (Gauss–Markov).
3. **Drone guidance.** A drone knows the formation layout and the leader's broadcast commands;
   it keeps a track of the leader's pose from what its camera sees (the leader itself, or any
   follower plus the layout) and dead-reckons it in between. Its commanded point is the scheduled
   midpoint ``p_0 − r_des,i / 2`` (or the measured midpoint when both robots are in view), with the
   leader's velocity as feed-forward.
4. **Sensing** — the tick's readings, one :class:`~relloc.core.recording.Measurements` batch:
   ``range`` rows between every pair of UGVs every ``uwb_every`` ticks (observer < target), with
   errors from the fitted real-data model (:func:`relloc.models.uwb_noise.sample_range_errors`:
   bias, correlated core, outliers); a camera frame every ``camera_every`` ticks: a drone
   detects a pair ``{R_0, R_i}`` only if its altitude is inside the detection band and both
   robots' markers lie inside the footprint (``|Δx| ≤ z tan(hfov/2) − margin``, same for y),
   each with probability ``p_detect``; it then broadcasts a ``pair_sighting`` row (observer the
   drone, target R_i): the bearing φ_i of ``p_0 − p_i`` in F_G and the headings θ_i, θ_0, with
   white noise plus its own slowly varying heading-hold error (common to the three angles).
5. **Estimation.** The estimators are driven through the contract by
   :func:`relloc.core.events.run_events` over the one event at the end of the tick: advance
   with the UGVs' commands as odometry ``(v, 0, 0, ω)`` (a drone's: its commanded planar
   velocity ``(v_x, v_y, 0, 0)`` along F_G, its commanded heading), measure the batch, record
   the beliefs. The simulator imports the contract, never an estimator.

This tick loop is the closed-loop counterpart of :func:`relloc.pipeline.replay.replay`: the
result's :class:`~relloc.core.recording.Recording` holds the truth, the commands as odometry and
every reading, and replaying it through fresh estimators started from the same priors gives the
same estimates (the controller only closes the loop; it reads nothing the recording lacks).
All randomness comes from the generator passed in.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Literal, Protocol

import numpy as np
from numpy.typing import NDArray

from relloc.control.drone_schedule import DroneSchedule, Policy
from relloc.control.formation import Frame, desired_relative
from relloc.core.contract import Estimator
from relloc.core.estimates import Estimates, Recorder
from relloc.core.events import run_events
from relloc.core.gaussian import Gaussian
from relloc.core.recording import (
    GroundTruth,
    Measurements,
    Odometry,
    Recording,
    empty_measurements,
    measurement_rows,
)
from relloc.errors import ConfigError
from relloc.models.airground import drone_step
from relloc.models.unicycle import unicycle_step
from relloc.models.uwb_noise import UwbNoiseModel, sample_range_errors

Array = NDArray[np.float64]
PathKind = Literal["arc", "s_curve", "straight"]
Control = Literal["external", "formation"]
#: The frame the followers' beliefs must be in for the controller (:mod:`relloc.pipeline.frames`).
FOLLOWER_FRAME = "airground_follower"


def _positive(owner: str, **values: float) -> None:
    for name, value in values.items():
        if not (math.isfinite(value) and value > 0.0):
            raise ConfigError(f"{owner}.{name}: must be > 0, got {value!r}")


@dataclass(frozen=True, kw_only=True)
class CameraSettings:
    """Downward camera of a drone (defaults: a Raspberry Pi camera, 62°×49° field of view)."""

    hfov: float = math.radians(62.0)
    vfov: float = math.radians(49.0)
    min_altitude: float = 1.40
    max_altitude: float = 1.85
    marker_margin: float = 0.10
    p_detect: float = 0.95
    bearing_sigma: float = 0.015
    heading_sigma: float = 0.025

    def __post_init__(self) -> None:
        _positive(
            "CameraSettings",
            hfov=self.hfov,
            vfov=self.vfov,
            min_altitude=self.min_altitude,
            bearing_sigma=self.bearing_sigma,
            heading_sigma=self.heading_sigma,
        )
        if not self.max_altitude > self.min_altitude:
            raise ConfigError("CameraSettings.max_altitude: must exceed min_altitude")
        if not 0.0 < self.p_detect <= 1.0:
            raise ConfigError(f"CameraSettings.p_detect: must be in (0, 1], got {self.p_detect}")
        if not self.marker_margin >= 0.0:
            raise ConfigError("CameraSettings.marker_margin: must be ≥ 0")

    def half_extent(self, altitude: float) -> tuple[float, float]:
        """Usable half-width of the footprint along x and y at ``altitude``."""
        return (
            altitude * math.tan(0.5 * self.hfov) - self.marker_margin,
            altitude * math.tan(0.5 * self.vfov) - self.marker_margin,
        )


@dataclass(frozen=True, kw_only=True)
class DroneSettings:
    """Drone flight: altitude hold (with wander), planar P control, heading-hold error."""

    altitude: float = 1.75
    altitude_sigma: float = 0.04
    altitude_tau: float = 3.0
    gain: float = 1.2
    v_max: float = 0.6
    yaw_sigma: float = 0.01
    yaw_tau: float = 5.0
    midpoint_sigma: float = 0.02

    def __post_init__(self) -> None:
        _positive(
            "DroneSettings",
            altitude=self.altitude,
            altitude_tau=self.altitude_tau,
            gain=self.gain,
            v_max=self.v_max,
            yaw_tau=self.yaw_tau,
        )
        for name in ("altitude_sigma", "yaw_sigma", "midpoint_sigma"):
            if not getattr(self, name) >= 0.0:
                raise ConfigError(f"DroneSettings.{name}: must be ≥ 0")


@dataclass(frozen=True, kw_only=True)
class LeaderPath:
    """Leader commands: constant arc ``(v, ω)``, straight ``(v, 0)`` or S-curve."""

    kind: PathKind = "arc"
    speed: float = 0.1
    turn_rate: float = 0.04
    period: float = 40.0

    def __post_init__(self) -> None:
        if self.kind not in ("arc", "s_curve", "straight"):
            raise ConfigError(f"LeaderPath.kind: 'arc', 's_curve' or 'straight', got {self.kind!r}")
        _positive("LeaderPath", speed=self.speed, period=self.period)
        if not math.isfinite(self.turn_rate):
            raise ConfigError("LeaderPath.turn_rate: not finite")

    def command(self, t: float) -> tuple[float, float]:
        """``(v_0, ω_0)`` at time ``t``."""
        if self.kind == "arc":
            return self.speed, self.turn_rate
        if self.kind == "straight":
            return self.speed, 0.0
        return self.speed, self.turn_rate * math.sin(2.0 * math.pi * t / self.period)


@dataclass(frozen=True, kw_only=True)
class AirGroundScenario:
    """One air-ground run. ``offsets[i-1]`` is follower i's desired ``r = p_0 − p_i``
    (``offset_frame`` says in which frame); the team starts in that formation. ``control``:
    the followers are commanded rigidly on the leader's arc (``"external"``) or by the
    controller given to :func:`simulate_airground` (``"formation"``). Each follower's estimator
    starts from a guess drawn around the truth with ``init_position_sigma`` /
    ``init_heading_sigma`` (also its stated prior covariance)."""

    offsets: tuple[tuple[float, float], ...]
    offset_frame: Frame = "leader"
    n_drones: int = 1
    duration: float = 60.0
    dt: float = 0.05
    uwb_every: int = 2
    camera_every: int = 2
    dwell_time: float = 8.0
    schedule_policy: Policy = "sliding"
    schedule_offset: int = 0
    control: Control = "formation"
    leader: LeaderPath = field(default_factory=LeaderPath)
    leader_start_heading: float = 0.0
    velocity_noise: tuple[float, float] = (0.01, 0.02)
    uwb: UwbNoiseModel = field(
        default_factory=lambda: UwbNoiseModel(
            bias=0.0, spread=0.05, outlier_rate=0.0, outlier_excess_mean=0.0
        )
    )
    uwb_link_bias: bool = False
    camera: CameraSettings = field(default_factory=CameraSettings)
    drone: DroneSettings = field(default_factory=DroneSettings)
    init_position_sigma: float = 0.2
    init_heading_sigma: float = 0.15

    def __post_init__(self) -> None:
        if not self.offsets:
            raise ConfigError("AirGroundScenario.offsets: need at least one follower")
        for i, off in enumerate(self.offsets, start=1):
            if len(off) != 2 or not all(math.isfinite(v) for v in off):
                raise ConfigError(f"AirGroundScenario.offsets[{i - 1}]: need two finite numbers")
            if math.hypot(*off) < 0.1:
                raise ConfigError(
                    f"AirGroundScenario.offsets[{i - 1}]: follower {i} sits on the leader"
                )
        if self.offset_frame not in ("global", "leader"):
            raise ConfigError("AirGroundScenario.offset_frame: 'global' or 'leader'")
        if self.control not in ("external", "formation"):
            raise ConfigError("AirGroundScenario.control: 'external' or 'formation'")
        if self.n_drones < 1:
            raise ConfigError(f"AirGroundScenario.n_drones: must be ≥ 1, got {self.n_drones}")
        _positive(
            "AirGroundScenario",
            duration=self.duration,
            dt=self.dt,
            dwell_time=self.dwell_time,
            init_position_sigma=self.init_position_sigma,
            init_heading_sigma=self.init_heading_sigma,
        )
        if self.uwb_every < 1 or self.camera_every < 1:
            raise ConfigError("AirGroundScenario.uwb_every / camera_every: must be ≥ 1 ticks")
        if self.camera_every % self.uwb_every != 0:
            raise ConfigError(
                "AirGroundScenario.camera_every: must be a multiple of uwb_every (every camera "
                "frame needs fresh ranges for the triangle bearing)"
            )
        if len(self.velocity_noise) != 2 or min(self.velocity_noise) < 0.0:
            raise ConfigError("AirGroundScenario.velocity_noise: (σ_v, σ_ω), both ≥ 0")
        if self.control == "external" and self.offset_frame != "leader":
            raise ConfigError(
                "AirGroundScenario.offset_frame: external (rigid) motion needs 'leader' offsets"
            )

    @property
    def n_followers(self) -> int:
        """N."""
        return len(self.offsets)

    @property
    def n_steps(self) -> int:
        """Number of ticks."""
        return round(self.duration / self.dt)

    def schedule(self) -> DroneSchedule:
        """The drones' midpoint schedule (dwell ``k_m = dwell_time / dt`` ticks)."""
        return DroneSchedule(
            n_followers=self.n_followers,
            n_drones=self.n_drones,
            dwell_steps=max(1, round(self.dwell_time / self.dt)),
            policy=self.schedule_policy,
            offset=self.schedule_offset,
        )


class FollowerController(Protocol):
    """Commands ``(N, 2)`` ``(v_i, ω_i)`` of the followers from their estimates ``(N, 4)``
    ``[r_x, r_y, θ_i, θ_0]`` and the leader's broadcast command ``(v_0, ω_0)``."""

    def commands(self, estimates: Array, leader_u: tuple[float, float]) -> Array: ...


#: Builds follower ``owner``'s estimator from the team's robot names and its prior at t = 0.
EstimatorFactory = Callable[[Sequence[str], str, Gaussian], Estimator]


@dataclass(frozen=True, kw_only=True)
class AirGroundRun:
    """One closed-loop run.

    ``recording``: truth of every robot (UGVs ``(x, y, 0, θ)``, drones ``(x, y, z, ψ)`` with ψ
    the heading-hold error) at ``t = k dt``, the commands as odometry and every reading;
    ``estimates``: the followers' beliefs at every tick ``k ≥ 1``; ``priors[owner]``: the belief
    each follower's estimator started from; ``formation_error (K, N, 2)``: the true
    ``r − r_des`` of every follower at the same ticks (the controller's figure of merit).
    """

    recording: Recording
    estimates: Estimates
    priors: Mapping[str, Gaussian]
    formation_error: Array


def robot_names(sc: AirGroundScenario) -> tuple[str, ...]:
    """The team in recording order: ``R_0`` (leader), ``R_1 … R_N``, then ``D_1 … D_M``."""
    ugvs = tuple(f"R_{i}" for i in range(sc.n_followers + 1))
    return ugvs + tuple(f"D_{j}" for j in range(1, sc.n_drones + 1))


def _initial_poses(sc: AirGroundScenario) -> Array:
    """Leader at the origin; followers at ``p_0 − r_des``; headings per the control mode."""
    th0 = sc.leader_start_heading
    poses = np.zeros((sc.n_followers + 1, 3))
    poses[0, 2] = th0
    v0, w0 = sc.leader.command(0.0)
    for i, off in enumerate(sc.offsets, start=1):
        r = desired_relative(np.array(off), th0, sc.offset_frame)
        poses[i, :2] = -r
        poses[i, 2] = th0
        if sc.control == "external" and sc.leader.kind == "arc" and abs(w0) > 1e-9:
            centre = np.array([-math.sin(th0), math.cos(th0)]) * (v0 / w0)
            radial = poses[i, :2] - centre
            poses[i, 2] = math.atan2(radial[1], radial[0]) + math.copysign(0.5 * math.pi, w0)
    return poses


def _rigid_commands(sc: AirGroundScenario, poses0: Array, v0: float, w0: float) -> Array:
    """External commands that keep the initial layout rigid on the leader's arc."""
    u = np.zeros((sc.n_followers, 2))
    if abs(w0) < 1e-9:
        u[:, 0] = v0
        return u
    centre = poses0[0, :2] + np.array([-math.sin(poses0[0, 2]), math.cos(poses0[0, 2])]) * (v0 / w0)
    for i in range(1, sc.n_followers + 1):
        radius = float(np.hypot(*(poses0[i, :2] - centre)))
        u[i - 1] = (abs(w0) * radius, w0)
    return u


def _in_footprint(cam: CameraSettings, drone: Array, point: Array) -> bool:
    hx, hy = cam.half_extent(float(drone[2]))
    return abs(point[0] - drone[0]) <= hx and abs(point[1] - drone[1]) <= hy


def _check_controller(sc: AirGroundScenario, controller: FollowerController | None) -> None:
    if sc.control == "formation" and controller is None:
        raise ConfigError("simulate_airground: control='formation' needs a follower controller")
    if sc.control == "external" and controller is not None:
        raise ConfigError(
            "simulate_airground: control='external' commands the followers rigidly; "
            "pass no controller"
        )


def _follower_estimates(estimators: Sequence[Estimator], leader: str) -> Array:
    """``(N, 4)`` means of the followers' beliefs of the leader (what the controller reads)."""
    out = np.zeros((len(estimators), 4))
    for i, est in enumerate(estimators):
        found = [b for b in est.beliefs() if b.subject == leader and b.frame == FOLLOWER_FRAME]
        if not found:
            raise ConfigError(
                f"simulate_airground: {est.owner}'s estimator holds no {FOLLOWER_FRAME} belief "
                f"of {leader}"
            )
        out[i] = found[0].mean
    return out


def simulate_airground(
    sc: AirGroundScenario,
    make_estimator: EstimatorFactory,
    controller: FollowerController | None,
    rng: np.random.Generator,
) -> AirGroundRun:
    """Run one closed-loop simulation (module docstring).

    ``make_estimator(robots, owner, prior)`` builds each follower's estimator (called for
    ``R_1 … R_N`` in order); ``controller`` commands the followers when
    ``sc.control == "formation"`` (``None`` for ``"external"``).
    """
    _check_controller(sc, controller)
    n, m, dt, steps = sc.n_followers, sc.n_drones, sc.dt, sc.n_steps
    names = robot_names(sc)
    schedule = sc.schedule()
    offsets = np.array(sc.offsets, dtype=float)
    poses = _initial_poses(sc)
    poses0 = poses.copy()
    # UWB links: every unordered UGV pair (a < b), errors drawn for every UWB epoch up front.
    links = [(a, b) for a in range(n + 1) for b in range(a + 1, n + 1)]
    n_epochs = steps // sc.uwb_every + 1
    range_err = sample_range_errors(
        sc.uwb, n_epochs, len(links), dt * sc.uwb_every, rng, link_bias=sc.uwb_link_bias
    )
    # Estimators, started from a guess drawn around the truth with the stated prior.
    priors: dict[str, Gaussian] = {}
    p0_sig = np.array([sc.init_position_sigma] * 2 + [sc.init_heading_sigma] * 2)
    for i in range(1, n + 1):
        true_x = np.array([*(poses[0, :2] - poses[i, :2]), poses[i, 2], poses[0, 2]])
        mean = true_x + p0_sig * rng.standard_normal(4)
        priors[names[i]] = Gaussian(mean, np.diag(p0_sig**2))
    estimators = [make_estimator(names, owner, prior) for owner, prior in priors.items()]
    for owner, est in zip(priors, estimators, strict=True):
        if est.owner != owner:
            raise ConfigError(f"simulate_airground: the estimator for {owner} says {est.owner}")
    drones = _Drones.start(sc, poses, offsets, rng)
    times = np.arange(steps + 1, dtype=np.float64) * dt
    truth = np.zeros((steps + 1, n + 1 + m, 4))
    truth[0] = _truth_row(poses, drones)
    commands = np.zeros((steps, n + 1 + m, 4))
    formation_error = np.zeros((steps, n, 2))
    batches: list[Measurements] = []
    recorder = Recorder("+".join(sorted({e.name for e in estimators})))
    sv, sw = sc.velocity_noise

    for k in range(steps):
        t = float(times[k])
        v0, w0 = sc.leader.command(t)
        # 1. commands
        if controller is None:
            u_f = _rigid_commands(sc, poses0, v0, w0)
        else:
            u_f = np.asarray(
                controller.commands(_follower_estimates(estimators, names[0]), (v0, w0)),
                dtype=float,
            )
        u_cmd = np.vstack([[v0, w0], u_f])
        # 2. motion (actual = commanded + noise)
        u_act = u_cmd + rng.standard_normal(u_cmd.shape) * np.array([sv, sw])
        poses = unicycle_step(poses, u_act, dt)
        drones.fly(sc, schedule.targets(k), (v0, w0), offsets, rng)
        # 3.-4. sensing, stamped at the end of the tick
        t1 = float(times[k + 1])
        parts = []
        if k % sc.uwb_every == 0:
            parts.append(_uwb_ranges(t1, poses, links, range_err[k // sc.uwb_every]))
        if k % sc.camera_every == 0:
            parts.append(drones.camera_frame(sc, t1, poses, offsets, rng))
        batch = Measurements.concatenate(parts) if parts else empty_measurements()
        batches.append(batch)
        # 5. estimation: the one event at the end of the tick
        commands[k, : n + 1, 0] = u_cmd[:, 0]
        commands[k, : n + 1, 3] = u_cmd[:, 1]
        commands[k, n + 1 :, :2] = drones.velocity
        run_events(
            estimators,
            times[k + 1 : k + 2],
            commands[k][None],
            np.full((1, n + 1 + m), t),
            batch,
            times[k + 1 : k + 2],
            recorder,
        )
        # record
        truth[k + 1] = _truth_row(poses, drones)
        for i in range(1, n + 1):
            desired = desired_relative(offsets[i - 1], poses[0, 2], sc.offset_frame)
            formation_error[k, i - 1] = (poses[0, :2] - poses[i, :2]) - desired
    return AirGroundRun(
        recording=_recording(sc, names, times, truth, commands, batches),
        estimates=recorder.results(),
        priors=priors,
        formation_error=formation_error,
    )


def _truth_row(poses: Array, drones: _Drones) -> Array:
    """Poses ``(x, y, z, ψ)`` of the UGVs (on the ground) and the drones (ψ: heading-hold error)."""
    ugv = np.column_stack([poses[:, :2], np.zeros(poses.shape[0]), poses[:, 2]])
    return np.vstack([ugv, np.column_stack([drones.position, drones.yaw_error])])


def _uwb_ranges(
    t: float, poses: Array, links: list[tuple[int, int]], errors: Array
) -> Measurements:
    """One UWB epoch: a ``range`` row per link ``(a, b)`` (a < b), true distance plus the
    link's error of this epoch (kept positive)."""
    d = [
        max(1e-3, float(np.hypot(*(poses[a, :2] - poses[b, :2]))) + float(errors[li]))
        for li, (a, b) in enumerate(links)
    ]
    return measurement_rows(
        "range",
        t=np.full(len(links), t),
        observer=np.array([a for a, _ in links], dtype=np.int64),
        target=np.array([b for _, b in links], dtype=np.int64),
        value=np.array(d),
    )


def _recording(
    sc: AirGroundScenario,
    names: tuple[str, ...],
    times: Array,
    truth: Array,
    commands: Array,
    batches: list[Measurements],
) -> Recording:
    n_ugv = sc.n_followers + 1
    sv, sw = sc.velocity_noise
    sigma = [np.array([sv, 0.0, 0.0, sw])] * n_ugv + [np.zeros(4)] * sc.n_drones
    return Recording(
        robots=names,
        platforms=("ground",) * n_ugv + ("aerial",) * sc.n_drones,
        odometry=tuple(
            Odometry(
                t=times[:-1], velocity=commands[:, r], sigma=sigma[r], where=f"{name} commands"
            )
            for r, name in enumerate(names)
        ),
        measurements=Measurements.concatenate(batches),
        truth=tuple(
            GroundTruth(t=times, pose=truth[:, r], where=f"{name} truth")
            for r, name in enumerate(names)
        ),
        source="sim.airground",
        meta={"common_frame_yaw": 0.0, "dt": sc.dt},
    )


@dataclass(kw_only=True)
class _Drones:
    """The drones' state: ``position (M, 3)`` (x, y, z), commanded planar ``velocity (M, 2)``,
    each drone's ``leader_track (M, 3)`` (its estimate of the leader's pose), the altitude
    deviation and the heading-hold error ``yaw_error (M,)`` (both Gauss–Markov)."""

    position: Array
    velocity: Array
    leader_track: Array
    altitude_deviation: Array
    yaw_error: Array

    @staticmethod
    def start(
        sc: AirGroundScenario, poses: Array, offsets: Array, rng: np.random.Generator
    ) -> _Drones:
        """Hovering above their first midpoints at the set altitude, tracking the true leader."""
        m = sc.n_drones
        position = np.zeros((m, 3))
        first = sc.schedule().targets(0)
        for j in range(m):
            r = desired_relative(offsets[first[j] - 1], poses[0, 2], sc.offset_frame)
            position[j, :2] = poses[0, :2] - 0.5 * r
            position[j, 2] = sc.drone.altitude
        return _Drones(
            position=position,
            velocity=np.zeros((m, 2)),
            leader_track=np.tile(poses[0], (m, 1)),
            altitude_deviation=np.zeros(m),
            yaw_error=rng.normal(0.0, sc.drone.yaw_sigma, m),
        )

    def fly(
        self,
        sc: AirGroundScenario,
        targets: tuple[int, ...],
        leader_u: tuple[float, float],
        offsets: Array,
        rng: np.random.Generator,
    ) -> None:
        """One tick: dead-reckon the leader track with the leader's broadcast command, fly
        toward the scheduled midpoint ``p_0 − r_des / 2`` with the leader's velocity as
        feed-forward, let altitude and heading-hold error wander."""
        dt, d = sc.dt, sc.drone
        a_alt = math.exp(-dt / d.altitude_tau)
        a_yaw = math.exp(-dt / d.yaw_tau)
        v0, _ = leader_u
        for j in range(sc.n_drones):
            track = self.leader_track
            track[j] = unicycle_step(track[j], np.array(leader_u), dt)
            r = desired_relative(offsets[targets[j] - 1], float(track[j, 2]), sc.offset_frame)
            command = track[j, :2] - 0.5 * r
            ff = v0 * np.array([math.cos(track[j, 2]), math.sin(track[j, 2])])
            self.position[j, :2], self.velocity[j] = drone_step(
                self.position[j, :2], command, dt, gain=d.gain, v_max=d.v_max, feedforward=ff
            )
            self.altitude_deviation[j] = (
                a_alt * self.altitude_deviation[j]
                + d.altitude_sigma * math.sqrt(1 - a_alt**2) * rng.standard_normal()
            )
            self.position[j, 2] = d.altitude + self.altitude_deviation[j]
            self.yaw_error[j] = (
                a_yaw * self.yaw_error[j]
                + d.yaw_sigma * math.sqrt(1 - a_yaw**2) * rng.standard_normal()
            )

    def camera_frame(
        self,
        sc: AirGroundScenario,
        t: float,
        poses: Array,
        offsets: Array,
        rng: np.random.Generator,
    ) -> Measurements:
        """One camera frame of every drone: a ``pair_sighting`` row per detected pair
        {R_0, R_i} (the first drone that sees a pair reports it); re-anchors the leader tracks."""
        n, cam = sc.n_followers, sc.camera
        seen: list[int] = []
        observers: list[int] = []
        values: list[tuple[float, float, float]] = []
        for j in range(sc.n_drones):
            if not cam.min_altitude <= float(self.position[j, 2]) <= cam.max_altitude:
                continue
            visible = [
                i
                for i in range(n + 1)
                if _in_footprint(cam, self.position[j], poses[i, :2])
                and rng.random() < cam.p_detect
            ]
            self._update_leader_track(j, visible, poses, offsets, sc, rng)
            if 0 not in visible:
                continue
            yaw = self.yaw_error[j]
            for i in visible:
                if i == 0 or i in seen:
                    continue
                seen.append(i)
                observers.append(n + 1 + j)
                rel = poses[0, :2] - poses[i, :2]
                bearing = (
                    math.atan2(rel[1], rel[0]) + yaw + cam.bearing_sigma * rng.standard_normal()
                )
                heading_i = poses[i, 2] + yaw + cam.heading_sigma * rng.standard_normal()
                heading_0 = poses[0, 2] + yaw + cam.heading_sigma * rng.standard_normal()
                values.append((bearing, heading_i, heading_0))
        return measurement_rows(
            "pair_sighting",
            t=np.full(len(seen), t),
            observer=np.array(observers, dtype=np.int64),
            target=np.array(seen, dtype=np.int64),
            value=np.array(values, dtype=float).reshape(-1, 3),
        )

    def _update_leader_track(
        self,
        j: int,
        visible: list[int],
        poses: Array,
        offsets: Array,
        sc: AirGroundScenario,
        rng: np.random.Generator,
    ) -> None:
        """Re-anchor drone j's leader track on what its camera sees (leader first, else a
        follower plus the formation layout); headings are read from the markers."""
        track, sig = self.leader_track, sc.drone.midpoint_sigma
        if 0 in visible:
            track[j, :2] = poses[0, :2] + sig * rng.standard_normal(2)
            track[j, 2] = poses[0, 2] + sc.camera.heading_sigma * rng.standard_normal()
            return
        if visible:
            i = visible[0]
            r = desired_relative(offsets[i - 1], float(track[j, 2]), sc.offset_frame)
            track[j, :2] = poses[i, :2] + r + sig * rng.standard_normal(2)
