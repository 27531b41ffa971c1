"""Bad and degenerate input to the air-ground simulator, the formation controller and the drone
schedule: each is a ConfigError (a setting) or a DataError (an estimate or a command) naming the
field, never a raw exception, a NaN command or a camera that silently sees nothing."""

import math

import numpy as np
import pytest

from relloc.control import DroneSchedule, FormationController, FormationSettings
from relloc.control.formation import formation_command
from relloc.errors import ConfigError, DataError
from relloc.sim.airground import (
    AirGroundScenario,
    AirGroundWorld,
    CameraSettings,
    DroneSettings,
    LeaderPath,
)

OFFSETS = ((0.5, 0.5), (-0.5, 0.5))


def _scenario(**changes):
    return AirGroundScenario(
        **{"offsets": OFFSETS, "offset_frame": "global", "duration": 0.5, **changes}
    )


# --------------------------------------------------------------------------- formation control


@pytest.mark.parametrize("gain", ["0.6", None, True, 1e308])
def test_formation_gain_of_wrong_type_or_value_names_the_field(gain):
    with pytest.raises(ConfigError, match=r"FormationSettings\.gain"):
        FormationSettings(gain=gain)


@pytest.mark.parametrize(
    ("estimate", "leader_u"),
    [
        ([math.nan, 0.0, 0.0, 0.0], (0.1, 0.0)),
        ([1.0, 0.0, 0.0, math.inf], (0.1, 0.0)),
        ([1.0, 0.0, 0.0, 0.0], (math.nan, 0.0)),
        ([1.0, 0.0], (0.1, 0.0)),
        ([1.0, 0.0, 0.0, 0.0], (0.1,)),
        ([1e300, 0.0, 0.0, 0.0], (0.1, 0.0)),
        ([1.0, 0.0, 0.0, 0.0], (1e300, 0.0)),
    ],
)
def test_a_bad_estimate_or_leader_command_is_a_data_error_never_a_nan_command(estimate, leader_u):
    with pytest.raises(DataError, match=r"estimate|leader command"):
        formation_command(
            np.array(estimate), np.array([0.5, 0.5]), "global", leader_u, FormationSettings()
        )
    controller = FormationController(offsets=OFFSETS, frame="global")
    with pytest.raises(DataError, match="follower 2"):
        controller.command(2, np.array(estimate), leader_u)


def test_an_offset_of_the_wrong_shape_is_a_config_error():
    with pytest.raises(ConfigError, match="offset"):
        formation_command(np.zeros(4), np.zeros(3), "global", (0.1, 0.0), FormationSettings())


@pytest.mark.parametrize(
    ("offsets", "where"),
    [
        (((1.0, 2.0, 3.0),), r"offsets\[0\]"),
        (((math.nan, 1.0),), r"offsets\[0\]\[0\]"),
        (("ab",), r"offsets\[0\]"),
        ("ab", "offsets"),
        ((1.0, 2.0), r"offsets\[0\]"),
        (((True, 1.0),), r"offsets\[0\]\[0\]"),
        (((0.0, 0.0),), "sits on the leader"),
        (((0.5, 0.5), (0.5, 0.52)), "follower 2 sits on follower 1"),
    ],
)
def test_formation_offsets_are_checked_where_they_are_given(offsets, where):
    with pytest.raises(ConfigError, match=where):
        FormationController(offsets=offsets, frame="global")
    with pytest.raises(ConfigError, match=where):
        _scenario(offsets=offsets)


@pytest.mark.parametrize("follower", [1.0, True, "1"])
def test_follower_index_must_be_an_integer_in_range(follower):
    controller = FormationController(offsets=OFFSETS, frame="global")
    with pytest.raises(ConfigError, match="follower"):
        controller.command(follower, np.zeros(4), (0.1, 0.0))


def test_controller_settings_of_the_wrong_type_are_refused():
    with pytest.raises(ConfigError, match="settings"):
        FormationController(offsets=OFFSETS, frame="global", settings=None)  # type: ignore[arg-type]


def test_degenerate_but_valid_formations_command_finite_values():
    """A formation of one; a follower on its target (zero command); a follower estimated on the
    leader (r = 0); a huge admissible gain (saturated)."""
    one = FormationController(offsets=((0.5, 0.0),), frame="leader")
    assert one.command(1, np.array([0.5, 0.0, 0.0, 0.0]), (0.0, 0.0)) == (0.0, 0.0)
    strong = FormationSettings(gain=1e6, heading_gain=1e6)
    for estimate in (np.zeros(4), np.array([1e5, -1e5, 3.0, -3.0])):
        v, w = formation_command(estimate, np.array([0.5, 0.5]), "leader", (0.1, 0.2), strong)
        assert math.isfinite(v) and abs(v) <= strong.v_max
        assert math.isfinite(w) and abs(w) <= strong.w_max


# --------------------------------------------------------------------------- drone schedule


@pytest.mark.parametrize(
    "change",
    [
        {"n_followers": 2.5},
        {"n_followers": "3"},
        {"n_followers": True},
        {"n_drones": 1.5},
        {"n_drones": None},
        {"dwell_steps": 1.5},
        {"offset": 0.5},
    ],
)
def test_schedule_counts_must_be_integers(change):
    field = next(iter(change))
    with pytest.raises(ConfigError, match=f"DroneSchedule.{field}"):
        DroneSchedule(**{"n_followers": 3, "n_drones": 1, "dwell_steps": 2, **change})


@pytest.mark.parametrize("step", [1.5, "3", None])
def test_schedule_step_must_be_an_integer(step):
    schedule = DroneSchedule(n_followers=3, n_drones=1, dwell_steps=2)
    with pytest.raises(ConfigError, match="step"):
        schedule.targets(step)


# --------------------------------------------------------------------------- air-ground scenario


@pytest.mark.parametrize(
    ("change", "where"),
    [
        ({"dt": "0.05"}, "dt"),
        ({"duration": None}, "duration"),
        ({"dt": 1.0}, "shorter than one tick"),
        ({"duration": 0.01}, "shorter than one tick"),
        ({"duration": 1e9, "dt": 1e-3}, "MAX_SIMULATED_STEPS"),
        ({"n_drones": 1.5}, "n_drones"),
        ({"n_drones": True}, "n_drones"),
        ({"uwb_every": 2.0, "camera_every": 2.0}, "uwb_every"),
        ({"camera_every": "2"}, "camera_every"),
        ({"schedule_offset": 0.5}, "schedule_offset"),
        ({"schedule_policy": "random"}, "schedule_policy"),
        ({"velocity_noise": (math.nan, 0.1)}, r"velocity_noise\[0\]"),
        ({"velocity_noise": (0.01, math.inf)}, r"velocity_noise\[1\]"),
        ({"velocity_noise": 0.1}, "velocity_noise"),
        ({"leader_start_heading": math.nan}, "leader_start_heading"),
        ({"leader_start_heading": "0"}, "leader_start_heading"),
        ({"init_heading_sigma": 1e308}, "init_heading_sigma"),
        ({"uwb_link_bias": "no"}, "uwb_link_bias"),
        ({"leader": None}, "leader"),
        ({"camera": None}, "camera"),
        ({"drone": None}, "drone"),
        ({"uwb": None}, "uwb"),
        ({"drone": DroneSettings(altitude=3.0)}, "detection band"),
    ],
)
def test_bad_air_ground_scenario_names_the_field(change, where):
    with pytest.raises(ConfigError, match=where):
        _scenario(**change)


@pytest.mark.parametrize(
    ("cls", "change", "where"),
    [
        (CameraSettings, {"hfov": 4.0}, "hfov"),  # tan(hfov/2) < 0: a footprint that sees nothing
        (CameraSettings, {"vfov": 7.0}, "vfov"),
        (CameraSettings, {"hfov": "1"}, "hfov"),
        (CameraSettings, {"p_detect": "1"}, "p_detect"),
        (CameraSettings, {"marker_margin": math.inf}, "marker_margin"),
        (CameraSettings, {"min_altitude": True}, "min_altitude"),
        (DroneSettings, {"altitude_sigma": math.inf}, "altitude_sigma"),
        (DroneSettings, {"midpoint_sigma": math.inf}, "midpoint_sigma"),
        (DroneSettings, {"gain": "1"}, "gain"),
        (LeaderPath, {"speed": 1e308}, "speed"),
        (LeaderPath, {"turn_rate": "1"}, "turn_rate"),
    ],
)
def test_bad_sensor_and_motion_settings_name_the_field(cls, change, where):
    with pytest.raises(ConfigError, match=f"{cls.__name__}.{where}"):
        cls(**change)


def test_a_dwell_longer_than_the_run_is_one_window():
    """``dwell_time / dt`` overflows to infinity; the schedule is still one window."""
    schedule = _scenario(dwell_time=1.7e308, dt=1e-3).schedule()
    assert schedule.targets(0) == schedule.targets(499)


def test_a_valid_degenerate_world_runs_with_finite_truth():
    """One follower, one drone, the shortest run (one tick), at rest."""
    sc = AirGroundScenario(offsets=((0.0, 0.5),), offset_frame="global", duration=0.05)
    world = AirGroundWorld.start(sc, np.random.default_rng(0))
    world.step(np.zeros((2, 2)), np.zeros((1, 2)))
    recording = world.recording()
    assert world.done and all(np.isfinite(g.pose).all() for g in recording.truth or ())
