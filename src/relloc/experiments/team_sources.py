"""Reproductions whose team runs as robot processes: ``relloc team up NAME`` / ``relloc node
--scenario NAME``.

Every process of such a team builds the same seeded recording (the reproduction's simulator is
deterministic for a given seed sequence) and keeps its own robot's slice and estimator — the
very estimator the in-process reproduction gives that robot:

- ``desilva2015`` (seed 002): leaders L1, L2 each run their
  :class:`~relloc.fusion.gaussian_sum_estimator.GaussianSumEstimator` (the settings of
  :meth:`relloc.experiments.desilva2015.RunConfig.settings` with the team's sharing policy,
  equivalent measurements every second) and record their dominant tracks at their scan
  times; pods P1–P3 only share their odometry. With ``--sensing`` (the team's sensing robots,
  parsed by :func:`relloc.experiments.desilva2015.sensing_robots`) those robots scan and run
  the fusers instead of the leaders, the others only share their odometry; every process
  simulates the same sensing robots. ``desilva2015-kidnapped``: the same with the
  kidnapped-robot scenario (:func:`kidnap_of`). Run ``i`` of
  seed ``S`` is run ``i`` of ``relloc reproduce desilva2015 --seed S`` (the Monte-Carlo
  task's seed sequence ``SeedSequence(S).spawn(n)[i]``), shortened to ``duration`` seconds.
- ``sharma2013`` (seed 001): every agent (robots 1–5) shares its odometry and its readings
  (bearings of robots and landmarks, robot 1's GPS fixes) and runs the team EIF
  (:class:`~relloc.estimators.cooperative.CooperativeEstimator`, the settings of one case of
  :data:`relloc.experiments.sharma2013.CASES`) on all it received, recording every robot's
  pose every 0.5 s; run ``i`` as above. A teammate whose odometry has stopped (its process
  died) is *lost*: still, with the position and heading variance of a robot moving at up to
  the scenario's speed and turn rate
  (:attr:`~relloc.estimators.cooperative.OdometryModel.lost_speed`); on a perfect network no
  robot is ever lost, so the in-process reference runs the same filter.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np

from relloc.core.recording import Recording
from relloc.errors import ConfigError
from relloc.experiments.desilva2015 import (
    DURATION_S,
    FUSION_PERIOD_S,
    KIDNAP,
    RunConfig,
    sensing_robots,
)
from relloc.fusion.gaussian_sum_estimator import GaussianSumEstimator
from relloc.pipeline.montecarlo import spawn_seeds
from relloc.runtime.estimation import (
    OdometryOnly,
    WindowDriver,
    grid_record_times,
    scan_record_times,
)
from relloc.runtime.node import NodeParts
from relloc.runtime.scenario import REPRODUCTIONS
from relloc.runtime.sources import RecordingSource
from relloc.sim.multihypothesis import DeSilvaScenario, simulate

KIDNAPPED = {name: name.endswith("-kidnapped") for name in REPRODUCTIONS if "desilva" in name}
CHECKPOINT_WINDOWS = 50
"""Windows an agent of seed 001 can go back to re-filter a late reading (5 s at 10 Hz)."""
SHARMA_RECORD_RATE_HZ = 2.0
"""The team EIF's record rate in ``relloc reproduce sharma2013`` (every 0.5 s)."""


def team_names() -> tuple[str, ...]:
    """The reproductions ``relloc team up`` runs as processes."""
    return REPRODUCTIONS


def desilva_scenario(
    name: str, duration_s: float | None, sensing: tuple[int, ...] | None = None
) -> DeSilvaScenario:
    """The scenario of ``desilva2015`` / ``desilva2015-kidnapped`` (default: the paper's 30 s);
    ``sensing``: the sensing robots' indices (default: the paper's leaders)."""
    if name not in KIDNAPPED:
        raise ConfigError(f"team source: {name!r} is not one of {team_names()}")
    duration = DURATION_S if duration_s is None else float(duration_s)
    return DeSilvaScenario(
        duration=duration,
        kidnap=kidnap_of(duration) if KIDNAPPED[name] else None,
        sensing=sensing_robots(None) if sensing is None else sensing,
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


def desilva_recording(
    name: str,
    seed: int,
    run: int,
    duration_s: float | None,
    sensing: tuple[int, ...] | None = None,
) -> Recording:
    """The recording every process of the team builds (``sensing``: as :func:`desilva_scenario`)."""
    scenario = desilva_scenario(name, duration_s, sensing)
    return simulate(scenario, np.random.default_rng(run_seed(seed, run)))


def named_node_parts(
    name: str,
    robot: str,
    seed: int,
    run: int,
    duration_s: float | None,
    case: str = "two_landmarks",
    sharing_policy: str = "all",
    sensing: tuple[int, ...] | None = None,
) -> NodeParts:
    """Robot ``robot``'s sensors and estimator in the team ``name`` (module docstring);
    desilva2015 only: ``sharing_policy``, the leaders'; ``sensing``, the indices of the sensing
    robots, those that run the fusers (default: the paper's leaders L1, L2)."""
    if name == "sharma2013":
        return sharma_node_parts(robot, seed, run, duration_s, case)
    scenario = desilva_scenario(name, duration_s, sensing)
    settings = RunConfig(scenario=scenario, sharing_policy=sharing_policy).settings()
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
            settings,
            sharing=True,
            fusion_period=FUSION_PERIOD_S,
        )
    else:
        estimator = OdometryOnly(robot)
    driver = WindowDriver(estimator, recording.robots, robot, record_times=scan_record_times(index))
    source = RecordingSource(recording, robot, all_readings=True)
    return NodeParts(recording.robots, source, driver, talkers=leaders)


def sharma_sim(seed: int, run: int, duration_s: float | None) -> tuple[Any, Any]:
    """Run ``run`` of ``relloc reproduce sharma2013 --seed SEED``: its scenario and its
    simulation (recording and the filter's prior), shortened to ``duration_s``."""
    from relloc.experiments.sharma2013 import DURATION_S as SHARMA_DURATION_S
    from relloc.experiments.sharma2013 import _scenario
    from relloc.sim.cooperative import simulate as simulate_cooperative

    scenario = _scenario(SHARMA_DURATION_S if duration_s is None else float(duration_s))
    return scenario, simulate_cooperative(scenario, np.random.default_rng(run_seed(seed, run)))


def check_sharma_case(case: str) -> None:
    """ConfigError naming ``--case`` unless ``case`` is one of seed 001's cases."""
    from relloc.experiments.sharma2013 import CASES

    if case not in CASES:
        raise ConfigError(f"--case: {case!r} is not one of {sorted(CASES)}")


def sharma_estimator(sim: Any, scenario: Any, case: str) -> Any:
    """The team EIF of one case of seed 001 (that of the in-process reproduction)."""
    from relloc.estimators.cooperative import CooperativeEstimator
    from relloc.experiments.sharma2013 import case_settings

    check_sharma_case(case)
    rec = sim.recording
    settings = case_settings(scenario, case)
    # a teammate whose process died keeps driving: lost at the platform's speed and turn rate
    odometry = replace(
        settings.odometry, lost_speed=scenario.speed, lost_turn_rate=scenario.max_turn_rate
    )
    settings = replace(settings, odometry=odometry)
    return CooperativeEstimator(
        rec.robots, sim.prior, settings, rec.landmarks, record_updates=False
    )


def sharma_node_parts(
    robot: str, seed: int, run: int, duration_s: float | None, case: str
) -> NodeParts:
    """Seed 001's agent ``robot``: it shares its odometry and readings and runs the team EIF
    on everything it received (every agent the same filter, decentralised)."""
    scenario, sim = sharma_sim(seed, run, duration_s)
    recording = sim.recording
    if robot not in recording.robots:
        raise ConfigError(f"--robot: {robot!r} is not in sharma2013 {recording.robots}")
    driver = WindowDriver(
        sharma_estimator(sim, scenario, case),
        recording.robots,
        robot,
        record_times=grid_record_times(SHARMA_RECORD_RATE_HZ, 0.0),
        checkpoint_windows=CHECKPOINT_WINDOWS,
    )
    source = RecordingSource(recording, robot, all_readings=True)
    return NodeParts(recording.robots, source, driver, share_rows=True)
