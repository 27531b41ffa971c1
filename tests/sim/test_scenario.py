"""Scenario TOML loading: the default team, and validation errors that name the field."""

import textwrap

import pytest

from relloc.errors import ConfigError
from relloc.sim.scenario import (
    SensorSpec,
    VelocityMotion,
    WaypointMotion,
    default_scenario,
    load_scenario,
)

MINIMAL = """
name = "pair"
duration_s = 5.0

[[robots]]
name = "l"
kind = "ground"
initial_pose = [5.0, 2.0, 1.57]
[robots.motion]
type = "velocity"
mean = [0.1, 0.0, 0.0, 0.0]
[robots.sensor]
fov_deg = 90.0

[[robots]]
name = "c"
kind = "aerial"
height = 2.0
[robots.motion]
type = "waypoints"
points = [[4.0, 6.0], [6.0, 6.0], [5.0, 8.0]]
"""


def _write(tmp_path, text):
    path = tmp_path / "team.toml"
    path.write_text(textwrap.dedent(text))
    return path


def test_default_scenario_is_the_seed_000_team():
    sc = default_scenario()
    kinds = {r.name: (r.kind, r.height) for r in sc.robots}
    observers = [r for r in sc.robots if r.is_observer]
    assert len(observers) == 1 and observers[0].kind == "ground"
    observed = sorted(h for k, h in kinds.values() if k == "aerial")
    assert observed == [1.5, 2.0]
    assert sorted(h for n, (k, h) in kinds.items() if k == "ground" and n != observers[0].name) == [
        -0.2,
        -0.1,
    ]
    s = observers[0].sensor
    assert (s.sigma_range, s.sigma_azimuth, s.sigma_elevation, s.rate_hz) == (
        0.0068,
        0.0036,
        0.0036,
        10.0,
    )
    assert sc.propagation_rate_hz == 100.0
    assert (sc.arena.x[1] - sc.arena.x[0], sc.arena.y[1] - sc.arena.y[0]) == (10.0, 20.0)
    assert sc.arena.z[1] - sc.arena.z[0] == 3.0
    assert len(sc.pairs()) == 4


def test_minimal_file_loads(tmp_path):
    sc = load_scenario(_write(tmp_path, MINIMAL))
    assert sc.pairs() == (("l", "c"),)
    assert isinstance(sc.robots[0].motion, VelocityMotion)
    assert isinstance(sc.robots[1].motion, WaypointMotion)
    assert sc.robots[0].sensor == SensorSpec(fov_deg=90.0)


@pytest.mark.parametrize(
    ("old", "new", "message"),
    [
        ("fov_deg = 90.0", "fov_deg = 400.0", "robots[0].sensor.fov_deg: must be in (0, 360]"),
        ("fov_deg = 90.0", "fov = 90.0", "robots[0].sensor.fov: unknown key"),
        ("fov_deg = 90.0", 'fov_deg = "wide"', "robots[0].sensor.fov_deg: expected a number"),
        ('kind = "aerial"', 'kind = "boat"', "robots[1].kind: must be 'ground' or 'aerial'"),
        ("duration_s = 5.0", "duration_s = -1.0", "duration_s: must be in (0, ∞)"),
        ('type = "waypoints"', 'type = "teleport"', "robots[1].motion.type: must be"),
        ("[[4.0, 6.0], [6.0, 6.0], [5.0, 8.0]]", "[[4.0, 6.0]]", "robots[1].motion.points"),
        ("[0.1, 0.0, 0.0, 0.0]", "[0.1, 0.3, 0.0, 0.0]", "robots[0].motion.mean[1]: a ground"),
        ("initial_pose = [5.0, 2.0, 1.57]\n", "", "robots[0].initial_pose: required"),
        ('name = "c"', 'name = "l"', "robots[1].name: duplicate robot name"),
        ("fov_deg = 90.0", "fov_deg = 90.0\nrate_hz = 0.0", "robots[0].sensor.rate_hz"),
    ],
)
def test_validation_errors_name_the_field(tmp_path, old, new, message):
    assert old in MINIMAL
    path = _write(tmp_path, MINIMAL.replace(old, new, 1))
    with pytest.raises(ConfigError) as err:
        load_scenario(path)
    assert message in str(err.value)
    assert str(path) in str(err.value)


def test_observes_unknown_robot_and_no_observer(tmp_path):
    bad = MINIMAL.replace("[robots.sensor]", "[robots.sensor]\n", 1).replace(
        'kind = "ground"\n', 'kind = "ground"\nobserves = ["ghost"]\n', 1
    )
    with pytest.raises(ConfigError, match=r"robots\[0\].observes\[0\]: unknown robot 'ghost'"):
        load_scenario(_write(tmp_path, bad))
    no_sensor = MINIMAL.replace("[robots.sensor]\nfov_deg = 90.0\n", "")
    with pytest.raises(ConfigError, match="at least one robot needs a sensor"):
        load_scenario(_write(tmp_path, no_sensor))


def test_malformed_toml_and_missing_file(tmp_path):
    with pytest.raises(ConfigError, match="not valid TOML"):
        load_scenario(_write(tmp_path, "robots = [[[\n"))
    with pytest.raises(ConfigError, match="cannot read scenario file"):
        load_scenario(tmp_path / "absent.toml")


def test_dataclass_validation_without_toml():
    with pytest.raises(ConfigError, match="max_range: must exceed min_range"):
        SensorSpec(min_range=2.0, max_range=1.0)
    with pytest.raises(ConfigError, match=r"period_s\[0\]"):
        VelocityMotion(period_s=(0.0, 1.0, 1.0, 1.0))


def test_numpy_scalars_are_numbers():
    """Before: a numpy integer (e.g. from an array a caller indexed) was refused as 'expected a
    number'; numpy's bool is still refused, like Python's."""
    import numpy as np

    motion = WaypointMotion(
        points=((0, 0), (np.int64(3), 0), (3, np.float32(2))), speed=np.int64(1)
    )
    assert motion.speed == 1.0 and isinstance(motion.speed, float)
    assert motion.points[1] == (3.0, 0.0)
    with pytest.raises(ConfigError, match="speed: expected a number"):
        WaypointMotion(points=((0, 0), (3, 0), (3, 2)), speed=np.bool_(True))
