"""Every settings dataclass of relloc that can be built from its defaults and checks itself
(``__post_init__``) refuses a string, a bool and NaN in each of its number fields with a
relloc error (:mod:`relloc.core.checks`), never a raw ``TypeError`` or a silent acceptance.

The classes are found by walking the package, so a settings class added later is covered
without being listed here; the ones listed in :data:`ONCE_UNCHECKED` accepted such values or
raised a raw exception before they used :mod:`relloc.core.checks`.
"""

from __future__ import annotations

import dataclasses
import importlib
import math
import pkgutil
from typing import Any

import pytest

import relloc
from relloc.errors import ConfigError, DataError

ONCE_UNCHECKED = {
    "relloc.bench.intervals.IntervalBenchSize",
    "relloc.estimators.initialisation.InitPolicy",
    "relloc.estimators.switching_ekf.SwitchingEkfSettings",
    "relloc.experiments.team_run.TeamRunSettings",
    "relloc.experiments.wanasinghe2014.Wanasinghe2014Config",
    "relloc.experiments.wanasinghe2014_sim.SimSettings",
    "relloc.observability.builtin.ModelOptions",
    "relloc.observability.rpmg.SensorSettings",
    "relloc.runtime.faults.FaultSettings",
    "relloc.runtime.launcher.ProcessTeam",
    "relloc.runtime.transport.TransportSettings",
}


def _settings_classes() -> dict[str, type]:
    """Dataclasses defined in relloc with their own ``__post_init__`` and a default for every
    field (``__main__`` is left out: importing it runs the command line)."""
    found: dict[str, type] = {}
    for info in pkgutil.walk_packages(relloc.__path__, "relloc."):
        if info.name.endswith("__main__"):
            continue
        module = importlib.import_module(info.name)
        for obj in vars(module).values():
            if not (isinstance(obj, type) and dataclasses.is_dataclass(obj)):
                continue
            if obj.__module__ != module.__name__ or "__post_init__" not in vars(obj):
                continue
            fields = [f for f in dataclasses.fields(obj) if f.init]
            if all(
                f.default is not dataclasses.MISSING or f.default_factory is not dataclasses.MISSING
                for f in fields
            ):
                found[f"{obj.__module__}.{obj.__qualname__}"] = obj
    return found


CLASSES = _settings_classes()


def _number_fields(cls: type) -> list[str]:
    out = []
    for f in dataclasses.fields(cls):
        default: Any = f.default
        if default is dataclasses.MISSING and f.default_factory is not dataclasses.MISSING:
            default = f.default_factory()
        if f.init and isinstance(default, (int, float)) and not isinstance(default, bool):
            out.append(f.name)
    return out


CASES = [
    pytest.param(cls, name, bad, id=f"{path.rsplit('.', 1)[1]}.{name}={bad!r}")
    for path, cls in sorted(CLASSES.items())
    for name in _number_fields(cls)
    for bad in ("0.5", True, math.nan)
]


def test_the_walk_finds_the_settings_classes():
    assert ONCE_UNCHECKED <= set(CLASSES)
    assert len(CASES) >= 100


@pytest.mark.parametrize(("cls", "name", "bad"), CASES)
def test_a_number_field_refuses_a_string_a_bool_and_nan(cls, name, bad):
    cls()  # the defaults are valid
    with pytest.raises((ConfigError, DataError)):
        cls(**{name: bad})
