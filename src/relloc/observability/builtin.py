"""Built-in models for ``relloc observability MODEL`` and user models from entry points.

``BUILTIN_MODELS`` maps a name to a one-line description; :func:`resolve_models` turns a name
(or ``package.module:function``) plus options into the :class:`SymbolicModel` instances to
analyse. A user entry point is a zero-argument callable returning one
:class:`~relloc.models.symbolic.SymbolicModel` (or a sequence of them).
"""

from __future__ import annotations

import importlib
from collections.abc import Sequence
from dataclasses import dataclass

from relloc.core.checks import count
from relloc.errors import ConfigError, ModelError
from relloc.models import symbolic as S

BUILTIN_MODELS: dict[str, str] = {
    "relative-pseudo-linear": "seed 000 4-DOF pair, pseudo-linear rows of H_pmo "
    "(--measurements range azimuth elevation)",
    "relative-nonlinear": "seed 000 4-DOF pair, nonlinear range/azimuth/elevation "
    "(--measurements range azimuth elevation)",
    "unicycle-landmarks": "one unicycle, bearing and/or range to --landmarks L known landmarks "
    "(--measurements bearing range)",
    "unicycle-team": "seed 001 team of --robots N unicycles, bearing chain 1→2→…→N, robot 1 "
    "sees --landmarks L landmarks, --gps robots",
    "airground": "seed 003 follower model, measurement modes sw = --mode 1 2 3 (default all)",
}


READ_BY: dict[str, tuple[str, ...]] = {
    "measurements": ("relative-pseudo-linear", "relative-nonlinear", "unicycle-landmarks"),
    "landmarks": ("unicycle-landmarks", "unicycle-team"),
    "robots": ("unicycle-team",),
    "gps": ("unicycle-team",),
    "mode": ("airground",),
}
"""The built-in models that read each model option (a user model reads none of them; every
model reads ``--inputs``); another is refused (:func:`relloc.core.checks.refuse_unread`)."""


@dataclass(frozen=True, kw_only=True)
class ModelOptions:
    """Options of the built-in models (validated; defaults per model when ``None``)."""

    measurements: tuple[str, ...] | None = None
    landmarks: int = 1
    robots: int = 3
    gps: tuple[int, ...] = ()
    modes: tuple[int, ...] = S.AIRGROUND_MODES
    inputs: tuple[str, ...] | None = None

    def __post_init__(self) -> None:
        count(self.landmarks, "--landmarks", low=0)
        if count(self.robots, "--robots") > 6:
            raise ConfigError(f"--robots must be in 1..6 for symbolic analysis, got {self.robots}")
        bad = [m for m in self.modes if m not in S.AIRGROUND_MODES]
        if bad or not self.modes:
            raise ConfigError(f"--mode must be among {S.AIRGROUND_MODES}, got {self.modes}")
        bad_gps = [g for g in self.gps if not 1 <= g <= self.robots]
        if bad_gps:
            raise ConfigError(f"--gps robots must be in 1..{self.robots}, got {bad_gps}")


def _load_entry_point(spec: str) -> list[S.SymbolicModel]:
    module_name, _, attr = spec.partition(":")
    if not module_name or not attr:
        raise ConfigError(f"user model must be 'package.module:function', got {spec!r}")
    try:
        module = importlib.import_module(module_name)
    except ImportError as exc:
        raise ConfigError(f"cannot import {module_name!r} for user model {spec!r}: {exc}") from exc
    fn = getattr(module, attr, None)
    if not callable(fn):
        raise ConfigError(f"{spec!r}: {attr!r} is not a callable in {module_name!r}")
    try:
        made = fn()
    except TypeError as exc:  # it needs arguments: not a model factory
        raise ConfigError(f"{spec!r}: calling {attr}() failed ({exc})") from None
    models = list(made) if isinstance(made, (list, tuple)) else [made]
    for m in models:
        if not isinstance(m, S.SymbolicModel):
            raise ModelError(
                f"{spec!r} must return relloc.models.symbolic.SymbolicModel, got {type(m).__name__}"
            )
    return models


def _measurements(
    opts: ModelOptions, default: Sequence[str], allowed: Sequence[str] | None = None
) -> tuple[str, ...]:
    """The measured outputs asked for (``--measurements``), checked against ``allowed``."""
    if not opts.measurements:
        return tuple(default)
    unknown = [m for m in opts.measurements if m not in (allowed or default)]
    if unknown:
        raise ConfigError(
            f"--measurements: unknown {', '.join(map(repr, unknown))}; "
            f"choose from {', '.join(allowed or default)}"
        )
    return tuple(opts.measurements)


def resolve_models(name: str, opts: ModelOptions) -> list[S.SymbolicModel]:
    """The models to analyse for ``name`` (a built-in or ``package.module:function``)."""
    if name == "relative-pseudo-linear":
        models = [S.relative_pseudo_linear(_measurements(opts, S.RELATIVE_MEASUREMENTS))]
    elif name == "relative-nonlinear":
        models = [S.relative_nonlinear(_measurements(opts, S.RELATIVE_MEASUREMENTS))]
    elif name == "unicycle-landmarks":
        measured = _measurements(opts, ("bearing",), allowed=("bearing", "range"))
        if opts.landmarks < 1:
            raise ConfigError(f"--landmarks: {name!r} needs at least 1, got {opts.landmarks}")
        models = [S.unicycle_landmarks(opts.landmarks, measured)]
    elif name == "unicycle-team":
        n = opts.robots
        models = [
            S.unicycle_team(
                n,
                robot_edges=[(i, i + 1) for i in range(1, n)],
                landmark_edges=[(1, k) for k in range(1, opts.landmarks + 1)],
                n_landmarks=opts.landmarks,
                gps=opts.gps,
            )
        ]
    elif name == "airground":
        models = [S.airground_follower(m) for m in opts.modes]
    elif ":" in name:
        models = _load_entry_point(name)
    else:
        raise ConfigError(
            f"unknown model {name!r}; built-ins: {', '.join(BUILTIN_MODELS)}, "
            "or a user model 'package.module:function'"
        )
    if opts.inputs is not None:
        try:
            models = [m.with_inputs(opts.inputs) for m in models]
        except ModelError as exc:
            raise ConfigError(f"--inputs: {exc}") from None
    return models
