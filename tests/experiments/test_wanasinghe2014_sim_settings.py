"""Settings of the seed-000 reproduction that cannot run are refused naming the setting; the
odometry-noise sweep scales every robot's odometry σ and nothing else."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from relloc.errors import ConfigError
from relloc.experiments.wanasinghe2014 import Wanasinghe2014Config
from relloc.experiments.wanasinghe2014_mrclam import ReplaySettings
from relloc.experiments.wanasinghe2014_sim import SimSettings, simulated_recording
from relloc.sim.scenario import default_scenario

SCENARIO = default_scenario()


def test_the_sweep_scales_every_robots_odometry_sigma() -> None:
    assert SimSettings(scenario=SCENARIO).simulated_scenario() is SCENARIO
    scaled = SimSettings(scenario=SCENARIO, odometry_scale=4.0).simulated_scenario()
    for before, after in zip(SCENARIO.robots, scaled.robots, strict=True):
        assert after.odometry.sigma_v == pytest.approx(4.0 * before.odometry.sigma_v)
        assert after.odometry.sigma_vz == pytest.approx(4.0 * before.odometry.sigma_vz)
        assert after.odometry.sigma_w == pytest.approx(4.0 * before.odometry.sigma_w)
        assert dataclasses.replace(after, odometry=before.odometry) == before
    assert dataclasses.replace(scaled, robots=SCENARIO.robots) == SCENARIO


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"observer": "ghost"}, r"SimSettings\.observer: 'ghost' is not in \('observer', "),
        ({"observer": "aerial1"}, r"SimSettings\.observer: 'aerial1' observes no robot"),
        ({"table1_target": "observer"}, r"SimSettings\.table1_target: 'observer' is not observed"),
    ],
)
def test_sim_settings_that_cannot_run_name_the_setting(changes: dict, message: str) -> None:
    with pytest.raises(ConfigError, match=message):
        SimSettings(scenario=SCENARIO, **changes)


def test_a_target_the_observer_never_sees_is_refused() -> None:
    observer = SCENARIO.robots[0]
    assert observer.sensor is not None
    blind = dataclasses.replace(observer.sensor, max_range=0.31)
    scenario = dataclasses.replace(
        SCENARIO,
        duration_s=1.0,
        robots=(dataclasses.replace(observer, sensor=blind), *SCENARIO.robots[1:]),
    )
    with pytest.raises(ConfigError, match=r"scenario: 'observer' never sees 'aerial1'"):
        simulated_recording(SimSettings(scenario=scenario), np.random.default_rng(0))


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"observed": 1, "observer": 1}, r"ReplaySettings\.observed: must differ"),
        ({"duration_s": 0.0}, r"ReplaySettings\.duration_s: must be a positive number, got 0"),
        ({"height": float("inf")}, r"ReplaySettings\.height: must be finite, got inf"),
        ({"calibration_noise_windows_s": ()}, r"calibration_noise_windows_s: positive window"),
        ({"calibration_noise_windows_s": (1.0, -2.0)}, r"calibration_noise_windows_s: positive"),
        ({"init_range": (8.0, 0.3)}, r"ReplaySettings\.init_range: need 0 ≤ min < max"),
    ],
)
def test_replay_settings_that_cannot_run_name_the_setting(changes: dict, message: str) -> None:
    with pytest.raises(ConfigError, match=message):
        ReplaySettings(dataset=Path("unused"), **changes)


def test_a_sweep_without_scales_is_refused() -> None:
    replay = ReplaySettings(dataset=Path("unused"))
    with pytest.raises(ConfigError, match="sweep_scales: at least one scale"):
        Wanasinghe2014Config(sweep_scales=(), replay=replay)
