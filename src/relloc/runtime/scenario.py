"""The team a runtime run replays: a scenario (built-in or TOML) or a recorded dataset folder.

Every process of a team (each robot, the launcher that scores the run) calls :func:`load_team`
with the same source and seed and gets the same :class:`~relloc.core.recording.Recording` — the
simulator and the dataset replay are deterministic for a given generator state — so each robot
can read its own sensor slice without any sensor data crossing the network. Sources:

- ``"default"``: the built-in seed-000 team (:func:`relloc.sim.scenario.default_scenario`);
- a ``.toml`` file: a user scenario (:func:`relloc.sim.scenario.load_scenario`);
- a folder in MRCLAM layout: the recorded team replayed as in seed 000 §6
  (:func:`relloc.runtime.dataset.mrclam_team_recording`).

The seed gives run 0 of ``relloc run --seed SEED``: the simulation (or sensor-noise) stream and
the initialisation stream of its Monte-Carlo task (:func:`run_seeds`).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from relloc.core.recording import Recording
from relloc.errors import ConfigError
from relloc.pipeline.montecarlo import spawn_seeds
from relloc.runtime.keys import check_robot_id
from relloc.sim.scenario import Scenario, default_scenario, load_scenario
from relloc.sim.simulate import simulate


@dataclass(frozen=True)
class Team:
    """A team to run: its name, its seeded recording and, for simulations, its scenario."""

    name: str
    description: str
    recording: Recording
    scenario: Scenario | None


REPRODUCTIONS = ("desilva2015", "desilva2015-kidnapped", "sharma2013")
"""Reproductions whose teams run as processes (:mod:`relloc.experiments.team_sources`)."""


def check_source(spec: str) -> str:
    """``spec`` if it names a team source (see module docstring) or a reproduction of
    :data:`REPRODUCTIONS`, else a ConfigError."""
    if spec != "default" and spec not in REPRODUCTIONS and not Path(spec).exists():
        raise ConfigError(
            f"team source: {spec!r} is neither 'default', a reproduction "
            f"({', '.join(REPRODUCTIONS)}), a scenario file nor a dataset folder"
        )
    return spec


def run_seeds(seed: int) -> tuple[np.random.SeedSequence, np.random.SeedSequence]:
    """``(simulation, initialisation)`` seeds of run 0 of ``relloc run --seed SEED``."""
    if seed < 0:
        raise ConfigError(f"--seed: {seed} must be ≥ 0")
    sim_seed, init_seed = spawn_seeds(seed, 1)[0].spawn(2)
    return sim_seed, init_seed


def load_team_scenario(spec: str) -> Scenario:
    """``"default"`` → the built-in team; anything else is a TOML path. Robot names must be
    valid runtime ids (they become key-expression segments) other than the clock's."""
    scenario = default_scenario() if spec == "default" else load_scenario(check_source(spec))
    for name in scenario.robot_names:
        check_robot_id(name, f"scenario robot name {name!r}")
    return scenario


def load_team(spec: str, seed: int) -> Team:
    """The team of a source and seed (see module docstring)."""
    rng = np.random.default_rng(run_seeds(seed)[0])
    if Path(check_source(spec)).is_dir():
        from relloc.runtime.dataset import mrclam_team_recording

        recording = mrclam_team_recording(spec, rng)
        name = f"recorded trajectories of {Path(spec).name}, readings synthesised (seed 000 §6)"
        return Team(name=name, description=recording.source, recording=recording, scenario=None)
    scenario = load_team_scenario(spec)
    return Team(
        name=scenario.name,
        description=scenario.description,
        recording=simulate(scenario, rng),
        scenario=scenario,
    )
