"""The team a runtime run simulates: the built-in default or a scenario file, and its seeded log.

Every process of a team (each robot, the launcher that scores the run) calls
:func:`simulate_team` with the same scenario and seed and gets the same
:class:`~relloc.sim.log.Log` — the simulator is deterministic for a given generator state — so each
robot can read its own sensor slice without any sensor data crossing the network.
"""

from __future__ import annotations

import numpy as np

from relloc.errors import ConfigError
from relloc.experiments.montecarlo import spawn_seeds
from relloc.runtime.keys import check_id
from relloc.sim.log import Log
from relloc.sim.scenario import Scenario, default_scenario, load_scenario
from relloc.sim.simulate import simulate


def load_team_scenario(spec: str) -> Scenario:
    """``"default"`` → the built-in seed-000 team; anything else is a TOML path. Robot names
    must be valid runtime ids (they become key-expression segments)."""
    scenario = default_scenario() if spec == "default" else load_scenario(spec)
    for name in scenario.robot_names:
        check_id(name, f"scenario robot name {name!r}")
    return scenario


def run_seeds(seed: int) -> tuple[np.random.SeedSequence, np.random.SeedSequence]:
    """``(simulation, initialisation)`` seeds of run 0 of ``relloc run --seed SEED`` — the same
    streams :func:`relloc.experiments.team_run.team_task` uses, so a team run and the
    in-process run see the very same log."""
    if seed < 0:
        raise ConfigError(f"--seed: {seed} must be ≥ 0")
    sim_seed, init_seed = spawn_seeds(seed, 1)[0].spawn(2)
    return sim_seed, init_seed


def simulate_team(scenario: Scenario, seed: int) -> Log:
    """The seeded log every process of a run shares (run 0 of ``relloc run --seed SEED``)."""
    return simulate(scenario, np.random.default_rng(run_seeds(seed)[0]))
