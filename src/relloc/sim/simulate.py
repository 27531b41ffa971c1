"""``simulate(scenario, rng) -> Recording``: a team's truth, odometry and inter-robot measurements.

1. Every robot's true motion is integrated exactly from its body-velocity commands on the
   propagation grid ``t_k = k Δt`` (Δt = 1 / propagation_rate_hz, seed 000 §5: 100 Hz); a
   trajectory that leaves the arena or is not finite is a :class:`ConfigError` naming the
   robot and the time.
2. Odometry = the held command plus white Gaussian noise of the robot's per-channel σ, one draw
   per propagation step (the "noisy body velocities" the relative motion model consumes).
3. Each observing robot measures each of its targets at its sensor's rate (seed 000: 10 Hz)
   from the ground truth with additive noise; targets outside the field of view or range are
   not reported, so robots leave and re-enter view. The readings are rows of kind
   ``range_bearing_elevation`` of :class:`relloc.core.recording.Measurements`, sorted by
   (time, observer, target). A reported range beyond ``MAX_SENSOR_RANGE_M`` (σ_r or
   ``max_range`` set too large) is a :class:`ConfigError` naming the robot's sensor.

The random stream is consumed in a fixed order (odometry in robot order, then measurements in
(observer, observed) pair order, noise drawn whether or not the target is visible), so a given
``rng`` state always produces the same recording.
"""

from __future__ import annotations

import numpy as np

from relloc.core.limits import MAX_SENSOR_RANGE_M
from relloc.core.recording import GroundTruth, Odometry, Recording, measurement_rows
from relloc.errors import ConfigError
from relloc.sim.scenario import Scenario
from relloc.sim.sensors import measurement_times, sense
from relloc.sim.trajectories import robot_motion


def propagation_grid(scenario: Scenario) -> np.ndarray:
    """The odometry/truth time grid ``0, Δt, …, NΔt`` of a scenario (``N = scenario.steps``)."""
    return np.arange(scenario.steps + 1) / scenario.propagation_rate_hz


def _check_motion(scenario: Scenario, index: int, t: np.ndarray, poses: np.ndarray) -> None:
    """A robot's true poses must be finite and inside the arena; else ConfigError naming it."""
    name = scenario.robots[index].name
    finite = np.all(np.isfinite(poses), axis=1)
    if not finite.all():
        k = int(np.argmin(finite))
        raise ConfigError(
            f"robots[{index}].motion: robot {name!r} has no defined pose at t={t[k]:.2f} s "
            "(e.g. a way-point path that doubles back on itself has no heading at the turn)"
        )
    arena = scenario.arena
    lo = np.array([arena.x[0], arena.y[0], arena.z[0]]) - 1e-9
    hi = np.array([arena.x[1], arena.y[1], arena.z[1]]) + 1e-9
    outside = np.any((poses[:, :3] < lo) | (poses[:, :3] > hi), axis=1)
    if outside.any():
        k = int(np.argmax(outside))
        x, y, z = poses[k, :3]
        raise ConfigError(
            f"robots[{index}].motion: robot {name!r} leaves the arena at "
            f"t={t[k]:.2f} s (x={x:.2f}, y={y:.2f}, z={z:.2f}); arena x={arena.x}, y={arena.y}, "
            f"z={arena.z}"
        )


def checked_motions(scenario: Scenario) -> list[tuple[np.ndarray, np.ndarray]]:
    """Every robot's true poses and body-velocity commands on the propagation grid, each
    checked (finite, inside the arena: ConfigError naming the robot and the time). No
    randomness: a command line checks a scenario file with it before any run starts."""
    t = propagation_grid(scenario)
    motions = []
    for i, spec in enumerate(scenario.robots):
        poses, commands = robot_motion(spec, t)
        _check_motion(scenario, i, t, poses)
        motions.append((poses, commands))
    return motions


def simulate(scenario: Scenario, rng: np.random.Generator) -> Recording:
    """Simulate ``scenario`` with randomness from ``rng`` (see module docstring)."""
    t = propagation_grid(scenario)
    truth: list[GroundTruth] = []
    odometry: list[Odometry] = []
    for spec, (poses, commands) in zip(scenario.robots, checked_motions(scenario), strict=True):
        truth.append(GroundTruth(t=t, pose=poses, where=f"truth[{spec.name}]"))
        sigma = np.asarray(spec.odometry.sigma_for(spec.kind))
        noisy = commands + sigma * rng.standard_normal(commands.shape)
        odometry.append(
            Odometry(t=t[:-1], velocity=noisy, sigma=sigma, where=f"odometry[{spec.name}]")
        )

    names = scenario.robot_names
    rows_t, rows_obs, rows_tgt, rows_z, rows_sigma = [], [], [], [], []
    for obs_name, tgt_name in scenario.pairs():
        i, j = names.index(obs_name), names.index(tgt_name)
        sensor = scenario.robots[i].sensor
        if sensor is None:  # pairs() only lists robots with a sensor
            raise ConfigError(f"robots[{i}].sensor: required to observe {tgt_name!r}")
        tm = measurement_times(sensor.rate_hz, float(t[-1]))  # within the simulated span
        z, seen = sense(truth[i].at(tm), truth[j].at(tm), sensor, rng)
        far = seen & (z[:, 0] > MAX_SENSOR_RANGE_M)
        if far.any():  # the recording would refuse it as a logging fault, naming no field
            raise ConfigError(
                f"robots[{i}].sensor ({obs_name}): a simulated range to {tgt_name!r} of "
                f"{z[np.argmax(far), 0]:g} m is beyond the {MAX_SENSOR_RANGE_M:g} m a reading "
                f"may have; lower sigma_range ({sensor.sigma_range:g} m) or max_range "
                f"({sensor.max_range:g} m)"
            )
        rows_t.append(tm[seen])
        rows_obs.append(np.full(int(seen.sum()), i, dtype=np.int64))
        rows_tgt.append(np.full(int(seen.sum()), j, dtype=np.int64))
        rows_z.append(z[seen])
        rows_sigma.append(np.tile(sensor.sigma, (int(seen.sum()), 1)))

    mt = np.concatenate(rows_t)
    mo = np.concatenate(rows_obs)
    mc = np.concatenate(rows_tgt)
    order = np.lexsort((mc, mo, mt))
    measurements = measurement_rows(
        "range_bearing_elevation",
        t=mt[order],
        observer=mo[order],
        target=mc[order],
        value=np.concatenate(rows_z)[order],
        sigma=np.concatenate(rows_sigma)[order],
    )
    return Recording(
        robots=names,
        platforms=tuple(r.kind for r in scenario.robots),
        truth=tuple(truth),
        odometry=tuple(odometry),
        measurements=measurements,
        source=f"simulation of scenario {scenario.name!r}",
    )
