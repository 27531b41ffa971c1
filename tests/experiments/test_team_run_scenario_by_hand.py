"""``relloc run`` on hand-made scenarios: a robot with an ``observes`` list is blamed only for
the robots it lists, the sensor drawing's unlimited range is the arena's own diagonal wherever
the arena lies, a negative settling time is refused, and only run 0 keeps the true paths."""

from __future__ import annotations

import math
from typing import Any

import pytest

from relloc.errors import ConfigError
from relloc.experiments.team_run import (
    TeamRunSettings,
    pairs_never_read,
    run_scenario,
    sensor_views,
)
from relloc.sim.scenario import Arena, RobotSpec, Scenario, SensorSpec, VelocityMotion


def _scenario(observes: tuple[str, ...] | None, arena: Arena) -> Scenario:
    """a (360°, unlimited range) at (1.5, 2.5) m, b 1 m east of it, c 3 m north; only a has a
    sensor."""
    still = VelocityMotion()
    return Scenario(
        name="hand",
        duration_s=2.0,
        arena=arena,
        robots=(
            RobotSpec(
                name="a",
                kind="ground",
                motion=still,
                initial_pose=(1.5, 2.5, 0.0),
                sensor=SensorSpec(max_range=math.inf),
                observes=observes,
            ),
            RobotSpec(name="b", kind="ground", motion=still, initial_pose=(2.5, 2.5, 0.0)),
            RobotSpec(name="c", kind="ground", motion=still, initial_pose=(1.5, 5.5, 0.0)),
        ),
    )


ARENA = Arena(x=(1.0, 4.0), y=(2.0, 6.0))  # 3 m × 4 m away from the origin: diagonal 5 m


def _tracked(*pairs: tuple[str, str]) -> dict[str, Any]:
    return {"pairs": {f"{o}->{s}": {"observer": o, "observed": s} for o, s in pairs}}


def test_a_robot_observing_a_list_is_named_for_each_listed_robot_never_read() -> None:
    assert pairs_never_read(_scenario(("c",), ARENA), _tracked()) == ["a->c"]
    assert pairs_never_read(_scenario(("c",), ARENA), _tracked(("a", "c"))) == []
    assert pairs_never_read(_scenario(None, ARENA), _tracked(("a", "c"))) == ["a->b"]


def test_an_unlimited_range_is_drawn_to_the_diagonal_of_an_arena_off_the_origin() -> None:
    assert sensor_views(_scenario(None, ARENA)) == {"a": (360.0, 5.0)}


def test_a_negative_settling_time_is_refused() -> None:
    with pytest.raises(ConfigError, match=r"^settle_s: must be a finite number in \[0, inf\)"):
        TeamRunSettings(settle_s=-0.5)


def test_only_run_0_keeps_the_true_paths_for_the_figure() -> None:
    # seed 604219: used nowhere else in the tests (nothing statistical is checked)
    settings = TeamRunSettings(runs=2, seed=604219, executor="serial", quiet=True, settle_s=0.5)
    _, results = run_scenario(_scenario(None, ARENA), settings)
    assert results[1].paths is None and results[1].path_t is None
    paths = results[0].paths
    assert paths is not None and set(paths) == {"a", "b", "c"}
    assert paths["b"][0][:2] == pytest.approx([2.5, 2.5])
    assert paths["c"][-1][:2] == pytest.approx([1.5, 5.5])
