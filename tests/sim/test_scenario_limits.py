"""Scenario files that used to crash the parser or the simulator: each is now a ConfigError
naming the file and the field (or, where documented, a valid scenario that measures less)."""

import dataclasses
from importlib import resources

import numpy as np
import pytest

from relloc.errors import ConfigError
from relloc.sim import scenario as scn
from relloc.sim.scenario import (
    RobotSpec,
    Scenario,
    SensorSpec,
    VelocityMotion,
    WaypointMotion,
    load_scenario,
)
from relloc.sim.simulate import simulate

DEFAULT = resources.files("relloc.sim").joinpath("scenarios/default.toml").read_text("utf-8")
AERIAL1_POINTS = "[[3.0, 9.0], [6.5, 8.5], [8.0, 12.0], [6.0, 16.5], [3.0, 14.0]]"
OBSERVER = 'name = "observer"\n'
DESCRIPTION = next(line for line in DEFAULT.splitlines() if line.startswith("description = "))


def _edit(old: str, new: str) -> str:
    assert old in DEFAULT, old
    return DEFAULT.replace(old, new, 1)


def _load(tmp_path, text: str):
    path = tmp_path / "my.toml"
    path.write_text(text, encoding="utf-8")
    return path, load_scenario(path)


def _error(tmp_path, text: str) -> str:
    path = tmp_path / "my.toml"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(ConfigError) as err:
        load_scenario(path)
    message = str(err.value)
    assert message.startswith(f"{path}: "), message
    return message[len(f"{path}: ") :]


STEPS = "duration_s × propagation_rate_hz: "
STEP_LIMIT = "the limit is 1e+07 (MAX_SIMULATED_STEPS)"


@pytest.mark.parametrize(
    ("old", "new", "expected"),
    [
        # Work: overflow (1e308), an integer beyond int64 (9.2e18) and a 745 GiB allocation (1e9).
        ("duration_s = 60.0", "duration_s = 1e308", [STEPS, "inf simulated steps", STEP_LIMIT]),
        ("duration_s = 60.0", "duration_s = 9.2e18", [STEPS, "4.6e+21", STEP_LIMIT]),
        ("duration_s = 60.0", "duration_s = 1e9", [STEPS, "5 robot(s) × 1e+11 steps", STEP_LIMIT]),
        ("duration_s = 60.0", "duration_s = 1" + "0" * 40, [STEPS, STEP_LIMIT]),
        ("propagation_rate_hz = 100.0", "propagation_rate_hz = 1e308", [STEPS, STEP_LIMIT]),
        ("propagation_rate_hz = 100.0", "propagation_rate_hz = 9.2e18", [STEPS, STEP_LIMIT]),
        (
            "propagation_rate_hz = 100.0",
            "propagation_rate_hz = 1e-308",
            ["propagation_rate_hz: must be in [0.001, ∞), got 1e-308"],
        ),
        (
            "duration_s = 60.0",
            "duration_s = 1e-308",
            ["duration_s: shorter than one propagation step"],
        ),
        (
            "rate_hz = 10.0",
            "rate_hz = 10000.0",
            ["robots[0].sensor.rate_hz: must not exceed propagation_rate_hz (100)"],
        ),
        # Space.
        ("x = [0.0, 10.0]", "x = [0.0, 1e308]", ["arena.x[1]: must be in [-1e+06, 1e+06]"]),
        ("y = [0.0, 20.0]", "y = [-inf, 20.0]", ["arena.y[0]: must be finite, got -inf"]),
        ("z = [-0.5, 2.5]", "z = [2.5, -0.5]", ["arena.z: lower bound 2.5 must be below"]),
        ("height = 2.0", "height = 1e300", ["robots[1].height: must be in [-1e+06, 1e+06]"]),
        ("height = 2.0", "height = " + "9" * 400, ["robots[1].height: must be finite"]),
        (
            "initial_pose = [5.0, 2.5, 1.5707963267948966]",
            "initial_pose = [5.0, 2.5, 1e300]",
            ["robots[0].initial_pose[2]: must be in [-6.28319, 6.28319]"],
        ),
        # Motion and noise that would overflow or turn into NaN.
        ("speed = 0.45", "speed = 1e308", ["robots[1].motion.speed: must be in (0, 100]"]),
        (
            "period_s = [20.0, 10.0, 10.0, 16.0]",
            "period_s = [1e-308, 10.0, 10.0, 16.0]",
            ["robots[0].motion.period_s[0]: must be in [0.001, ∞)"],
        ),
        (
            "amplitude = [0.06, 0.0, 0.0, 0.15]",
            "amplitude = [0.06, 0.0, 0.0, 1e9]",
            ["robots[0].motion.amplitude[3]: must be in [0, 100]"],
        ),
        (
            "mean = [0.06, 0.0, 0.0, 0.0]",
            "mean = [-1e200, 0.0, 0.0, 0.0]",
            ["robots[0].motion.mean[0]: must be in [-100, 100]"],
        ),
        ("z_period_s = 12.0", "z_period_s = 1e-300", ["robots[2].motion.z_period_s"]),
        ("z_amplitude = 0.2", "z_amplitude = 1e300", ["robots[2].motion.z_amplitude"]),
        ("yaw_rad = 0.5", "yaw_rad = 1e300", ["robots[2].motion.yaw_rad: must be in"]),
        (
            "sigma_range = 0.0068",
            "sigma_range = 1e-308",
            ["robots[0].sensor.sigma_range: must be in [1e-06, 1e+06], got 1e-308"],
        ),
        (
            "sigma_azimuth = 0.0036",
            "sigma_azimuth = 1e308",
            ["robots[0].sensor.sigma_azimuth: must be in [1e-06, 3.14159]"],
        ),
        (
            "sigma_w = 0.05     # rad/s",
            "sigma_w = 1e308",
            ["robots[0].odometry.sigma_w: must be in [0, 100]"],
        ),
        ("min_range = 0.3", "min_range = nan", ["robots[0].sensor.min_range: must be finite"]),
        ("fov_deg = 120.0", "fov_deg = 400.0", ["robots[0].sensor.fov_deg: must be in (0, 360]"]),
        ("fov_deg = 120.0", "fov_deg = 0.0", ["robots[0].sensor.fov_deg: must be in (0, 360]"]),
        # Way-points: non-finite, repeated, closing on themselves, too close, too many.
        (AERIAL1_POINTS, "[[3.0, nan], [6.5, 8.5], [8.0, 12.0]]", ["points[0][1]: must be finite"]),
        (AERIAL1_POINTS, "[[3.0, 9.0], [inf, 8.5], [8.0, 12.0]]", ["points[1][0]: must be finite"]),
        (
            AERIAL1_POINTS,
            "[[3.0, 9.0], [3.0, 9.0], [8.0, 12.0]]",
            ["robots[1].motion.points[1]: 0 m from points[0]; consecutive way-points must be"],
        ),
        (
            AERIAL1_POINTS,
            "[[3.0, 9.0], [3.0, 9.0000000000001], [8.0, 12.0]]",
            ["robots[1].motion.points[1]: 9.9476e-14 m from points[0]", "at least 0.001 m"],
        ),
        (
            AERIAL1_POINTS,
            "[[3.0, 9.0], [6.5, 8.5], [8.0, 12.0], [3.0, 9.0]]",
            ["robots[1].motion.points[3]: 0 m from points[0]; a closed path returns"],
        ),
        (
            AERIAL1_POINTS,
            "[" + ", ".join(f"[{1 + i * 1e-3:.3f}, 9.0]" for i in range(1001)) + "]",
            ["robots[1].motion.points: 1001 way-points; the limit is 1000 (MAX_WAYPOINTS)"],
        ),
        (
            AERIAL1_POINTS,
            "[[3.0, 9.0], [6.5], [8.0, 12.0]]",
            ["robots[1].motion.points[1]: expected 2"],
        ),
        (AERIAL1_POINTS, '"around"', ["robots[1].motion.points: expected a list"]),
        # Robot names become parts of file names.
        ('name = "aerial1"', 'name = "a/b"', ["robots[1].name: must match [A-Za-z0-9_-]{1,64}"]),
        ('name = "aerial1"', 'name = "a*"', ["robots[1].name: must match", "got 'a*'"]),
        ('name = "aerial1"', 'name = "' + "a" * 10_000 + '"', ["robots[1].name: must match"]),
        ('name = "aerial1"', 'name = ""', ["robots[1].name: must match"]),
        ('name = "aerial1"', 'name = "aerial 1"', ["robots[1].name: must match"]),
        ('name = "aerial1"', 'name = "aerial1\\n"', ["robots[1].name: must match"]),
        ('name = "aerial1"', "name = 7", ["robots[1].name: must match", "got 7"]),
        # The field named is the field that is wrong.
        (
            "amplitude = [0.06, 0.0, 0.0, 0.15]",
            "amplitude = [0.06, 0.3, 0.0, 0.15]",
            ["robots[0].motion.amplitude[1]: a ground robot cannot move along v_y"],
        ),
        (
            "mean = [0.06, 0.0, 0.0, 0.0]",
            "mean = [0.06, 0.0, 0.2, 0.0]",
            ["robots[0].motion.mean[2]: a ground robot cannot move along v_z"],
        ),
        (
            "speed = 0.4\nclosed = true\n[robots.odometry]\nsigma_v = 0.05\nsigma_vz = 0.02\n"
            'sigma_w = 0.05\n\n[[robots]]\nname = "ground2"',
            "speed = 0.4\nclosed = true\nz_amplitude = 0.1\n[robots.odometry]\nsigma_v = 0.05\n"
            'sigma_vz = 0.02\nsigma_w = 0.05\n\n[[robots]]\nname = "ground2"',
            ["robots[3].motion.z_amplitude: a ground robot moves on a flat plane"],
        ),
        # Types: strings, booleans, tables, dates where numbers are expected; unknown keys.
        ("duration_s = 60.0", 'duration_s = "60"', ["duration_s: expected a number, got '60'"]),
        ("duration_s = 60.0", "duration_s = true", ["duration_s: expected a number, got True"]),
        ("duration_s = 60.0", "duration_s = 1979-05-27", ["duration_s: expected a number"]),
        ("speed = 0.45", "speed = {a = 1}", ["robots[1].motion.speed: expected a number"]),
        ("speed = 0.45", "speed = [0.45]", ["robots[1].motion.speed: expected a number"]),
        ("closed = true", 'closed = "yes"', ["robots[1].motion.closed: expected true or false"]),
        ('heading = "fixed"', "heading = 1", ["robots[2].motion.heading: must be 'tangent'"]),
        ('kind = "aerial"', 'kind = ["aerial"]', ["robots[1].kind: must be 'ground' or 'aerial'"]),
        ('type = "waypoints"', "type = 3", ["robots[1].motion.type: must be 'waypoints' or"]),
        (
            "[arena]\nx = [0.0, 10.0]\ny = [0.0, 20.0]\nz = [-0.5, 2.5]",
            "arena = 3",
            ["arena: expected a table, got 3"],
        ),
        ('name = "aerial1"\n', 'name = "aerial1"\nsensor = 1\n', ["robots[1].sensor: expected a"]),
        ("[robots.sensor]", "[robots.sensors]", ["robots[0].sensors: unknown key"]),
        ("[robots.odometry]", "[robots.odometry.x]", ["robots[0].odometry.x: unknown key"]),
        ("speed = 0.45", "speed = 0.45\nbogus = 1", ["robots[1].motion.bogus: unknown key"]),
        ("speed = 0.45", 'speed = 0.45\n"a.b\\n" = 1', ["robots[1].motion.'a.b\\n': unknown key"]),
        ("[arena]", "bogus = 1\n[arena]", ["bogus: unknown key; expected one of arena"]),
        ("x = [0.0, 10.0]", "x = [0.0, 10.0]\nw = [0.0, 1.0]", ["arena.w: unknown key"]),
        ('name = "wanasinghe2014-air-ground"', "name = 5", ["name: expected a one-line text"]),
        ('name = "wanasinghe2014-air-ground"', 'name = ""', ["name: expected a one-line text"]),
        (DESCRIPTION, "description = 5", ["description: expected a text, got 5"]),
        ('type = "waypoints"', 'type = "waypoints"\npoints = 1\nspeed = 1', ["Cannot overwrite"]),
        (
            '[robots.motion]\ntype = "waypoints"\npoints',
            "[robots.motion]\npoints",
            ["robots[1].motion.type: must be 'waypoints' or 'velocity', got None"],
        ),
        (
            AERIAL1_POINTS,
            "[[3.0, 9.0], [6.5, 8.5]]",
            ["robots[1].motion.points: a closed path needs at least three points"],
        ),
        (
            'name = "aerial1"\n',
            'name = "aerial1"\ninitial_pose = [1.0, 1.0, 0.0]\n',
            ["robots[1].initial_pose: not used with way-points"],
        ),
        (
            "[0.8, 12.0]]",
            '[0.8, 12.0]]\nheading = "fixed"',
            ["robots[3].motion.heading: a ground robot follows its path's tangent; must be"],
        ),
        (
            OBSERVER,
            OBSERVER + 'observes = "aerial1"\n',
            ["robots[0].observes: expected a list of robot names, got 'aerial1'"],
        ),
        (
            OBSERVER,
            OBSERVER + "observes = [" + ", ".join(f'"r{i}"' for i in range(65)) + "]\n",
            ["robots[0].observes: 65 names; the limit is 64 (MAX_ROBOTS)"],
        ),
        (OBSERVER, OBSERVER + "observes = [1]\n", ["robots[0].observes[0]: expected a robot name"]),
        (
            OBSERVER,
            OBSERVER + 'observes = ["observer"]\n',
            ["robots[0].observes[0]: a robot cannot observe itself"],
        ),
        (
            "[robots.motion]            # slow",
            "motion = 5\n[robots.unused]            # slow",
            ["robots[0].motion: expected a table with type = 'waypoints' or 'velocity'"],
        ),
    ],
)
def test_bad_value_is_a_config_error_naming_the_field(tmp_path, old, new, expected):
    message = _error(tmp_path, _edit(old, new))
    for part in expected:
        assert part in message


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        (
            DEFAULT.replace(f"points = {AERIAL1_POINTS}\n", ""),
            "robots[1].motion.points: required",
        ),
        (DEFAULT.replace('kind = "aerial"\n', "", 1), "robots[1].kind: required"),
        ("duration_s = 1.0\n", "robots: required"),
        ("robots = 3\n", "robots: expected an array of tables"),
        ("robots = [1]\n", "robots[0]: expected a table, got 1"),
        ("robots = []\n", "robots: a scenario needs at least one robot"),
    ],
)
def test_missing_and_misshapen_tables_are_named(tmp_path, text, expected):
    assert expected in _error(tmp_path, text)


def test_robot_and_measurement_counts_are_bounded(tmp_path):
    extra = "".join(
        f'\n[[robots]]\nname = "r{i}"\nkind = "ground"\ninitial_pose = [1.0, 1.0, 0.0]\n'
        '[robots.motion]\ntype = "velocity"\n'
        for i in range(scn.MAX_ROBOTS)
    )
    assert "robots: 69 robots; the limit is 64 (MAX_ROBOTS)" in _error(tmp_path, DEFAULT + extra)
    # 4 pairs × 30 s × 10 kHz = 1.2e6 measurements, but only 1.5e6 robot-steps.
    fast = _edit("propagation_rate_hz = 100.0", "propagation_rate_hz = 10000.0")
    fast = fast.replace("duration_s = 60.0", "duration_s = 30.0").replace(
        "rate_hz = 10.0", "rate_hz = 10000.0"
    )
    message = _error(tmp_path, fast)
    assert "robots[*].sensor.rate_hz × duration_s: 4 observed pair(s) take 1.2e+06" in message
    assert "the limit is 1e+06 (MAX_MEASUREMENTS)" in message


def test_file_encoding_size_and_nesting(tmp_path):
    path = tmp_path / "latin1.toml"
    path.write_bytes(
        _edit('name = "aerial1"', 'name = "a\xe9"').encode("utf-8").replace(b"a\xc3\xa9", b"a\xe9")
    )
    with pytest.raises(ConfigError, match=rf"{path}: not UTF-8 text \(byte \d+: invalid"):
        load_scenario(path)
    bom = tmp_path / "bom.toml"
    bom.write_bytes(b"\xef\xbb\xbf" + DEFAULT.encode("utf-8"))
    assert load_scenario(bom).robot_names[0] == "observer"
    big = DEFAULT + "#" * scn.MAX_FILE_BYTES
    assert "larger than 4194304 bytes (MAX_FILE_BYTES)" in _error(tmp_path, big)
    for depth in (500, 5000):
        deep = "x = " + "[" * depth + "]" * depth + "\n" + DEFAULT
        assert "nested too deeply" in _error(tmp_path, deep)
    deep_value = _edit("speed = 0.45", "speed = " + "[" * 50 + "1" + "]" * 50)
    message = _error(tmp_path, deep_value)
    assert message.startswith("robots[1].motion.speed: expected a number, got [[[")
    assert len(message) < 200


def test_tiny_rates_and_views_are_valid_and_measure_nothing(tmp_path):
    """Documented choice: a positive sensor rate or field of view is valid however small;
    such a sensor simply yields no measurements."""
    for old, new in (
        ("rate_hz = 10.0", "rate_hz = 1e-308"),
        ("fov_deg = 120.0", "fov_deg = 1e-308"),
        ("elevation_fov_deg = 120.0", "elevation_fov_deg = 1e-308"),
    ):
        _, sc = _load(tmp_path, _edit(old, new))
        log = simulate(sc, np.random.default_rng(0))
        assert log.measurements.t.size == 0


def test_a_robot_that_observes_nothing_is_valid_but_a_team_must_measure_something(tmp_path):
    sensor = "[robots.sensor]\nrate_hz = 5.0\n"
    text = DEFAULT.replace("z_period_s = 12.0\n", "z_period_s = 12.0\n" + sensor, 1)
    text = text.replace('name = "aerial2"\n', 'name = "aerial2"\nobserves = []\n', 1)
    _, sc = _load(tmp_path, text)
    assert sc.targets_of("aerial2") == () and len(sc.pairs()) == 4
    assert simulate(sc, np.random.default_rng(0)).measurements.t.size > 0
    nothing = _edit(OBSERVER, OBSERVER + "observes = []\n")
    assert "robots: nothing to measure" in _error(tmp_path, nothing)
    lonely = DEFAULT[: DEFAULT.index('[[robots]]\nname = "aerial1"')]
    assert "robots: nothing to measure" in _error(tmp_path, lonely)
    twice = _edit(OBSERVER, OBSERVER + 'observes = ["aerial1", "aerial1"]\n')
    assert "robots[0].observes[1]: 'aerial1' is already listed" in _error(tmp_path, twice)


def test_a_range_noise_that_draws_readings_past_the_sensor_limit_names_the_sensor(tmp_path):
    """σ_r = 5000 m is accepted by the scenario (σ_r ≤ 10⁶ m; max_range may be infinite), but
    about 2.3 % of the readings (ν > 2σ) then land more than 10⁴ m out, some in the first
    run's hundreds: the simulator names the sensor and both fields, not a recording row."""
    _, sc = _load(tmp_path, _edit("sigma_range = 0.0068", "sigma_range = 5000"))
    with pytest.raises(ConfigError) as e:
        simulate(sc, np.random.default_rng(0))
    message = str(e.value)
    assert message.startswith("robots[0].sensor (observer): a simulated range to ")
    assert "beyond the 10000 m a reading may have" in message
    assert "lower sigma_range (5000 m) or max_range (15 m)" in message


def test_a_path_that_doubles_back_onto_a_cusp_is_named_by_the_simulator():
    """At a cusp the spline's tangent vanishes and the ground robot's yaw rate is 0/0; this
    speed puts a propagation step's midpoint exactly on it."""
    observer = RobotSpec(
        name="o",
        kind="ground",
        initial_pose=(5.0, 5.0, 0.0),
        motion=VelocityMotion(),
        sensor=SensorSpec(),
    )
    back = WaypointMotion(
        points=((1.0, 1.0), (3.0, 1.0), (1.0, 1.0)), closed=False, speed=26.666625
    )
    sc = Scenario(robots=(observer, RobotSpec(name="c", kind="ground", motion=back)), duration_s=1)
    with pytest.raises(ConfigError, match=r"robots\[1\].motion: robot 'c' has no defined pose"):
        simulate(sc, np.random.default_rng(0))


def test_dataclasses_check_their_parts_without_toml():
    observer = RobotSpec(
        name="o",
        kind="ground",
        initial_pose=(0.0, 0.0, 0.0),
        motion=VelocityMotion(),
        sensor=SensorSpec(),
    )
    with pytest.raises(ConfigError, match=r"robots\[1\]: expected a robot, got 'x'"):
        Scenario(robots=(observer, "x"))  # type: ignore[arg-type]
    with pytest.raises(ConfigError, match="motion: expected way-points or velocity commands"):
        RobotSpec(name="o", kind="ground", motion="circle")  # type: ignore[arg-type]
    with pytest.raises(ConfigError, match="observes: only a robot with a sensor can observe"):
        RobotSpec(
            name="o",
            kind="aerial",
            motion=VelocityMotion(),
            initial_pose=(0, 0, 0),
            observes=("a",),
        )


def test_dataclass_parts_of_the_wrong_type_or_too_many_robots_are_named():
    default = scn.default_scenario()
    observer = default.robots[0]
    with pytest.raises(ConfigError, match="odometry: expected an odometry noise table"):
        dataclasses.replace(observer, odometry="quiet")
    with pytest.raises(ConfigError, match="sensor: expected a sensor table"):
        dataclasses.replace(observer, sensor="camera")
    with pytest.raises(ConfigError, match="arena: expected an arena table"):
        dataclasses.replace(default, arena="field")
    with pytest.raises(ConfigError, match=r"robots: 65 robots; the limit is 64 \(MAX_ROBOTS\)"):
        dataclasses.replace(default, robots=default.robots * 13)
