"""Simulation part of the seed-000 reproduction: accuracy of the team and Table 1.

One Monte-Carlo draw (:func:`team_task`) simulates the built-in default scenario
(:func:`relloc.sim.scenario.default_scenario`: one observing ground robot, aerial robots at
+2.0 m and +1.5 m, ground robots at −0.1 m and −0.2 m, Table-2 case-(1) sensor at 10 Hz,
100 Hz propagation) and runs, on that one recording, every filter the reproduction needs — all of
them side by side in one :class:`~relloc.estimators.relative_batch.RelativeFilterBatch` of the
observer, through :func:`relloc.pipeline.replay.replay`
(:func:`relloc.experiments.wanasinghe2014_filters.run_filters`):

* **accuracy** (seed 000 §5, Figs. 3–4): a PLKF per observed robot started from the known
  pose (case 1), scored with σ, NEES, NIS and conditioning at every update;
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

from relloc.core.checks import count, positive
from relloc.core.estimates import Estimates
from relloc.core.recording import Recording, relative_pose
from relloc.errors import ConfigError
from relloc.estimators.initialisation import (
    FieldOfView,
    fully_unknown,
    known_pose,
    known_position_unknown_yaw,
    known_yaw_unknown_position,
    poses_spread_in_fov,
)
from relloc.estimators.relative_batch import TrackSpec
from relloc.estimators.yaw_bank import YawBankSettings
from relloc.experiments.wanasinghe2014_filters import filter_estimates, run_filters
from relloc.pipeline.evaluation import SeriesEvaluation
from relloc.sim.scenario import OdometryNoise, Scenario, SensorSpec, default_scenario
from relloc.sim.simulate import propagation_grid, simulate
from relloc.sim.trajectories import robot_motion

Array = NDArray[np.float64]

CASES: tuple[str, ...] = ("case1", "case2", "case3", "case4")


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
        count(self.n_poses, "SimSettings.n_poses")
        positive(self.odometry_scale, "SimSettings.odometry_scale")

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


def simulated_recording(settings: SimSettings, rng: np.random.Generator) -> Recording:
    """One draw of the (noise-scaled) scenario; every observed robot must be seen."""
    recording = simulate(settings.simulated_scenario(), rng)
    m = recording.measurements
    i = recording.index(settings.observer)
    for name in settings.targets:
        if not np.any((m.observer == i) & (m.target == recording.index(name))):
            raise ConfigError(
                f"scenario: {settings.observer!r} never sees {name!r}; nothing to track"
            )
    return recording


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


ACCURACY = "accuracy"
"""Label of the accuracy filter of each observed robot (PLKF, known initial pose)."""


def table1_label(case: str, filt: str, guess: int) -> str:
    """Label of the Table-1 filter ``filt`` of ``case`` started from initial guess ``guess``."""
    return f"table1/{case}/{filt}/guess{guess}"


def _accuracy_specs(
    recording: Recording, settings: SimSettings, rng: np.random.Generator
) -> list[TrackSpec]:
    i = recording.index(settings.observer)
    specs = []
    for name in settings.targets:
        truth0 = recording.relative_truth(i, recording.index(name), 0.0)[0]
        prior = known_pose(truth0, rng=rng)
        specs.append(
            TrackSpec(
                label=ACCURACY,
                subject=name,
                kind="plkf",
                prior_mean=prior.mean,
                prior_cov=prior.cov,
            )
        )
    return specs


def _table1_specs(
    recording: Recording, settings: SimSettings, rng: np.random.Generator
) -> list[TrackSpec]:
    """Every Table-1 filter of every case and guess (case 1's PLKF is the accuracy filter of
    the Table-1 robot: same prior, same data)."""
    target = settings.table1_target
    truth0 = recording.relative_truth(
        recording.index(settings.observer), recording.index(target), 0.0
    )[0]
    priors = table1_priors(truth0, settings, rng)
    return [
        TrackSpec(
            label=table1_label(case, filt, g),
            subject=target,
            kind="tekf" if filt == "TEKF" else "plkf",
            prior_mean=mean,
            prior_cov=cov,
            bank=filt == "bank",
        )
        for case in CASES
        for filt in _table1_filters(case)
        for g, (mean, cov) in enumerate(priors[case])
    ]


def team_task(
    seed: np.random.SeedSequence, run_index: int, settings: SimSettings
) -> dict[str, Any]:
    """One Monte-Carlo draw of the team (see module docstring); picklable for any executor.

    Returns ``{"accuracy": {robot: SeriesEvaluation at its updates}, "table1": {case: {filter:
    errors (n_guesses, updates, 4)}}}`` (case 1's PLKF is the accuracy filter).
    """
    rng = np.random.default_rng(seed)
    recording = simulated_recording(settings, rng)
    specs = _accuracy_specs(recording, settings, rng)
    if settings.table1:
        specs += _table1_specs(recording, settings, rng)
    scored = run_filters(recording, specs, observer=settings.observer, bank=settings.bank)
    out: dict[str, Any] = {
        "accuracy": {name: scored[(name, ACCURACY)] for name in settings.targets},
        "table1": {},
    }
    if settings.table1:
        out["table1"] = _table1_errors(scored, settings)
    return out


def accuracy_run(
    seed: np.random.SeedSequence, settings: SimSettings
) -> tuple[Estimates, Recording]:
    """The accuracy PLKFs of the team draw of ``seed``, as estimates, with its recording
    (``--mcap``/``--tum``): the recording and priors of :func:`team_task` for that seed, which
    draws the Table-1 guesses only after them; the Table-1 filters are not run."""
    rng = np.random.default_rng(seed)
    recording = simulated_recording(settings, rng)
    specs = _accuracy_specs(recording, settings, rng)
    estimates = filter_estimates(recording, specs, observer=settings.observer, bank=settings.bank)
    return estimates, recording


def _table1_errors(
    scored: dict[tuple[str, str], SeriesEvaluation], settings: SimSettings
) -> dict[str, dict[str, Array]]:
    """``{case: {filter: errors (n_guesses, updates, 4)}}`` of the Table-1 robot's filters."""
    target = settings.table1_target
    table1: dict[str, dict[str, Array]] = {
        "case1": {"PLKF": scored[(target, ACCURACY)].error[None]}
    }
    for case in CASES:
        guesses = 1 if case == "case1" else settings.n_poses
        for filt in _table1_filters(case):
            table1.setdefault(case, {})[filt] = np.stack(
                [scored[(target, table1_label(case, filt, g))].error for g in range(guesses)]
            )
    return table1


def _table1_filters(case: str) -> tuple[str, ...]:
    """Filters run per case: case 1 adds the TEKF to the accuracy PLKF; case 3 has a known yaw,
    where the bank would be the PLKF itself."""
    if case == "case1":
        return ("TEKF",)
    if case == "case3":
        return ("PLKF", "TEKF")
    return ("PLKF", "TEKF", "bank")


def sweep_task(
    seed: np.random.SeedSequence, run_index: int, settings: SimSettings
) -> dict[str, SeriesEvaluation]:
    """One draw of the accuracy filters only (the odometry-noise sweep): their evaluation at
    their updates, per observed robot."""
    rng = np.random.default_rng(seed)
    recording = simulated_recording(settings, rng)
    specs = _accuracy_specs(recording, settings, rng)
    scored = run_filters(recording, specs, observer=settings.observer, bank=settings.bank)
    return {name: scored[(name, ACCURACY)] for name in settings.targets}


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
