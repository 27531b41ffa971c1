"""Bad and degenerate input to the scenario API and to the cooperative (seed 001) and
multi-hypothesis (seed 002) simulators: each is a ConfigError naming the field, never a raw
exception, a hang, a silent truncation or a NaN passed on to the recording."""

import dataclasses
import math

import numpy as np
import pytest

from relloc.core.recording import kind_code
from relloc.errors import ConfigError
from relloc.sim import cooperative, multihypothesis
from relloc.sim.cooperative import CooperativeScenario, grid_team_scenario, sharma2013_scenario
from relloc.sim.multihypothesis import DeSilvaScenario
from relloc.sim.scenario import Arena, WaypointMotion, default_scenario, scenario_from_dict

# --------------------------------------------------------------------------- scenario API


@pytest.mark.parametrize("robots", [None, 5])
def test_scenario_robots_that_are_not_a_list_name_the_field(robots):
    with pytest.raises(ConfigError, match="robots: expected a list"):
        dataclasses.replace(default_scenario(), robots=robots)


def test_a_document_that_is_not_a_table_is_a_config_error():
    with pytest.raises(ConfigError, match="scenario: expected a table"):
        scenario_from_dict(["robots"])  # type: ignore[arg-type]


# --------------------------------------------------------------------------- cooperative


@pytest.mark.parametrize(
    ("change", "where"),
    [
        ({"dt": "0.1"}, "dt"),
        ({"dt": True}, "dt"),
        ({"fov": 7.0}, "fov"),
        ({"sigma_bearing": 1e300}, "sigma_bearing"),
        ({"sigma_range": "1"}, "sigma_range"),
        ({"sigma_range": math.inf}, "sigma_range"),
        ({"initial_sigma": (math.nan, 1.0, 1.0)}, r"initial_sigma\[0\]"),
        ({"initial_sigma": (1.0, 1.0)}, "initial_sigma"),
        ({"gps_sigma": (1.0, 1.0)}, "gps_sigma"),
        ({"gps_robots": (0, 0)}, "already listed"),
        ({"gps_robots": (0.5,)}, r"gps_robots\[0\]"),
        ({"gps_robots": (True,)}, r"gps_robots\[0\]"),
        ({"start_poses": np.full((5, 3), np.nan)}, "start_poses"),
        ({"waypoints": (np.full((2, 2), np.nan),) * 5}, r"waypoints\[0\]"),
        ({"waypoints": None}, "waypoints"),
        ({"landmarks_xy": np.array([[np.nan, 0.0]])}, "landmarks_xy"),
        ({"landmarks_xy": np.zeros(3)}, "landmarks_xy"),
        ({"landmarks_xy": "ab"}, "landmarks_xy"),
        ({"speed": 1e308}, "speed"),
        ({"duration": 1e12}, "MAX_SIMULATED_STEPS"),
        ({"waypoints": (np.zeros((0, 2)),) * 5}, r"waypoints\[0\] must have shape \(k, 2\)"),
        ({"waypoints": (np.zeros((2, 3)),) * 5}, r"waypoints\[0\] must have shape \(k, 2\)"),
        ({"duration": 0.001}, "duration must be ≥ dt"),
        ({"gps_robots": (7,)}, r"gps_robots\[0\]: robot index 7 out of range 0\.\.4"),
        ({"landmarks_xy": np.array([[1e9, 0.0]])}, "landmarks_xy: a position beyond 100000 m"),
    ],
)
def test_bad_cooperative_scenario_names_the_field(change, where):
    with pytest.raises(ConfigError, match=f"CooperativeScenario.{where}|{where}"):
        sharma2013_scenario(**change)


@pytest.mark.parametrize("n", [1.5, "2"])
def test_grid_team_size_must_be_an_integer(n):
    with pytest.raises(ConfigError, match="grid_team_scenario: n"):
        grid_team_scenario(n)


def test_numpy_arrays_are_accepted_where_lists_are():
    """An array of way-points or an array range was refused as 'not a list'."""
    points = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]]
    assert WaypointMotion(points=np.array(points)) == WaypointMotion(points=points)
    assert Arena(x=np.array([0.0, 4.0])) == Arena(x=(0.0, 4.0))
    with pytest.raises(ConfigError, match=r"points\[0\]: expected 2 numbers, got 3"):
        WaypointMotion(points=np.zeros((3, 3)))
    with pytest.raises(ConfigError, match="points: expected a list of at least two"):
        WaypointMotion(points="abc")


def test_a_gps_period_beyond_every_float_tick_gives_no_fixes():
    """``gps_period / dt`` overflows to infinity: no fix falls inside the run."""
    scenario = sharma2013_scenario(duration=1.0, gps_robots=(0,), gps_period=1.7e308, dt=0.01)
    rec = cooperative.simulate(scenario, np.random.default_rng(0)).recording
    assert not np.any(rec.measurements.kind == kind_code("pose"))


def test_a_one_robot_team_simulates():
    scenario = CooperativeScenario(
        start_poses=np.zeros((1, 3)),
        waypoints=(np.array([[5.0, 0.0], [5.0, 5.0]]),),
        landmarks_xy=np.array([[2.0, 2.0]]),
        duration=1.0,
        speed=1.0,
    )
    rec = cooperative.simulate(scenario, np.random.default_rng(0)).recording
    assert rec.robots == ("1",) and len(rec.measurements.t) > 0


# --------------------------------------------------------------------------- multi-hypothesis


@pytest.mark.parametrize(
    ("change", "where"),
    [
        ({"duration": 0.01}, "shorter than one filter step"),
        ({"duration": "1"}, "duration"),
        ({"filter_rate": 1e9}, "MAX_SIMULATED_STEPS"),
        ({"p_detect": "1"}, "p_detect"),
        ({"clutter_density": 1e300}, "MAX_MEASUREMENTS"),
        ({"max_range": 1e308}, "max_range"),
        ({"group_speed": math.nan}, "group_speed"),
        ({"group_turn_rate": "0.1"}, "group_turn_rate"),
        ({"kidnap": (0, 0.5, math.nan, 0.0, 0.0)}, r"kidnap\[2\]"),
        ({"kidnap": (0.5, 0.5, 0.0, 0.0, 0.0)}, r"kidnap\[0\]"),
        ({"kidnap": (0, 0.5)}, "kidnap"),
        ({"sensing": (1.5,)}, r"sensing\[0\]"),
        ({"sensing": (True,)}, r"sensing\[0\]"),
        ({"sensing": "01"}, "sensing"),
        ({"direct_rate": 3.0}, r"direct_rate must divide filter_rate \(3\.0 vs 20\.0\)"),
        ({"direct_rate": 40.0}, r"direct_rate must divide filter_rate \(40\.0 vs 20\.0\)"),
        ({"kidnap": (9, 0.5, 0.0, 0.0, 0.0)}, r"kidnap\[0\] \(robot\): no robot 9 \(0 to 4\)"),
    ],
)
def test_bad_desilva_scenario_names_the_field(change, where):
    with pytest.raises(ConfigError, match=f"DeSilvaScenario.{where}|{where}"):
        DeSilvaScenario(**{"duration": 1.0, **change})


@pytest.mark.parametrize("turn_rate", [0.0, 1e-310])
def test_a_group_that_does_not_turn_drives_straight(turn_rate):
    """ω = 0 divided by zero; a subnormal ω overflowed the radius ``v / ω`` into NaN poses."""
    scenario = DeSilvaScenario(duration=1.0, group_turn_rate=turn_rate)
    rec = multihypothesis.simulate(scenario, np.random.default_rng(0))
    leader = rec.truth[0].pose if rec.truth else np.zeros((0, 4))
    assert np.isfinite(leader).all() and leader[-1, 0] > leader[0, 0]
