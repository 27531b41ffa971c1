"""The seed-000 replay's steady state against the windows it is cut from: a noise-inflation fit
whose calibration stretches never reach the steady state has nothing to fit on and is refused
(before: it reported ×1, "met", at 0 % of 0 updates), and a replay steady state no shorter
than the scored window is refused when the configuration is built (before: the whole run went
through and then failed with "math domain error" in the turn-rate summary)."""

from __future__ import annotations

from pathlib import Path

import pytest

from relloc.errors import ConfigError, DataError
from relloc.experiments.wanasinghe2014 import Wanasinghe2014Config
from relloc.experiments.wanasinghe2014_mrclam import ReplaySettings, prepare_replays


@pytest.fixture(scope="module")
def short_dataset(tmp_path_factory: pytest.TempPathFactory, mrclam_run6_cut) -> Path:
    """Robots 1-3, the first 45 s of run 6: a 10 s scored window leaves two 10 s stretches."""
    return mrclam_run6_cut(tmp_path_factory.mktemp("mrclam") / "MRCLAM_short")


def test_an_inflation_fit_without_steady_state_updates_is_refused(short_dataset: Path) -> None:
    """Both calibration stretches last 10 s; a 12 s steady state leaves no update to count.
    (The seed is not statistical here: no draw reaches the steady state; root 46017 is used
    nowhere else in the tests.)"""
    settings = ReplaySettings(
        dataset=short_dataset, duration_s=10.0, min_duration_s=8.0, start_after_odometry_s=1.0
    )
    with pytest.raises(DataError, match=r"lasts past the 12 s steady state .*noise inflation"):
        prepare_replays(settings, steady_state_s=12.0, seed=46017, executor="serial", quiet=True)


def test_a_replay_steady_state_as_long_as_the_scored_window_is_refused() -> None:
    replay = ReplaySettings(dataset=Path("unused"), duration_s=30.0)
    with pytest.raises(ConfigError, match="replay_steady_state_s"):
        Wanasinghe2014Config(replay=replay, replay_steady_state_s=30.0)
    with pytest.raises(ConfigError, match="replay_steady_state_s"):
        Wanasinghe2014Config(replay=replay, replay_steady_state_s=40.0)
    assert Wanasinghe2014Config(replay=replay, replay_steady_state_s=29.5).replay is replay
