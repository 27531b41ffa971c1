"""Simulation part of the seed-000 reproduction: accuracy of the team and Table 1.

One Monte-Carlo draw (:func:`team_task`) simulates the built-in default scenario
(:func:`relloc.sim.scenario.default_scenario`: one observing ground robot, aerial robots at
+2.0 m and +1.5 m, ground robots at −0.1 m and −0.2 m, Table-2 case-(1) sensor at 10 Hz,
100 Hz propagation) and runs, on that one log, every filter the reproduction needs:

* **accuracy** (seed 000 §5, Figs. 3–4): a PLKF per observed robot started from the known
  pose (case 1), with σ, NEES, NIS and conditioning recorded;
* **Table 1** (§5.1) for the aerial robot at +2.0 m: case 1 (known pose) for PLKF and TEKF,
  and for cases 2–4 the 13 initial guesses of :func:`relloc.estimators.initialisation.
  poses_spread_in_fov` (spread over the sensor's field of view and the circle of yaws) for the
  PLKF, the TEKF and relloc's yaw bank (:mod:`relloc.estimators.yaw_bank`; case 3 has a known
  yaw, where the bank is the PLKF itself).

Initial guesses are the same on every draw (the paper's 13 fixed poses); the draws differ in the
odometry and sensor noise (and in the case-1 initial error drawn from its prior). The
odometry-noise sweep (:func:`sweep_task`) reruns the accuracy filters with every robot's
odometry σ multiplied by a factor, simulating and filtering with the same scaled noise.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from relloc.core.recording import Recording as Log
from relloc.core.recording import relative_pose
from relloc.errors import ConfigError
from relloc.estimators.initialisation import (
    FieldOfView,
    fully_unknown,
    known_pose,
    known_position_unknown_yaw,
    known_yaw_unknown_position,
    poses_spread_in_fov,
)
from relloc.estimators.yaw_bank import YawBankSettings
from relloc.experiments.wanasinghe2014_filters import (
    PairStreams,
    TargetStream,
    TrackRecord,
    TrackSpec,
    run_tracks,
)
from relloc.models.measurement import RangeBearingNoise
from relloc.models.motion import VelocityNoise
from relloc.sim.scenario import OdometryNoise, Scenario, SensorSpec, default_scenario
from relloc.sim.simulate import propagation_grid, simulate
from relloc.sim.trajectories import robot_motion

Array = NDArray[np.float64]

CASES: tuple[str, ...] = ("case1", "case2", "case3", "case4")
FILTERS: tuple[str, ...] = ("PLKF", "TEKF")
KIND = {"PLKF": "plkf", "TEKF": "tekf"}


@dataclass(frozen=True, kw_only=True)
class SimSettings:
    """What the simulation draws run (defaults: the paper's §5 set-up on the default team).

    ``table1_target``: the observed robot of Table 1 (the aerial robot 2 m above the observer);
    ``n_poses``: initial guesses per case (paper: 13); ``odometry_scale``: multiplies every
    robot's odometry σ (the sweep); ``table1``: whether to run the Table-1 filters.
    """

    scenario: Scenario = field(default_factory=default_scenario)
    observer: str = "observer"
    table1_target: str = "aerial1"
    n_poses: int = 13
    bank: YawBankSettings = field(default_factory=YawBankSettings)
    odometry_scale: float = 1.0
    table1: bool = True

    def __post_init__(self) -> None:
        names = self.scenario.robot_names
        if self.observer not in names:
            raise ConfigError(f"SimSettings.observer: {self.observer!r} is not in {names}")
        targets = self.scenario.targets_of(self.observer)
        if not targets:
            raise ConfigError(f"SimSettings.observer: {self.observer!r} observes no robot")
        if self.table1 and self.table1_target not in targets:
            raise ConfigError(
                f"SimSettings.table1_target: {self.table1_target!r} is not observed by "
                f"{self.observer!r} (targets: {targets})"
            )
        if self.n_poses < 1:
            raise ConfigError(f"SimSettings.n_poses: must be ≥ 1, got {self.n_poses}")
        if not (np.isfinite(self.odometry_scale) and self.odometry_scale > 0):
            raise ConfigError(f"SimSettings.odometry_scale: > 0, got {self.odometry_scale}")

    @property
    def targets(self) -> tuple[str, ...]:
        """The observed robots, in scenario order."""
        return self.scenario.targets_of(self.observer)

    @property
    def sensor(self) -> SensorSpec:
        """The observer's sensor."""
        spec = self.scenario.robots[self.scenario.robot_names.index(self.observer)]
        if spec.sensor is None:
            raise ConfigError(f"SimSettings.observer: {self.observer!r} has no sensor")
        return spec.sensor

    def simulated_scenario(self) -> Scenario:
        """The scenario with every robot's odometry σ multiplied by ``odometry_scale``."""
        if self.odometry_scale == 1.0:
            return self.scenario
        s = self.odometry_scale
        robots = tuple(
            dataclasses.replace(
                r,
                odometry=OdometryNoise(
                    sigma_v=r.odometry.sigma_v * s,
                    sigma_vz=r.odometry.sigma_vz * s,
                    sigma_w=r.odometry.sigma_w * s,
                ),
            )
            for r in self.scenario.robots
        )
        return dataclasses.replace(self.scenario, robots=robots)


def streams_from_log(log: Log, observer: str, targets: tuple[str, ...]) -> PairStreams:
    """The observer's and each target's odometry and measurements as :class:`PairStreams`."""
    i = log.index(observer)
    odo_l = log.odometry[i]
    dt = float(odo_l.t[1] - odo_l.t[0])
    streams = []
    for name in targets:
        j = log.index(name)
        m = log.measurements
        rows = (m.observer == i) & (m.target == j)
        t_m = m.t[rows]
        step = np.rint(t_m / dt).astype(np.int64)
        if not rows.any():
            raise ConfigError(f"scenario: {observer!r} never sees {name!r}; nothing to track")
        sigma = m.sigma[rows][0]
        streams.append(
            TargetStream(
                name=name,
                u_c=np.asarray(log.odometry[j].velocity),
                noise=VelocityNoise(
                    observer=tuple(odo_l.sigma.tolist()),  # type: ignore[arg-type]
                    observed=tuple(log.odometry[j].sigma.tolist()),  # type: ignore[arg-type]
                ),
                sensor=RangeBearingNoise(
                    sigma_r=float(sigma[0]),
                    sigma_azimuth=float(sigma[1]),
                    sigma_elevation=float(sigma[2]),
                ),
                step=step,
                z=np.asarray(m.value[rows]),
                truth=log.relative_truth(i, j, t_m),
            )
        )
    return PairStreams(dt=dt, u_l=np.asarray(odo_l.velocity), targets=tuple(streams))


def initial_guesses(settings: SimSettings) -> Array:
    """The ``n_poses`` fixed initial guesses ``(x, y, z, φ)`` spread over the field of view."""
    sensor = settings.sensor
    return poses_spread_in_fov(
        settings.n_poses,
        fov_deg=sensor.fov_deg,
        range_limits=(sensor.min_range, sensor.max_range),
    )


def table1_priors(
    truth0: Array, settings: SimSettings, rng: np.random.Generator
) -> dict[str, list[tuple[Array, Array]]]:
    """Priors ``(mean, cov)`` of Table-1 cases 1–4 for a true initial relative pose ``truth0``.

    Case 1 is drawn from its prior around the truth (the initial error agrees with ``P₀``);
    cases 2–4 use the fixed guesses of :func:`initial_guesses` with the σ of an unknown yaw
    (π/√3) and of a position uniform over the sensor's range (``max_range/√3``).
    """
    sensor = settings.sensor
    sigma_position = FieldOfView(
        fov_deg=sensor.fov_deg, range_limits=(sensor.min_range, sensor.max_range)
    ).sigma_position
    guesses = initial_guesses(settings)

    def pair(g: Any) -> tuple[Array, Array]:
        return np.asarray(g.mean), np.asarray(g.cov)

    return {
        "case1": [pair(known_pose(truth0, rng=rng))],
        "case2": [pair(known_position_unknown_yaw(truth0, float(g[3]))) for g in guesses],
        "case3": [
            pair(known_yaw_unknown_position(truth0, g[:3], sigma_position=sigma_position))
            for g in guesses
        ],
        "case4": [pair(fully_unknown(g, sigma_position=sigma_position)) for g in guesses],
    }


def _accuracy_specs(log: Log, settings: SimSettings, rng: np.random.Generator) -> list[TrackSpec]:
    i = log.index(settings.observer)
    specs = []
    for j, name in enumerate(settings.targets):
        truth0 = log.relative_truth(i, log.index(name), 0.0)[0]
        prior = known_pose(truth0, rng=rng)
        specs.append(
            TrackSpec(
                target=j, kind="plkf", prior_mean=prior.mean, prior_cov=prior.cov, detail=True
            )
        )
    return specs


def team_task(
    seed: np.random.SeedSequence, run_index: int, settings: SimSettings
) -> dict[str, Any]:
    """One Monte-Carlo draw of the team (see module docstring); picklable for any executor.

    Returns ``{"accuracy": {robot: record dict}, "table1": {case: {filter: errors
    (n_guesses, updates, 4)}}, "table1_detail": {filter: record dict of guess 0 of case 4}}``.
    """
    rng = np.random.default_rng(seed)
    scenario = settings.simulated_scenario()
    log = simulate(scenario, rng)
    streams = streams_from_log(log, settings.observer, settings.targets)
    specs = _accuracy_specs(log, settings, rng)
    records_needed: list[tuple[str, str, int]] = []  # (case, filter, spec index)
    if settings.table1:
        j = settings.targets.index(settings.table1_target)
        truth0 = log.relative_truth(
            log.index(settings.observer), log.index(settings.table1_target), 0.0
        )[0]
        priors = table1_priors(truth0, settings, rng)
        # case 1 PLKF is the accuracy filter of the Table-1 robot (same prior, same data)
        records_needed.append(("case1", "PLKF", j))
        for case in CASES:
            for filt in _table1_filters(case):
                for g, (mean, cov) in enumerate(priors[case]):
                    records_needed.append((case, filt, len(specs)))
                    specs.append(
                        TrackSpec(
                            target=j,
                            kind="tekf" if filt == "TEKF" else "plkf",
                            prior_mean=mean,
                            prior_cov=cov,
                            bank=filt == "bank",
                            detail=case == "case4" and g == 0 and filt != "bank",
                        )
                    )
    records = run_tracks(streams, specs, settings.bank)
    times = {t.name: np.asarray(t.step * streams.dt, dtype=float) for t in streams.targets}
    out: dict[str, Any] = {
        "accuracy": {
            name: _as_dict(records[j], times[name]) for j, name in enumerate(settings.targets)
        },
        "table1": {},
        "table1_detail": {},
    }
    errors: dict[str, dict[str, list[Array]]] = {}
    alive: dict[str, list[Array]] = {}
    for case, filt, idx in records_needed:
        rec = records[idx]
        errors.setdefault(case, {}).setdefault(filt, []).append(rec.errors)
        if rec.n_alive is not None:
            alive.setdefault(case, []).append(rec.n_alive)
        if case == "case4" and rec.detail:
            out["table1_detail"][filt] = _as_dict(rec, times[settings.table1_target])
    out["table1"] = {
        case: {filt: np.stack(errs) for filt, errs in by_filter.items()}
        for case, by_filter in errors.items()
    }
    out["bank_alive"] = {case: np.stack(series) for case, series in alive.items()}
    return out


def _table1_filters(case: str) -> tuple[str, ...]:
    """Filters run per case: case 1 adds the TEKF to the accuracy PLKF; case 3 has a known yaw,
    where the bank would be the PLKF itself."""
    if case == "case1":
        return ("TEKF",)
    if case == "case3":
        return ("PLKF", "TEKF")
    return ("PLKF", "TEKF", "bank")


def _as_dict(record: TrackRecord, t: Array) -> dict[str, Array]:
    out = {"t": t, "errors": record.errors}
    out.update(record.detail)
    return out


def sweep_task(
    seed: np.random.SeedSequence, run_index: int, settings: SimSettings
) -> dict[str, dict[str, Array]]:
    """One draw of the accuracy filters only (the odometry-noise sweep)."""
    rng = np.random.default_rng(seed)
    log = simulate(settings.simulated_scenario(), rng)
    streams = streams_from_log(log, settings.observer, settings.targets)
    records = run_tracks(streams, _accuracy_specs(log, settings, rng), settings.bank)
    return {
        name: {
            "t": np.asarray(streams.targets[j].step * streams.dt, dtype=float),
            "errors": records[j].errors,
        }
        for j, name in enumerate(settings.targets)
    }


def true_pair_inputs(settings: SimSettings, target: str) -> tuple[Array, Array, Array, Array]:
    """Noise-free grid ``t (T+1,)``, relative truth ``(T+1, 4)`` and true inputs of a pair.

    The inputs ``u_l, u_c (T+1, 4)`` are the commands the simulator integrates (the last row
    repeats the final command; it drives no step). Used for the PCRLB.
    """
    scenario = settings.scenario
    t = propagation_grid(scenario)
    motions = {}
    for name in (settings.observer, target):
        spec = scenario.robots[scenario.robot_names.index(name)]
        motions[name] = robot_motion(spec, t)
    truth = relative_pose(motions[settings.observer][0], motions[target][0])
    u_l = np.vstack([motions[settings.observer][1], motions[settings.observer][1][-1:]])
    u_c = np.vstack([motions[target][1], motions[target][1][-1:]])
    return t, truth, u_l, u_c
