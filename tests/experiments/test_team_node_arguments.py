"""What ``relloc node`` and ``relloc team up`` build one robot from: a robot, case, team source,
seed or run the team does not have is refused naming the flag; the externally commanded
air-ground case has no follower controller."""

from __future__ import annotations

from pathlib import Path

import pytest

from relloc.control.formation import FormationController
from relloc.errors import ConfigError
from relloc.experiments import guler2023_team, team_sources
from relloc.sim.airground import robot_names


@pytest.mark.parametrize(
    ("build", "message"),
    [
        (
            lambda: team_sources.named_node_parts("desilva2015", "ghost", 0, 0, 1.0),
            r"--robot: 'ghost' is not in desilva2015 \('L1', 'L2', 'P1', 'P2', 'P3'\)",
        ),
        (
            lambda: team_sources.named_node_parts("sharma2013", "ghost", 1, 0, 1.0),
            r"--robot: 'ghost' is not in sharma2013 \('1', '2', '3', '4', '5'\)",
        ),
        (
            lambda: team_sources.named_node_parts("sharma2013", "1", 1, 0, 1.0, case="nope"),
            r"--case: 'nope' is not one of \[",
        ),
        (
            lambda: team_sources.desilva_scenario("nope", None),
            r"team source: 'nope' is not one of \('desilva2015', ",
        ),
        (lambda: team_sources.run_seed(0, -1), r"--run: -1 must be ≥ 0"),
        (
            lambda: guler2023_team.run_seed(-1, "one_drone", 0),
            r"--seed -1 / --run 0: must be ≥ 0",
        ),
        (
            lambda: guler2023_team.team_case("nope", None),
            r"--case: 'nope' is not one of one_drone, two_drones, formation",
        ),
        (
            lambda: guler2023_team.team_case("one_drone", 1e-6),
            r"--duration: 1e-06 s is shorter than one tick",
        ),
        (
            lambda: guler2023_team.GulerTeamSettings(out_dir=Path("unused"), case="nope"),
            r"--case: 'nope' is not one of one_drone, two_drones, formation",
        ),
    ],
)
def test_what_the_team_does_not_have_is_refused_naming_the_flag(build, message) -> None:
    with pytest.raises(ConfigError, match=message):
        build()


def test_an_air_ground_robot_is_one_of_the_team_and_external_followers_have_no_controller():
    case = guler2023_team.team_case("one_drone", 0.5)
    assert case.scenario.control == "external"
    assert guler2023_team.controller_of(case) is None
    formation = guler2023_team.team_case("formation", 0.5)
    assert isinstance(guler2023_team.controller_of(formation), FormationController)
    seed = guler2023_team.run_seed(0, "one_drone", 0)
    follower = robot_names(case.scenario)[1]
    role = guler2023_team.role_of(case, follower, seed)
    assert type(role).__name__ == "FollowerRole"
    with pytest.raises(ConfigError, match=r"--robot: 'ghost' is not in the team R_0, R_1, "):
        guler2023_team.role_of(case, "ghost", seed)
