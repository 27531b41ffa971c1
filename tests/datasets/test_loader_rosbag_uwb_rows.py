"""UWB readings of a ROS 2 bag as recording rows, on small hand-written bags: who observes,
with which of its radios, where a carried radio is, and robots whose motion capture is too
short to be ground truth."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from bag_samples import ODOM, POSE, RANGE, mocap, odometry, pose, uwb, write_bag
from bag_samples import SAMPLE_MAPPING as MAPPING

from relloc.datasets.bag_mapping import parse_mapping
from relloc.datasets.rosbag import load_bag

S = 1_000_000_000
T0 = 1_000 * S
#: alpha carries n_1 and n_5 (n_5 at 1 m ahead, 2 m left of its centre), beta carries n_2.
TWO_RADIOS = MAPPING + '[[uwb.nodes]]\nname = "n_5"\nrobot = "alpha"\noffset = [1.0, 2.0, 0.0]\n'


def _bag(tmp_path: Path, extra: list[tuple[str, str, int, object]], *, beta_truth: int = 3) -> Path:
    """alpha at (1, 2) facing +y (yaw π/2), beta at (3, 2); stamps 0, 0.1, 0.2 s after T0."""
    msgs: list[tuple[str, str, int, object]] = []
    for k in range(3):
        t = T0 + k * S // 10
        msgs.append(("/alpha/odom", ODOM, t, odometry(t, 0.1, 0.0)))
        msgs.append(("/mocap/alpha", POSE, t, mocap(t, pose(1.0, 2.0, 0.0, math.pi / 2))))
        if k < beta_truth:
            msgs.append(("/mocap/beta", POSE, t, mocap(t, pose(3.0, 2.0, 0.0, 0.0))))
    msgs.extend(extra)
    return write_bag(tmp_path / "bag", sorted(msgs, key=lambda m: m[2]))


def test_a_robot_with_one_motion_capture_message_has_no_ground_truth(tmp_path):
    bag = load_bag(_bag(tmp_path, [], beta_truth=1), parse_mapping(MAPPING, "m.toml"))
    assert bag.recording.truth is None
    assert bag.recording.meta["robots_without_truth"] == ["beta"]


def test_the_radio_that_read_a_range_is_the_observers_sensor(tmp_path):
    """alpha carries two radios, so it observes beta either way; n_1 is its sensor 0, n_5 its
    sensor 1."""
    t1, t2 = T0 + 50_000_000, T0 + 150_000_000
    extra = [
        ("/u/n_5/n_2/d", RANGE, t1, uwb(t1, 2.5)),
        ("/u/n_2/n_1/d", RANGE, t2, uwb(t2, 2.0)),
    ]
    bag = load_bag(_bag(tmp_path, extra), parse_mapping(TWO_RADIOS, "m.toml"))
    m = bag.recording.measurements
    assert m.t.tolist() == [0.05, 0.15]
    assert m.observer.tolist() == [0, 0]
    assert m.target.tolist() == [1, 1]
    assert m.sensor.tolist() == [1, 0]
    assert m.value[:, 0].tolist() == [2.5, 2.0]


def test_between_robots_carrying_one_radio_each_the_topics_first_radio_observes(tmp_path):
    t1, t2 = T0 + 50_000_000, T0 + 150_000_000
    extra = [
        ("/u/n_1/n_2/d", RANGE, t1, uwb(t1, 2.0)),
        ("/u/n_2/n_1/d", RANGE, t2, uwb(t2, 2.1)),
    ]
    mapping = MAPPING.replace("sigma = 0.1", "sigma = 0.1\nfold_directions = false")
    bag = load_bag(_bag(tmp_path, extra), parse_mapping(mapping, "m.toml"))
    m = bag.recording.measurements
    assert m.observer.tolist() == [0, 1]
    assert m.target.tolist() == [1, 0]


def test_a_carried_radio_sits_at_its_offset_turned_with_the_robot(tmp_path):
    """alpha at (1, 2) with yaw π/2: n_5's offset (1, 2) in its body frame is (−2, 1) in the
    world, so n_5 is at (−1, 3)."""
    bag = load_bag(_bag(tmp_path, []), parse_mapping(TWO_RADIOS, "m.toml"))
    n5 = [n.name for n in bag.mapping.uwb.nodes].index("n_5")
    np.testing.assert_allclose(bag.node_truth(n5, np.array([0.0, 0.1])), [[-1, 3, 0]] * 2)


def test_the_summary_gives_the_time_origin_in_unix_seconds(tmp_path):
    bag = load_bag(_bag(tmp_path, []), parse_mapping(MAPPING, "m.toml"))
    assert bag.time_origin_ns == T0
    assert bag.to_dict()["time_origin_unix_s"] == 1000.0
