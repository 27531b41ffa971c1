"""Closed-loop simulator of the air-ground team of seed 003 (leader, N followers, M drones).

One run is a world and its robots. The **world** (:class:`AirGroundWorld`) holds the true
motion and every sensor, and all the randomness; the **robots** hold only their own code and
what they sensed or heard: the leader follows its path (constant arc, or an S-shaped curve with
``ω_0(t) = ω̄ sin(2πt/T)``); each follower is a :class:`FollowerAgent` (its estimator, driven
through the estimator contract of :mod:`relloc.core.contract`, and its command); each drone is
a :class:`DroneGuidance`. :func:`simulate_airground` runs them all in one process; a team of
processes (:mod:`relloc.runtime.airground`) runs the same objects, one robot per process, around
the same world. Per tick ``k`` (period ``dt``, the filters' 20 Hz of the paper):

1. **Estimation** (``k ≥ 1``). Each follower's estimator processes the event at ``t_k``
   (:func:`relloc.core.events.run_events`): advance with the commands of tick ``k − 1`` as
   odometry ``(v, 0, 0, ω)`` (its own and the leader's), measure the readings taken at ``t_k``,
   record the beliefs. The simulator imports the contract, never an estimator.
2. **Commands.** The leader's path command; each follower's — rigidly on the leader's arc
   (``control="external"``) or by the controller from *its own estimate* (``control="formation"``,
   e.g. :class:`relloc.control.formation.FormationController`); each drone's: it knows the
   formation layout and the leader's broadcast commands, keeps a track of the leader's pose from
   what its camera saw (the leader itself, or any follower plus the layout: a
   :class:`MarkerFix`) and dead-reckons it in between; its commanded point is the scheduled
   midpoint ``p_0 − r_des,i / 2``, with the leader's velocity as feed-forward
   (:func:`relloc.models.airground.drone_velocity`).
3. **Motion.** Every UGV moves with its commands perturbed by white velocity noise (slip,
   actuation), :func:`relloc.models.unicycle.unicycle_step`. Each drone flies its commanded
   velocity at a constant heading (ψ̄ = 0, the x-axis of F_G); its altitude wanders around the
   set altitude (Gauss–Markov).
4. **Sensing** — the readings at ``t_{k+1}``, one :class:`~relloc.core.recording.Measurements`
   batch: ``range`` rows between every pair of UGVs every ``uwb_every`` ticks (observer <
   target), with errors from the fitted real-data model
   (:func:`relloc.models.uwb_noise.sample_range_errors`: bias, correlated core, outliers); a
   camera frame every ``camera_every`` ticks: a drone detects a pair ``{R_0, R_i}`` only if its
   altitude is inside the detection band and both robots' markers lie inside the footprint
   (``|Δx| ≤ z tan(hfov/2) − margin``, same for y), each with probability ``p_detect``; it then
   broadcasts a ``pair_sighting`` row (observer the drone, target R_i): the bearing φ_i of
   ``p_0 − p_i`` in F_G and the headings θ_i, θ_0, with white noise plus its own slowly varying
   heading-hold error (common to the three angles); and each drone's marker fix.

This tick loop is the closed-loop counterpart of :func:`relloc.pipeline.replay.replay`: the
result's :class:`~relloc.core.recording.Recording` holds the truth, the commands as odometry and
every reading, and replaying it through fresh estimators started from the same priors gives the
same estimates (the controller only closes the loop; it reads nothing the recording lacks).
All randomness comes from the generator passed in, drawn by the world in a fixed order.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Literal, Protocol

import numpy as np
from numpy.typing import NDArray

from relloc.control.drone_schedule import DroneSchedule, Policy
from relloc.control.formation import Frame, desired_relative, formation_offsets
from relloc.core import checks
from relloc.core.contract import Estimator
from relloc.core.estimates import Estimates, Recorder
from relloc.core.events import run_events
from relloc.core.gaussian import Gaussian
from relloc.core.limits import MAX_ABS_POSITION_M, MAX_SPEED_M_S, MAX_YAW_RATE_RAD_S
from relloc.core.recording import (
    GroundTruth,
    Measurements,
    Odometry,
    Recording,
    empty_measurements,
    measurement_rows,
)
from relloc.errors import ConfigError
from relloc.models.airground import drone_velocity
from relloc.models.unicycle import unicycle_step
from relloc.models.uwb_noise import UwbNoiseModel, sample_range_errors
from relloc.sim.scenario import MAX_ANGLE_RAD, MAX_MEASUREMENTS, MAX_SIMULATED_STEPS

Array = NDArray[np.float64]
PathKind = Literal["arc", "s_curve", "straight"]
Control = Literal["external", "formation"]
#: The frame the followers' beliefs must be in for the controller (:mod:`relloc.pipeline.frames`).
FOLLOWER_FRAME = "airground_follower"


def _positive(owner: str, **values: object) -> None:
    """Each value a finite number > 0 (:func:`relloc.core.checks.positive`)."""
    for name, value in values.items():
        checks.positive(value, f"{owner}.{name}")


def _angle_sigma(owner: str, **values: object) -> None:
    """Each value an angle σ in (0, π] (rad): a wider angle noise carries no information."""
    for name, value in values.items():
        checks.number(value, f"{owner}.{name}", low=0.0, open_low=True, high=math.pi)


def _instance(owner: str, name: str, value: object, cls: type) -> None:
    if not isinstance(value, cls):
        raise ConfigError(f"{owner}.{name}: expected {cls.__name__}, got {value!r:.40}")


@dataclass(frozen=True, kw_only=True)
class CameraSettings:
    """Downward camera of a drone (defaults: a Raspberry Pi camera, 62°×49° field of view).

    Fields of view in (0, π) rad (a pinhole footprint ``z tan(fov/2)`` is finite and positive
    only there), altitudes ``0 < min_altitude < max_altitude``, ``marker_margin ≥ 0``,
    ``p_detect`` in (0, 1], noise σ in (0, π]; all finite, else ConfigError naming the field.
    """

    hfov: float = math.radians(62.0)
    vfov: float = math.radians(49.0)
    min_altitude: float = 1.40
    max_altitude: float = 1.85
    marker_margin: float = 0.10
    p_detect: float = 0.95
    bearing_sigma: float = 0.015
    heading_sigma: float = 0.025

    def __post_init__(self) -> None:
        for name in ("hfov", "vfov"):
            checks.number(
                getattr(self, name),
                f"CameraSettings.{name}",
                low=0.0,
                high=math.pi,
                open_low=True,
                open_high=True,
            )
        _positive("CameraSettings", min_altitude=self.min_altitude)
        checks.number(
            self.max_altitude,
            "CameraSettings.max_altitude (must exceed min_altitude)",
            low=self.min_altitude,
            open_low=True,
        )
        checks.number(self.p_detect, "CameraSettings.p_detect", low=0.0, high=1.0, open_low=True)
        checks.number(self.marker_margin, "CameraSettings.marker_margin", low=0.0)
        _angle_sigma(
            "CameraSettings", bearing_sigma=self.bearing_sigma, heading_sigma=self.heading_sigma
        )

    def half_extent(self, altitude: float) -> tuple[float, float]:
        """Usable half-width of the footprint along x and y at ``altitude``."""
        return (
            altitude * math.tan(0.5 * self.hfov) - self.marker_margin,
            altitude * math.tan(0.5 * self.vfov) - self.marker_margin,
        )


@dataclass(frozen=True, kw_only=True)
class DroneSettings:
    """Drone flight: altitude hold (with wander), planar P control, heading-hold error.

    ``altitude``, the time constants and ``gain`` finite and > 0, ``v_max`` in
    (0, ``MAX_SPEED_M_S``], the σ finite and ≥ 0 (``yaw_sigma`` ≤ π); else ConfigError.
    """

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
            yaw_tau=self.yaw_tau,
        )
        checks.number(self.v_max, "DroneSettings.v_max", low=0.0, open_low=True, high=MAX_SPEED_M_S)
        for name, high in (
            ("altitude_sigma", math.inf),
            ("yaw_sigma", math.pi),
            ("midpoint_sigma", math.inf),
        ):
            checks.number(getattr(self, name), f"DroneSettings.{name}", low=0.0, high=high)


@dataclass(frozen=True, kw_only=True)
class LeaderPath:
    """Leader commands: constant arc ``(v, ω)``, straight ``(v, 0)`` or S-curve.

    ``speed`` in (0, ``MAX_SPEED_M_S``], ``|turn_rate|`` ≤ ``MAX_YAW_RATE_RAD_S``, ``period``
    finite and > 0; else ConfigError naming the field.
    """

    kind: PathKind = "arc"
    speed: float = 0.1
    turn_rate: float = 0.04
    period: float = 40.0

    def __post_init__(self) -> None:
        if self.kind not in ("arc", "s_curve", "straight"):
            raise ConfigError(f"LeaderPath.kind: 'arc', 's_curve' or 'straight', got {self.kind!r}")
        checks.number(self.speed, "LeaderPath.speed", low=0.0, open_low=True, high=MAX_SPEED_M_S)
        bound = MAX_YAW_RATE_RAD_S
        checks.number(self.turn_rate, "LeaderPath.turn_rate", low=-bound, high=bound)
        _positive("LeaderPath", period=self.period)

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
    ``init_heading_sigma`` (also its stated prior covariance).

    Validation (ConfigError naming the field): offsets by
    :func:`relloc.control.formation.formation_offsets` (finite, no follower on the leader or on
    another follower); counts (``n_drones``, ``uwb_every``, ``camera_every`` ≥ 1,
    ``schedule_offset`` ≥ 0) integers; times finite and > 0, with at least one tick
    (``round(duration / dt) ≥ 1``); ``velocity_noise`` two finite σ ≥ 0 within
    ``MAX_SPEED_M_S`` and ``MAX_YAW_RATE_RAD_S``; ``|leader_start_heading|`` ≤ 2π;
    ``init_position_sigma`` ≤ ``MAX_ABS_POSITION_M`` and ``init_heading_sigma`` ≤ π; the
    settings of their own types, the drones' set altitude inside the camera's detection band.
    So that no scenario asks for unbounded work,
    ``robots × ticks`` ≤ :data:`~relloc.sim.scenario.MAX_SIMULATED_STEPS` and the UWB ranges
    ``links × ticks / uwb_every`` ≤ :data:`~relloc.sim.scenario.MAX_MEASUREMENTS`."""

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
        owner = "AirGroundScenario"
        formation_offsets(self.offsets, f"{owner}.offsets")
        if self.offset_frame not in ("global", "leader"):
            raise ConfigError(f"{owner}.offset_frame: 'global' or 'leader'")
        if self.control not in ("external", "formation"):
            raise ConfigError(f"{owner}.control: 'external' or 'formation'")
        checks.count(self.n_drones, f"{owner}.n_drones")
        checks.count(self.uwb_every, f"{owner}.uwb_every")
        checks.count(self.camera_every, f"{owner}.camera_every")
        checks.count(self.schedule_offset, f"{owner}.schedule_offset", low=0)
        _positive(owner, duration=self.duration, dt=self.dt, dwell_time=self.dwell_time)
        checks.number(
            self.init_position_sigma,
            f"{owner}.init_position_sigma",
            low=0.0,
            open_low=True,
            high=MAX_ABS_POSITION_M,
        )
        _angle_sigma(owner, init_heading_sigma=self.init_heading_sigma)
        checks.number(
            self.leader_start_heading,
            f"{owner}.leader_start_heading",
            low=-MAX_ANGLE_RAD,
            high=MAX_ANGLE_RAD,
        )
        if self.camera_every % self.uwb_every != 0:
            raise ConfigError(
                f"{owner}.camera_every: must be a multiple of uwb_every (every camera "
                "frame needs fresh ranges for the triangle bearing)"
            )
        where = f"{owner}.velocity_noise"
        noise = checks.sequence(self.velocity_noise, where, "(σ_v, σ_ω)", length=2)
        checks.number(noise[0], f"{owner}.velocity_noise[0]", low=0.0, high=MAX_SPEED_M_S)
        checks.number(noise[1], f"{owner}.velocity_noise[1]", low=0.0, high=MAX_YAW_RATE_RAD_S)
        if self.control == "external" and self.offset_frame != "leader":
            raise ConfigError(
                f"{owner}.offset_frame: external (rigid) motion needs 'leader' offsets"
            )
        if not isinstance(self.uwb_link_bias, bool):
            raise ConfigError(
                f"{owner}.uwb_link_bias: expected true or false, got {self.uwb_link_bias!r:.40}"
            )
        for name, cls in (
            ("leader", LeaderPath),
            ("uwb", UwbNoiseModel),
            ("camera", CameraSettings),
            ("drone", DroneSettings),
        ):
            _instance(owner, name, getattr(self, name), cls)
        if not self.camera.min_altitude <= self.drone.altitude <= self.camera.max_altitude:
            raise ConfigError(
                f"{owner}.drone.altitude: {self.drone.altitude:g} m is outside the camera's "
                f"detection band [{self.camera.min_altitude:g}, {self.camera.max_altitude:g}] m; "
                "the drones would see nothing"
            )
        self._check_work()
        try:
            self.schedule()
        except ConfigError as exc:
            raise ConfigError(f"{owner}.schedule_policy: {exc}") from None

    def _check_work(self) -> None:
        """At least one tick; at most ``MAX_SIMULATED_STEPS`` robot-ticks and
        ``MAX_MEASUREMENTS`` UWB ranges (class docstring)."""
        ticks = self.duration / self.dt
        robots = self.n_followers + 1 + self.n_drones
        if robots * ticks > MAX_SIMULATED_STEPS:
            raise ConfigError(
                f"AirGroundScenario.duration / dt: {robots} robots × {ticks:.6g} ticks; the "
                f"limit is {MAX_SIMULATED_STEPS:.0e} robot-ticks (MAX_SIMULATED_STEPS)"
            )
        if round(ticks) < 1:
            raise ConfigError(
                f"AirGroundScenario.duration: shorter than one tick ({self.duration:g} s at "
                f"dt = {self.dt:g} s)"
            )
        links = (self.n_followers + 1) * self.n_followers // 2
        if links * ticks / self.uwb_every > MAX_MEASUREMENTS:
            raise ConfigError(
                f"AirGroundScenario.uwb_every: {links} UWB links × {ticks / self.uwb_every:.6g} "
                f"epochs; the limit is {MAX_MEASUREMENTS:.0e} ranges (MAX_MEASUREMENTS)"
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
        """The drones' midpoint schedule (dwell ``k_m = dwell_time / dt`` ticks; a dwell longer
        than the run is one window, ``n_steps + 1`` ticks, so that ``k_m`` stays finite)."""
        return DroneSchedule(
            n_followers=self.n_followers,
            n_drones=self.n_drones,
            dwell_steps=max(1, round(min(self.dwell_time / self.dt, self.n_steps + 1))),
            policy=self.schedule_policy,
            offset=self.schedule_offset,
        )


class FollowerController(Protocol):
    """Command ``(v_i, ω_i)`` of follower ``R_i`` (``1 ≤ i ≤ N``) from its own estimate
    ``[r_x, r_y, θ_i, θ_0]`` and the leader's broadcast command ``(v_0, ω_0)``."""

    def command(
        self, follower: int, estimate: Array, leader_u: tuple[float, float]
    ) -> tuple[float, float]: ...


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


def tick_times(sc: AirGroundScenario) -> Array:
    """``t_k = k dt`` for ``k = 0 … K`` (every process of a team uses these very numbers)."""
    return np.arange(sc.n_steps + 1, dtype=np.float64) * sc.dt


def initial_poses(sc: AirGroundScenario) -> Array:
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


def rigid_command(
    sc: AirGroundScenario, follower: int, v0: float, w0: float
) -> tuple[float, float]:
    """External command of follower ``R_follower`` that keeps the initial layout rigid on the
    leader's arc (``control="external"``)."""
    poses0 = initial_poses(sc)
    if abs(w0) < 1e-9:
        return v0, 0.0
    centre = poses0[0, :2] + np.array([-math.sin(poses0[0, 2]), math.cos(poses0[0, 2])]) * (v0 / w0)
    radius = float(np.hypot(*(poses0[follower, :2] - centre)))
    return abs(w0) * radius, w0


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


def own_velocities(n_robots: int, u: Mapping[int, Array]) -> Array:
    """``(n_robots, 4)`` body velocities with the rows ``u`` known (robot index → velocity),
    zero elsewhere (a follower's filter reads only its own and the leader's)."""
    out = np.zeros((n_robots, 4))
    for r, v in u.items():
        out[r] = v
    return out


def ugv_velocity(v: float, w: float) -> Array:
    """A UGV's command as body velocity ``(v, 0, 0, ω)`` (its odometry)."""
    return np.array([v, 0.0, 0.0, w])


class FollowerAgent:
    """What runs on follower ``R_i``: its estimator (through the contract, one event per tick)
    and its command — the controller's from its own belief of the leader, or the external
    rigid command. The same object runs in :func:`simulate_airground` and in the follower's
    own process."""

    def __init__(
        self,
        sc: AirGroundScenario,
        follower: int,
        estimator: Estimator,
        controller: FollowerController | None,
    ) -> None:
        self.sc = sc
        self.follower = follower
        self.estimator = estimator
        self.controller = controller
        self.leader = robot_names(sc)[0]

    def estimate(
        self, t_prev: float, t: float, velocities: Array, batch: Measurements, recorder: Recorder
    ) -> None:
        """The event at ``t``: advance with ``velocities (R, 4)`` held since ``t_prev``, fuse the
        tick's ``batch``, record the beliefs (:func:`relloc.core.events.run_events`)."""
        times = np.array([t])
        run_events(
            [self.estimator],
            times,
            velocities[None],
            np.full((1, velocities.shape[0]), t_prev),
            batch,
            times,
            recorder,
        )

    def belief_mean(self) -> Array:
        """The mean of the estimator's belief of the leader (what the controller reads)."""
        found = [
            b
            for b in self.estimator.beliefs()
            if b.subject == self.leader and b.frame == FOLLOWER_FRAME
        ]
        if not found:
            raise ConfigError(
                f"simulate_airground: {self.estimator.owner}'s estimator holds no "
                f"{FOLLOWER_FRAME} belief of {self.leader}"
            )
        return found[0].mean

    def command(self, t: float, leader_u: tuple[float, float]) -> tuple[float, float]:
        """``(v_i, ω_i)`` for the tick starting at ``t``."""
        if self.controller is None:
            return rigid_command(self.sc, self.follower, *leader_u)
        return self.controller.command(self.follower, self.belief_mean(), leader_u)


@dataclass(frozen=True)
class MarkerFix:
    """What a drone's camera tells its guidance in one frame: the position of robot
    ``subject``'s marker (UGV index; 0 = the leader) in F_G and, for the leader, its heading."""

    subject: int
    position: Array
    heading: float | None = None


class DroneGuidance:
    """What runs on drone ``D_j``: it keeps a track of the leader's pose — re-anchored on what
    its camera sees (the leader itself, or a follower plus the formation layout), dead-reckoned
    with the leader's broadcast command in between — and flies toward its scheduled midpoint
    ``p_0 − r_des,i / 2`` with the leader's velocity as feed-forward. The same object runs in
    :func:`simulate_airground` and in the drone's own process."""

    def __init__(self, sc: AirGroundScenario, drone: int, leader_track: Array | None) -> None:
        self.sc = sc
        self.drone = drone
        self.schedule = sc.schedule()
        self.offsets = np.array(sc.offsets, dtype=float)
        self.leader_track = None if leader_track is None else np.array(leader_track, dtype=float)

    @staticmethod
    def at_start(sc: AirGroundScenario, drone: int) -> DroneGuidance:
        """Drone ``drone`` (0-based) at the start of a run: tracking the true leader."""
        return DroneGuidance(sc, drone, initial_poses(sc)[0])

    def apply_fix(self, fix: MarkerFix | None) -> None:
        """Re-anchor the leader track on a camera fix (nothing seen: keep dead-reckoning)."""
        if fix is None:
            return
        if fix.subject == 0:
            assert fix.heading is not None
            self.leader_track = np.array([fix.position[0], fix.position[1], fix.heading])
        elif self.leader_track is not None:
            track = self.leader_track
            r = desired_relative(
                self.offsets[fix.subject - 1], float(track[2]), self.sc.offset_frame
            )
            track[:2] = fix.position + r

    def velocity(self, k: int, leader_u: tuple[float, float], position: Array) -> Array:
        """The planar velocity command of tick ``k`` from the drone's position ``(2,)``
        (zero while it has no leader track: a restarted drone hovers until it sees one)."""
        if self.leader_track is None:
            return np.zeros(2)
        d = self.sc.drone
        track = self.leader_track = unicycle_step(self.leader_track, np.array(leader_u), self.sc.dt)
        target = self.schedule.targets(k)[self.drone]
        r = desired_relative(self.offsets[target - 1], float(track[2]), self.sc.offset_frame)
        command = track[:2] - 0.5 * r
        ff = leader_u[0] * np.array([math.cos(track[2]), math.sin(track[2])])
        return drone_velocity(position, command, gain=d.gain, v_max=d.v_max, feedforward=ff)


class AirGroundWorld:
    """The world of one run: the robots' true motion and every sensor (module docstring,
    steps 2 and 4). :meth:`start` draws what is drawn before the first tick (the UWB errors,
    the followers' initial guesses, the drones' heading-hold errors); :meth:`step` moves the
    world one tick under the robots' commands and takes the readings at its end (``batch``, and
    each drone's camera fix in ``fixes``). All randomness comes from the generator given to
    :meth:`start`, drawn in a fixed order."""

    def __init__(self, sc: AirGroundScenario, rng: np.random.Generator) -> None:
        n, m, steps = sc.n_followers, sc.n_drones, sc.n_steps
        self.sc = sc
        self.rng = rng
        self.names = robot_names(sc)
        self.times = tick_times(sc)
        self.offsets = np.array(sc.offsets, dtype=float)
        self.poses = initial_poses(sc)
        self.k = 0
        # UWB links: every unordered UGV pair (a < b), errors drawn for every UWB epoch up front
        self.links = [(a, b) for a in range(n + 1) for b in range(a + 1, n + 1)]
        self.range_errors = sample_range_errors(
            sc.uwb,
            steps // sc.uwb_every + 1,
            len(self.links),
            sc.dt * sc.uwb_every,
            rng,
            link_bias=sc.uwb_link_bias,
        )
        self.priors = self._draw_priors()
        self.drones = _Drones.start(sc, self.poses, self.offsets, rng)
        self.batch = empty_measurements()
        self.fixes: list[MarkerFix | None] = [None] * m
        self._truth = np.zeros((steps + 1, n + 1 + m, 4))
        self._truth[0] = _truth_row(self.poses, self.drones)
        self._commands = np.zeros((steps, n + 1 + m, 4))
        self._formation_error = np.zeros((steps, n, 2))
        self._batches: list[Measurements] = []

    @staticmethod
    def start(sc: AirGroundScenario, rng: np.random.Generator) -> AirGroundWorld:
        """The world at ``t = 0`` (its first draws made)."""
        return AirGroundWorld(sc, rng)

    def _draw_priors(self) -> dict[str, Gaussian]:
        """Each follower's initial guess, drawn around the truth with the stated prior."""
        sc, poses = self.sc, self.poses
        p0_sig = np.array([sc.init_position_sigma] * 2 + [sc.init_heading_sigma] * 2)
        priors: dict[str, Gaussian] = {}
        for i in range(1, sc.n_followers + 1):
            true_x = np.array([*(poses[0, :2] - poses[i, :2]), poses[i, 2], poses[0, 2]])
            mean = true_x + p0_sig * self.rng.standard_normal(4)
            priors[self.names[i]] = Gaussian(mean, np.diag(p0_sig**2))
        return priors

    @property
    def done(self) -> bool:
        return self.k >= self.sc.n_steps

    def drone_position(self, drone: int) -> Array:
        """Drone ``drone``'s position ``(x, y, z)`` now (it knows its own position)."""
        return self.drones.position[drone].copy()

    def readings_of(self, robot: int) -> Measurements:
        """The readings robot ``robot`` took at the end of the last tick (its sensor slice)."""
        return self.batch.select(self.batch.observer == robot)

    def step(self, ugv_u: Array, drone_v: Array) -> None:
        """Tick ``k → k + 1`` under the UGVs' commands ``(N + 1, 2)`` ``(v, ω)`` and the drones'
        planar velocity commands ``(M, 2)``; then the readings at ``t_{k+1}``."""
        sc, k = self.sc, self.k
        n = sc.n_followers
        if self.done:
            raise ConfigError(f"AirGroundWorld.step: the run ended at tick {k}")
        u_cmd = np.asarray(ugv_u, dtype=float)
        # motion (actual = commanded + noise)
        u_act = u_cmd + self.rng.standard_normal(u_cmd.shape) * np.array(sc.velocity_noise)
        self.poses = unicycle_step(self.poses, u_act, sc.dt)
        self.drones.fly(sc, np.asarray(drone_v, dtype=float), self.rng)
        # sensing, stamped at the end of the tick
        t1 = float(self.times[k + 1])
        parts = []
        if k % sc.uwb_every == 0:
            parts.append(
                _uwb_ranges(t1, self.poses, self.links, self.range_errors[k // sc.uwb_every])
            )
        self.fixes = [None] * sc.n_drones
        if k % sc.camera_every == 0:
            frame, self.fixes = self.drones.camera_frame(sc, t1, self.poses, self.rng)
            parts.append(frame)
        self.batch = Measurements.concatenate(parts) if parts else empty_measurements()
        self._batches.append(self.batch)
        # record
        self._commands[k, : n + 1, 0] = u_cmd[:, 0]
        self._commands[k, : n + 1, 3] = u_cmd[:, 1]
        self._commands[k, n + 1 :, :2] = self.drones.velocity
        self._truth[k + 1] = _truth_row(self.poses, self.drones)
        for i in range(1, n + 1):
            desired = desired_relative(self.offsets[i - 1], self.poses[0, 2], sc.offset_frame)
            self._formation_error[k, i - 1] = (self.poses[0, :2] - self.poses[i, :2]) - desired
        self.k = k + 1

    @property
    def formation_error(self) -> Array:
        """``(k, N, 2)`` the true ``r − r_des`` of every follower at the ticks stepped so far."""
        return self._formation_error[: self.k]

    def commands_of(self, k: int) -> Array:
        """``(R, 4)`` every robot's command of tick ``k`` as body velocity (odometry)."""
        return self._commands[k].copy()

    def recording(self) -> Recording:
        """Truth, commands and readings of the ticks stepped so far."""
        k = self.k
        return airground_recording(
            self.sc,
            self.names,
            self.times[: k + 1],
            self._truth[: k + 1],
            self._commands[:k],
            self._batches,
        )

    def run(self, estimates: Estimates) -> AirGroundRun:
        """The finished run with the followers' ``estimates``."""
        return AirGroundRun(
            recording=self.recording(),
            estimates=estimates,
            priors=self.priors,
            formation_error=self.formation_error,
        )


def simulate_airground(
    sc: AirGroundScenario,
    make_estimator: EstimatorFactory,
    controller: FollowerController | None,
    rng: np.random.Generator,
) -> AirGroundRun:
    """Run one closed-loop simulation (module docstring) in this process.

    ``make_estimator(robots, owner, prior)`` builds each follower's estimator (called for
    ``R_1 … R_N`` in order); ``controller`` commands the followers when
    ``sc.control == "formation"`` (``None`` for ``"external"``). Per tick ``k``: the followers
    estimate at ``t_k`` (``k ≥ 1``) with the commands of tick ``k − 1`` and the readings taken
    at ``t_k``, then every robot commands tick ``k`` — the leader its path, each drone its
    :class:`DroneGuidance`, each follower its :class:`FollowerAgent` — and the world steps.
    A team of processes runs these very objects, one per process, and steps the same world.
    """
    _check_controller(sc, controller)
    world = AirGroundWorld.start(sc, rng)
    names = world.names
    followers = []
    for i, (owner, prior) in enumerate(world.priors.items(), start=1):
        est = make_estimator(names, owner, prior)
        if est.owner != owner:
            raise ConfigError(f"simulate_airground: the estimator for {owner} says {est.owner}")
        followers.append(FollowerAgent(sc, i, est, controller))
    drones = [DroneGuidance.at_start(sc, j) for j in range(sc.n_drones)]
    recorder = Recorder("+".join(sorted({f.estimator.name for f in followers})))
    times = world.times
    for k in range(sc.n_steps + 1):
        t = float(times[k])
        if k >= 1:
            held = world.commands_of(k - 1)
            for f in followers:
                f.estimate(float(times[k - 1]), t, held, world.batch, recorder)
        if world.done:
            break
        leader_u = sc.leader.command(t)
        ugv_u = np.array([leader_u, *(f.command(t, leader_u) for f in followers)], dtype=float)
        drone_v = np.zeros((sc.n_drones, 2))
        for j, guidance in enumerate(drones):
            guidance.apply_fix(world.fixes[j])
            drone_v[j] = guidance.velocity(k, leader_u, world.drone_position(j)[:2])
        world.step(ugv_u, drone_v)
    return world.run(recorder.results())


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


def airground_recording(
    sc: AirGroundScenario,
    names: tuple[str, ...],
    times: Array,
    truth: Array,
    commands: Array,
    batches: list[Measurements],
) -> Recording:
    """The run's :class:`Recording`: truth ``(K+1, R, 4)`` at ``times``, the commands
    ``(K, R, 4)`` as odometry, the readings of every tick."""
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
    """The drones' physical state: ``position (M, 3)`` (x, y, z), the planar ``velocity (M, 2)``
    they fly, the altitude deviation and the heading-hold error ``yaw_error (M,)`` (both
    Gauss–Markov)."""

    position: Array
    velocity: Array
    altitude_deviation: Array
    yaw_error: Array

    @staticmethod
    def start(
        sc: AirGroundScenario, poses: Array, offsets: Array, rng: np.random.Generator
    ) -> _Drones:
        """Hovering above their first midpoints at the set altitude."""
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
            altitude_deviation=np.zeros(m),
            yaw_error=rng.normal(0.0, sc.drone.yaw_sigma, m),
        )

    def fly(self, sc: AirGroundScenario, velocity: Array, rng: np.random.Generator) -> None:
        """One tick: fly the commanded planar ``velocity (M, 2)``; altitude and heading-hold
        error wander."""
        dt, d = sc.dt, sc.drone
        a_alt = math.exp(-dt / d.altitude_tau)
        a_yaw = math.exp(-dt / d.yaw_tau)
        for j in range(sc.n_drones):
            self.velocity[j] = velocity[j]
            self.position[j, :2] = self.position[j, :2] + velocity[j] * dt
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
        self, sc: AirGroundScenario, t: float, poses: Array, rng: np.random.Generator
    ) -> tuple[Measurements, list[MarkerFix | None]]:
        """One camera frame of every drone: a ``pair_sighting`` row per detected pair
        {R_0, R_i} (the first drone that sees a pair reports it), and each drone's marker fix
        for its leader track."""
        n, cam = sc.n_followers, sc.camera
        seen: list[int] = []
        observers: list[int] = []
        values: list[tuple[float, float, float]] = []
        fixes: list[MarkerFix | None] = [None] * sc.n_drones
        for j in range(sc.n_drones):
            if not cam.min_altitude <= float(self.position[j, 2]) <= cam.max_altitude:
                continue
            visible = [
                i
                for i in range(n + 1)
                if _in_footprint(cam, self.position[j], poses[i, :2])
                and rng.random() < cam.p_detect
            ]
            fixes[j] = _marker_fix(visible, poses, sc, rng)
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
        rows = measurement_rows(
            "pair_sighting",
            t=np.full(len(seen), t),
            observer=np.array(observers, dtype=np.int64),
            target=np.array(seen, dtype=np.int64),
            value=np.array(values, dtype=float).reshape(-1, 3),
        )
        return rows, fixes


def _marker_fix(
    visible: list[int], poses: Array, sc: AirGroundScenario, rng: np.random.Generator
) -> MarkerFix | None:
    """The marker a drone's guidance re-anchors on: the leader's pose if it is in view, else
    the first visible follower's position (noise: ``midpoint_sigma`` per axis, the camera's
    heading σ)."""
    sig = sc.drone.midpoint_sigma
    if 0 in visible:
        position = poses[0, :2] + sig * rng.standard_normal(2)
        heading = poses[0, 2] + sc.camera.heading_sigma * rng.standard_normal()
        return MarkerFix(0, position, float(heading))
    if visible:
        i = visible[0]
        return MarkerFix(i, poses[i, :2] + sig * rng.standard_normal(2))
    return None
