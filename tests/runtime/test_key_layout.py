"""The documented key-expression layout: id syntax and the parsers of robot, clock and
liveliness keys at their edges."""

from __future__ import annotations

import pytest

from relloc.errors import ConfigError
from relloc.runtime import keys


def test_an_id_is_1_to_64_letters_digits_underscores_or_dashes():
    assert keys.check_id("a" * 64, "robot") == "a" * 64
    assert keys.check_id("A-z_09", "robot") == "A-z_09"
    for bad in ("a" * 65, "a.b", "a/b", "a*", "", "a b"):
        with pytest.raises(ConfigError, match="not a valid id"):
            keys.check_id(bad, "robot")


def test_a_robot_key_has_exactly_five_parts():
    assert keys.parse_robot_key("relloc/team/robot/flyer/odom") == ("flyer", "odom")
    assert keys.parse_robot_key("relloc/team/robot/flyer/odom/extra") is None
    assert keys.parse_robot_key("other/team/robot/flyer/odom") is None
    assert keys.parse_robot_key("relloc/team/robot/flyer/tick") is None
    assert keys.parse_robot_key(None) is None  # type: ignore[arg-type]


def test_a_clock_key_has_exactly_four_parts():
    assert keys.parse_clock_key("relloc/team/clock/tick") == "tick"
    assert keys.parse_clock_key("relloc/team/clock/tick/extra") is None
    assert keys.parse_clock_key("relloc/team/clock/odom") is None
    assert keys.parse_clock_key(7) is None  # type: ignore[arg-type]


def test_a_liveliness_key_names_its_token_kind_and_member():
    assert keys.parse_presence_key("relloc/team/alive/flyer") == ("alive", "flyer")
    assert keys.parse_presence_key(keys.ready_key("team", "rover")) == ("ready", "rover")
    for other in (
        "relloc/team/alive/",
        "relloc/team/alive/*",
        "relloc/team/alive/fl*",
        "relloc//alive/flyer",
        "other/team/alive/flyer",
        "relloc/team/gone/flyer",
        "relloc/team/alive/flyer/x",
        "relloc/team/**",
    ):
        assert keys.parse_presence_key(other) is None, other
    assert keys.parse_presence_key(None) is None  # type: ignore[arg-type]


def test_the_ready_token_is_not_the_alive_token():
    assert keys.ready_key("team", "flyer") == "relloc/team/ready/flyer"
    assert keys.alive_key("team", "flyer") == "relloc/team/alive/flyer"
    assert keys.ready_wildcard("team") == "relloc/team/ready/*"
