"""``relloc reproduce tiers-uwb`` on a bag whose mapping names a robot without motion capture,
and ``--map`` given without ``--bag``: refused, naming the robot or the flag."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

from relloc.cli import main
from relloc.datasets.bag_mapping import parse_mapping
from relloc.datasets.rosbag import load_bag
from relloc.errors import DataError
from relloc.experiments.tiers_uwb import analyse_bag

sys.path.insert(0, str(Path(__file__).parents[1] / "datasets"))
from bag_samples import POSE, RANGE, SAMPLE_MAPPING, mocap, pose, uwb, write_bag

S = 1_000_000_000
T0 = 1_000 * S


def test_a_robot_without_motion_capture_is_named(tmp_path: Path) -> None:
    msgs = []
    for k in range(10):
        t = T0 + k * S // 10
        msgs.append(("/mocap/alpha", POSE, t, mocap(t, pose(1.0, 2.0, 0.1, 0.5))))
        msgs.append(("/mocap/beta", POSE, t, mocap(t, pose(3.0, 2.0, 0.1, -0.5))))
        msgs.append(("/u/n_1/n_2/d", RANGE, t + 1, uwb(t + 1, 2.0)))
    bag = write_bag(tmp_path / "bag", msgs)
    mapping = SAMPLE_MAPPING.replace('odometry = "/alpha/odom"\n', "")
    ghost = mapping.replace("[uwb]", '[[robots]]\nname = "ghost"\n[uwb]')
    loaded = load_bag(bag, parse_mapping(ghost, "ghost.toml"))
    with pytest.raises(
        DataError, match=rf"^{bag}: tiers-uwb scores against motion capture, and ghost have none"
    ):
        analyse_bag(loaded, None)


def test_a_map_without_a_bag_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    argv = ["reproduce", "tiers-uwb", "--out", str(tmp_path), "--map", "tiers_relative"]
    assert main(argv) == 2
    assert "--map needs --bag" in capsys.readouterr().err
