"""The bag mapping file (:mod:`relloc.datasets.bag_mapping`) at its edges: the UWB topic
template, names, topics, list lengths, a byte-order mark and a local file named like a shipped
mapping."""

from __future__ import annotations

import pytest

from relloc.datasets.bag_mapping import (
    UwbNode,
    UwbTopics,
    load_mapping,
    parse_mapping,
    shipped_mappings,
)
from relloc.errors import ConfigError

ROBOT = '[[robots]]\nname = "alpha"\nodometry = "/alpha/odom"\n'
NODES = (UwbNode(name="n_1"), UwbNode(name="n_2"))


def test_a_template_naming_b_first_still_gives_a_then_b():
    uwb = UwbTopics(topics="/uwb/from_{b}/to_{a}/range", nodes=NODES)
    assert uwb.link_of("/uwb/from_n_2/to_n_1/range") == ("n_1", "n_2")


@pytest.mark.parametrize(
    "topic",
    ["/u/n_1/n_2/d/extra", "/u/n/1/n_2/d", "/u/n_1/n_2/dd", "/x/u/n_1/n_2/d"],
)
def test_a_topic_matches_the_template_whole_and_node_names_hold_no_slash(topic):
    uwb = UwbTopics(topics="/u/{a}/{b}/d", nodes=NODES)
    assert uwb.link_of("/u/n_1/n_2/d") == ("n_1", "n_2")
    assert uwb.link_of(topic) is None


def test_a_robot_name_must_be_letters_digits_and_dot_dash_underscore_throughout():
    with pytest.raises(ConfigError, match=r"^m\.toml: robots\[0\]\.name: 'tb 1' is not a name"):
        parse_mapping('[[robots]]\nname = "tb 1"\n', "m.toml")


def test_a_topic_must_start_with_a_slash():
    with pytest.raises(ConfigError, match=r"^m\.toml: robots\[0\]\.odometry: a topic starts with"):
        parse_mapping('[[robots]]\nname = "alpha"\nodometry = "alpha/odom"\n', "m.toml")


def test_an_offset_of_four_numbers_is_refused():
    text = ROBOT + '[uwb]\ntopics = "/u/{a}/{b}/d"\n[[uwb.nodes]]\nname = "n_1"\nrobot = "alpha"\n'
    assert parse_mapping(text + "offset = [0.1, 0.2, 0.3]\n", "m.toml").uwb.nodes[0].offset == (
        0.1,
        0.2,
        0.3,
    )
    with pytest.raises(ConfigError, match=r"uwb\.nodes\[0\]\.offset: expected a list of 3 numbers"):
        parse_mapping(text + "offset = [0.1, 0.2, 0.3, 0.4]\n", "m.toml")


def test_a_mapping_file_may_start_with_a_byte_order_mark(tmp_path):
    path = tmp_path / "bom.toml"
    path.write_bytes(b"\xef\xbb\xbf" + ('name = "with-bom"\n' + ROBOT).encode())
    mapping = load_mapping(path)
    assert mapping.name == "with-bom"
    assert mapping.robots[0].odometry == "/alpha/odom"


def test_a_local_file_named_like_a_shipped_mapping_is_read_instead(tmp_path, monkeypatch):
    name = shipped_mappings()[0]
    monkeypatch.chdir(tmp_path)
    (tmp_path / name).write_text('name = "local"\n' + ROBOT)
    assert load_mapping(name).name == "local"
    assert load_mapping(name).source == name


def test_directions_are_folded_unless_the_mapping_says_otherwise():
    text = ROBOT + '[uwb]\ntopics = "/u/{a}/{b}/d"\n[[uwb.nodes]]\nname = "n_1"\n'
    assert parse_mapping(text, "m.toml").uwb.fold_directions is True
    off = text.replace("[[uwb.nodes]]", "fold_directions = false\n[[uwb.nodes]]")
    assert parse_mapping(off, "m.toml").uwb.fold_directions is False


def test_odometry_sigma_is_read_in_the_order_vx_vy_vz_wz():
    text = ROBOT + "odometry_sigma = [0.1, 0.2, 0.3, 0.4]\n"
    assert parse_mapping(text, "m.toml").robots[0].odometry_sigma == (0.1, 0.2, 0.3, 0.4)


def test_an_integer_too_long_to_write_is_named_by_its_full_key_path():
    huge = "0x" + "f" * 4000  # about 4800 decimal digits
    text = ROBOT + f"odometry_sigma = [0.1, {huge}, 0.0, 0.0]\n"
    with pytest.raises(
        ConfigError, match=r"^m\.toml: robots\[0\]\.odometry_sigma\[1\]: an integer of over"
    ):
        parse_mapping(text, "m.toml")
