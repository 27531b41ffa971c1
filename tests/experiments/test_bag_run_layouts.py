"""``relloc run BAG --map MAP`` on a team of three of which only two robots are linked by UWB,
on a bag with no ranges at all, and without an output folder."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import pytest

from relloc.datasets.bag_mapping import parse_mapping
from relloc.errors import DataError
from relloc.experiments.bag_run import antenna_offset_m, run_bag

sys.path.insert(0, str(Path(__file__).parents[1] / "datasets"))
from bag_samples import ODOM, POSE, RANGE, mocap, odometry, pose, uwb, write_bag

S = 1_000_000_000
T0 = 1_000 * S
ROBOTS = (
    "".join(
        f'[[robots]]\nname = "{r}"\nodometry = "/{r}/odom"\ntruth = "/mocap/{r}"\n'
        for r in ("alpha", "beta")
    )
    + '[[robots]]\nname = "gamma"\ntruth = "/mocap/gamma"\n'
)
MAPPING = ROBOTS + (
    '[uwb]\ntopics = "/u/{a}/{b}/d"\n'
    '[[uwb.nodes]]\nname = "n_1"\nrobot = "alpha"\n'
    '[[uwb.nodes]]\nname = "n_2"\nrobot = "beta"\n'
)


def _bag(path: Path, ranges: bool) -> Path:
    """4 s of three robots at 10 Hz: alpha and beta driving, gamma standing without odometry;
    with ``ranges``, UWB between alpha and beta only."""
    msgs = []
    for k in range(40):
        t, s = T0 + k * S // 10, k / 10
        for name, v, (x, y, yaw) in (
            ("alpha", 0.1, (0.1 * s, 0.0, 0.0)),
            ("beta", 0.1, (3.0, 0.1 * s, math.pi / 2)),
            ("gamma", 0.0, (0.0, 3.0, 0.0)),
        ):
            if name != "gamma":
                msgs.append((f"/{name}/odom", ODOM, t, odometry(t, v, 0.0)))
            msgs.append((f"/mocap/{name}", POSE, t, mocap(t, pose(x, y, 0.0, yaw))))
        if ranges:
            msgs.append(
                ("/u/n_1/n_2/d", RANGE, t + 1, uwb(t + 1, math.hypot(3 - 0.1 * s, 0.1 * s)))
            )
    return write_bag(path, msgs)


def test_only_robots_linked_by_ranges_are_tracked_and_nothing_is_written(tmp_path: Path) -> None:
    """gamma, without odometry and linked to no one, is not a pair left untracked."""
    bag = _bag(tmp_path / "bag", ranges=True)
    summary, files = run_bag(bag, parse_mapping(MAPPING, "three.toml"), plots=False)
    assert files == []
    assert list(summary["pairs"]) == ["alpha->beta"]
    assert summary["range_pairs_without_odometry"] == {}
    assert summary["range_sigma_m"] == 0.1  # the mapping states no uwb.sigma
    assert not list(tmp_path.glob("*.json"))


def test_a_bag_without_ranges_has_nothing_to_track(tmp_path: Path) -> None:
    bag = _bag(tmp_path / "bag", ranges=False)
    with pytest.raises(DataError, match=rf"^{bag}: nothing to track: no two robots with odometry"):
        run_bag(bag, parse_mapping(MAPPING, "three.toml"))


def test_a_mapping_without_radios_places_no_antenna() -> None:
    assert antenna_offset_m(parse_mapping(ROBOTS, "robots.toml")) == 0.0
