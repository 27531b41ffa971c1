"""Scenarios: the team, its motions, sensors and noise, as frozen keyword-only dataclasses.

A :class:`Scenario` is what :func:`relloc.sim.simulate.simulate` turns into a
:class:`relloc.core.recording.Recording`. It is usually loaded from TOML with :func:`load_scenario`
(the built-in default is ``relloc/sim/scenarios/default.toml``, the seed-000 air-ground team of
§5: one observing ground robot, two aerial observed robots whose planes sit 2.0 m and 1.5 m
above the observer's sensor plane and two ground observed robots 0.1 m and 0.2 m below it, in a
10 m × 20 m × 3 m arena, observed with the Table-2 case-(1) sensor at 10 Hz, propagated at
100 Hz).

The world frame has z = 0 on the observing robots' sensor plane; every robot moves on its own
horizontal plane at ``height`` (aerial robots may add a vertical oscillation). Ground robots are
unicycles (body velocity ``(v_x, 0, 0, ω_z)``); aerial robots obey the hovering condition and
may move sideways and vertically (seed 000 §3.1, condition 6).

Every field is validated in ``__post_init__``; errors are :class:`relloc.errors.ConfigError`
naming the field, and the TOML loader prefixes the file and the path, e.g.
``my.toml: robots[2].sensor.fov_deg: must be in (0, 360], got 400``.

Limits. So that no file can ask for unbounded work or for numbers that overflow, a scenario
stays inside these bounds (module constants):

- the file: at most :data:`MAX_FILE_BYTES` (4 MiB) of UTF-8 TOML (a leading byte-order mark is
  allowed);
- the team: 1 to :data:`MAX_ROBOTS` (64) robots, named by :data:`ROBOT_NAME_PATTERN`
  (``[A-Za-z0-9_-]{1,64}``: names become parts of file names);
- the work: ``robots × duration_s × propagation_rate_hz`` ≤ :data:`MAX_SIMULATED_STEPS`
  (10⁷ robot-steps, about 1.2 GB of simulated arrays) and, summed over every
  (observer, observed) pair, ``duration_s × rate_hz`` ≤ :data:`MAX_MEASUREMENTS` (10⁶);
  at least one propagation step, and ``propagation_rate_hz`` ≥
  :data:`MIN_PROPAGATION_RATE_HZ` (10⁻³ Hz), so ``duration_s`` < 10¹⁰ s;
- space: arena bounds, way-points, initial positions, heights and the vertical oscillation
  within ±:data:`MAX_EXTENT_M` (10⁶ m); consecutive way-points (and, on a closed path, the
  last and the first) at least :data:`MIN_SEGMENT_M` (1 mm) apart; at most
  :data:`MAX_WAYPOINTS` (1000) way-points per path;
- motion: speeds and linear-velocity commands within ±:data:`~relloc.core.limits.MAX_SPEED_M_S`
  (100 m/s), yaw rates within ±:data:`~relloc.core.limits.MAX_YAW_RATE_RAD_S` (100 rad/s),
  angles (yaw, phase) within ±2π, oscillation periods at least :data:`MIN_PERIOD_S` (1 ms);
- noise: odometry σ within the same speed and yaw-rate bounds; sensor σ_r, σ_θ, σ_α at least
  :data:`MIN_SENSOR_SIGMA` (10⁻⁶ m or rad: the filters square them, and a vanishing σ makes the
  innovation covariance singular), σ_r ≤ ``MAX_EXTENT_M`` and σ_θ, σ_α ≤ π (a wider bearing
  noise carries no information).

Fields of view and sensor rates only need to be positive: a very narrow view or a very slow
sensor is valid and simply yields few or no measurements. A robot with a sensor whose
``observes`` list is empty is valid too (it measures nothing), but the scenario as a whole must
measure at least one (observer, observed) pair.
"""

from __future__ import annotations

import math
import numbers
import re
import reprlib
import tomllib
from collections.abc import Callable, Mapping, Sequence
from dataclasses import MISSING, dataclass, field, fields
from importlib import resources
from pathlib import Path
from typing import Any, Literal

from relloc.core import checks
from relloc.core.limits import MAX_SPEED_M_S, MAX_YAW_RATE_RAD_S
from relloc.errors import ConfigError

RobotKind = Literal["ground", "aerial"]

# --------------------------------------------------------------------------- limits

MAX_FILE_BYTES = 4 * 1024 * 1024
MAX_ROBOTS = 64
ROBOT_NAME_PATTERN = "[A-Za-z0-9_-]{1,64}"
MAX_SCENARIO_NAME_CHARS = 200
MAX_SIMULATED_STEPS = 10_000_000
MAX_MEASUREMENTS = 1_000_000
MIN_PROPAGATION_RATE_HZ = 1e-3
MAX_EXTENT_M = 1e6
MIN_SEGMENT_M = 1e-3
MAX_WAYPOINTS = 1000
MAX_ANGLE_RAD = 2.0 * math.pi
MIN_PERIOD_S = 1e-3
MIN_SENSOR_SIGMA = 1e-6

_ROBOT_NAME = re.compile(ROBOT_NAME_PATTERN)
_BARE_KEY = re.compile("[A-Za-z0-9_-]{1,64}")  # a TOML bare key, short enough to print as is
# Per-component bounds of a body velocity (v_x, v_y, v_z, ω_z) and of an initial pose (x, y, ψ).
_CHANNEL_LIMITS = (MAX_SPEED_M_S, MAX_SPEED_M_S, MAX_SPEED_M_S, MAX_YAW_RATE_RAD_S)
_POSE_LIMITS = (MAX_EXTENT_M, MAX_EXTENT_M, MAX_ANGLE_RAD)
_XY_LIMITS = (MAX_EXTENT_M, MAX_EXTENT_M)  # a way-point; an arena interval (lower, upper)

_SHORT = reprlib.Repr()
_SHORT.maxstring = _SHORT.maxother = 60
_SHORT.maxlist = _SHORT.maxtuple = _SHORT.maxdict = 6
_SHORT.maxlevel = 3


def _show(value: object) -> str:
    """A short ``repr`` of a user value for an error message (long or deep values elided)."""
    return _SHORT.repr(value)


def _key(key: str) -> str:
    """A TOML key as it would be written: bare if it can be, quoted and shortened otherwise."""
    return key if _BARE_KEY.fullmatch(key) else _show(key)


# --------------------------------------------------------------------------- field checks


def _interval(low: float | None, high: float | None, low_open: bool) -> str:
    """``[low, high]`` as text, e.g. ``(0, 360]`` or ``[0.001, ∞)``."""
    left = "(-∞" if low is None else f"{'(' if low_open else '['}{low:g}"
    right = "∞)" if high is None else f"{high:g}]"
    return f"{left}, {right}"


def _number(
    name: str,
    value: object,
    *,
    low: float | None = None,
    high: float | None = None,
    low_open: bool = False,
    allow_inf: bool = False,
) -> float:
    """``value`` as a float in ``[low, high]`` (``(low, high]`` if ``low_open``; a missing bound
    is unbounded), finite unless ``allow_inf``; otherwise ConfigError naming ``name``. Any
    real number but a bool is one (numpy's scalars too, as a Python caller passes them)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise ConfigError(f"{name}: expected a number, got {_show(value)}")
    try:
        v = float(value)
    except OverflowError:  # an integer beyond the float range
        raise ConfigError(f"{name}: must be finite, got {_show(value)}") from None
    if math.isnan(v) or (math.isinf(v) and not allow_inf):
        raise ConfigError(f"{name}: must be finite, got {_show(value)}")
    too_low = low is not None and (v < low or (low_open and v == low))
    too_high = high is not None and v > high
    if too_low or too_high:
        interval = _interval(low, high, low_open)
        raise ConfigError(f"{name}: must be in {interval}, got {_show(value)}")
    return v


def _vector(name: str, value: object, size: int, **limits: Any) -> tuple[float, ...]:
    """``value`` as ``size`` floats, each checked by :func:`_number` with ``limits``."""
    items = checks.sequence(value, name, f"a list of {size} numbers")
    if len(items) != size:
        raise ConfigError(f"{name}: expected {size} numbers, got {len(items)}")
    return tuple(_number(f"{name}[{i}]", v, **limits) for i, v in enumerate(items))


def _bounded(
    name: str, value: object, bounds: Sequence[float], *, signed: bool = True
) -> tuple[float, ...]:
    """``value`` as ``len(bounds)`` floats with ``|value_i| ≤ bounds_i`` (``0 ≤ value_i`` unless
    ``signed``)."""
    values = _vector(name, value, len(bounds))
    for i, (v, b) in enumerate(zip(values, bounds, strict=True)):
        _number(f"{name}[{i}]", v, low=-b if signed else 0.0, high=b)
    return values


def _set(obj: object, name: str, value: object) -> None:
    object.__setattr__(obj, name, value)


# --------------------------------------------------------------------------- parts


@dataclass(frozen=True, kw_only=True)
class Arena:
    """Axis-aligned box the robots must stay inside (m); z is relative to the sensor plane."""

    x: tuple[float, float] = (0.0, 10.0)
    y: tuple[float, float] = (0.0, 20.0)
    z: tuple[float, float] = (-0.5, 2.5)

    def __post_init__(self) -> None:
        for axis in ("x", "y", "z"):
            lo, hi = _bounded(axis, getattr(self, axis), _XY_LIMITS)
            if not lo < hi:
                raise ConfigError(f"{axis}: lower bound {lo:g} must be below upper bound {hi:g}")
            _set(self, axis, (lo, hi))


@dataclass(frozen=True, kw_only=True)
class SensorSpec:
    """Range/azimuth/elevation sensor of an observing robot (seed 000 Eq. 2, Table 2).

    Defaults are Table 2 case (1): σ_r = 0.0068 m, σ_θ = σ_α = 0.0036 rad at 10 Hz.
    ``fov_deg`` is the horizontal field of view centred on the body x axis (|θ| ≤ fov/2),
    ``elevation_fov_deg`` the vertical one (|α| ≤ elevation_fov/2); targets outside
    ``[min_range, max_range]`` are not seen.
    """

    sigma_range: float = 0.0068
    sigma_azimuth: float = 0.0036
    sigma_elevation: float = 0.0036
    rate_hz: float = 10.0
    fov_deg: float = 360.0
    elevation_fov_deg: float = 180.0
    max_range: float = 30.0
    min_range: float = 0.05

    def __post_init__(self) -> None:
        for name, high in (
            ("sigma_range", MAX_EXTENT_M),
            ("sigma_azimuth", math.pi),
            ("sigma_elevation", math.pi),
        ):
            _set(self, name, _number(name, getattr(self, name), low=MIN_SENSOR_SIGMA, high=high))
        view: tuple[tuple[str, float | None], ...] = (
            ("rate_hz", None),
            ("fov_deg", 360.0),
            ("elevation_fov_deg", 180.0),
        )
        for name, limit in view:
            value = _number(name, getattr(self, name), low=0.0, low_open=True, high=limit)
            _set(self, name, value)
        _set(self, "min_range", _number("min_range", self.min_range, low=0.0))
        _set(
            self,
            "max_range",
            _number("max_range", self.max_range, low=0.0, low_open=True, allow_inf=True),
        )
        if self.max_range <= self.min_range:
            raise ConfigError(
                f"max_range: must exceed min_range ({self.min_range:g}), got {self.max_range:g}"
            )

    @property
    def sigma(self) -> tuple[float, float, float]:
        """(σ_r, σ_θ, σ_α)."""
        return (self.sigma_range, self.sigma_azimuth, self.sigma_elevation)


@dataclass(frozen=True, kw_only=True)
class OdometryNoise:
    """White noise on the body velocities a robot reports, one sample per propagation step.

    ``sigma_v`` (m/s) on each horizontal channel an aerial robot has (v_x, v_y) and on the
    forward speed of a ground robot, ``sigma_vz`` (m/s) on an aerial robot's climb rate,
    ``sigma_w`` (rad/s) on the yaw rate. Channels a ground robot cannot move along (v_y, v_z)
    are known to be zero and carry no noise.
    """

    sigma_v: float = 0.05
    sigma_vz: float = 0.02
    sigma_w: float = 0.05

    def __post_init__(self) -> None:
        for name, high in (
            ("sigma_v", MAX_SPEED_M_S),
            ("sigma_vz", MAX_SPEED_M_S),
            ("sigma_w", MAX_YAW_RATE_RAD_S),
        ):
            _set(self, name, _number(name, getattr(self, name), low=0.0, high=high))

    def sigma_for(self, kind: RobotKind) -> tuple[float, float, float, float]:
        """Per-channel σ of ``(v_x, v_y, v_z, ω_z)`` for a robot of this kind."""
        if kind == "ground":
            return (self.sigma_v, 0.0, 0.0, self.sigma_w)
        return (self.sigma_v, self.sigma_v, self.sigma_vz, self.sigma_w)


def _check_segments(points: tuple[tuple[float, ...], ...], *, closed: bool) -> None:
    """Consecutive way-points (and, when ``closed``, the last and the first) must be at least
    :data:`MIN_SEGMENT_M` apart: the spline is parametrised by the cumulative chord length,
    which must increase strictly."""
    n = len(points)
    for k in range(1, n + 1 if closed else n):
        length = math.dist(points[k - 1], points[k % n])
        if length >= MIN_SEGMENT_M:
            continue
        if k < n:
            raise ConfigError(
                f"points[{k}]: {length:g} m from points[{k - 1}]; consecutive way-points must "
                f"be at least {MIN_SEGMENT_M:g} m apart"
            )
        raise ConfigError(
            f"points[{n - 1}]: {length:g} m from points[0]; a closed path returns to its first "
            "point by itself, so leave the repeated point out (way-points at least "
            f"{MIN_SEGMENT_M:g} m apart)"
        )


@dataclass(frozen=True, kw_only=True)
class WaypointMotion:
    """Follow a smooth (cubic-spline) path through ``points`` at constant ``speed``.

    ``closed`` loops the path (periodic spline) and repeats it; an open path stops at its end.
    ``heading = "tangent"`` points the body x axis along the path (mandatory for ground robots);
    ``"fixed"`` keeps the initial yaw ``yaw_rad`` (aerial robots fly sideways).
    ``z_amplitude``/``z_period_s`` add a vertical oscillation (aerial robots only).
    """

    points: tuple[tuple[float, float], ...]
    speed: float = 0.4
    closed: bool = True
    heading: Literal["tangent", "fixed"] = "tangent"
    yaw_rad: float = 0.0
    z_amplitude: float = 0.0
    z_period_s: float = 20.0

    def __post_init__(self) -> None:
        if not isinstance(self.closed, bool):
            raise ConfigError(f"closed: expected true or false, got {_show(self.closed)}")
        what = "a list of at least two [x, y] points"
        pts = checks.sequence(self.points, "points", what)
        if len(pts) < 2:
            raise ConfigError(f"points: expected {what}, got {len(pts)}")
        if len(pts) > MAX_WAYPOINTS:
            raise ConfigError(
                f"points: {len(pts)} way-points; the limit is {MAX_WAYPOINTS} (MAX_WAYPOINTS)"
            )
        if self.closed and len(pts) < 3:
            raise ConfigError("points: a closed path needs at least three points")
        points = tuple(_bounded(f"points[{i}]", p, _XY_LIMITS) for i, p in enumerate(pts))
        _check_segments(points, closed=self.closed)
        _set(self, "points", points)
        _set(
            self, "speed", _number("speed", self.speed, low=0.0, low_open=True, high=MAX_SPEED_M_S)
        )
        if self.heading not in ("tangent", "fixed"):
            raise ConfigError(f"heading: must be 'tangent' or 'fixed', got {_show(self.heading)}")
        _set(
            self,
            "yaw_rad",
            _number("yaw_rad", self.yaw_rad, low=-MAX_ANGLE_RAD, high=MAX_ANGLE_RAD),
        )
        _set(
            self,
            "z_amplitude",
            _number("z_amplitude", self.z_amplitude, low=0.0, high=MAX_EXTENT_M),
        )
        _set(self, "z_period_s", _number("z_period_s", self.z_period_s, low=MIN_PERIOD_S))


@dataclass(frozen=True, kw_only=True)
class VelocityMotion:
    """Body-velocity commands ``u_i(t) = mean_i + amplitude_i · sin(2π t / period_i + phase_i)``.

    Channels ``i`` are ``(v_x, v_y, v_z, ω_z)``; constant commands have zero amplitude. The
    robot starts at its :attr:`RobotSpec.initial_pose`.
    """

    mean: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 0.0)
    amplitude: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 0.0)
    period_s: tuple[float, float, float, float] = (10.0, 10.0, 10.0, 10.0)
    phase_rad: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        _set(self, "mean", _bounded("mean", self.mean, _CHANNEL_LIMITS))
        _set(
            self, "amplitude", _bounded("amplitude", self.amplitude, _CHANNEL_LIMITS, signed=False)
        )
        _set(self, "period_s", _vector("period_s", self.period_s, 4, low=MIN_PERIOD_S))
        _set(self, "phase_rad", _bounded("phase_rad", self.phase_rad, (MAX_ANGLE_RAD,) * 4))


Motion = WaypointMotion | VelocityMotion


@dataclass(frozen=True, kw_only=True)
class RobotSpec:
    """One robot: name, kind, plane height, motion, odometry noise and (optionally) a sensor.

    A robot with a ``sensor`` is an observing robot; it observes the robots named in
    ``observes`` (``None``: every other robot; an empty list: none). ``initial_pose = (x, y,
    yaw)`` is required for velocity commands and must be left out for way-points (the path
    gives the start). ``name`` matches :data:`ROBOT_NAME_PATTERN`.
    """

    name: str
    kind: RobotKind
    motion: Motion
    height: float = 0.0
    initial_pose: tuple[float, float, float] | None = None
    odometry: OdometryNoise = field(default_factory=OdometryNoise)
    sensor: SensorSpec | None = None
    observes: tuple[str, ...] | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not _ROBOT_NAME.fullmatch(self.name):
            raise ConfigError(
                f"name: must match {ROBOT_NAME_PATTERN} (letters, digits, '_' and '-'; "
                f"names become parts of file names), got {_show(self.name)}"
            )
        if self.kind not in ("ground", "aerial"):
            raise ConfigError(f"kind: must be 'ground' or 'aerial', got {_show(self.kind)}")
        _set(self, "height", _number("height", self.height, low=-MAX_EXTENT_M, high=MAX_EXTENT_M))
        m = self.motion
        if isinstance(m, VelocityMotion):
            self._check_velocity_motion(m)
        elif isinstance(m, WaypointMotion):
            self._check_waypoint_motion(m)
        else:
            raise ConfigError("motion: expected way-points or velocity commands")
        if not isinstance(self.odometry, OdometryNoise):
            raise ConfigError("odometry: expected an odometry noise table")
        if self.sensor is not None and not isinstance(self.sensor, SensorSpec):
            raise ConfigError("sensor: expected a sensor table")
        if self.observes is not None:
            _set(self, "observes", self._checked_observes(self.observes))

    def _check_velocity_motion(self, m: VelocityMotion) -> None:
        if self.initial_pose is None:
            raise ConfigError("initial_pose: required with velocity commands ([x, y, yaw])")
        _set(self, "initial_pose", _bounded("initial_pose", self.initial_pose, _POSE_LIMITS))
        if self.kind == "ground":
            for ch, label in ((1, "v_y"), (2, "v_z")):
                for part in ("mean", "amplitude"):
                    value = getattr(m, part)[ch]
                    if value != 0.0:
                        raise ConfigError(
                            f"motion.{part}[{ch}]: a ground robot cannot move along {label}; "
                            f"must be 0, got {value:g}"
                        )

    def _check_waypoint_motion(self, m: WaypointMotion) -> None:
        if self.initial_pose is not None:
            raise ConfigError(
                "initial_pose: not used with way-points (the path's first point is the start)"
            )
        if self.kind == "ground" and m.heading != "tangent":
            raise ConfigError(
                f"motion.heading: a ground robot follows its path's tangent; must be 'tangent', "
                f"got {m.heading!r}"
            )
        if self.kind == "ground" and m.z_amplitude != 0.0:
            raise ConfigError(
                f"motion.z_amplitude: a ground robot moves on a flat plane; must be 0, got "
                f"{m.z_amplitude:g}"
            )

    def _checked_observes(self, obs: object) -> tuple[str, ...]:
        if self.sensor is None:
            raise ConfigError("observes: only a robot with a sensor can observe")
        if isinstance(obs, str) or not isinstance(obs, Sequence):
            raise ConfigError(f"observes: expected a list of robot names, got {_show(obs)}")
        if len(obs) > MAX_ROBOTS:
            raise ConfigError(f"observes: {len(obs)} names; the limit is {MAX_ROBOTS} (MAX_ROBOTS)")
        for i, o in enumerate(obs):
            if not isinstance(o, str):
                raise ConfigError(f"observes[{i}]: expected a robot name, got {_show(o)}")
            if o in obs[:i]:
                raise ConfigError(f"observes[{i}]: {_show(o)} is already listed")
        return tuple(obs)

    @property
    def is_observer(self) -> bool:
        return self.sensor is not None


@dataclass(frozen=True, kw_only=True)
class Scenario:
    """A team scenario: robots, arena, duration and the propagation (odometry) rate."""

    robots: tuple[RobotSpec, ...]
    name: str = "scenario"
    description: str = ""
    duration_s: float = 60.0
    propagation_rate_hz: float = 100.0
    arena: Arena = field(default_factory=Arena)

    def __post_init__(self) -> None:
        if (
            not isinstance(self.name, str)
            or not 0 < len(self.name) <= MAX_SCENARIO_NAME_CHARS
            or not self.name.isprintable()
        ):
            raise ConfigError(
                f"name: expected a one-line text of 1 to {MAX_SCENARIO_NAME_CHARS} printable "
                f"characters, got {_show(self.name)}"
            )
        if not isinstance(self.description, str):
            raise ConfigError(f"description: expected a text, got {_show(self.description)}")
        _set(self, "duration_s", _number("duration_s", self.duration_s, low=0.0, low_open=True))
        rate = _number("propagation_rate_hz", self.propagation_rate_hz, low=MIN_PROPAGATION_RATE_HZ)
        _set(self, "propagation_rate_hz", rate)
        if not isinstance(self.arena, Arena):
            raise ConfigError("arena: expected an arena table")
        if isinstance(self.robots, (str, bytes)) or not isinstance(self.robots, Sequence):
            raise ConfigError(f"robots: expected a list of robots, got {_show(self.robots)}")
        robots = tuple(self.robots)
        if not robots:
            raise ConfigError("robots: a scenario needs at least one robot")
        if len(robots) > MAX_ROBOTS:
            raise ConfigError(
                f"robots: {len(robots)} robots; the limit is {MAX_ROBOTS} (MAX_ROBOTS)"
            )
        for i, r in enumerate(robots):
            if not isinstance(r, RobotSpec):
                raise ConfigError(f"robots[{i}]: expected a robot, got {_show(r)}")
        _set(self, "robots", robots)
        self._check_steps()
        self._check_team()
        self._check_measurements()

    def _check_steps(self) -> None:
        """``1 ≤ round(duration_s · propagation_rate_hz)`` and, over all robots, at most
        :data:`MAX_SIMULATED_STEPS` robot-steps."""
        steps = self.duration_s * self.propagation_rate_hz
        total = len(self.robots) * steps
        if total > MAX_SIMULATED_STEPS:
            raise ConfigError(
                f"duration_s × propagation_rate_hz: {len(self.robots)} robot(s) × {steps:.6g} "
                f"steps = {total:.3g} simulated steps; the limit is {MAX_SIMULATED_STEPS:.0e} "
                "(MAX_SIMULATED_STEPS)"
            )
        if round(steps) < 1:
            raise ConfigError(
                f"duration_s: shorter than one propagation step ({self.duration_s:g} s at "
                f"propagation_rate_hz = {self.propagation_rate_hz:g})"
            )

    def _check_team(self) -> None:
        """Unique names, at least one observer, known targets, sensor rates within the
        propagation rate, and at least one (observer, observed) pair."""
        names = [r.name for r in self.robots]
        for i, name in enumerate(names):
            if name in names[:i]:
                raise ConfigError(f"robots[{i}].name: duplicate robot name {name!r}")
        if not any(r.is_observer for r in self.robots):
            raise ConfigError("robots: at least one robot needs a sensor (an observing robot)")
        for i, r in enumerate(self.robots):
            for j, target in enumerate(r.observes or ()):
                if target not in names:
                    raise ConfigError(
                        f"robots[{i}].observes[{j}]: unknown robot {_show(target)}; "
                        f"robots are {', '.join(names)}"
                    )
                if target == r.name:
                    raise ConfigError(f"robots[{i}].observes[{j}]: a robot cannot observe itself")
            if r.sensor is not None and r.sensor.rate_hz > self.propagation_rate_hz:
                raise ConfigError(
                    f"robots[{i}].sensor.rate_hz: must not exceed propagation_rate_hz "
                    f"({self.propagation_rate_hz:g}), got {r.sensor.rate_hz:g}"
                )
        if not self.pairs():
            raise ConfigError(
                "robots: nothing to measure; no observing robot has another robot to observe"
            )

    def _check_measurements(self) -> None:
        """At most :data:`MAX_MEASUREMENTS` sensor epochs ``duration_s · rate_hz`` over all
        pairs (the robots need not be visible at each)."""
        total = 0.0
        for observer, _ in self.pairs():
            sensor = self.robots[self.robot_names.index(observer)].sensor
            total += self.duration_s * (sensor.rate_hz if sensor is not None else 0.0)
        if total > MAX_MEASUREMENTS:
            raise ConfigError(
                f"robots[*].sensor.rate_hz × duration_s: {len(self.pairs())} observed pair(s) "
                f"take {total:.3g} measurements; the limit is {MAX_MEASUREMENTS:.0e} "
                "(MAX_MEASUREMENTS)"
            )

    @property
    def steps(self) -> int:
        """Propagation steps ``N = round(duration_s · propagation_rate_hz)`` (validated ≥ 1)."""
        return round(self.duration_s * self.propagation_rate_hz)

    @property
    def robot_names(self) -> tuple[str, ...]:
        return tuple(r.name for r in self.robots)

    def targets_of(self, observer: str) -> tuple[str, ...]:
        """Names of the robots ``observer`` observes (empty if it has no sensor)."""
        spec = self.robots[self.robot_names.index(observer)]
        if spec.sensor is None:
            return ()
        if spec.observes is not None:
            return spec.observes
        return tuple(n for n in self.robot_names if n != observer)

    def pairs(self) -> tuple[tuple[str, str], ...]:
        """Every (observer, observed) pair the scenario measures, in robot order."""
        return tuple((r.name, t) for r in self.robots for t in self.targets_of(r.name))


# --------------------------------------------------------------------------- TOML loading


def _build(cls: Callable[..., Any], table: object, where: str, **converted: Any) -> Any:
    """Construct ``cls`` from a TOML table, naming unknown and missing keys and prefixing errors
    with ``where`` (``robots[2].sensor``); ``converted`` holds sub-tables already built."""
    prefix = f"{where}." if where else ""
    if not isinstance(table, Mapping):
        raise ConfigError(f"{where or 'scenario'}: expected a table, got {_show(table)}")
    known = {f.name: f for f in fields(cls)}  # type: ignore[arg-type]
    for key in table:
        if key not in known:
            raise ConfigError(
                f"{prefix}{_key(key)}: unknown key; expected one of {', '.join(sorted(known))}"
            )
    for name, f in known.items():
        required = f.default is MISSING and f.default_factory is MISSING
        if required and name not in table and name not in converted:
            raise ConfigError(f"{prefix}{name}: required")
    try:
        return cls(**{**table, **converted})
    except ConfigError as exc:
        raise ConfigError(f"{prefix}{exc}") from None


def _motion_from(table: object, where: str) -> Motion:
    if not isinstance(table, Mapping):
        raise ConfigError(f"{where}: expected a table with type = 'waypoints' or 'velocity'")
    body = dict(table)
    kind = body.pop("type", None)
    if kind == "waypoints":
        return _build(WaypointMotion, body, where)  # type: ignore[no-any-return]
    if kind == "velocity":
        return _build(VelocityMotion, body, where)  # type: ignore[no-any-return]
    raise ConfigError(f"{where}.type: must be 'waypoints' or 'velocity', got {_show(kind)}")


def _robot_from(table: object, where: str) -> RobotSpec:
    if not isinstance(table, Mapping):
        raise ConfigError(f"{where}: expected a table, got {_show(table)}")
    converted: dict[str, Any] = {}
    if "motion" in table:
        converted["motion"] = _motion_from(table["motion"], f"{where}.motion")
    if "sensor" in table:
        converted["sensor"] = _build(SensorSpec, table["sensor"], f"{where}.sensor")
    if "odometry" in table:
        converted["odometry"] = _build(OdometryNoise, table["odometry"], f"{where}.odometry")
    return _build(RobotSpec, table, where, **converted)  # type: ignore[no-any-return]


def scenario_from_dict(data: Mapping[str, Any]) -> Scenario:
    """Build a :class:`Scenario` from a parsed TOML document (errors name the field path; a
    document that is not a table is a ConfigError too)."""
    if not isinstance(data, Mapping):
        raise ConfigError(f"scenario: expected a table, got {_show(data)}")
    if "robots" not in data:
        raise ConfigError("robots: required (one [[robots]] table per robot)")
    raw_robots = data["robots"]
    if not isinstance(raw_robots, list):
        raise ConfigError("robots: expected an array of tables ([[robots]])")
    if len(raw_robots) > MAX_ROBOTS:
        raise ConfigError(
            f"robots: {len(raw_robots)} robots; the limit is {MAX_ROBOTS} (MAX_ROBOTS)"
        )
    robots = tuple(_robot_from(r, f"robots[{i}]") for i, r in enumerate(raw_robots))
    converted: dict[str, Any] = {"robots": robots}
    if "arena" in data:
        converted["arena"] = _build(Arena, data["arena"], "arena")
    return _build(Scenario, data, "", **converted)  # type: ignore[no-any-return]


def load_scenario(path: Path | str) -> Scenario:
    """Load a scenario TOML file; every error is a ConfigError naming the file and the field.

    The file must be UTF-8 (a byte-order mark is allowed) and at most :data:`MAX_FILE_BYTES`.
    """
    p = Path(path)
    try:
        with p.open("rb") as f:
            raw = f.read(MAX_FILE_BYTES + 1)
    except OSError as exc:
        raise ConfigError(f"{p}: cannot read scenario file ({exc.strerror or exc})") from None
    if len(raw) > MAX_FILE_BYTES:
        raise ConfigError(
            f"{p}: larger than {MAX_FILE_BYTES} bytes (MAX_FILE_BYTES); a scenario is a short "
            "TOML file"
        )
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise ConfigError(
            f"{p}: not UTF-8 text (byte {exc.start}: {exc.reason}); save the scenario as UTF-8"
        ) from None
    return _parse(text, str(p))


def _parse(text: str, origin: str) -> Scenario:
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{origin}: not valid TOML ({exc})") from None
    except RecursionError:
        raise ConfigError(
            f"{origin}: not valid TOML (arrays or tables nested too deeply)"
        ) from None
    try:
        return scenario_from_dict(data)
    except ConfigError as exc:
        raise ConfigError(f"{origin}: {exc}") from None
    except RecursionError:
        raise ConfigError(f"{origin}: values nested too deeply") from None


def default_scenario() -> Scenario:
    """The built-in seed-000 air-ground team (``relloc/sim/scenarios/default.toml``)."""
    res = resources.files("relloc.sim").joinpath("scenarios").joinpath("default.toml")
    return _parse(res.read_text(encoding="utf-8"), "default.toml")
