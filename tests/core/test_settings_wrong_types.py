"""Every settings class of relloc that checks itself (``__post_init__``) refuses a string, a
bool and NaN in each of its number fields with a relloc error (:mod:`relloc.core.checks`),
never a raw ``TypeError`` or a silent acceptance.

The classes are found by walking the package. One whose fields all have defaults is built from
them; one with required fields is built from :data:`REQUIRED`; one that holds data rather than
settings is listed in :data:`DATA_RECORDS`, with where its checks are tested. A class added
later that is in none of these fails :func:`test_every_checked_class_is_covered`, so none is
left out silently. :data:`ONCE_UNCHECKED` lists the classes that accepted such values or raised
a raw exception before they used :mod:`relloc.core.checks`.
"""

from __future__ import annotations

import dataclasses
import importlib
import math
import pkgutil
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import relloc
from relloc.errors import ConfigError, DataError, ModelError
from relloc.models.motion import VelocityNoise
from relloc.runtime.transport import TransportSettings

ONCE_UNCHECKED = {
    "relloc.bench.intervals.IntervalBenchSize",
    "relloc.estimators.initialisation.InitPolicy",
    "relloc.estimators.switching_ekf.SwitchingEkfSettings",
    "relloc.experiments.guler2023_team.GulerTeamSettings",
    "relloc.experiments.registry.ReproduceArgs",
    "relloc.experiments.team_run.TeamRunSettings",
    "relloc.experiments.wanasinghe2014.Wanasinghe2014Config",
    "relloc.experiments.wanasinghe2014_sim.SimSettings",
    "relloc.observability.builtin.ModelOptions",
    "relloc.observability.rpmg.SensorSettings",
    "relloc.runtime.airground.RobotSettings",
    "relloc.runtime.airground.WorldSettings",
    "relloc.runtime.clock.ClockSettings",
    "relloc.runtime.faults.FaultSettings",
    "relloc.runtime.faults.Partition",
    "relloc.runtime.faults.RobotEvent",
    "relloc.runtime.faults.Stall",
    "relloc.runtime.launcher.ProcessTeam",
    "relloc.runtime.node.NodeSettings",
    "relloc.runtime.realtime.WallClockSettings",
    "relloc.runtime.transport.TransportSettings",
}

_SIGMAS = (0.05, 0.05, 0.01, 0.05)
_TRANSPORT = TransportSettings()
_OUT = Path("out")

#: Valid values of the required fields of each settings class that has some.
REQUIRED: dict[str, dict[str, Any]] = {
    "relloc.calibration.window.CalibrationWindow": {"start_s": 0.0, "end_s": 1.0, "source": "s"},
    "relloc.control.drone_schedule.DroneSchedule": {
        "n_followers": 2,
        "n_drones": 1,
        "dwell_steps": 1,
    },
    "relloc.estimators.cooperative.OdometryModel": {"q_v0": 1e-3, "q_w0": 1e-3},
    "relloc.estimators.cooperative.SensorModel": {"sigma_bearing": 0.05},
    "relloc.estimators.gaussian_sum.GaussianSumSettings": {
        "velocity_noise": VelocityNoise(observer=_SIGMAS, observed=_SIGMAS),
        "sigma_height": 0.01,
        "sigma_range": 0.1,
        "sigma_azimuth": 0.03,
        "sigma_elevation": 0.03,
    },
    "relloc.experiments.guler2023_team.GulerTeamSettings": {"out_dir": _OUT},
    "relloc.experiments.registry.ReproduceArgs": {"out_dir": _OUT},
    "relloc.experiments.sharma2013_team.SharmaTeamSettings": {"out_dir": _OUT},
    "relloc.models.measurement.RangeBearingNoise": {
        "sigma_r": 0.1,
        "sigma_azimuth": 0.1,
        "sigma_elevation": 0.1,
    },
    "relloc.models.uwb_noise.UwbNoiseModel": {
        "bias": 0.0,
        "spread": 0.1,
        "outlier_rate": 0.01,
        "outlier_excess_mean": 0.1,
    },
    "relloc.runtime.airground.WorldSettings": {"team": "t", "transport": _TRANSPORT},
    "relloc.runtime.airground.RobotSettings": {
        "team": "t",
        "robot": "r",
        "transport": _TRANSPORT,
    },
    "relloc.runtime.clock.ClockSettings": {
        "team": "t",
        "roster": ("a", "b"),
        "tick_s": 0.1,
        "duration_s": 1.0,
        "transport": _TRANSPORT,
    },
    "relloc.runtime.faults.Partition": {"side": ("a",), "start_s": 0.0, "end_s": 1.0},
    "relloc.runtime.faults.Stall": {"sender": "a", "receiver": "b", "at_s": 0.0, "wall_s": 1.0},
    "relloc.runtime.faults.RobotEvent": {"robot": "a", "at_s": 1.0},
    "relloc.runtime.launcher.TeamSettings": {"scenario": "default", "out_dir": _OUT},
    "relloc.runtime.node.NodeSettings": {
        "team": "t",
        "robot": "a",
        "roster": ("a", "b"),
        "transport": _TRANSPORT,
    },
    "relloc.runtime.realtime.WallClockSettings": {"duration_s": 1.0},
    "relloc.sim.airground.AirGroundScenario": {"offsets": ((-1.0, 1.0), (-1.0, -1.0))},
    "relloc.sim.cooperative.CooperativeScenario": {
        "start_poses": np.zeros((1, 3)),
        "waypoints": (np.array([[5.0, 0.0], [5.0, 5.0]]),),
        "landmarks_xy": np.array([[2.0, 2.0]]),
    },
    "relloc.sim.scenario.WaypointMotion": {"points": [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]]},
}

#: Classes with required fields that hold data or compose other settings, not number
#: settings of their own: where their checks are tested.
DATA_RECORDS = {
    "relloc.core.contract.Belief": "tests/core/test_kalman_and_beliefs_bad_input.py",
    "relloc.core.gaussian.Gaussian": "tests/core/test_models_core_bad_input.py",
    "relloc.core.gaussian.GaussianMixture": "tests/core/test_models_core_bad_input.py",
    "relloc.core.gaussian.InformationState": "tests/core/test_belief_stack.py",
    "relloc.core.recording.FileSkips": "tests/core/test_models_core_bad_input.py",
    "relloc.core.recording.GroundTruth": "tests/core/test_recording.py",
    "relloc.core.recording.Measurements": "tests/core/test_recording.py",
    "relloc.core.recording.Odometry": "tests/core/test_recording.py",
    "relloc.core.recording.Recording": "tests/core/test_recording.py",
    "relloc.control.formation.FormationController": "tests/airground/test_airground_bad_input.py",
    "relloc.datasets.mrclam.GroundTruth": "tests/datasets/test_dataset_containers.py",
    "relloc.datasets.mrclam.Measurements": "tests/datasets/test_dataset_containers.py",
    "relloc.datasets.mrclam.Odometry": "tests/datasets/test_dataset_containers.py",
    "relloc.datasets.uwb.UwbRecording": "tests/datasets/test_dataset_containers.py",
    "relloc.estimators.cooperative.CooperativeSettings": "tests/estimators/test_settings_checks.py",
    "relloc.estimators.gaussian_sum.Tracks": "tests/multihypothesis/test_gaussian_sum.py",
    "relloc.estimators.relative.FilterSettings": "tests/estimators/test_settings_checks.py",
    "relloc.estimators.relative_batch.TrackSpec": "tests/estimators/test_relative_batch.py",
    "relloc.experiments.desilva2015.RunConfig": "tests/multihypothesis/test_desilva_sensing.py",
    "relloc.experiments.wanasinghe2014_mrclam.ReplaySettings": (
        "tests/experiments/test_wanasinghe2014_pairs.py"
    ),
    "relloc.fusion.messages.EquivalentMeasurement": (
        "tests/multihypothesis/test_fusion_bad_input.py"
    ),
    "relloc.models.motion.VelocityNoise": "tests/estimators/test_settings_checks.py",
    "relloc.models.planar_measurement.ScalarRows": "tests/core/test_models_core_bad_input.py",
    "relloc.models.symbolic.SymbolicModel": "tests/observability/test_analysis.py",
    "relloc.sim.scenario.RobotSpec": "tests/sim/test_scenario.py",
    "relloc.sim.scenario.Scenario": "tests/sim/test_scenario.py",
}


def _checked_classes() -> dict[str, type]:
    """Dataclasses defined in relloc with their own ``__post_init__`` (``__main__`` is left
    out: importing it runs the command line)."""
    found: dict[str, type] = {}
    for info in pkgutil.walk_packages(relloc.__path__, "relloc."):
        if info.name.endswith("__main__"):
            continue
        module = importlib.import_module(info.name)
        for obj in vars(module).values():
            if not (isinstance(obj, type) and dataclasses.is_dataclass(obj)):
                continue
            if obj.__module__ == module.__name__ and "__post_init__" in vars(obj):
                found[f"{obj.__module__}.{obj.__qualname__}"] = obj
    return found


def _has_required_fields(cls: type) -> bool:
    return any(
        f.init and f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING
        for f in dataclasses.fields(cls)
    )


CHECKED = _checked_classes()
SETTINGS = {
    path: (cls, REQUIRED.get(path, {}))
    for path, cls in CHECKED.items()
    if not _has_required_fields(cls) or path in REQUIRED
}


def _number_fields(cls: type, base: dict[str, Any]) -> list[str]:
    out = []
    for f in dataclasses.fields(cls):
        value: Any = base.get(f.name, f.default)
        if value is dataclasses.MISSING and f.default_factory is not dataclasses.MISSING:
            value = f.default_factory()
        if f.init and isinstance(value, (int, float)) and not isinstance(value, bool):
            out.append(f.name)
    return out


CASES = [
    pytest.param(cls, base, name, bad, id=f"{path.rsplit('.', 1)[1]}.{name}={bad!r}")
    for path, (cls, base) in sorted(SETTINGS.items())
    for name in _number_fields(cls, base)
    for bad in ("0.5", True, math.nan)
]


def test_every_checked_class_is_covered():
    assert ONCE_UNCHECKED <= set(SETTINGS)
    uncovered = {p for p in CHECKED if p not in SETTINGS and p not in DATA_RECORDS}
    assert not uncovered, f"add to REQUIRED or DATA_RECORDS: {sorted(uncovered)}"
    assert set(REQUIRED) <= set(CHECKED) and set(DATA_RECORDS) <= set(CHECKED)
    root = Path(__file__).resolve().parents[2]
    assert all((root / where).is_file() for where in DATA_RECORDS.values())
    assert len(CASES) >= 300


@pytest.mark.parametrize(("cls", "base", "name", "bad"), CASES)
def test_a_number_field_refuses_a_string_a_bool_and_nan(cls, base, name, bad):
    cls(**base)  # the base values are valid
    with pytest.raises((ConfigError, DataError, ModelError)):
        cls(**{**base, name: bad})
