"""Fuzzing of the key parsers of :mod:`relloc.runtime.keys` with the keys a peer could publish
on: any text, keys of the layout with a part changed, dropped or repeated, and values that are
not text. A robot or clock key parses to the parts it is made of or to None; a presence key to
``(alive|ready, member)`` or None — never an exception."""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from relloc.runtime import keys
from relloc.runtime.transport import Incoming, Roll

_part = st.one_of(
    st.sampled_from(
        ["relloc", "t", "robot", "clock", "alive", "ready", "a", "odom", "tick", "", "*", "**"]
    ),
    st.text(max_size=6),
)
_layout = st.one_of(
    st.builds(
        keys.robot_key,
        st.just("t"),
        st.sampled_from(["a", "b_1"]),
        st.sampled_from(keys.ROBOT_KINDS),
    ),
    st.builds(keys.clock_key, st.just("t"), st.sampled_from(keys.CLOCK_KINDS)),
    st.builds(keys.alive_key, st.just("t"), st.sampled_from(["a", "clock"])),
    st.builds(keys.ready_key, st.just("t"), st.sampled_from(["a", "clock"])),
)


@st.composite
def _edited(draw: st.DrawFn) -> str:
    """A key of the layout with one part replaced, dropped or repeated, or a part added."""
    parts = draw(_layout).split("/")
    i = draw(st.integers(0, len(parts) - 1))
    how = draw(st.sampled_from(["replace", "drop", "repeat", "add"]))
    if how == "replace":
        parts[i] = draw(_part)
    elif how == "drop":
        del parts[i]
    elif how == "repeat":
        parts.insert(i, parts[i])
    else:
        parts.insert(i, draw(_part))
    return "/".join(parts)


KEYS = st.one_of(
    st.text(max_size=30),
    st.text(alphabet="relocbtaivdy/*_-", max_size=30),
    st.lists(_part, max_size=6).map("/".join),
    _layout,
    _edited(),
)
NOT_TEXT = st.one_of(
    st.none(), st.integers(), st.binary(max_size=12), st.lists(st.text(), max_size=2)
)


def _check(key: object) -> None:
    robot = keys.parse_robot_key(key)  # type: ignore[arg-type]
    if robot is not None:
        sender, kind = robot
        assert isinstance(key, str) and kind in keys.ROBOT_KINDS
        team = key.split("/")[1]
        assert f"relloc/{team}/robot/{sender}/{kind}" == key
    clock = keys.parse_clock_key(key)  # type: ignore[arg-type]
    if clock is not None:
        assert isinstance(key, str) and clock in keys.CLOCK_KINDS
        assert key == keys.clock_key(key.split("/")[1], clock)
    presence = keys.parse_presence_key(key)  # type: ignore[arg-type]
    if presence is None:
        return
    token, member = presence
    assert isinstance(key, str) and token in ("alive", "ready") and member and "*" not in key
    team = key.split("/")[1]
    assert team and key == f"relloc/{team}/{token}/{member}"


@settings(derandomize=True, max_examples=200, deadline=None)
@given(key=KEYS)
def test_a_hostile_key_parses_to_its_parts_or_is_refused(key):
    _check(key)


@settings(derandomize=True, max_examples=50, deadline=None)
@given(key=NOT_TEXT)
def test_a_key_that_is_not_text_is_no_stream_and_no_presence(key):
    assert keys.parse_robot_key(key) is None  # type: ignore[arg-type]
    assert keys.parse_clock_key(key) is None  # type: ignore[arg-type]
    _check(key)


@pytest.mark.parametrize("key", ["relloc/t/**", "relloc/t/alive/**", "relloc/t/*/a", "x", "/"])
def test_a_wildcard_or_foreign_token_is_no_member(key):
    """A liveliness subscriber hears every token overlapping its wildcard, a peer's wildcard
    token too: it raised a DataError (and ``"x"`` an IndexError) in every process's presence
    handling; ``relloc/t/*/a`` counted as robot ``a`` joining."""
    assert keys.parse_presence_key(key) is None
    roll = Roll(["a", "b"])
    assert roll.update(Incoming(key, b"", "joined")) is None
    assert roll.present == set() and roll.ready == set()


def test_the_keys_of_the_layout_parse_back():
    assert keys.parse_robot_key(keys.robot_key("t", "a", "odom")) == ("a", "odom")
    assert keys.parse_clock_key(keys.clock_key("t", "sense")) == "sense"
    assert keys.parse_presence_key(keys.alive_key("t", "clock")) == ("alive", "clock")
    assert keys.parse_presence_key(keys.ready_key("t", "a")) == ("ready", "a")
