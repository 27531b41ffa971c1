"""Names accepted by ``relloc reproduce NAME`` and the module implementing each.

Each module exposes ``reproduce(args: ReproduceArgs) -> dict`` that writes summary.json,
report.md and figures into ``args.out_dir`` and returns the summary.

A module whose runs produce estimates may also write one representative run for ROS tools and
evo (``--mcap``/``--tum``): it states which run in a module constant ``EXPORTED_RUN`` (a
sentence) and, when ``args.export`` is set, writes that run's
:class:`~relloc.core.estimates.Estimates` with its recording through
:func:`relloc.pipeline.export.export_estimates`, putting the returned section under
``summary["export"]``. :func:`exported_run` reads the constant (``None``: nothing to export).

Some of :class:`ReproduceArgs`' inputs are read by only some experiments (:data:`READ_BY`);
:func:`refuse_unread` refuses them for the others (the function :func:`get` returns does so
before it runs), so a flag is never silently ignored.
"""

from __future__ import annotations

import functools
import importlib
import importlib.util
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from relloc.core import checks
from relloc.errors import ConfigError
from relloc.pipeline.montecarlo import MAX_RUNS

if TYPE_CHECKING:
    from relloc.pipeline.export import ExportRequest

EXPERIMENTS: dict[str, str] = {
    "wanasinghe2014": "relloc.experiments.wanasinghe2014",
    "wanasinghe2014-pairs": "relloc.experiments.wanasinghe2014_pairs",
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
    """What every reproduction receives. ``runs=None`` means the paper's run count;
    ``seed=None`` the default master seed :data:`DEFAULT_SEED` (:attr:`master_seed`);
    ``export`` the ``--mcap``/``--tum`` request (module docstring), ``None`` when not asked.

    ``bag``, ``map`` and ``calibrate_on`` are read by the experiments on ROS 2 bags (a bag, its
    topic mapping, and another bag of the same hardware to calibrate on);
    ``calibration_window`` by mrclam-cl (which side of the run its error models are fitted on,
    :func:`relloc.calibration.window.split_span`; ``None``: the experiment's default);
    ``pairs`` by wanasinghe2014 (one ``(observer, observed)`` pair of the dataset's robots for
    its real-trajectory replay) and wanasinghe2014-pairs (the pairs it replays; ``None``: each
    experiment's default); ``sensing`` by desilva2015
    (which simulated robots sense, as ``--sensing`` gives it; ``None``: the paper's leaders)."""

    out_dir: Path
    runs: int | None = None
    seed: int | None = None
    dataset: Path | None = None
    executor: str | None = None
    quiet: bool = False
    export: ExportRequest | None = None
    bag: Path | None = None
    map: Path | None = None
    calibrate_on: Path | None = None
    calibration_window: str | None = None
    pairs: tuple[tuple[int, int], ...] | None = None
    sensing: str | None = None

    def __post_init__(self) -> None:
        if self.runs is not None:
            checks.count(self.runs, "--runs", high=MAX_RUNS)
        if self.seed is not None:
            checks.count(self.seed, "--seed", low=0)
        if self.pairs is not None:
            if not self.pairs:
                raise ConfigError("--pair: at least one pair OBSERVER,OBSERVED")
            for pair in self.pairs:
                if len(pair) != 2 or pair[0] == pair[1]:
                    raise ConfigError(f"--pair: two different robots OBSERVER,OBSERVED, got {pair}")
            if len(set(self.pairs)) != len(self.pairs):
                raise ConfigError(f"--pair: a pair is given twice in {list(self.pairs)}")

    @property
    def master_seed(self) -> int:
        """The seed every random draw of the reproduction derives from."""
        return DEFAULT_SEED if self.seed is None else self.seed


#: The master seed of a reproduction not given ``--seed``.
DEFAULT_SEED = 2026

#: :class:`ReproduceArgs` inputs read by only some experiments → those experiments.
READ_BY: dict[str, tuple[str, ...]] = {
    "seed": tuple(name for name in EXPERIMENTS if name != "tiers-uwb"),  # it draws nothing
    "runs": (
        "wanasinghe2014",
        "wanasinghe-observability",
        "sharma-observability",
        "sharma2013",
        "desilva2015",
        "mrclam-association",
        "guler2023",
    ),
    "executor": tuple(
        name
        for name in EXPERIMENTS
        if name not in ("tiers-uwb", "wanasinghe-observability", "mrclam-association")
    ),  # those three run in this process
    "dataset": ("wanasinghe2014", "wanasinghe2014-pairs", "mrclam-cl", "mrclam-association"),
    "bag": ("tiers-uwb",),
    "map": ("tiers-uwb",),
    "calibrate_on": ("tiers-uwb",),
    "calibration_window": ("mrclam-cl",),
    "pairs": ("wanasinghe2014", "wanasinghe2014-pairs"),
    "sensing": ("desilva2015",),
}

#: The command-line flag of a :class:`ReproduceArgs` input whose name is not its field's.
FLAGS: dict[str, str] = {"pairs": "--pair"}


def refuse_unread(name: str, args: ReproduceArgs) -> None:
    """ConfigError naming the flag when ``args`` sets an input experiment ``name`` does not read
    (:data:`READ_BY`)."""
    given = [field for field in READ_BY if getattr(args, field) is not None]
    checks.refuse_unread(name, given, READ_BY, flags=FLAGS)


def available() -> list[str]:
    """Experiment names whose module is installed."""
    return [name for name, mod in EXPERIMENTS.items() if importlib.util.find_spec(mod) is not None]


def get(name: str) -> Callable[[ReproduceArgs], dict[str, Any]]:
    """The ``reproduce`` function of experiment ``name`` (ConfigError if unknown), which first
    refuses an input the experiment does not read (:func:`refuse_unread`), from the command
    line and from Python alike."""
    if name not in EXPERIMENTS or importlib.util.find_spec(EXPERIMENTS[name]) is None:
        raise ConfigError(f"unknown experiment {name!r}; available: {', '.join(available())}")
    module = importlib.import_module(EXPERIMENTS[name])

    @functools.wraps(module.reproduce)
    def reproduce(args: ReproduceArgs) -> dict[str, Any]:
        refuse_unread(name, args)
        return module.reproduce(args)  # type: ignore[no-any-return]

    return reproduce


def exported_run(name: str) -> str | None:
    """Which run experiment ``name`` writes with ``--mcap``/``--tum``, or ``None`` if it has no
    estimates to write (module docstring)."""
    get(name)
    module = importlib.import_module(EXPERIMENTS[name])
    note = getattr(module, "EXPORTED_RUN", None)
    return note if isinstance(note, str) else None
