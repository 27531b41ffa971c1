"""Scenarios: the team, its motions, sensors and noise, as frozen keyword-only dataclasses.

A :class:`Scenario` is what :func:`relloc.sim.simulate.simulate` turns into a
:class:`relloc.sim.log.Log`. It is usually loaded from TOML with :func:`load_scenario`
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
naming the field, and the TOML loader prefixes the path, e.g.
``robots[2].sensor.fov_deg: must be in (0, 360], got 400``.
"""

from __future__ import annotations

import math
import tomllib
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, fields
from importlib import resources
from pathlib import Path
from typing import Any, Literal

from relloc.errors import ConfigError

RobotKind = Literal["ground", "aerial"]


# --------------------------------------------------------------------------- field checks


def _number(
    name: str,
    value: object,
    *,
    low: float | None = None,
    high: float | None = None,
    low_open: bool = False,
    high_open: bool = False,
    allow_inf: bool = False,
) -> float:
    """``value`` as a float inside the interval, or ConfigError naming ``name``."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ConfigError(f"{name}: expected a number, got {value!r}")
    v = float(value)
    if math.isnan(v) or (math.isinf(v) and not allow_inf):
        raise ConfigError(f"{name}: must be finite, got {value!r}")
    if low is not None and (v < low or (low_open and v == low)):
        interval = f"{'(' if low_open else '['}{low:g}, {'∞' if high is None else f'{high:g}'}"
        interval += ")" if high is None or high_open else "]"
        raise ConfigError(f"{name}: must be in {interval}, got {value!r}")
    if high is not None and (v > high or (high_open and v == high)):
        interval = f"{'(' if low_open else '['}{'-∞' if low is None else f'{low:g}'}, {high:g}"
        interval += ")" if high_open else "]"
        raise ConfigError(f"{name}: must be in {interval}, got {value!r}")
    return v


def _vector(name: str, value: object, size: int, **limits: Any) -> tuple[float, ...]:
    if isinstance(value, (str, bytes)) or not isinstance(value, Sequence):
        raise ConfigError(f"{name}: expected a list of {size} numbers, got {value!r}")
    if len(value) != size:
        raise ConfigError(f"{name}: expected {size} numbers, got {len(value)}")
    return tuple(_number(f"{name}[{i}]", v, **limits) for i, v in enumerate(value))


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
            lo, hi = _vector(axis, getattr(self, axis), 2)
            if not lo < hi:
                raise ConfigError(f"{axis}: lower bound {lo:g} must be below upper bound {hi:g}")
            _set(self, axis, (lo, hi))

    def contains(self, x: float, y: float, z: float, *, margin: float = 1e-9) -> bool:
        return bool(
            self.x[0] - margin <= x <= self.x[1] + margin
            and self.y[0] - margin <= y <= self.y[1] + margin
            and self.z[0] - margin <= z <= self.z[1] + margin
        )


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
        for name in ("sigma_range", "sigma_azimuth", "sigma_elevation", "rate_hz"):
            _set(self, name, _number(name, getattr(self, name), low=0.0, low_open=True))
        _set(self, "fov_deg", _number("fov_deg", self.fov_deg, low=0.0, high=360.0, low_open=True))
        _set(
            self,
            "elevation_fov_deg",
            _number(
                "elevation_fov_deg", self.elevation_fov_deg, low=0.0, high=180.0, low_open=True
            ),
        )
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
        for name in ("sigma_v", "sigma_vz", "sigma_w"):
            _set(self, name, _number(name, getattr(self, name), low=0.0))

    def sigma_for(self, kind: RobotKind) -> tuple[float, float, float, float]:
        """Per-channel σ of ``(v_x, v_y, v_z, ω_z)`` for a robot of this kind."""
        if kind == "ground":
            return (self.sigma_v, 0.0, 0.0, self.sigma_w)
        return (self.sigma_v, self.sigma_v, self.sigma_vz, self.sigma_w)


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
        pts = self.points
        if isinstance(pts, (str, bytes)) or not isinstance(pts, Sequence) or len(pts) < 2:
            raise ConfigError("points: expected a list of at least two [x, y] points")
        _set(self, "points", tuple(_vector(f"points[{i}]", p, 2) for i, p in enumerate(pts)))
        if self.closed and len(self.points) < 3:
            raise ConfigError("points: a closed path needs at least three points")
        for i in range(1, len(self.points)):
            if self.points[i] == self.points[i - 1]:
                raise ConfigError(f"points[{i}]: repeats the previous point")
        _set(self, "speed", _number("speed", self.speed, low=0.0, low_open=True))
        if not isinstance(self.closed, bool):
            raise ConfigError(f"closed: expected true or false, got {self.closed!r}")
        if self.heading not in ("tangent", "fixed"):
            raise ConfigError(f"heading: must be 'tangent' or 'fixed', got {self.heading!r}")
        _set(self, "yaw_rad", _number("yaw_rad", self.yaw_rad))
        _set(self, "z_amplitude", _number("z_amplitude", self.z_amplitude, low=0.0))
        _set(self, "z_period_s", _number("z_period_s", self.z_period_s, low=0.0, low_open=True))


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
        _set(self, "mean", _vector("mean", self.mean, 4))
        _set(self, "amplitude", _vector("amplitude", self.amplitude, 4, low=0.0))
        _set(self, "period_s", _vector("period_s", self.period_s, 4, low=0.0, low_open=True))
        _set(self, "phase_rad", _vector("phase_rad", self.phase_rad, 4))


Motion = WaypointMotion | VelocityMotion


@dataclass(frozen=True, kw_only=True)
class RobotSpec:
    """One robot: name, kind, plane height, motion, odometry noise and (optionally) a sensor.

    A robot with a ``sensor`` is an observing robot; it observes the robots named in
    ``observes`` (``None``: every other robot). ``initial_pose = (x, y, yaw)`` is required for
    velocity commands and must be left out for way-points (the path gives the start).
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
        if not isinstance(self.name, str) or not self.name.strip():
            raise ConfigError(f"name: expected a non-empty string, got {self.name!r}")
        if self.kind not in ("ground", "aerial"):
            raise ConfigError(f"kind: must be 'ground' or 'aerial', got {self.kind!r}")
        _set(self, "height", _number("height", self.height))
        m = self.motion
        if not isinstance(m, (WaypointMotion, VelocityMotion)):
            raise ConfigError("motion: expected way-points or velocity commands")
        if isinstance(m, VelocityMotion):
            if self.initial_pose is None:
                raise ConfigError("initial_pose: required with velocity commands ([x, y, yaw])")
            if self.kind == "ground":
                for ch, label in ((1, "v_y"), (2, "v_z")):
                    if m.mean[ch] != 0.0 or m.amplitude[ch] != 0.0:
                        raise ConfigError(
                            f"motion.mean[{ch}]: a ground robot cannot move along {label}; "
                            "its mean and amplitude must be 0"
                        )
        else:
            if self.initial_pose is not None:
                raise ConfigError(
                    "initial_pose: not used with way-points (the path's first point is the start)"
                )
            if self.kind == "ground" and (m.heading != "tangent" or m.z_amplitude != 0.0):
                raise ConfigError(
                    "motion.heading: a ground robot follows its path tangent on a flat plane "
                    "(heading = 'tangent', z_amplitude = 0)"
                )
        if self.initial_pose is not None:
            _set(self, "initial_pose", _vector("initial_pose", self.initial_pose, 3))
        if not isinstance(self.odometry, OdometryNoise):
            raise ConfigError("odometry: expected an odometry noise table")
        if self.sensor is not None and not isinstance(self.sensor, SensorSpec):
            raise ConfigError("sensor: expected a sensor table")
        if self.observes is not None:
            if self.sensor is None:
                raise ConfigError("observes: only a robot with a sensor can observe")
            obs = self.observes
            if isinstance(obs, str) or not isinstance(obs, Sequence):
                raise ConfigError(f"observes: expected a list of robot names, got {obs!r}")
            for i, o in enumerate(obs):
                if not isinstance(o, str):
                    raise ConfigError(f"observes[{i}]: expected a robot name, got {o!r}")
            _set(self, "observes", tuple(obs))

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
        _set(self, "duration_s", _number("duration_s", self.duration_s, low=0.0, low_open=True))
        _set(
            self,
            "propagation_rate_hz",
            _number("propagation_rate_hz", self.propagation_rate_hz, low=0.0, low_open=True),
        )
        if not isinstance(self.arena, Arena):
            raise ConfigError("arena: expected an arena table")
        robots = tuple(self.robots)
        if not robots:
            raise ConfigError("robots: a scenario needs at least one robot")
        names = [r.name for r in robots]
        for i, name in enumerate(names):
            if name in names[:i]:
                raise ConfigError(f"robots[{i}].name: duplicate robot name {name!r}")
        if not any(r.is_observer for r in robots):
            raise ConfigError("robots: at least one robot needs a sensor (an observing robot)")
        for i, r in enumerate(robots):
            for j, target in enumerate(r.observes or ()):
                if target not in names:
                    raise ConfigError(
                        f"robots[{i}].observes[{j}]: unknown robot {target!r}; "
                        f"robots are {', '.join(names)}"
                    )
                if target == r.name:
                    raise ConfigError(f"robots[{i}].observes[{j}]: a robot cannot observe itself")
            if r.sensor is not None and r.sensor.rate_hz > self.propagation_rate_hz:
                raise ConfigError(
                    f"robots[{i}].sensor.rate_hz: must not exceed propagation_rate_hz "
                    f"({self.propagation_rate_hz:g}), got {r.sensor.rate_hz:g}"
                )
        _set(self, "robots", robots)

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
    """Construct ``cls`` from a TOML table, naming unknown keys and prefixing errors with
    ``where`` (``robots[2].sensor``)."""
    if not isinstance(table, Mapping):
        raise ConfigError(f"{where}: expected a table, got {table!r}")
    known = {f.name for f in fields(cls)}  # type: ignore[arg-type]
    prefix = f"{where}." if where else ""
    for key in table:
        if key not in known:
            raise ConfigError(
                f"{prefix}{key}: unknown key; expected one of {', '.join(sorted(known))}"
            )
    kwargs = {k: v for k, v in table.items() if k not in converted}
    kwargs.update(converted)
    try:
        return cls(**kwargs)
    except ConfigError as exc:
        raise ConfigError(f"{prefix}{exc}") from None
    except TypeError as exc:  # a required key is missing
        raise ConfigError(f"{where or 'scenario'}: {exc}") from None


def _motion_from(table: object, where: str) -> Motion:
    if not isinstance(table, Mapping):
        raise ConfigError(f"{where}: expected a table with type = 'waypoints' or 'velocity'")
    body = dict(table)
    kind = body.pop("type", None)
    if kind == "waypoints":
        if "points" not in body:
            raise ConfigError(f"{where}.points: required for type = 'waypoints'")
        return _build(WaypointMotion, body, where)  # type: ignore[no-any-return]
    if kind == "velocity":
        return _build(VelocityMotion, body, where)  # type: ignore[no-any-return]
    raise ConfigError(f"{where}.type: must be 'waypoints' or 'velocity', got {kind!r}")


def _robot_from(table: object, where: str) -> RobotSpec:
    if not isinstance(table, Mapping):
        raise ConfigError(f"{where}: expected a table")
    for key in ("name", "kind", "motion"):
        if key not in table:
            raise ConfigError(f"{where}.{key}: required")
    converted: dict[str, Any] = {"motion": _motion_from(table["motion"], f"{where}.motion")}
    if "sensor" in table:
        converted["sensor"] = _build(SensorSpec, table["sensor"], f"{where}.sensor")
    if "odometry" in table:
        converted["odometry"] = _build(OdometryNoise, table["odometry"], f"{where}.odometry")
    return _build(RobotSpec, table, where, **converted)  # type: ignore[no-any-return]


def scenario_from_dict(data: Mapping[str, Any]) -> Scenario:
    """Build a :class:`Scenario` from a parsed TOML document (errors name the field path)."""
    if "robots" not in data:
        raise ConfigError("robots: required (one [[robots]] table per robot)")
    raw_robots = data["robots"]
    if not isinstance(raw_robots, list):
        raise ConfigError("robots: expected an array of tables ([[robots]])")
    robots = tuple(_robot_from(r, f"robots[{i}]") for i, r in enumerate(raw_robots))
    converted: dict[str, Any] = {"robots": robots}
    if "arena" in data:
        converted["arena"] = _build(Arena, data["arena"], "arena")
    return _build(Scenario, data, "", **converted)  # type: ignore[no-any-return]


def load_scenario(path: Path | str) -> Scenario:
    """Load a scenario TOML file; every error is a ConfigError naming the file and the field."""
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except OSError as exc:
        raise ConfigError(f"{p}: cannot read scenario file ({exc.strerror or exc})") from None
    return _parse(text, str(p))


def _parse(text: str, origin: str) -> Scenario:
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{origin}: not valid TOML ({exc})") from None
    try:
        return scenario_from_dict(data)
    except ConfigError as exc:
        raise ConfigError(f"{origin}: {exc}") from None


def default_scenario() -> Scenario:
    """The built-in seed-000 air-ground team (``relloc/sim/scenarios/default.toml``)."""
    res = resources.files("relloc.sim").joinpath("scenarios").joinpath("default.toml")
    return _parse(res.read_text(encoding="utf-8"), "default.toml")
