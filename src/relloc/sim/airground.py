"""Closed-loop simulator of the air-ground team of seed 003 (leader, N followers, M drones).

Per tick ``k`` (period ``dt``, the filters' 20 Hz of the paper):

1. **Commands.** The leader follows its path (constant arc, or an S-shaped curve with
   ``ω_0(t) = ω̄ sin(2πt/T)``). Followers are either externally commanded to move rigidly with
   the leader on the arc (``control="external"``) or run :func:`relloc.control.formation_command`
   on *their own estimate* (``control="formation"``).
2. **Motion.** Every UGV moves with its commands perturbed by white velocity noise (slip,
   actuation), :func:`relloc.models.unicycle.unicycle_step`. Each drone flies at a constant
   heading (ψ̄ = 0, the x-axis of F_G) with :func:`relloc.models.airground.drone_step` toward
   its commanded midpoint; its altitude wanders around the set altitude (Gauss–Markov).
3. **Drone guidance.** A drone knows the formation layout and the leader's broadcast commands;
   it keeps a track of the leader's pose from what its camera sees (the leader itself, or any
   follower plus the layout) and dead-reckons it in between. Its commanded point is the scheduled
   midpoint ``p_0 − r_des,i / 2`` (or the measured midpoint when both robots are in view), with the
   leader's velocity as feed-forward.
4. **Sensing.** UWB ranges between every pair of UGVs every ``uwb_every`` ticks, with errors from
   the fitted real-data model (:func:`relloc.models.uwb_noise.sample_range_errors`: bias,
   correlated core, outliers). A camera frame every ``camera_every`` ticks: a drone detects a
   pair ``{R_0, R_i}`` only if its altitude is inside the detection band and both robots'
   markers lie inside the footprint (``|Δx| ≤ z tan(hfov/2) − margin``, same for y), each with
   probability ``p_detect``; it then broadcasts φ_i, θ_i, θ_0 with white noise plus its own slowly
   varying heading-hold error (common to the three angles).
5. **Estimation.** Each follower's :class:`relloc.estimators.switching_ekf.SwitchingEkf` ticks.

The result holds the full traces (truth, drones, estimates, covariances, modes, detections).
All randomness comes from the generator passed in.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from relloc.control.drone_schedule import DroneSchedule, Policy
from relloc.control.formation import FormationSettings, Frame, desired_relative, formation_command
from relloc.core.gaussian import Gaussian
from relloc.errors import ConfigError
from relloc.estimators.switching_ekf import (
    FilterCounters,
    PairSighting,
    SwitchingEkf,
    SwitchingEkfSettings,
    TickInputs,
)
from relloc.geometry.triangle import side_of
from relloc.models.airground import drone_step
from relloc.models.unicycle import unicycle_step
from relloc.models.uwb_noise import UwbNoiseModel, sample_range_errors

Array = NDArray[np.float64]
PathKind = Literal["arc", "s_curve", "straight"]
Control = Literal["external", "formation"]


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
    (``offset_frame`` says in which frame); the team starts in that formation."""

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
    formation: FormationSettings = field(default_factory=FormationSettings)
    filter: SwitchingEkfSettings = field(default_factory=SwitchingEkfSettings)
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
        """Number of filter ticks."""
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


@dataclass(frozen=True, kw_only=True)
class AirGroundRun:
    """Traces of one run. Index ``[k]`` is after tick k; followers are columns 0..N−1 (= R_1..R_N).

    ``truth[k, 0]`` is the leader's pose; ``estimates[k, i-1]`` follower i's ``[r_x, r_y, θ_i,
    θ_0]``; ``true_state`` the same quantities from ground truth; ``modes[k, i-1]`` its sw;
    ``detected[k, i-1]`` whether {R_0, R_i} is in the drones' latest broadcast; ``targets[k, j]``
    drone j's scheduled follower.
    """

    t: Array
    truth: Array
    drones: Array
    estimates: Array
    covariances: Array
    true_state: Array
    desired: Array
    modes: NDArray[np.int64]
    detected: NDArray[np.bool_]
    targets: NDArray[np.int64]
    counters: tuple[FilterCounters, ...]


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


def simulate_airground(sc: AirGroundScenario, rng: np.random.Generator) -> AirGroundRun:
    """Run one closed-loop simulation (see module docstring)."""
    n, m, dt, steps = sc.n_followers, sc.n_drones, sc.dt, sc.n_steps
    schedule = sc.schedule()
    offsets = np.array(sc.offsets, dtype=float)
    poses = _initial_poses(sc)
    poses0 = poses.copy()
    # UWB links: every unordered UGV pair (a < b), errors drawn for every UWB epoch up front.
    links = [(a, b) for a in range(n + 1) for b in range(a + 1, n + 1)]
    link_index = {pair: k for k, pair in enumerate(links)}
    n_epochs = steps // sc.uwb_every + 1
    range_err = sample_range_errors(
        sc.uwb, n_epochs, len(links), dt * sc.uwb_every, rng, link_bias=sc.uwb_link_bias
    )
    # Sides of follower i w.r.t. the line R_0 R_j, from the formation layout (leader frame and
    # global layouts are rotations of each other, so the sign is the same).
    sides = {
        (i, j): side_of((0.0, 0.0), tuple(-offsets[j - 1]), tuple(-offsets[i - 1]))
        for i in range(1, n + 1)
        for j in range(1, n + 1)
        if i != j
    }
    # Filters, initialised around the truth with the stated prior.
    filters = []
    p0_sig = np.array([sc.init_position_sigma] * 2 + [sc.init_heading_sigma] * 2)
    for i in range(1, n + 1):
        true_x = np.array([*(poses[0, :2] - poses[i, :2]), poses[i, 2], poses[0, 2]])
        mean = true_x + p0_sig * rng.standard_normal(4)
        filters.append(SwitchingEkf(i, Gaussian(mean, np.diag(p0_sig**2)), sc.filter))
    # Drones start hovering above their first midpoint; each keeps a track of the leader pose.
    drones = np.zeros((m, 3))
    first = schedule.targets(0)
    for j in range(m):
        r = desired_relative(offsets[first[j] - 1], poses[0, 2], sc.offset_frame)
        drones[j, :2] = poses[0, :2] - 0.5 * r
        drones[j, 2] = sc.drone.altitude
    leader_track = np.tile(poses[0], (m, 1))
    alt_dev = np.zeros(m)
    yaw_err = rng.normal(0.0, sc.drone.yaw_sigma, m)
    a_alt = math.exp(-dt / sc.drone.altitude_tau)
    a_yaw = math.exp(-dt / sc.drone.yaw_tau)
    detected: tuple[int, ...] = ()

    out_t = np.arange(1, steps + 1, dtype=np.float64) * dt
    truth = np.zeros((steps, n + 1, 3))
    drone_tr = np.zeros((steps, m, 3))
    est = np.zeros((steps, n, 4))
    cov = np.zeros((steps, n, 4, 4))
    true_state = np.zeros((steps, n, 4))
    desired = np.zeros((steps, n, 2))
    modes = np.zeros((steps, n), dtype=np.int64)
    det = np.zeros((steps, n), dtype=bool)
    targets = np.zeros((steps, m), dtype=np.int64)
    sv, sw = sc.velocity_noise

    for k in range(steps):
        t = k * dt
        v0, w0 = sc.leader.command(t)
        # 1. commands
        if sc.control == "external":
            u_f = _rigid_commands(sc, poses0, v0, w0)
        else:
            u_f = np.array(
                [
                    formation_command(
                        filters[i].belief.mean, offsets[i], sc.offset_frame, (v0, w0), sc.formation
                    )
                    for i in range(n)
                ]
            )
        u_cmd = np.vstack([[v0, w0], u_f])
        # 2. motion (actual = commanded + noise)
        u_act = u_cmd + rng.standard_normal(u_cmd.shape) * np.array([sv, sw])
        poses = unicycle_step(poses, u_act, dt)
        tgt = schedule.targets(k)
        for j in range(m):
            leader_track[j] = unicycle_step(leader_track[j], np.array([v0, w0]), dt)
            r = desired_relative(offsets[tgt[j] - 1], float(leader_track[j, 2]), sc.offset_frame)
            command = leader_track[j, :2] - 0.5 * r
            ff = v0 * np.array([math.cos(leader_track[j, 2]), math.sin(leader_track[j, 2])])
            drones[j, :2], _ = drone_step(
                drones[j, :2], command, dt, gain=sc.drone.gain, v_max=sc.drone.v_max, feedforward=ff
            )
            alt_dev[j] = (
                a_alt * alt_dev[j]
                + sc.drone.altitude_sigma * math.sqrt(1 - a_alt**2) * rng.standard_normal()
            )
            drones[j, 2] = sc.drone.altitude + alt_dev[j]
            yaw_err[j] = (
                a_yaw * yaw_err[j]
                + sc.drone.yaw_sigma * math.sqrt(1 - a_yaw**2) * rng.standard_normal()
            )
        # 3.-4. sensing
        ranges: dict[tuple[int, int], float] = {}
        if k % sc.uwb_every == 0:
            epoch = k // sc.uwb_every
            for (a, b), li in link_index.items():
                d_true = float(np.hypot(*(poses[a, :2] - poses[b, :2])))
                ranges[(a, b)] = max(1e-3, d_true + float(range_err[epoch, li]))
        sightings: list[PairSighting] = []
        if k % sc.camera_every == 0:
            seen: set[int] = set()
            for j in range(m):
                z = float(drones[j, 2])
                if not sc.camera.min_altitude <= z <= sc.camera.max_altitude:
                    continue
                visible = [
                    i
                    for i in range(n + 1)
                    if _in_footprint(sc.camera, drones[j], poses[i, :2])
                    and rng.random() < sc.camera.p_detect
                ]
                _update_leader_track(leader_track, j, visible, poses, offsets, sc, rng)
                if 0 not in visible:
                    continue
                for i in visible:
                    if i == 0 or i in seen:
                        continue
                    seen.add(i)
                    rel = poses[0, :2] - poses[i, :2]
                    cam_sig, head_sig = sc.camera.bearing_sigma, sc.camera.heading_sigma
                    sightings.append(
                        PairSighting(
                            follower=i,
                            bearing=math.atan2(rel[1], rel[0])
                            + yaw_err[j]
                            + cam_sig * rng.standard_normal(),
                            heading_follower=poses[i, 2]
                            + yaw_err[j]
                            + head_sig * rng.standard_normal(),
                            heading_leader=poses[0, 2]
                            + yaw_err[j]
                            + head_sig * rng.standard_normal(),
                        )
                    )
            detected = tuple(sorted(seen))
        # 5. estimation
        for i in range(1, n + 1):
            fresh = bool(ranges)
            tick = TickInputs(
                u=np.array([*u_cmd[i], v0, w0]),
                detected=detected,
                range_0i=ranges.get((0, i)) if fresh else None,
                ranges_0j={j: ranges[(0, j)] for j in range(1, n + 1) if j != i and fresh},
                ranges_ij={
                    j: ranges[(min(i, j), max(i, j))] for j in range(1, n + 1) if j != i and fresh
                },
                sightings=tuple(sightings),
                sides={j: sides[(i, j)] for j in range(1, n + 1) if j != i},
            )
            modes[k, i - 1] = int(filters[i - 1].tick(tick, dt, t + dt))
        # record
        truth[k] = poses
        drone_tr[k] = drones
        targets[k] = tgt
        for i in range(1, n + 1):
            est[k, i - 1] = filters[i - 1].belief.mean
            cov[k, i - 1] = filters[i - 1].belief.cov
            true_state[k, i - 1] = [*(poses[0, :2] - poses[i, :2]), poses[i, 2], poses[0, 2]]
            desired[k, i - 1] = desired_relative(offsets[i - 1], poses[0, 2], sc.offset_frame)
            det[k, i - 1] = i in detected
    return AirGroundRun(
        t=out_t,
        truth=truth,
        drones=drone_tr,
        estimates=est,
        covariances=cov,
        true_state=true_state,
        desired=desired,
        modes=modes,
        detected=det,
        targets=targets,
        counters=tuple(f.counters for f in filters),
    )


def _update_leader_track(
    track: Array,
    j: int,
    visible: list[int],
    poses: Array,
    offsets: Array,
    sc: AirGroundScenario,
    rng: np.random.Generator,
) -> None:
    """Re-anchor drone j's leader track on what its camera sees (leader first, else a follower
    plus the formation layout); headings are read from the markers."""
    sig = sc.drone.midpoint_sigma
    if 0 in visible:
        track[j, :2] = poses[0, :2] + sig * rng.standard_normal(2)
        track[j, 2] = poses[0, 2] + sc.camera.heading_sigma * rng.standard_normal()
        return
    if visible:
        i = visible[0]
        theta0 = float(track[j, 2])
        r = desired_relative(offsets[i - 1], theta0, sc.offset_frame)
        track[j, :2] = poses[i, :2] + r + sig * rng.standard_normal(2)
