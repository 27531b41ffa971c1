"""The ROS 2 bag loader: real bags written with rosbags (.db3 and .mcap), the TIERS bags,
mapping errors naming their key, and fuzzed mappings and messages."""

from __future__ import annotations

import math
import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from relloc.core.recording import kind_code
from relloc.datasets.bag_mapping import BagMapping, load_mapping, mapping_from_dict, parse_mapping
from relloc.datasets.paths import shared_data_dir
from relloc.datasets.rosbag import (
    BadMessage,
    inspect_bag,
    load_bag,
    odometry_sample,
    range_sample,
    truth_sample,
)
from relloc.errors import ConfigError, DataError

sys.path.insert(0, str(Path(__file__).parent))
from bag_samples import (
    ODOM,
    POSE,
    RANGE,
    STRING,
    T,
    mocap,
    odometry,
    pose,
    quaternion_pose,
    uwb,
    write_bag,
)
from bag_samples import (
    SAMPLE_MAPPING as MAPPING,
)

S = 1_000_000_000
T0 = 1_000 * S  # header stamps
LAG = 2 * S  # bag receive time − header stamp


def _messages() -> list[tuple[str, str, int, object]]:
    out: list[tuple[str, str, int, object]] = []

    def add(topic: str, msgtype: str, stamp: int, msg: object, receive: int | None = None) -> None:
        out.append((topic, msgtype, stamp + LAG if receive is None else receive, msg))

    for k in range(5):
        add("/alpha/odom", ODOM, T0 + k * S // 10, odometry(T0 + k * S // 10, 0.1, 0.2))
    add("/alpha/odom", ODOM, T0 + 5 * S // 10, odometry(T0 + 5 * S // 10, math.nan, 0.2))
    add("/alpha/odom", ODOM, T0 + 4 * S // 10, odometry(T0 + 4 * S // 10, 0.1, 0.2))  # duplicate
    add("/alpha/odom", ODOM, 0, odometry(0, 0.3, 0.0), receive=T0 + 6 * S // 10 + LAG)  # unset
    for k in range(4):
        t = T0 + k * S // 10
        add("/mocap/alpha", POSE, t, mocap(t, pose(1.0 + 0.01 * k, 2.0, 0.1, 0.5)))
        add("/mocap/beta", POSE, t, mocap(t, pose(3.0, 2.0, 0.1, -0.5)))
    add("/mocap/alpha", POSE, T0 + 5 * S // 10, mocap(0, quaternion_pose(1, 2, 0, (0, 0, 0, 0))))
    for k, r in enumerate((2.0, 2.1, -1.0, math.nan)):
        add("/u/n_1/n_2/d", RANGE, T0 + k * S // 10 + 1, uwb(T0 + k * S // 10 + 1, r))
    add("/u/n_2/n_1/d", RANGE, T0 + 2, uwb(T0 + 2, 2.0))
    add("/u/n_1/n_3/d", RANGE, T0 + 3, uwb(T0 + 3, 5.0, 0.1, 10.0))
    add("/u/n_1/n_3/d", RANGE, T0 + 4 + S, uwb(T0 + 4 + S // 10, 11.0, 0.1, 10.0))
    add("/u/n_1/n_4/d", RANGE, T0 + 5, uwb(T0 + 5, 4.0))
    for k in range(2):  # the other direction of n_1–n_4 has more messages: it is the one read
        add("/u/n_4/n_1/d", RANGE, T0 + 7 + k, uwb(T0 + 7 + k, 4.1))
    add("/u/n_1/n_9/d", RANGE, T0 + 6, uwb(T0 + 6, 4.0))
    add("/chatter", STRING, T0, T[STRING](data="hello"))
    out.sort(key=lambda m: m[2])
    return out


@pytest.mark.parametrize("storage", ["sqlite3", "mcap"])
def test_a_written_bag_reads_back_with_every_bad_message_counted(tmp_path, storage):
    path = write_bag(tmp_path / "bag", _messages(), storage=storage)
    bag = load_bag(path, parse_mapping(MAPPING, "sample.toml"))
    rec = bag.recording
    assert rec.robots == ("alpha", "beta")
    od = rec.odometry[0]
    assert od.t.size == 6  # 5 good + the unset stamp placed by its receive time
    np.testing.assert_allclose(od.t, [0, 0.1, 0.2, 0.3, 0.4, 0.6], atol=1e-9)
    np.testing.assert_allclose(od.velocity[-1], [0.3, 0, 0, 0])
    assert rec.odometry[1].t.size == 0
    assert bag.stamps_from_receive == {"/alpha/odom": 1}
    assert bag.stamp_offset_s["bag"] == pytest.approx(2.0)
    skips = {f.file.split(":")[-1]: dict(f.skipped) for f in rec.skips.files}
    assert skips["/alpha/odom"] == {"not finite": 1, "stamp not after the previous message": 1}
    assert skips["/mocap/alpha"] == {"zero quaternion": 1}
    assert skips["/u/n_1/n_2/d"] == {"range ≤ 0": 1, "not finite": 1}
    assert skips["/u/n_2/n_1/d"] == {"folded: other direction": 1}
    assert skips["/u/n_1/n_3/d"] == {"range out of bounds": 1}
    assert skips["/u/n_1/n_9/d"] == {"unknown node": 1}
    assert [t.topic for t in bag.unknown_topics] == ["/chatter"]
    assert rec.truth is not None
    np.testing.assert_allclose(rec.truth[1].pose[0], [3.0, 2.0, 0.1, -0.5], atol=1e-12)
    assert skips["/u/n_1/n_4/d"] == {"folded: other direction": 1}
    # radio level: n_1–n_2 (2), n_1–n_3 (1), n_4–n_1 (2); the recording has no unsurveyed radio
    assert bag.ranges.t.size == 5
    np.testing.assert_allclose(bag.ranges.value[bag.ranges.link_mask(0, 3)], [4.1, 4.1], rtol=1e-6)
    m = rec.measurements
    assert m.size == 3 and set(m.kind.tolist()) == {kind_code("range")}
    np.testing.assert_allclose(rec.landmarks, [[0.0, 5.0, 0.0]])
    lm = m.landmark >= 0
    assert m.value[lm, 0].tolist() == [5.0] and m.target[lm].tolist() == [-1]
    np.testing.assert_allclose(m.sigma[:, 0], 0.1)
    np.testing.assert_allclose(bag.node_truth(2, np.array([0.1])), [[0.0, 5.0, 0.0]])
    assert bag.time_origin_ns == T0


def test_messages_the_metadata_lists_but_the_storage_lacks_are_counted(tmp_path):
    """Messages whose stored topic id no topic of the bag has were lost without a count."""
    import sqlite3

    path = write_bag(tmp_path / "bag", _messages())
    db = next(path.glob("*.db3"))
    with sqlite3.connect(db) as con:
        (odom_id,) = con.execute("SELECT id FROM topics WHERE name = '/alpha/odom'").fetchone()
        ids = [r[0] for r in con.execute(f"SELECT id FROM messages WHERE topic_id = {odom_id}")]
        con.execute(f"UPDATE messages SET topic_id = 9999 WHERE id IN ({ids[1]}, {ids[2]})")
    bag = load_bag(path, parse_mapping(MAPPING, "sample.toml"))
    skips = {f.file.split(":")[-1]: dict(f.skipped) for f in bag.recording.skips.files}
    assert skips["/alpha/odom"]["not in storage"] == 2
    assert bag.recording.odometry[0].t.size == 4  # of the 6 read before


def test_a_robot_without_motion_capture_is_named_when_truth_is_needed(tmp_path):
    """The message once said the recording had no ground truth at all."""
    path = write_bag(tmp_path / "bag", _messages())
    ghost = MAPPING.replace("[uwb]", '[[robots]]\nname = "ghost"\n[uwb]')
    rec = load_bag(path, parse_mapping(ghost, "ghost.toml")).recording
    with pytest.raises(
        DataError, match=r"scoring needs ground truth of every robot; .* for robots ghost"
    ):
        rec.require_truth("scoring")


def test_inspect_lists_every_topic(tmp_path):
    path = write_bag(tmp_path / "bag", _messages())
    infos = {i.topic: i for i in inspect_bag(path)}
    assert infos["/alpha/odom"].count == 8 and infos["/alpha/odom"].msgtype == ODOM
    assert infos["/chatter"].count == 1 and infos["/chatter"].rate_hz == 0.0


def test_the_inspect_skeleton_is_a_valid_mapping(tmp_path, capsys):
    from relloc.cli import main

    path = write_bag(tmp_path / "bag", _messages())
    assert main(["bag", "inspect", str(path)]) == 0
    out = capsys.readouterr().out
    assert "/u/n_1/n_2/d" in out
    skeleton = out[out.index("# relloc bag mapping") :]
    mapping = parse_mapping(skeleton, "skeleton")
    assert mapping.uwb is not None and mapping.uwb.topics == "/u/{a}/{b}/d"
    assert {n.name for n in mapping.uwb.nodes} == {"n_1", "n_2", "n_3", "n_4", "n_9"}


def test_a_missing_or_wrong_topic_names_the_key(tmp_path):
    path = write_bag(tmp_path / "bag", _messages())
    wrong = MAPPING.replace('truth = "/mocap/beta"', 'truth = "/alpha/odom"')
    with pytest.raises(ConfigError, match=r"robots\[1\]\.truth: .*nav_msgs/msg/Odometry"):
        load_bag(path, parse_mapping(wrong, "m.toml"))
    missing = MAPPING.replace('truth = "/mocap/beta"', 'truth = "/nowhere"')
    with pytest.raises(ConfigError, match=r"m\.toml: robots\[1\]\.truth: topic '/nowhere'"):
        load_bag(path, parse_mapping(missing, "m.toml"))
    with pytest.raises(DataError, match="no such bag"):
        load_bag(tmp_path / "absent", parse_mapping(MAPPING, "m.toml"))
    # robots that name no topic: the reader once took "no topics" for "every topic"
    with pytest.raises(DataError, match="no usable message on the mapped topics"):
        load_bag(path, parse_mapping('[[robots]]\nname = "a"\n', "m.toml"))
    (tmp_path / "junk.mcap").write_bytes(b"not a bag")
    with pytest.raises(DataError, match=r"junk\.mcap"):
        load_bag(tmp_path / "junk.mcap", parse_mapping(MAPPING, "m.toml"))


@pytest.mark.parametrize(
    ("edit", "key"),
    [
        (('name = "alpha"', 'name = "alpha"\ncolour = 3'), r"robots\[0\]\.colour: unknown key"),
        (('odometry = "/alpha/odom"', "odometry = 3"), r"robots\[0\]\.odometry"),
        (('robot = "beta"', 'robot = "gamma"'), r"uwb\.nodes\[1\]\.robot: 'gamma'"),
        (('topics = "/u/{a}/{b}/d"', 'topics = "/u/{a}/d"'), r"uwb\.topics: must contain \{b\}"),
        (
            ("sigma = 0.1", "sigma = -1"),
            r"uwb\.sigma: must be a finite number in \(0, 10000\], got -1",
        ),
        # finite but absurd: 1e300 once overflowed the range filter (OverflowError)
        (
            ("sigma = 0.1", "sigma = 1e300"),
            r"uwb\.sigma: must be a finite number in \(0, 10000\], got 1e\+300",
        ),
        (
            ("sigma = 0.1", "sigma = 1" + "0" * 400),
            r"uwb\.sigma: must be a finite number in \(0, 10000\], got 1000",
        ),
        (
            ('robot = "beta"', 'robot = "beta"\noffset = [1e300, 0.0, 0.0]'),
            r"uwb\.nodes\[1\]\.offset\[0\]: must be .* \[-100000, 100000\], got 1e\+300",
        ),
        (
            ("position = [0.0, 5.0, 0.0]", "position = [0.0, -2e5, 0.0]"),
            r"uwb\.nodes\[2\]\.position\[1\]: must be .* \[-100000, 100000\], got -2",
        ),
        (
            (
                'odometry = "/alpha/odom"',
                'odometry = "/alpha/odom"\nodometry_sigma = [1, 0, 0, 1e300]',
            ),
            r"robots\[0\]\.odometry_sigma\[3\]: must be a finite number in \[0, 100\], got 1e\+300",
        ),
        (('name = "n_4"', 'name = "n_3"'), r"uwb\.nodes\[3\]\.name: 'n_3' is named twice"),
        (("position = [0.0, 5.0, 0.0]", "position = [0.0, 5.0]"), r"uwb\.nodes\[2\]\.position"),
        (('name = "sample"', 'name = "sample"\nstamp = "gps"'), r"stamp: must be one of"),
        (
            ('"/mocap/beta"', '"/mocap/alpha"'),
            r"robots\[1\]\.truth: '/mocap/alpha' is robots\[0\]'s",
        ),
    ],
)
def test_mapping_errors_name_the_key(edit, key):
    text = MAPPING.replace(*edit, 1)
    assert text != MAPPING
    with pytest.raises(ConfigError, match=r"^m\.toml: " + key):
        parse_mapping(text, "m.toml")


def test_shipped_mappings_load_by_name_and_by_path():
    for name in ("tiers_cooperative", "tiers_relative"):
        mapping = load_mapping(name)
        assert mapping.uwb is not None and len(mapping.uwb.nodes) == 8
    with pytest.raises(ConfigError, match="cannot read mapping file"):
        load_mapping("/nowhere/map.toml")


# ----------------------------------------------------------------------------------------------
# The TIERS bags
# ----------------------------------------------------------------------------------------------

TIERS = shared_data_dir() / "tiers"
needs_tiers = pytest.mark.skipif(
    not TIERS.is_dir(), reason=f"TIERS bags not found at {TIERS} (outside the workspace)"
)


@needs_tiers
def test_tiers_cooperative_bag():
    bag = load_bag(TIERS / "cooperative_shortbag", load_mapping("tiers_cooperative"))
    rec = bag.recording
    assert rec.robots == ("turtlebot1", "turtlebot3", "turtlebot4", "turtlebot5")
    assert [od.t.size for od in rec.odometry] == [338, 340, 178, 338]
    # the README: bag time = header stamp + 4,160,411.02 s; /cali/turtle05 has zero stamps
    assert bag.stamp_offset_s["bag"] == pytest.approx(4_160_411.02, abs=0.01)
    assert bag.stamps_from_receive == {"/cali/turtle05/odom": 338}
    assert len(bag.ranges.links()) == 28
    assert rec.skips.n_skipped == 0
    unknown = {t.topic for t in bag.unknown_topics}
    assert "/vrpn_client_node/chair2/pose" in unknown
    assert "/turtle01/color/yolov4_Spatial_detections" in unknown
    # robot–robot links only (the static radios' positions are unknown): 6 links
    m = rec.measurements
    assert len({(min(a, b), max(a, b)) for a, b in zip(m.observer, m.target, strict=True)}) == 6


@needs_tiers
def test_tiers_relative_bag_folds_both_directions():
    bag = load_bag(TIERS / "relative_case4_test1", load_mapping("tiers_relative"))
    rec = bag.recording
    assert bag.stamp_offset_s["bag"] == pytest.approx(5_172_498.30, abs=0.01)
    assert rec.skips.skipped_by_reason() == {"folded: other direction": 8004}
    assert len(bag.ranges.links()) == 28 and bag.ranges.t.size == 8007
    assert all(od.t.size == 0 for od in rec.odometry)
    # n_5–n_8 ride on one robot: kept at radio level only
    assert rec.measurements.size == bag.ranges.t.size - int(bag.ranges.link_mask(4, 7).sum())


# ----------------------------------------------------------------------------------------------
# Fuzz
# ----------------------------------------------------------------------------------------------

_leaf = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(-5, 5),
    st.floats(allow_nan=True, allow_infinity=True),
    st.text(max_size=12),
    st.sampled_from(["/a/odom", "/u/{a}/{b}/d", "alpha", "n_1", "ground", "header"]),
)
_value = st.recursive(
    _leaf,
    lambda inner: (
        st.lists(inner, max_size=4)
        | st.dictionaries(
            st.sampled_from(
                [
                    "name",
                    "robot",
                    "robots",
                    "uwb",
                    "nodes",
                    "topics",
                    "odometry",
                    "truth",
                    "position",
                    "offset",
                    "sigma",
                    "anchors",
                    "platform",
                    "odometry_sigma",
                    "stamp",
                    "x",
                ]
            ),
            inner,
            max_size=5,
        )
    ),
    max_leaves=20,
)


@settings(derandomize=True, max_examples=150, deadline=None)
@given(_value)
def test_fuzzed_mappings_parse_or_raise_config_error(doc):
    try:
        out = mapping_from_dict(doc if isinstance(doc, dict) else {"robots": doc})
    except ConfigError:
        return
    assert isinstance(out, BagMapping)


@settings(derandomize=True, max_examples=100, deadline=None)
@given(st.sampled_from(["robots", "uwb", "anchors", "stamp", "name"]), _value)
def test_a_fuzzed_key_of_a_valid_mapping_parses_or_names_the_key(key, value):
    import tomllib

    doc = tomllib.loads(MAPPING)
    doc[key] = value
    try:
        mapping_from_dict(doc)
    except ConfigError as exc:
        # the error names the fuzzed key, or the radio whose robot the fuzzed robots lack
        assert str(exc).startswith((key, "uwb.nodes")), str(exc)


_num = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.integers(-3, 3),
    st.none(),
    st.text(max_size=3),
)


def _ns(**kw: object) -> SimpleNamespace:
    return SimpleNamespace(**kw)


@settings(derandomize=True, max_examples=150, deadline=None)
@given(st.lists(_num, min_size=14, max_size=14), st.booleans())
def test_fuzzed_messages_convert_or_are_bad(v, drop):
    p = _ns(position=_ns(x=v[0], y=v[1], z=v[2]), orientation=_ns(x=v[3], y=v[4], z=v[5], w=v[6]))
    twist = _ns(linear=_ns(x=v[7], y=v[8], z=v[9]), angular=_ns(x=v[10], y=0.0, z=v[11]))
    odo = _ns(pose=_ns(pose=p), twist=_ns(twist=twist))
    rng = _ns(range=v[12], min_range=v[13], max_range=v[0])
    if drop:
        del odo.twist.twist.angular.z
        del rng.min_range
    for convert, msg in ((odometry_sample, odo), (truth_sample, _ns(pose=p)), (range_sample, rng)):
        try:
            out = convert(msg)
        except BadMessage as bad:
            assert bad.reason and bad.detail
            continue
        flat = np.hstack([np.ravel(x) for x in (out if isinstance(out, tuple) else (out,))])
        assert np.isfinite(flat.astype(float)).all()
        assert np.all(np.abs(flat.astype(float)) <= 1e5)  # nothing a filter would overflow on


@pytest.mark.parametrize(
    ("convert", "msg"),
    [
        (odometry_sample, "odometry"),
        (truth_sample, "truth"),
        (range_sample, "range"),
    ],
)
def test_finite_but_absurd_values_are_out_of_bounds(convert, msg):
    """1e300 m/s of odometry once ended, many steps later, in "covariance contains NaN or inf"
    naming no topic; a 3e38 m range in an outlier figure of 1.7e38 m."""
    p = _ns(position=_ns(x=1.0, y=2e5, z=0.0), orientation=_ns(x=0.0, y=0.0, z=0.0, w=1.0))
    message = {
        "odometry": _ns(
            pose=_ns(pose=_ns(position=_ns(x=0.0, y=0.0, z=0.0), orientation=p.orientation)),
            twist=_ns(twist=_ns(linear=_ns(x=1e300, y=0.0, z=0.0), angular=_ns(z=0.0))),
        ),
        "truth": _ns(pose=p),
        "range": _ns(range=3e38, min_range=0.0, max_range=0.0),
    }[msg]
    with pytest.raises(BadMessage) as bad:
        convert(message)
    assert bad.value.reason == "out of bounds"
