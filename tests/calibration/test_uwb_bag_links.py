"""The radio-name links of a bag's range rows (a robot carrying two radios, a surveyed static
radio) and a bag with no reading between radios of known position, on real bags written with
the sample writer of the loader tests."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

from relloc.calibration.uwb_bag import as_uwb_recording, row_links
from relloc.datasets.bag_mapping import parse_mapping
from relloc.datasets.rosbag import load_bag
from relloc.errors import DataError

sys.path.insert(0, str(Path(__file__).parents[1] / "datasets"))
from bag_samples import ODOM, POSE, RANGE, mocap, odometry, pose, uwb, write_bag
from bag_samples import SAMPLE_MAPPING as MAPPING

S = 1_000_000_000
T0 = 1_000 * S
#: both robots carry a second radio (n_5 on alpha, n_6 on beta)
TWO_EACH = MAPPING + "".join(
    f'[[uwb.nodes]]\nname = "{name}"\nrobot = "{robot}"\n'
    for name, robot in (("n_5", "alpha"), ("n_6", "beta"))
)


def _bag(tmp_path: Path, ranges: list[tuple[str, float]]) -> Path:
    """Both robots standing (alpha's odometry and both motion captures every 0.1 s for 1 s),
    ``ranges`` (topic, metres) read at each of the first five instants."""
    out = []
    for k in range(10):
        t = T0 + k * S // 10
        out.append(("/alpha/odom", ODOM, t, odometry(t, 0.0, 0.0)))
        out.append(("/mocap/alpha", POSE, t, mocap(t, pose(1.0, 2.0, 0.0, 0.5))))
        out.append(("/mocap/beta", POSE, t, mocap(t, pose(3.0, 2.0, 0.0, -0.5))))
        if k < 5:
            out.extend((topic, RANGE, t + 1, uwb(t + 1, r)) for topic, r in ranges)
    out.sort(key=lambda m: m[2])
    return write_bag(tmp_path / "bag", out)


def test_rows_to_a_robot_with_two_radios_have_no_link_and_static_radios_are_named(tmp_path):
    path = _bag(tmp_path, [("/u/n_1/n_2/d", 2.0), ("/u/n_1/n_3/d", 3.2)])
    bag = load_bag(path, parse_mapping(TWO_EACH, "m.toml"))
    m = bag.recording.measurements
    links = row_links(bag)
    assert len(links) == m.size == 10
    robot = m.target >= 0
    assert robot.sum() == 5 and m.landmark[~robot].tolist() == [0] * 5
    assert all(link is None for link, r in zip(links, robot, strict=True) if r)
    assert all(link == ("n_1", "n_3") for link, r in zip(links, robot, strict=True) if not r)
    # with one radio on each robot the rows between them name their link too
    single = row_links(load_bag(path, parse_mapping(MAPPING, "m.toml")))
    assert sorted(set(single)) == [("n_1", "n_2"), ("n_1", "n_3")]


def test_a_bag_without_readings_between_known_radios_cannot_be_calibrated(tmp_path):
    """n_4 is a static radio of unknown position: no true distance to compare with."""
    path = _bag(tmp_path, [("/u/n_1/n_4/d", 4.0)])
    with pytest.raises(DataError, match="no UWB reading between radios of known position"):
        as_uwb_recording(load_bag(path, parse_mapping(MAPPING, "m.toml")))
