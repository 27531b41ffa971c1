"""The ROS 2 bag loader on other layouts: receive-time stamps, the odometry's pose, robots
without motion capture, repeated or unusable UWB readings, corrupt payloads and bad stamps;
and mapping files that are wrong, too large, not UTF-8 or nested too deeply."""

from __future__ import annotations

import sqlite3
import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from relloc.datasets.bag_mapping import MAX_MAPPING_BYTES, load_mapping, parse_mapping
from relloc.datasets.rosbag import BadMessage, load_bag, stamp_ns, truth_sample
from relloc.errors import ConfigError

sys.path.insert(0, str(Path(__file__).parent))
from bag_samples import ODOM, POSE, RANGE, STRING, T, header, mocap, odometry, pose, uwb, write_bag
from bag_samples import SAMPLE_MAPPING as MAPPING

S = 1_000_000_000
T0 = 1_000 * S
LAG = 2 * S


def _bag(tmp_path: Path, extra: list[tuple[str, str, int, object]] | None = None) -> Path:
    """Alpha's odometry (with its pose) and both robots' motion capture, 0.1 s apart, received
    ``LAG`` after their stamps; ``extra`` messages added."""
    out: list[tuple[str, str, int, object]] = []
    for k in range(4):
        t = T0 + k * S // 10
        out.append(("/alpha/odom", ODOM, t + LAG, odometry(t, 0.1, 0.2, pose(k, 0, 0, 0.1 * k))))
        out.append(("/mocap/alpha", POSE, t + LAG, mocap(t, pose(1.0, 2.0, 0.1, 0.5))))
        out.append(("/mocap/beta", POSE, t + LAG, mocap(t, pose(3.0, 2.0, 0.1, -0.5))))
    out.extend(extra or [])
    out.sort(key=lambda m: m[2])
    return write_bag(tmp_path / "bag", out)


def _skips(bag) -> dict[str, dict[str, int]]:  # type: ignore[no-untyped-def]
    return {f.file.split(":")[-1]: dict(f.skipped) for f in bag.recording.skips.files}


def test_receive_stamps_time_every_message_by_the_bag(tmp_path):
    """``stamp = "receive"``: every time is the bag's receive time, offsets not applied."""
    path = _bag(tmp_path)
    mapping = parse_mapping('stamp = "receive"\n' + MAPPING, "m.toml")
    bag = load_bag(path, mapping)
    assert bag.time_origin_ns == T0 + LAG
    assert bag.stamps_from_receive == {}
    np.testing.assert_allclose(bag.recording.odometry[0].t, [0, 0.1, 0.2, 0.3], atol=1e-9)


def test_receive_stamps_place_a_message_whose_header_runs_backwards(tmp_path):
    """With header stamps a backwards stamp is skipped; with receive stamps it is kept."""
    t = T0 + 5 * S // 10
    back = [("/alpha/odom", ODOM, t + LAG, odometry(T0, 0.3, 0.0))]
    path = _bag(tmp_path, back)
    by_header = load_bag(path, parse_mapping(MAPPING, "m.toml"))
    assert _skips(by_header)["/alpha/odom"] == {"stamp not after the previous message": 1}
    by_receive = load_bag(path, parse_mapping('stamp = "receive"\n' + MAPPING, "m.toml"))
    assert "/alpha/odom" not in _skips(by_receive) or not _skips(by_receive)["/alpha/odom"]
    np.testing.assert_allclose(by_receive.recording.odometry[0].t[-1], 0.5, atol=1e-9)


def test_the_odometry_pose_is_kept_when_the_mapping_asks(tmp_path):
    path = _bag(tmp_path)
    plain = load_bag(path, parse_mapping(MAPPING, "m.toml"))
    assert plain.odometry_pose == {}
    asked = MAPPING.replace(
        'odometry = "/alpha/odom"', 'odometry = "/alpha/odom"\nodometry_pose = true'
    )
    bag = load_bag(path, parse_mapping(asked, "m.toml"))
    t, p = bag.odometry_pose["alpha"]
    np.testing.assert_allclose(t, [0, 0.1, 0.2, 0.3], atol=1e-9)
    np.testing.assert_allclose(p[:, 0], [0, 1, 2, 3])
    np.testing.assert_allclose(p[:, 3], [0, 0.1, 0.2, 0.3], atol=1e-12)


def test_a_carried_radio_has_no_position_when_a_robot_has_no_motion_capture(tmp_path):
    """A robot without truth leaves the recording without ground truth: a carried radio's
    position is unknown (NaN), a surveyed radio's still known."""
    path = _bag(tmp_path)
    ghost = MAPPING.replace("[uwb]", '[[robots]]\nname = "ghost"\n[uwb]')
    bag = load_bag(path, parse_mapping(ghost, "m.toml"))
    assert bag.recording.truth is None
    assert np.isnan(bag.node_truth(0, np.array([0.1, 0.2]))).all()
    np.testing.assert_allclose(bag.node_truth(2, np.array([0.1])), [[0.0, 5.0, 0.0]])


def test_both_directions_of_a_link_unfolded_repeat_and_are_counted(tmp_path):
    """Without folding, a link published both ways at one time is one reading twice where
    both directions land on the same observer's radio (alpha, carrying two radios, observes
    beta either way): the second is left out and counted under the bag's ``uwb`` entry."""
    both = []
    for k in range(3):
        t = T0 + k * S // 10 + 1
        both.append(("/u/n_1/n_2/d", RANGE, t + LAG, uwb(t, 2.0)))
        both.append(("/u/n_2/n_1/d", RANGE, t + LAG, uwb(t, 2.05)))
    path = _bag(tmp_path, both)
    two_radios = MAPPING + '[[uwb.nodes]]\nname = "n_5"\nrobot = "alpha"\n'
    unfolded = two_radios.replace("sigma = 0.1", "sigma = 0.1\nfold_directions = false")
    bag = load_bag(path, parse_mapping(unfolded, "m.toml"))
    assert bag.ranges.t.size == 6
    m = bag.recording.measurements
    assert m.size == 3 and set(m.observer.tolist()) == {0}
    (uwb_skips,) = [f for f in bag.recording.skips.files if f.file == f"{path}:uwb"]
    assert uwb_skips.skipped == {"repeats a reading of another topic": 3}
    assert (uwb_skips.rows_read, uwb_skips.rows_kept) == (6, 3)
    folded = load_bag(path, parse_mapping(two_radios, "m.toml"))
    assert folded.recording.measurements.size == 3
    assert not [f for f in folded.recording.skips.files if f.file.endswith(":uwb")]


def test_readings_no_filter_can_use_stay_at_radio_level(tmp_path):
    """Only readings to an unsurveyed radio: the ranges are kept, the recording has none."""
    lone = [("/u/n_1/n_4/d", RANGE, T0 + k + LAG, uwb(T0 + k, 4.0)) for k in range(3)]
    bag = load_bag(_bag(tmp_path, lone), parse_mapping(MAPPING, "m.toml"))
    assert bag.ranges.t.size == 3
    assert bag.recording.measurements.size == 0
    assert bag.radio_only == {"to a static radio of unknown position": 3}


def test_a_bag_without_usable_ranges_has_an_empty_range_table(tmp_path):
    only_self = [("/u/n_1/n_1/d", RANGE, T0 + LAG, uwb(T0, 1.0))]
    bag = load_bag(_bag(tmp_path, only_self), parse_mapping(MAPPING, "m.toml"))
    assert bag.ranges.t.size == 0 and bag.ranges.node_a.dtype == np.int64
    assert bag.recording.measurements.size == 0
    assert _skips(bag)["/u/n_1/n_1/d"] == {"node paired with itself": 1}


def test_a_uwb_topic_of_another_type_names_the_topic(tmp_path):
    wrong = [("/u/n_1/n_2/d", STRING, T0 + LAG, T[STRING](data="2.0"))]
    with pytest.raises(
        ConfigError, match=r"^m\.toml: uwb\.topics: '/u/n_1/n_2/d' .* std_msgs/msg/String"
    ):
        load_bag(_bag(tmp_path, wrong), parse_mapping(MAPPING, "m.toml"))


def test_a_corrupt_payload_is_counted_never_fatal(tmp_path):
    path = _bag(tmp_path)
    db = next(path.glob("*.db3"))
    with sqlite3.connect(db) as con:
        (topic_id,) = con.execute("SELECT id FROM topics WHERE name = '/mocap/beta'").fetchone()
        (first,) = con.execute(
            f"SELECT min(id) FROM messages WHERE topic_id = {topic_id}"
        ).fetchone()
        con.execute(f"UPDATE messages SET data = X'0001' WHERE id = {first}")
    bag = load_bag(path, parse_mapping(MAPPING, "m.toml"))
    assert _skips(bag)["/mocap/beta"] == {"cannot deserialise": 1}
    assert bag.recording.truth is not None and bag.recording.truth[1].t.size == 3


@pytest.mark.parametrize(("sec", "nanosec"), [(-1, 0), (1, 1_500_000_000)])
def test_a_header_stamp_out_of_range_is_a_malformed_header(tmp_path, sec, nanosec):
    msg = mocap(0, pose(3.0, 2.0, 0.1, -0.5))
    msg.header = header(0)
    msg.header.stamp = T["builtin_interfaces/msg/Time"](sec=sec, nanosec=nanosec)
    bag = load_bag(
        _bag(tmp_path, [("/mocap/beta", POSE, T0 + 9 * S // 10 + LAG, msg)]),
        parse_mapping(MAPPING, "m.toml"),
    )
    assert _skips(bag)["/mocap/beta"] == {"malformed header": 1}


def test_a_pose_message_without_its_fields_is_a_malformed_pose():
    for msg in (SimpleNamespace(), SimpleNamespace(pose=SimpleNamespace(position=None))):
        with pytest.raises(BadMessage) as caught:
            truth_sample(msg)
        assert caught.value.reason == "malformed pose"
    assert truth_sample(SimpleNamespace(pose=pose(1, 2, 3, 0.5)))[3] == pytest.approx(0.5)
    with pytest.raises(BadMessage, match="header stamp unreadable") as caught:
        stamp_ns(SimpleNamespace(header=None))
    assert caught.value.reason == "malformed header"


@pytest.mark.parametrize(
    ("edit", "key"),
    [
        (
            ('odometry = "/alpha/odom"', 'odometry = "/alpha/odom"\nodometry_pose = 1'),
            r"robots\[0\]\.odometry_pose: expected true or false, got 1",
        ),
        (
            ('name = "alpha"', 'name = "alpha"\nplatform = "boat"'),
            r"robots\[0\]\.platform: must be one of .*, got 'boat'",
        ),
        (
            ('robot = "beta"', 'robot = "beta"\nposition = [0.0, 0.0, 0.0]'),
            r"uwb\.nodes\[1\]\.position: a node on a robot moves with it",
        ),
        (
            ("position = [0.0, 5.0, 0.0]", "offset = [0.0, 5.0, 0.0]"),
            r"uwb\.nodes\[2\]\.offset: only a node carried by a robot",
        ),
        (
            ('topics = "/u/{a}/{b}/d"', 'topics = "/u/{a}{b}/d"'),
            r"uwb\.topics: \{a\} and \{b\} must be separated",
        ),
        (
            ('name = "beta"', 'name = "alpha"'),
            r"robots\[1\]\.name: 'alpha' is named twice",
        ),
        (
            ('name = "sample"', 'name = "sample"\nanchors = ["beta", "gamma"]'),
            r"anchors\[1\]: 'gamma' is not a robot of the mapping",
        ),
    ],
)
def test_more_mapping_errors_name_the_key(edit, key):
    text = MAPPING.replace(*edit, 1)
    assert text != MAPPING
    with pytest.raises(ConfigError, match=r"^m\.toml: " + key):
        parse_mapping(text, "m.toml")


def test_a_uwb_table_without_radios_is_refused():
    head = MAPPING.split("[[uwb.nodes]]")[0]
    with pytest.raises(ConfigError, match=r"^m\.toml: uwb\.nodes: required"):
        parse_mapping(head, "m.toml")


def test_a_mapping_nested_too_deeply_is_not_valid_toml():
    deep = "x = " + "[" * 100_000 + "]" * 100_000
    with pytest.raises(ConfigError, match=r"^m\.toml: not valid TOML \(nested too deeply\)"):
        parse_mapping(deep, "m.toml")


def test_a_mapping_file_too_large_or_not_utf8_names_the_file(tmp_path):
    big = tmp_path / "big.toml"
    big.write_bytes(b"#" * (MAX_MAPPING_BYTES + 1))
    with pytest.raises(ConfigError, match=rf"big\.toml: larger than {MAX_MAPPING_BYTES} bytes"):
        load_mapping(big)
    latin = tmp_path / "latin.toml"
    latin.write_bytes(MAPPING.encode() + b"\n# caf\xe9\n")
    at = len(MAPPING.encode()) + 6
    with pytest.raises(ConfigError, match=rf"latin\.toml: not UTF-8 text \(byte {at}\)"):
        load_mapping(latin)
