"""Reproductions whose team runs as robot processes: ``relloc team up NAME`` / ``relloc node
--scenario NAME``.

Every process of such a team builds the same seeded recording (the reproduction's simulator is
deterministic for a given seed sequence) and keeps its own robot's slice and estimator — the
very estimator the in-process reproduction gives that robot:

- ``desilva2015`` (seed 002): leaders L1, L2 each run their
  :class:`~relloc.fusion.gaussian_sum_estimator.GaussianSumEstimator` (the settings of
  :func:`relloc.experiments.desilva2015.filter_settings`, equivalent measurements every
  second) and record their dominant tracks at their scan times; pods P1–P3 only share their
  odometry. ``desilva2015-kidnapped``: the same with the kidnapped-robot scenario
  (:func:`kidnap_of`). Run ``i`` of
  seed ``S`` is run ``i`` of ``relloc reproduce desilva2015 --seed S`` (the Monte-Carlo
  task's seed sequence ``SeedSequence(S).spawn(n)[i]``), shortened to ``duration`` seconds.
"""

from __future__ import annotations

import numpy as np

from relloc.core.recording import Recording
from relloc.errors import ConfigError
from relloc.experiments.desilva2015 import DURATION_S, FUSION_PERIOD_S, KIDNAP, filter_settings
from relloc.fusion.gaussian_sum_estimator import GaussianSumEstimator
from relloc.pipeline.montecarlo import spawn_seeds
from relloc.runtime.estimation import OdometryOnly, WindowDriver, scan_record_times
from relloc.runtime.node import NodeParts
from relloc.runtime.scenario import REPRODUCTIONS
from relloc.runtime.sources import RecordingSource
from relloc.sim.multihypothesis import DeSilvaScenario, simulate

KIDNAPPED = {name: name.endswith("-kidnapped") for name in REPRODUCTIONS}


def team_names() -> tuple[str, ...]:
    """The reproductions ``relloc team up`` runs as processes."""
    return REPRODUCTIONS


def desilva_scenario(name: str, duration_s: float | None) -> DeSilvaScenario:
    """The scenario of ``desilva2015`` / ``desilva2015-kidnapped`` (default: the paper's 30 s)."""
    if name not in KIDNAPPED:
        raise ConfigError(f"team source: {name!r} is not one of {team_names()}")
    duration = DURATION_S if duration_s is None else float(duration_s)
    return DeSilvaScenario(
        duration=duration, kidnap=kidnap_of(duration) if KIDNAPPED[name] else None
    )


def kidnap_of(duration_s: float) -> tuple[int, float, float, float, float]:
    """The reproduction's kidnap (:data:`relloc.experiments.desilva2015.KIDNAP`: P2 moved at
    15 s of 30), at half the run when the run is shorter than 30 s."""
    robot, when, dx, dy, dyaw = KIDNAP
    return (robot, min(when, duration_s / 2.0), dx, dy, dyaw)


def run_seed(seed: int, run: int) -> np.random.SeedSequence:
    """Run ``run``'s seed sequence of a Monte-Carlo reproduction with seed ``seed``."""
    if run < 0:
        raise ConfigError(f"--run: {run} must be ≥ 0")
    return spawn_seeds(seed, run + 1)[run]


def desilva_recording(name: str, seed: int, run: int, duration_s: float | None) -> Recording:
    """The recording every process of the team builds."""
    scenario = desilva_scenario(name, duration_s)
    return simulate(scenario, np.random.default_rng(run_seed(seed, run)))


def named_node_parts(
    name: str, robot: str, seed: int, run: int, duration_s: float | None
) -> NodeParts:
    """Robot ``robot``'s sensors and estimator in the team ``name`` (module docstring)."""
    scenario = desilva_scenario(name, duration_s)
    recording = simulate(scenario, np.random.default_rng(run_seed(seed, run)))
    if robot not in recording.robots:
        raise ConfigError(f"--robot: {robot!r} is not in {name} {recording.robots}")
    index = recording.index(robot)
    leaders = tuple(recording.robots[i] for i in scenario.sensing)
    estimator: GaussianSumEstimator | OdometryOnly
    if robot in leaders:
        estimator = GaussianSumEstimator(
            recording.robots,
            index,
            filter_settings(scenario),
            sharing=True,
            fusion_period=FUSION_PERIOD_S,
        )
    else:
        estimator = OdometryOnly(robot)
    driver = WindowDriver(estimator, recording.robots, robot, record_times=scan_record_times(index))
    source = RecordingSource(recording, robot, all_readings=True)
    return NodeParts(recording.robots, source, driver, talkers=leaders)
