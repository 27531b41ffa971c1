"""Small arguments of the reproductions that cannot be met are refused naming them; the
default plan of guler2023 and the comparison of two teams' figures."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from relloc.core.recording import Odometry, Recording, empty_measurements
from relloc.datasets.bag_mapping import parse_mapping
from relloc.errors import ConfigError
from relloc.experiments.guler2023 import Plan, default_plan, hexagon_offsets
from relloc.experiments.guler2023_team import largest_difference
from relloc.experiments.registry import ReproduceArgs
from relloc.experiments.tiers_uwb_team import standing_robots


def test_an_empty_pair_list_is_refused() -> None:
    with pytest.raises(ConfigError, match=r"--pair: at least one pair OBSERVER,OBSERVED"):
        ReproduceArgs(out_dir=Path("unused"), pairs=())


@pytest.mark.parametrize("n", [0, 6])
def test_a_hexagon_holds_one_to_five_followers(n: int) -> None:
    with pytest.raises(ConfigError, match=rf"hexagon_offsets: 1 to 5 followers, got {n}"):
        hexagon_offsets(n, 0.9)


def test_the_default_plan_or_every_count_set_to_runs() -> None:
    assert default_plan(None) == Plan()
    plan = default_plan(3)
    assert (plan.one_drone_runs, plan.two_drones_runs, plan.formation_runs, plan.sweep_runs) == (
        3,
        3,
        3,
        3,
    )


def test_figures_of_another_shape_differ_without_bound() -> None:
    assert largest_difference([1.0, 2.0], [1.0]) == float("inf")
    assert largest_difference(1.0, [1.0]) == float("inf")
    assert largest_difference([1.0, None], [1.5, None]) == 0.5


def test_declared_anchors_are_taken_without_motion_capture() -> None:
    text = 'anchors = ["beta"]\n[[robots]]\nname = "alpha"\n[[robots]]\nname = "beta"\n'
    still = Odometry(t=np.zeros(0), velocity=np.zeros((0, 4)), sigma=(0, 0, 0, 0))
    rec = Recording(
        robots=("alpha", "beta"),
        platforms=("ground",) * 2,
        odometry=(still, still),
        measurements=empty_measurements(),
    )
    assert rec.truth is None
    assert standing_robots(rec, parse_mapping(text, "m.toml")) == [1]
