"""Simulator of a planar team doing bearing-only cooperative localization (seed 001 §4.1).

``n`` unicycles drive at constant speed ``V`` through their own cyclic way-point lists
(a saturated proportional heading controller ``ω = clip(k_ψ · wrap(atan2(Δy, Δx) − ψ), ±ω_max)``,
the next way-point taken once within ``capture_radius``). Every ``dt`` each robot

- reports odometry ``u + N(0, diag(σ_v², σ_ω²))`` (held over the step; seed 001 ``Q_i``);
- measures the bearing (and, if ``sigma_range`` is set, the range) of every robot and landmark
  within ``sensing_range`` and inside its field of view ``|η| ≤ fov/2`` (so the RPMG changes over
  time), with white noise ``σ_η`` (``σ_r``);
- robots listed in ``gps_robots`` get an absolute pose fix every ``gps_period`` with noise
  ``gps_sigma``.

The result is a :class:`~relloc.core.recording.Recording` (robots ``"1"`` … ``"n"``, odometry
``(v, 0, 0, ω)``, detections as rows of kind ``"bearing"`` — ``"range_bearing"`` when ranges are
simulated — of a robot (``target``) or a landmark (``landmark``), fixes as rows of kind
``"pose"``, every row with the noise it was drawn with as its ``sigma``; ground truth and the
landmarks) and the filter's initial estimate, drawn from ``N(X(0), diag(σ_x0², σ_y0², σ_ψ0²))``
per robot. The simulation is open loop: no estimator runs in it. Everything random goes through
the ``np.random.Generator`` passed in.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from relloc.core import checks
from relloc.core.angles import wrap_angle
from relloc.core.gaussian import Gaussian
from relloc.core.limits import MAX_ABS_POSITION_M, MAX_SPEED_M_S, MAX_YAW_RATE_RAD_S
from relloc.core.recording import (
    NO_TARGET,
    GroundTruth,
    Measurements,
    Odometry,
    Recording,
    measurement_rows,
)
from relloc.errors import ConfigError
from relloc.models.unicycle import unicycle_step
from relloc.sim.scenario import MAX_SIMULATED_STEPS

Array = NDArray[np.float64]


@dataclass(frozen=True, kw_only=True)
class CooperativeScenario:
    """A planar team scenario; ``waypoints[i]`` is robot ``i``'s cyclic way-point list (k, 2).

    Validation (ConfigError naming the field): poses, way-points and landmarks finite, their
    positions within ``MAX_ABS_POSITION_M``; every other number finite and > 0, ``speed`` and
    ``sigma_v`` within ``MAX_SPEED_M_S``, ``max_turn_rate`` and ``sigma_w`` within
    ``MAX_YAW_RATE_RAD_S``, ``fov`` at most 2π, ``sigma_bearing`` and the heading σ of
    ``initial_sigma``/``gps_sigma`` at most π, their position σ within ``MAX_ABS_POSITION_M``;
    ``gps_robots`` distinct robot indices (a robot listed twice would get every fix twice).
    At least one step (``duration ≥ dt``) and, so that no scenario asks for unbounded work,
    ``n · (n + landmarks) · steps`` ≤ :data:`~relloc.sim.scenario.MAX_SIMULATED_STEPS`
    (every pair is tested for a detection at every step).
    """

    start_poses: Array
    waypoints: tuple[Array, ...]
    landmarks_xy: Array
    speed: float = 5.0
    dt: float = 0.1
    duration: float = 150.0
    sensing_range: float = 120.0
    fov: float = 2.0 * np.pi
    sigma_v: float = 0.2
    sigma_w: float = 0.2
    sigma_bearing: float = 0.1
    sigma_range: float | None = None
    initial_sigma: tuple[float, float, float] = (5.0, 5.0, 0.2)
    gps_robots: tuple[int, ...] = ()
    gps_period: float = 1.0
    gps_sigma: tuple[float, float, float] = (1.0, 1.0, 0.05)
    heading_gain: float = 1.0
    max_turn_rate: float = 0.5
    capture_radius: float = 8.0

    def __post_init__(self) -> None:
        starts = _points("start_poses", self.start_poses)
        if starts.ndim != 2 or starts.shape[1] != 3 or starts.shape[0] < 1:
            raise ConfigError("CooperativeScenario.start_poses must have shape (n, 3)")
        wps = checks.sequence(
            self.waypoints,
            "CooperativeScenario.waypoints",
            "one way-point list per robot",
            length=len(starts),
        )
        for i, w in enumerate(wps):
            wi = _points(f"waypoints[{i}]", w)
            if wi.ndim != 2 or wi.shape[1] != 2 or len(wi) < 1:
                raise ConfigError(f"CooperativeScenario.waypoints[{i}] must have shape (k, 2)")
        lm = _points("landmarks_xy", self.landmarks_xy)
        if lm.size % 2:
            raise ConfigError("CooperativeScenario.landmarks_xy must have shape (k, 2)")
        lm = lm.reshape(-1, 2)
        object.__setattr__(self, "start_poses", starts)
        object.__setattr__(self, "landmarks_xy", lm)
        for name, high in (
            ("speed", MAX_SPEED_M_S),
            ("dt", math.inf),
            ("duration", math.inf),
            ("sensing_range", math.inf),
            ("fov", 2.0 * math.pi),
            ("sigma_v", MAX_SPEED_M_S),
            ("sigma_w", MAX_YAW_RATE_RAD_S),
            ("sigma_bearing", math.pi),
            ("gps_period", math.inf),
            ("heading_gain", math.inf),
            ("max_turn_rate", MAX_YAW_RATE_RAD_S),
            ("capture_radius", math.inf),
        ):
            checks.number(
                getattr(self, name),
                f"CooperativeScenario.{name}",
                low=0.0,
                open_low=True,
                high=high,
            )
        if self.sigma_range is not None:
            checks.positive(self.sigma_range, "CooperativeScenario.sigma_range")
        for name in ("initial_sigma", "gps_sigma"):
            _pose_sigma(name, getattr(self, name))
        if self.duration < self.dt:
            raise ConfigError("CooperativeScenario.duration must be ≥ dt")
        gps = checks.sequence(self.gps_robots, "CooperativeScenario.gps_robots", "robot indices")
        for k, r in enumerate(gps):
            where = f"CooperativeScenario.gps_robots[{k}]"
            if checks.count(r, where, low=0) >= starts.shape[0]:
                raise ConfigError(f"{where}: robot index {r} out of range 0..{starts.shape[0] - 1}")
            if r in self.gps_robots[:k]:
                raise ConfigError(f"{where}: robot {r} is already listed")
        n, seen = starts.shape[0], starts.shape[0] + lm.shape[0]
        steps = self.duration / self.dt
        if n * seen * steps > MAX_SIMULATED_STEPS:
            raise ConfigError(
                f"CooperativeScenario.duration / dt: {n} robots × {seen} robots and landmarks × "
                f"{steps:.6g} steps = {n * seen * steps:.3g} detection tests; the limit is "
                f"{MAX_SIMULATED_STEPS:.0e} (MAX_SIMULATED_STEPS)"
            )

    @property
    def n_robots(self) -> int:
        return int(self.start_poses.shape[0])

    @property
    def prior_cov(self) -> Array:
        """Initial joint covariance ``diag(σ_x0², σ_y0², σ_ψ0²)`` per robot."""
        return np.diag(np.tile(np.square(self.initial_sigma), self.n_robots))


def _points(name: str, value: object) -> Array:
    """``value`` as a float array of finite coordinates, the positions (first two columns)
    within ``MAX_ABS_POSITION_M``; else ConfigError naming ``name``."""
    a = checks.floats(value, f"CooperativeScenario.{name}", ConfigError)
    if not np.all(np.isfinite(a)):
        raise ConfigError(f"CooperativeScenario.{name}: non-finite value")
    xy = a[..., :2] if a.ndim == 2 else a
    if xy.size and np.max(np.abs(xy)) > MAX_ABS_POSITION_M:
        raise ConfigError(
            f"CooperativeScenario.{name}: a position beyond {MAX_ABS_POSITION_M:g} m "
            "(MAX_ABS_POSITION_M)"
        )
    return a


def _pose_sigma(name: str, value: object) -> None:
    """``value`` as ``(σ_x, σ_y, σ_ψ)``: positions in (0, ``MAX_ABS_POSITION_M``], heading in
    (0, π]; else ConfigError naming ``name``."""
    where = f"CooperativeScenario.{name}"
    value = checks.sequence(value, where, "(σ_x, σ_y, σ_ψ)", length=3)
    for k, (v, high) in enumerate(zip(value, (MAX_ABS_POSITION_M,) * 2 + (math.pi,), strict=True)):
        checks.number(v, f"{where}[{k}]", low=0.0, open_low=True, high=high)


@dataclass(frozen=True)
class CooperativeSim:
    """The recording of one simulated run (with its truth) and the filter's initial estimate."""

    recording: Recording
    prior: Gaussian


def sharma2013_scenario(**overrides: object) -> CooperativeScenario:
    """Five robots around two landmarks, as in seed 001 §4.1 (R 120 m, V 5 m/s, Ts 0.1 s).

    The paper does not list its way-points; here every robot laps its own copy of a 200 m × 120 m
    rectangle, shifted by a few metres, starting 20 m behind the previous robot, so the team
    stays within ~90 m (the RPMG stays connected) and robots never move exactly along the line
    joining them (Lemma 1). Landmarks sit inside the loop.
    """
    base = np.array([[100.0, -60.0], [100.0, 60.0], [-100.0, 60.0], [-100.0, -60.0]])
    offsets = np.array([[0.0, 0.0], [6.0, 10.0], [-8.0, -6.0], [10.0, -12.0], [-5.0, 14.0]])
    starts = np.array([[-20.0 * i - 40.0 + o[0], -60.0 + o[1], 0.0] for i, o in enumerate(offsets)])
    params: dict[str, object] = {
        "start_poses": starts,
        "waypoints": tuple(base + o for o in offsets),
        "landmarks_xy": np.array([[-40.0, 10.0], [45.0, -5.0]]),
    }
    params.update(overrides)
    return CooperativeScenario(**params)  # type: ignore[arg-type]


def grid_team_scenario(
    n: int, *, spacing: float = 30.0, **overrides: object
) -> CooperativeScenario:
    """``n`` robots on a square grid, each lapping a small square of its own; for scale tests.

    With the default 50 m sensing range every robot sees roughly its eight nearest neighbours; one
    landmark per 25 robots is scattered over the grid.
    """
    checks.count(n, "grid_team_scenario: n")
    side = int(np.ceil(np.sqrt(n)))
    cells = np.array([(i % side, i // side) for i in range(n)], dtype=float) * spacing
    square = np.array([[10.0, 0.0], [10.0, 10.0], [0.0, 10.0], [0.0, 0.0]])
    starts = np.column_stack([cells, np.zeros(n)])
    n_lm = max(2, n // 25)
    lm_cells = cells[np.linspace(0, n - 1, n_lm).astype(int)] + np.array([spacing / 2, 5.0])
    params: dict[str, object] = {
        "start_poses": starts,
        "waypoints": tuple(square + c for c in cells),
        "landmarks_xy": lm_cells,
        "speed": 1.0,
        "sensing_range": 50.0,
        "capture_radius": 2.0,
        "max_turn_rate": 1.0,
    }
    params.update(overrides)
    return CooperativeScenario(**params)  # type: ignore[arg-type]


def _controls(pose: Array, targets: Array, s: CooperativeScenario) -> Array:
    d = targets - pose[:, :2]
    err = np.asarray(wrap_angle(np.arctan2(d[:, 1], d[:, 0]) - pose[:, 2]))
    w = np.clip(s.heading_gain * err, -s.max_turn_rate, s.max_turn_rate)
    return np.column_stack([np.full(pose.shape[0], s.speed), w])


def _detect(
    pose: Array, points: Array, s: CooperativeScenario, exclude_self: bool
) -> tuple[NDArray[np.int64], NDArray[np.int64], Array, Array]:
    """``(observer, target, range, bearing)`` of every pair within sensing range and FOV."""
    d = points[None, :, :] - pose[:, None, :2]
    dist = np.hypot(d[..., 0], d[..., 1])
    brg = np.asarray(wrap_angle(np.arctan2(d[..., 1], d[..., 0]) - pose[:, None, 2]))
    visible = (dist <= s.sensing_range) & (np.abs(brg) <= s.fov / 2) & (dist > 1e-6)
    if exclude_self:
        np.fill_diagonal(visible, False)
    obs, tgt = np.nonzero(visible)
    return obs, tgt, dist[obs, tgt], brg[obs, tgt]


def simulate(s: CooperativeScenario, rng: np.random.Generator) -> CooperativeSim:
    """Run the scenario (deterministic for a given generator state)."""
    n, dt = s.n_robots, s.dt
    steps = round(s.duration / dt)
    t: Array = np.arange(steps + 1, dtype=np.float64) * dt
    truth = np.zeros((steps + 1, n, 3))
    truth[0] = s.start_poses
    odo_u = np.zeros((steps, n, 2))
    wp_index = np.zeros(n, dtype=int)
    det_cols: list[list[NDArray[Any]]] = [[], [], [], [], [], []]
    for k in range(steps):
        pose = truth[k]
        targets = np.array([s.waypoints[i][wp_index[i] % len(s.waypoints[i])] for i in range(n)])
        reached = np.hypot(*(targets - pose[:, :2]).T) < s.capture_radius
        wp_index += reached
        targets = np.array([s.waypoints[i][wp_index[i] % len(s.waypoints[i])] for i in range(n)])
        u = _controls(pose, targets, s)
        truth[k + 1] = unicycle_step(pose, u, dt)
        odo_u[k] = u + rng.normal(size=(n, 2)) * np.array([s.sigma_v, s.sigma_w])
        if k == 0:
            continue
        for is_lm, pts in ((False, pose[:, :2]), (True, s.landmarks_xy)):
            if pts.shape[0] == 0:
                continue
            obs, tgt, dist, brg = _detect(pose, pts, s, exclude_self=not is_lm)
            m = obs.size
            noisy_b = np.asarray(wrap_angle(brg + s.sigma_bearing * rng.normal(size=m)))
            if s.sigma_range is None:
                noisy_r = np.full(m, np.nan)
            else:
                noisy_r = dist + s.sigma_range * rng.normal(size=m)
            det_cols[0].append(np.full(m, t[k]))
            det_cols[1].append(obs)
            det_cols[2].append(np.where(is_lm, NO_TARGET, tgt))
            det_cols[3].append(np.where(is_lm, tgt, NO_TARGET))
            det_cols[4].append(noisy_r)
            det_cols[5].append(noisy_b)
    cols = [np.concatenate(c) if c else np.zeros(0) for c in det_cols]
    order = np.argsort(cols[0], kind="stable")
    detections = _detection_rows(s, *(c[order] for c in cols))
    fixes = _gps(s, t, truth, rng)
    recording = _recording(s, t, truth, odo_u, Measurements.concatenate([detections, fixes]))
    noise = rng.normal(size=(n, 3)) * np.asarray(s.initial_sigma)
    prior = Gaussian(mean=(truth[0] + noise).reshape(-1), cov=s.prior_cov)
    return CooperativeSim(recording=recording, prior=prior)


def _recording(
    s: CooperativeScenario, t: Array, truth: Array, odo_u: Array, measurements: Measurements
) -> Recording:
    """Robots ``"1"`` … ``"n"``: odometry ``(v, 0, 0, ω)`` reported at ``t[:-1]``, the
    measurements, truth ``(x, y, 0, ψ)`` at ``t`` and the landmarks at height 0."""
    n = s.n_robots
    robots = tuple(str(i + 1) for i in range(n))
    zero = np.zeros(t.size - 1)
    odometry = tuple(
        Odometry(
            t=t[:-1],
            velocity=np.column_stack([odo_u[:, i, 0], zero, zero, odo_u[:, i, 1]]),
            sigma=np.array([s.sigma_v, 0.0, 0.0, s.sigma_w]),
            where=f"odometry of robot {robots[i]}",
        )
        for i in range(n)
    )
    ground_truth = tuple(
        GroundTruth(
            t=t,
            pose=np.column_stack([truth[:, i, :2], np.zeros(t.size), truth[:, i, 2]]),
            where=f"truth of robot {robots[i]}",
        )
        for i in range(n)
    )
    return Recording(
        robots=robots,
        platforms=("ground",) * n,
        odometry=odometry,
        measurements=measurements,
        truth=ground_truth,
        landmarks=np.column_stack([s.landmarks_xy, np.zeros(s.landmarks_xy.shape[0])]),
        source="relloc.sim.cooperative",
        meta={"dt": s.dt, "duration": s.duration},
    )


def _detection_rows(
    s: CooperativeScenario,
    t: Array,
    observer: Array,
    target: Array,
    landmark: Array,
    rng: Array,
    bearing: Array,
) -> Measurements:
    """Detection rows in time order: ``"bearing"`` rows, or ``"range_bearing"`` rows where a
    range is simulated (a noisy range that came out ≤ 0 is dropped: the row is bearing-only)."""
    ids = {
        "observer": observer.astype(np.int64),
        "target": target.astype(np.int64),
        "landmark": landmark.astype(np.int64),
    }
    if s.sigma_range is None:
        return measurement_rows(
            "bearing", t=t, value=bearing, sigma=np.array([s.sigma_bearing]), **ids
        )
    ranged = rng > 0
    parts = [
        measurement_rows(
            "range_bearing",
            t=t[ranged],
            value=np.column_stack([rng[ranged], bearing[ranged]]),
            sigma=np.array([s.sigma_range, s.sigma_bearing]),
            **{k: v[ranged] for k, v in ids.items()},
        ),
        measurement_rows(
            "bearing",
            t=t[~ranged],
            value=bearing[~ranged],
            sigma=np.array([s.sigma_bearing]),
            **{k: v[~ranged] for k, v in ids.items()},
        ),
    ]
    return Measurements.concatenate(parts)


def _gps(s: CooperativeScenario, t: Array, truth: Array, rng: np.random.Generator) -> Measurements:
    """Absolute pose rows of the robots in ``gps_robots`` every ``gps_period`` (a period
    longer than the run gives none; it is capped at the run's length so the count stays
    finite)."""
    every = max(1, round(min(s.gps_period / s.dt, t.size)))
    ks = np.arange(every, t.size, every) if s.gps_robots else np.zeros(0, dtype=np.int64)
    robots = np.array(s.gps_robots, dtype=np.int64)
    tt = np.repeat(t[ks], robots.size)
    rr = np.tile(robots, ks.size)
    pose = truth[np.repeat(ks, robots.size), rr] + rng.normal(size=(tt.size, 3)) * np.asarray(
        s.gps_sigma
    )
    return measurement_rows("pose", t=tt, observer=rr, value=pose, sigma=np.asarray(s.gps_sigma))
