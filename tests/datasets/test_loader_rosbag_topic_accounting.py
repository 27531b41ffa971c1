"""What the ROS 2 bag loader reports per topic, on small hand-written bags: receive-time spans
of ``inspect_bag`` and the examples kept of skipped messages."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).parent))
from bag_samples import ODOM, POSE, mocap, odometry, pose, write_bag
from bag_samples import SAMPLE_MAPPING as MAPPING

from relloc.datasets.bag_mapping import parse_mapping
from relloc.datasets.rosbag import MAX_SKIP_EXAMPLES, inspect_bag, load_bag

S = 1_000_000_000
T0 = 1_000 * S


def _truths(k: int) -> list[tuple[str, str, int, object]]:
    t = T0 + k * S // 10
    return [
        ("/mocap/alpha", POSE, t, mocap(t, pose(1.0, 2.0, 0.0, 0.0))),
        ("/mocap/beta", POSE, t, mocap(t, pose(3.0, 2.0, 0.0, 0.0))),
    ]


def test_inspect_reports_each_topics_first_and_last_receive_time(tmp_path):
    """Bag start is the first message (T0); alpha's odometry is received at 1, 2, 4 s."""
    msgs = [m for k in range(2) for m in _truths(k)]
    msgs += [("/alpha/odom", ODOM, T0 + s * S, odometry(T0 + s * S, 0.1, 0.0)) for s in (1, 2, 4)]
    path = write_bag(tmp_path / "bag", sorted(msgs, key=lambda m: m[2]))
    info = {i.topic: i for i in inspect_bag(path)}
    odo = info["/alpha/odom"]
    assert (odo.msgtype, odo.count, odo.first_s, odo.last_s) == (ODOM, 3, 1.0, 4.0)
    assert odo.rate_hz == pytest.approx(2 / 3)
    assert (info["/mocap/beta"].first_s, info["/mocap/beta"].last_s) == (0.0, 0.1)


def test_a_topic_keeps_the_first_few_skipped_messages_as_examples(tmp_path):
    """Odometry messages 2 … 8 repeat message 1's stamp: seven skips counted, the first
    ``MAX_SKIP_EXAMPLES`` (messages 2 … 6) kept as examples."""
    msgs = [m for k in range(2) for m in _truths(k)]
    msgs += [("/alpha/odom", ODOM, T0 + k, odometry(T0, 0.1, 0.0)) for k in range(8)]
    path = write_bag(tmp_path / "bag", sorted(msgs, key=lambda m: m[2]))
    bag = load_bag(path, parse_mapping(MAPPING, "m.toml"))
    (odo,) = [f for f in bag.recording.skips.files if f.file == f"{path}:/alpha/odom"]
    assert dict(odo.skipped) == {"stamp not after the previous message": 7}
    assert (odo.rows_read, odo.rows_kept) == (8, 1)
    assert MAX_SKIP_EXAMPLES == 5
    assert [e.line for e in odo.examples] == [2, 3, 4, 5, 6]


def test_unset_stamps_take_receive_time_less_the_median_offset_of_set_ones(tmp_path):
    """Set stamps are received 2 s (odometry, alpha's motion capture: 3 messages) or 5 s (beta's:
    2 messages) late: the bag's median offset is 2 s (the mean would be 2.6 s). Odometry
    messages 2 and 3 have unset (zero) stamps and are received at T0 + 3 s and T0 + 4 s, so
    they are timed T0 + 1 s and T0 + 2 s. Each topic's offset is the median over its set
    stamps only."""
    from bag_samples import header

    msgs: list[tuple[str, str, int, object]] = [
        ("/alpha/odom", ODOM, T0 + 2 * S, odometry(T0, 0.1, 0.0)),
    ]
    for stamp_s, recv_s in ((0, 3), (0, 4)):
        m = odometry(T0, 0.2, 0.0)
        m.header = header(stamp_s)
        msgs.append(("/alpha/odom", ODOM, T0 + recv_s * S, m))
    for k in range(2):
        t = T0 + k * S // 10
        msgs.append(("/mocap/alpha", POSE, t + 2 * S, mocap(t, pose(1.0, 2.0, 0.0, 0.0))))
        msgs.append(("/mocap/beta", POSE, t + 5 * S, mocap(t, pose(3.0, 2.0, 0.0, 0.0))))
    path = write_bag(tmp_path / "bag", sorted(msgs, key=lambda m: m[2]))
    bag = load_bag(path, parse_mapping(MAPPING, "m.toml"))
    assert bag.stamp_offset_s == {
        "/alpha/odom": 2.0,
        "/mocap/alpha": 2.0,
        "/mocap/beta": 5.0,
        "bag": 2.0,
    }
    assert bag.stamps_from_receive == {"/alpha/odom": 2}
    assert bag.time_origin_ns == T0
    assert bag.recording.odometry[0].t.tolist() == [0.0, 1.0, 2.0]
    assert bag.recording.odometry[0].velocity[:, 0].tolist() == [0.1, 0.2, 0.2]
