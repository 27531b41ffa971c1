"""The clock process' settings: the roster, the fault schedule and the number of ticks a run
has, checked before any process starts."""

from __future__ import annotations

import pytest

from relloc.errors import ConfigError
from relloc.runtime.clock import ClockSettings
from relloc.runtime.faults import RobotEvent
from relloc.runtime.transport import TransportSettings


def _clock(**overrides: object) -> ClockSettings:
    settings: dict[str, object] = {
        "team": "t",
        "roster": ("a", "b"),
        "tick_s": 0.1,
        "duration_s": 1.0,
        "transport": TransportSettings(),
    }
    return ClockSettings(**(settings | overrides))  # type: ignore[arg-type]


def test_a_run_has_the_nearest_whole_number_of_ticks():
    assert _clock(duration_s=0.3, tick_s=0.1).n_ticks == 3  # 0.3 / 0.1 = 2.9999999999999996
    assert _clock(duration_s=0.7, tick_s=0.1).n_ticks == 7


def test_a_robot_named_twice_is_refused():
    with pytest.raises(ConfigError, match="a robot named twice"):
        _clock(roster=("a", "b", "a"))


def test_a_kill_of_a_robot_off_the_roster_is_refused():
    with pytest.raises(ConfigError, match="unknown robot 'z'"):
        _clock(kills=(RobotEvent(robot="z", at_s=0.5),))


@pytest.mark.parametrize(
    ("overrides", "field"),
    [
        ({"tick_s": 2.0}, "clock.tick_s"),
        ({"tick_s": 0.0}, "clock.tick_s"),
        ({"realtime_factor": -1.0}, "--realtime"),
        ({"ack_timeout_s": 0.0}, "clock.ack_timeout_s"),
        ({"startup_timeout_s": 0.0}, "clock.startup_timeout_s"),
        ({"team": "a/b"}, "clock.team"),
    ],
)
def test_a_clock_setting_out_of_range_names_its_field(overrides, field):
    with pytest.raises(ConfigError, match=field.replace(".", r"\.")):
        _clock(**overrides)
