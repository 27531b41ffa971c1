"""Air-ground scenarios that cannot run are refused naming the field; the straight leader
path, the rigid commands on it, a drone without a leader track and a world stepped past its
end."""

from __future__ import annotations

import numpy as np
import pytest

from relloc.control.formation import FormationController
from relloc.errors import ConfigError
from relloc.sim.airground import (
    AirGroundScenario,
    AirGroundWorld,
    DroneGuidance,
    LeaderPath,
    rigid_command,
    simulate_airground,
)

OFFSETS = ((0.5, 0.5), (-0.5, 0.5))
STRAIGHT = AirGroundScenario(
    offsets=OFFSETS, duration=0.5, control="external", leader=LeaderPath(kind="straight")
)


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        (
            {"camera_every": 3, "uwb_every": 2},
            r"camera_every: must be a multiple of uwb_every",
        ),
        (
            {"control": "external"},
            r"offset_frame: external \(rigid\) motion needs 'leader' offsets",
        ),
        (
            {
                "offsets": tuple((float(i), 1.0) for i in range(1, 30)),
                "duration": 500.0,
                "uwb_every": 1,
            },
            r"AirGroundScenario\.uwb_every: 435 UWB links × 10000 epochs; the limit is 1e\+06",
        ),
    ],
)
def test_a_scenario_that_cannot_run_names_the_field(changes, message):
    with pytest.raises(ConfigError, match=message):
        AirGroundScenario(
            **{"offsets": OFFSETS, "offset_frame": "global", "duration": 0.5, **changes}
        )


def test_a_straight_leader_and_its_rigid_team_drive_straight():
    assert STRAIGHT.leader.command(3.0) == (0.1, 0.0)
    assert rigid_command(STRAIGHT, 1, 0.1, 0.0) == (0.1, 0.0)


def test_an_external_team_takes_no_controller():
    with pytest.raises(ConfigError, match="control='external' commands the followers rigidly"):
        simulate_airground(
            STRAIGHT,
            lambda *a: None,
            FormationController(offsets=OFFSETS, frame="leader"),
            np.random.default_rng(0),
        )


def test_a_drone_without_a_leader_track_hovers_and_a_finished_world_refuses_a_step():
    np.testing.assert_array_equal(
        DroneGuidance(STRAIGHT, 0, None).velocity(0, (0.1, 0.0), np.zeros(2)), [0.0, 0.0]
    )
    world = AirGroundWorld.start(STRAIGHT, np.random.default_rng(0))
    for _ in range(STRAIGHT.n_steps):
        world.step(np.zeros((3, 2)), np.zeros((1, 2)))
    assert world.done
    with pytest.raises(ConfigError, match=r"AirGroundWorld\.step: the run ended at tick 10"):
        world.step(np.zeros((3, 2)), np.zeros((1, 2)))
