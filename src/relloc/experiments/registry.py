"""Names accepted by ``relloc reproduce NAME`` and the module implementing each.

Each module exposes ``reproduce(args: ReproduceArgs) -> dict`` that writes summary.json,
report.md and figures into ``args.out_dir`` and returns the summary.
"""

from __future__ import annotations

import importlib
import importlib.util
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from relloc.errors import ConfigError

EXPERIMENTS: dict[str, str] = {
    "wanasinghe2014": "relloc.experiments.wanasinghe2014",
    "wanasinghe-observability": "relloc.experiments.wanasinghe_observability",
    "sharma-observability": "relloc.experiments.sharma_observability",
    "sharma2013": "relloc.experiments.sharma2013",
    "mrclam-cl": "relloc.experiments.mrclam_cl",
    "desilva2015": "relloc.experiments.desilva2015",
    "mrclam-association": "relloc.experiments.mrclam_association",
    "guler2023": "relloc.experiments.guler2023",
    "tiers-uwb": "relloc.experiments.tiers_uwb",
}


@dataclass(frozen=True, kw_only=True)
class ReproduceArgs:
    """What every reproduction receives. ``runs=None`` means the paper's run count.

    ``bag``, ``map`` and ``calibrate_on`` are read by the experiments on ROS 2 bags (a bag, its
    topic mapping, and another bag of the same hardware to calibrate on)."""

    out_dir: Path
    runs: int | None = None
    seed: int = 2026
    dataset: Path | None = None
    executor: str | None = None
    quiet: bool = False
    bag: Path | None = None
    map: Path | None = None
    calibrate_on: Path | None = None

    def __post_init__(self) -> None:
        if self.runs is not None and self.runs < 1:
            raise ConfigError(f"--runs must be ≥ 1, got {self.runs}")
        if self.seed < 0:
            raise ConfigError(f"--seed must be ≥ 0, got {self.seed}")


def available() -> list[str]:
    """Experiment names whose module is installed."""
    return [name for name, mod in EXPERIMENTS.items() if importlib.util.find_spec(mod) is not None]


def get(name: str) -> Callable[[ReproduceArgs], dict[str, Any]]:
    """The ``reproduce`` function of experiment ``name`` (ConfigError if unknown)."""
    if name not in EXPERIMENTS or importlib.util.find_spec(EXPERIMENTS[name]) is None:
        raise ConfigError(f"unknown experiment {name!r}; available: {', '.join(available())}")
    module = importlib.import_module(EXPERIMENTS[name])
    return module.reproduce  # type: ignore[no-any-return]
