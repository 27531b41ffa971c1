"""A small 3-robot team scenario for the runtime tests (written per test into tmp_path)."""

from __future__ import annotations

from pathlib import Path

import pytest

pytest.importorskip("zenoh", reason="extra 'runtime' (eclipse-zenoh) not installed")


@pytest.fixture(scope="module")
def session():
    """A real Zenoh session connected to nothing, for nodes driven by hand (``node_harness``)."""
    from relloc.runtime.transport import TransportSettings, open_session

    s = open_session(TransportSettings())
    yield s
    s.close()


THREE_ROBOTS = """
name = "runtime-test-trio"
description = "one observing ground robot, one aerial and one ground teammate"
duration_s = DURATION
propagation_rate_hz = 100.0

[arena]
x = [0.0, 10.0]
y = [0.0, 20.0]
z = [-0.5, 2.5]

[[robots]]
name = "observer"
kind = "ground"
initial_pose = [5.0, 2.5, 1.5707963267948966]
[robots.motion]
type = "velocity"
mean = [0.05, 0.0, 0.0, 0.0]
amplitude = [0.0, 0.0, 0.0, 0.1]
period_s = [20.0, 10.0, 10.0, 16.0]
[robots.sensor]
sigma_range = 0.0068
sigma_azimuth = 0.0036
sigma_elevation = 0.0036
rate_hz = 10.0
fov_deg = 120.0
elevation_fov_deg = 120.0
max_range = 15.0
min_range = 0.3

[[robots]]
name = "flyer"
kind = "aerial"
height = 2.0
[robots.motion]
type = "waypoints"
points = [[3.0, 9.0], [6.5, 8.5], [8.0, 12.0], [6.0, 16.5], [3.0, 14.0]]
speed = 0.45

[[robots]]
name = "rover"
kind = "ground"
height = -0.1
[robots.motion]
type = "waypoints"
points = [[4.0, 8.0], [6.0, 11.0], [4.0, 14.0], [2.5, 11.0]]
speed = 0.4
"""


@pytest.fixture
def trio_scenario(tmp_path: Path):
    """Write the 3-robot scenario with a given duration; returns its path."""

    def write(duration_s: float = 8.0) -> Path:
        path = tmp_path / "trio.toml"
        path.write_text(THREE_ROBOTS.replace("DURATION", repr(duration_s)))
        return path

    return write
