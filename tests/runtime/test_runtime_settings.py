"""Settings of a team's processes refused before anything starts, each error naming the
setting: a node's roster and talkers, the clock's roster, the transport's endpoints, and the
robot id the clock process holds."""

from __future__ import annotations

from pathlib import Path

import pytest

from relloc.errors import ConfigError
from relloc.runtime import keys
from relloc.runtime.airground import RobotSettings
from relloc.runtime.certs import check_roster
from relloc.runtime.clock import ClockSettings
from relloc.runtime.node import NodeSettings
from relloc.runtime.scenario import load_team_scenario
from relloc.runtime.transport import Inbox, TransportSettings, loopback_endpoint, open_session


def _node(**overrides) -> NodeSettings:
    base = {"team": "t", "robot": "a", "roster": ("a", "b"), "transport": TransportSettings()}
    return NodeSettings(**(base | overrides))


@pytest.mark.parametrize(
    ("overrides", "message"),
    [
        ({"robot": "c"}, "node.robot: 'c' is not on the roster ('a', 'b')"),
        ({"roster": ("a", "b", "a")}, "node.roster: duplicate robot ids in ('a', 'b', 'a')"),
        ({"talkers": ("a", "z")}, "node.talkers: ('a', 'z') are not all on the roster"),
    ],
)
def test_a_node_off_its_roster_or_with_strangers_as_talkers_is_refused(overrides, message):
    with pytest.raises(ConfigError) as info:
        _node(**overrides)
    assert str(info.value) == message


def test_a_clock_without_robots_is_refused():
    with pytest.raises(ConfigError, match=r"clock\.roster: no robots"):
        ClockSettings(
            team="t", roster=(), tick_s=0.1, duration_s=1.0, transport=TransportSettings()
        )


def test_no_robot_may_take_the_clock_process_id(trio_scenario):
    """The clock (or world) process holds the ``alive`` token of id ``clock`` and sends as
    ``clock``: a robot of that id would be taken for it (its token for the clock's, its
    process for the clock's in the launcher), so the id is refused wherever a robot is named."""
    path = trio_scenario(4.0)
    path.write_text(path.read_text().replace('"rover"', '"clock"'))
    with pytest.raises(ConfigError) as info:
        load_team_scenario(str(path))
    assert "scenario robot name 'clock'" in str(info.value) and "reserved" in str(info.value)
    with pytest.raises(ConfigError, match=r"node\.robot: 'clock' is reserved"):
        _node(robot="clock", roster=("clock", "b"))
    with pytest.raises(ConfigError, match=r"node\.roster: 'clock' is reserved"):
        _node(roster=("a", "clock"))
    with pytest.raises(ConfigError, match=r"clock\.roster: 'clock' is reserved"):
        ClockSettings(
            team="t",
            roster=("a", "clock"),
            tick_s=0.1,
            duration_s=1.0,
            transport=TransportSettings(),
        )
    with pytest.raises(ConfigError, match=r"--robot: 'clock' is reserved"):
        RobotSettings(team="t", robot="clock", transport=TransportSettings())
    with pytest.raises(ConfigError, match=r"robots: 'clock' is reserved"):
        check_roster("t", ("a", "clock"))


@pytest.mark.parametrize(
    ("overrides", "message"),
    [
        ({"mode": "server"}, "transport.mode: 'server' is not peer, client or router"),
        ({"listen": ("127.0.0.1:7447",)}, "transport.listen: expected endpoints like"),
        ({"connect": ["tcp/127.0.0.1:7447"]}, "transport.connect: expected endpoints like"),
        ({"mode": "client"}, "transport.connect: a client needs at least one endpoint"),
        ({"config_file": Path("/nonexistent/zenoh.json5")}, "transport.config_file: /nonexistent"),
    ],
)
def test_bad_transport_settings_are_refused_naming_the_setting(overrides, message):
    with pytest.raises(ConfigError) as info:
        TransportSettings(**overrides)
    assert str(info.value).startswith(message)


def test_a_port_in_use_or_out_of_range_is_refused_naming_the_transport():
    with pytest.raises(ConfigError, match="port: 70000 outside 0–65535"):
        loopback_endpoint(70000)
    with pytest.raises(ConfigError, match="inbox capacity: 0 records"):
        Inbox(0)
    from relloc.runtime.transport import free_loopback_port

    endpoint = loopback_endpoint(free_loopback_port())
    first = open_session(TransportSettings(listen=(endpoint,)))
    try:
        with pytest.raises(ConfigError) as info:
            open_session(TransportSettings(listen=(endpoint,)))
        assert "transport: cannot open a Zenoh session" in str(info.value)
        assert endpoint in str(info.value)
    finally:
        first.close()


def test_keys_of_kinds_outside_the_layout_are_refused():
    with pytest.raises(ConfigError, match="robot_key: unknown kind 'tick'"):
        keys.robot_key("t", "a", "tick")
    with pytest.raises(ConfigError, match="clock_key: unknown kind 'odom'"):
        keys.clock_key("t", "odom")


def test_a_zenoh_config_file_that_does_not_parse_is_refused_naming_it(tmp_path: Path):
    path = tmp_path / "zenoh.json5"
    path.write_text("{ mode: 'peer', listen: ")
    with pytest.raises(ConfigError) as info:
        TransportSettings(config_file=path).zenoh_config()
    assert str(info.value).startswith(f"transport.config_file: {path}: ")
