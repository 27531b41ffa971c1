"""The fitted models of a recorded team as a JSON file (``fit.json``): what ``relloc team up
MRCLAM_DIR --estimator cooperative`` hands its robots and what ``--fit FILE`` reuses.

:func:`save_fit` writes :class:`~relloc.experiments.mrclam_cl.FittedModels` field by field.
:func:`load_fit` reads it back checked against the same dataclasses, so that a file that was
edited or written by hand fails with a :class:`~relloc.errors.DataError` naming the file and
the key (``camera.sigma_range``): every key known, every value of its declared type (a number
finite, a list of numbers, a window ``{start_s, end_s, source}``), and the values within what
the fits produce — σ, scales, inflation factors and the integration window > 0, variance rates
≥ 0, the latency and time constant inside the grids the odometry fit searches
(:data:`~relloc.calibration.odometry.LATENCY_GRID_S`,
:data:`~relloc.calibration.odometry.TIME_CONSTANT_GRID_S`). :func:`check_fit_for` adds what
needs the recording: one scale, offset and bias per robot, every window inside the recording.

A robot without samples in the odometry fit's window keeps scales of 1, which are not a fit:
``odometry.unfitted_robots`` lists such robots' subjects. The key is optional — written only
where a robot is unfitted, and read as none when absent — so files of a team fitted robot by
robot are the same as before the key existed, and every file written before it is still read.
"""

from __future__ import annotations

import dataclasses
import json
import math
import types
import typing
from pathlib import Path
from typing import Any

import numpy as np

from relloc.calibration.camera import BEARING_BIAS_TERMS as BIAS_TERMS
from relloc.calibration.odometry import LATENCY_GRID_S, TIME_CONSTANT_GRID_S
from relloc.calibration.window import CalibrationWindow
from relloc.errors import ConfigError, DataError
from relloc.experiments.mrclam_cl import FittedModels
from relloc.models.planar_measurement import RANGE_BIAS_FEATURES
from relloc.pipeline.output import write_json_file

MAX_FIT_BYTES = 1 << 20
"""Largest fit file read (a saved fit is a few kB)."""


def save_fit(fit: FittedModels, path: Path) -> None:
    """The fitted models as JSON (every value a number, a list, a string or a window);
    ``odometry.unfitted_robots`` only where it lists a robot (module docstring)."""
    raw = dataclasses.asdict(fit)
    if not fit.odometry.unfitted_robots:
        del raw["odometry"]["unfitted_robots"]
    write_json_file(path, raw, "--out")


def load_fit(path: Path) -> FittedModels:
    """The models :func:`save_fit` wrote; anything else is a DataError naming the file and key."""
    path = Path(path)
    try:
        if path.stat().st_size > MAX_FIT_BYTES:
            raise DataError(f"{path}: larger than {MAX_FIT_BYTES} bytes; not a fit file")
        raw = json.loads(path.read_text())
    except (OSError, ValueError, RecursionError) as exc:
        raise DataError(f"{path}: not the fitted models of relloc team up ({exc})") from None
    fit = _record(FittedModels, raw, f"{path}: ")
    _check_ranges(fit, f"{path}: ")
    return fit


def check_fit_for(fit: FittedModels, robots: int, span: tuple[float, float], where: str) -> None:
    """Raise a DataError (``where`` names the file) unless ``fit`` is of a team of ``robots``
    robots and its windows lie inside the recording's ``span`` (s)."""
    o, c = fit.odometry, fit.camera
    lengths = {
        "odometry.scale_v": (len(o.scale_v), (robots,)),
        "odometry.scale_w": (len(o.scale_w), (robots,)),
        "camera.bearing_offset": (len(c.bearing_offset), (robots,)),
        "camera.bearing_bias_coeffs": (len(c.bearing_bias_coeffs), (0, BIAS_TERMS * robots)),
        "camera.bearing_bias_limits": (len(c.bearing_bias_limits), (0, 2 * robots)),
    }
    for key, (n, allowed) in lengths.items():
        if n not in allowed:
            raise DataError(
                f"{where}{key}: {n} values, for a team of {robots} robots "
                f"{' or '.join(map(str, allowed))}"
            )
    lo, hi = span
    for key, w in _windows(fit):
        if w.start_s < lo - 1e-6 or w.end_s > hi + 1e-6:
            raise DataError(
                f"{where}{key}: {w.describe()} is not inside the recording [{lo:.2f}, {hi:.2f}] s"
            )


def _windows(fit: FittedModels) -> list[tuple[str, CalibrationWindow]]:
    inflation = fit.odometry_inflation
    found = [
        ("odometry.calibration_window", fit.odometry.calibration_window),
        ("camera.calibration_window", fit.camera.calibration_window),
        ("odometry_inflation.fitted_on", inflation.fitted_on),
        ("odometry_inflation.checked_on", inflation.checked_on),
    ]
    return [(key, w) for key, w in found if w is not None]


def _check_ranges(fit: FittedModels, where: str) -> None:
    o, c, k = fit.odometry, fit.camera, fit.odometry_inflation
    positive = {
        "odometry.odometry_window_s": o.odometry_window_s,
        "camera.sigma_bearing_raw": c.sigma_bearing_raw,
        "camera.bearing_inflation": c.bearing_inflation,
        "camera.sigma_bearing": c.sigma_bearing,
        "camera.sigma_range_raw": c.sigma_range_raw,
        "camera.range_inflation": c.range_inflation,
        "camera.sigma_range": c.sigma_range,
        "camera.range_interval_s": c.range_interval_s,
        "odometry_inflation.k": k.k,
        **{f"odometry.scale_v[{i}]": v for i, v in enumerate(o.scale_v)},
        **{f"odometry.scale_w[{i}]": v for i, v in enumerate(o.scale_w)},
    }
    for key, value in positive.items():
        if not value > 0:
            raise DataError(f"{where}{key}: must be > 0, got {value}")
    unfitted = o.unfitted_robots
    if (
        len(set(unfitted)) != len(unfitted)
        or len(unfitted) > len(o.scale_v)
        or min(unfitted, default=1) < 1
    ):
        raise DataError(
            f"{where}odometry.unfitted_robots: expected distinct robot subjects (≥ 1), at most "
            f"one per scale, got {list(unfitted)}"
        )
    rates = {"q_v0": o.q_v0, "k_v": o.k_v, "q_w0": o.q_w0, "k_w": o.k_w, "k_wv": o.k_wv}
    for key, value in rates.items():
        if not value >= 0:
            raise DataError(f"{where}odometry.{key}: must be ≥ 0, got {value}")
    grids = {
        "latency_s": (o.latency_s, np.asarray(LATENCY_GRID_S)),
        "time_constant_s": (o.time_constant_s, np.asarray(TIME_CONSTANT_GRID_S)),
    }
    for key, (value, grid) in grids.items():
        lo, hi = float(grid.min()), float(grid.max())
        if not lo - 1e-9 <= value <= hi + 1e-9:
            raise DataError(
                f"{where}odometry.{key}: {value} s is outside [{lo:g}, {hi:g}] s, where the fit "
                "searches"
            )
    if not 1 <= len(c.range_bias_coeffs) <= len(RANGE_BIAS_FEATURES):
        raise DataError(
            f"{where}camera.range_bias_coeffs: {len(c.range_bias_coeffs)} values; 1 to "
            f"{len(RANGE_BIAS_FEATURES)} coefficients of {', '.join(RANGE_BIAS_FEATURES)}"
        )
    if c.n_residuals < 0 or not 0 < k.target_percent < 100:
        raise DataError(
            f"{where}camera.n_residuals must be ≥ 0 and odometry_inflation.target_percent in "
            f"(0, 100), got {c.n_residuals} and {k.target_percent}"
        )


def _record(cls: Any, raw: Any, where: str) -> Any:
    """``cls`` (a dataclass) from the JSON object ``raw``, each field read as its declared type."""
    if not isinstance(raw, dict):
        raise DataError(f"{where.rstrip(': .')}: expected an object, got {_kind(raw)}")
    hints = typing.get_type_hints(cls)
    known = {f.name: f for f in dataclasses.fields(cls)}
    unknown = sorted(set(raw) - set(known))
    if unknown:
        raise DataError(f"{where}{unknown[0]}: unknown key; expected one of {', '.join(known)}")
    values = {}
    for name, f in known.items():
        if name in raw:
            values[name] = _value(hints[name], raw[name], f"{where}{name}")
        elif f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING:
            raise DataError(f"{where}{name}: missing")
    try:
        return cls(**values)
    except ConfigError as exc:  # a window's own checks
        raise DataError(f"{where.rstrip(': .')}: {exc}") from None


def _value(hint: Any, raw: Any, where: str) -> Any:
    """``raw`` read as type ``hint`` (the field types of the fit's dataclasses)."""
    origin, args = typing.get_origin(hint), typing.get_args(hint)
    if origin in (typing.Union, types.UnionType):  # X | None
        inner = [a for a in args if a is not type(None)]
        return None if raw is None else _value(inner[0], raw, where)
    if dataclasses.is_dataclass(hint):
        return _record(hint, raw, f"{where}.")
    if origin is tuple:
        if not isinstance(raw, list):
            raise DataError(f"{where}: expected a list, got {_kind(raw)}")
        items = args[:1] * len(raw) if args[-1] is Ellipsis else args
        if len(items) != len(raw):
            raise DataError(f"{where}: expected {len(items)} values, got {len(raw)}")
        return tuple(
            _value(a, r, f"{where}[{i}]") for i, (a, r) in enumerate(zip(items, raw, strict=True))
        )
    if origin is dict:
        if not isinstance(raw, dict):
            raise DataError(f"{where}: expected an object, got {_kind(raw)}")
        return {str(k): _value(args[1], v, f"{where}.{k}") for k, v in raw.items()}
    ok = {
        float: isinstance(raw, (int, float)) and not isinstance(raw, bool),
        int: isinstance(raw, int) and not isinstance(raw, bool),
        bool: isinstance(raw, bool),
        str: isinstance(raw, str),
    }[hint]
    if not ok:
        raise DataError(f"{where}: expected {hint.__name__}, got {_kind(raw)}")
    if hint is not float:
        return raw
    try:
        value = float(raw)
    except OverflowError:
        value = math.inf
    if not math.isfinite(value):
        raise DataError(f"{where}: must be a finite number, got {raw}")
    return value


def _kind(raw: Any) -> str:
    return {dict: "an object", list: "a list", str: "a string", type(None): "null"}.get(
        type(raw), repr(raw)
    )
