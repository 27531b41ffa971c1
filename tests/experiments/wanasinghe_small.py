"""The seed-000 reproduction's reduced configuration for tests on a truncated MRCLAM copy: a
6 s team, 3 initial guesses, 2 team draws, one replay draw of a 10 s window (shared by
``test_wanasinghe2014`` and ``test_wanasinghe2014_pairs``)."""

from __future__ import annotations

import dataclasses
from pathlib import Path

from relloc.experiments.wanasinghe2014 import Wanasinghe2014Config
from relloc.experiments.wanasinghe2014_mrclam import ReplaySettings
from relloc.experiments.wanasinghe2014_sim import SimSettings
from relloc.sim.scenario import default_scenario


def small_config(dataset: Path) -> Wanasinghe2014Config:
    return Wanasinghe2014Config(
        runs=2,
        replay_runs=1,
        sweep_runs=1,
        sweep_scales=(1.0,),
        sweep_duration_s=2.0,
        steady_state_s=1.0,
        replay_steady_state_s=3.0,
        sim=SimSettings(
            scenario=dataclasses.replace(default_scenario(), duration_s=6.0), n_poses=3
        ),
        replay=ReplaySettings(
            dataset=dataset,
            duration_s=10.0,
            min_duration_s=8.0,
            start_after_odometry_s=1.0,
            calibration_noise_windows_s=(1.0, 2.0),
        ),
    )
