"""The :class:`Recording`: what a team sensed — the one input type of every estimator.

Every simulator (all four seeds) and every loader (MRCLAM, the UWB CSV, bags) produces a
:class:`Recording`; :func:`relloc.pipeline.replay.replay` feeds it to any estimator. It holds,
for the robots ``0 … n−1`` named in :attr:`Recording.robots`:

- :class:`Odometry` per robot — body-frame velocities ``u = (v_x, v_y, v_z, ω_z)`` with their
  time stamps and the standard deviation of their noise; ``velocity[k]`` is held over
  ``[t[k], t[k+1])`` (zero-order hold); a unicycle reports ``(v, 0, 0, ω)``;
- one :class:`Measurements` table of everything the sensors measured, one row per reading:
  ``t``, ``kind`` (a :data:`KINDS` name, which fixes the meaning of the ``value`` columns),
  ``observer`` and ``sensor`` (which of the observer's sensors, 0 for the first), ``target``
  (a robot index, or :data:`NO_TARGET` when the reading is of a landmark, is absolute, or has
  *unknown correspondence*), ``landmark`` (an index into :attr:`Recording.landmarks` or
  :data:`NO_TARGET`), ``value`` and ``sigma`` (the sensor's stated standard deviation per
  column, NaN when the sensor states none) and ``origin`` — who really produced the reading (a
  robot index, :data:`CLUTTER`, or :data:`ORIGIN_UNKNOWN`), which only scoring may read, never
  an estimator;
- optional :class:`GroundTruth` per robot — poses ``(x, y, z, ψ)`` in one world frame;
- optional static landmarks ``(L, 3)`` world positions;
- ``meta`` (what the loader or simulator wants to state) and ``skips`` (the loader's
  :class:`SkipReport`: rows read, kept and skipped per file and reason).

Every array is validated on construction (shapes, finite numbers, strictly increasing time for
truth and odometry, non-decreasing time for measurements, no duplicated reading of a known
target, indices in range — a negative index only where it is a sentinel: ``target`` and
``landmark`` −1 (:data:`NO_TARGET`), ``origin`` −1 or −2 (:data:`CLUTTER`,
:data:`ORIGIN_UNKNOWN`)); a violation raises :class:`relloc.errors.DataError` naming the field
and the first offending row.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from numbers import Real
from types import MappingProxyType
from typing import Any

import numpy as np
from numpy.typing import NDArray

from relloc.core import checks
from relloc.core.angles import circular_interp, wrap_angle
from relloc.core.limits import MAX_SENSOR_RANGE_M
from relloc.errors import ConfigError, DataError

Array = NDArray[np.float64]
IntArray = NDArray[np.int64]
BoolArray = NDArray[np.bool_]

POSE_FIELDS = ("x", "y", "z", "yaw")
VELOCITY_FIELDS = ("v_x", "v_y", "v_z", "w_z")
PLATFORMS = ("ground", "aerial")

#: ``target`` / ``landmark`` of a row that names no robot / no landmark.
NO_TARGET = -1
#: ``origin`` of a false reading (clutter).
CLUTTER = -1
#: ``origin`` when the truth about a reading is not known (real data, unknown correspondence).
ORIGIN_UNKNOWN = -2

#: Width of the ``value`` and ``sigma`` columns (the widest kind).
VALUE_WIDTH = 3


@dataclass(frozen=True)
class MeasurementKind:
    """What the ``value`` columns of a row of this kind mean.

    ``fields`` name the columns in order (the rest of the row is NaN); ``angles`` are the
    columns that are angles (wrapped in residuals); ``positive`` the columns that must be > 0;
    ``needs_target``: ``"robot"`` (a known robot), ``"robot_or_landmark_or_unknown"``,
    ``"none"`` (absolute readings such as a GPS fix).
    """

    name: str
    fields: tuple[str, ...]
    angles: tuple[int, ...] = ()
    positive: tuple[int, ...] = ()
    needs_target: str = "robot_or_landmark_or_unknown"

    @property
    def dim(self) -> int:
        return len(self.fields)


#: Every kind of reading relloc understands, by name.
KINDS: Mapping[str, MeasurementKind] = MappingProxyType(
    {
        k.name: k
        for k in (
            # range, azimuth and elevation of a robot in the observer's body frame (seed 000 Eq. 2)
            MeasurementKind(
                "range_bearing_elevation", ("range", "azimuth", "elevation"), (1, 2), (0,)
            ),
            # planar range and bearing (MRCLAM camera, seed 001)
            MeasurementKind("range_bearing", ("range", "bearing"), (1,), (0,)),
            # planar bearing only (seed 001)
            MeasurementKind("bearing", ("bearing",), (0,)),
            # azimuth and elevation without range (seed 002's bearing sensor)
            MeasurementKind("bearing_elevation", ("azimuth", "elevation"), (0, 1)),
            # range only (UWB; seed 002's and seed 003's range sensors)
            MeasurementKind("range", ("range",), (), (0,)),
            # height of the target above the observer (seed 002's altimeter exchange)
            MeasurementKind("height", ("height",), needs_target="robot"),
            # absolute planar pose fix (GPS-like, seed 001)
            MeasurementKind("pose", ("x", "y", "yaw"), (2,), needs_target="none"),
            # a drone's reading of the pair {leader, target}: bearing of p_leader − p_target in
            # the world frame and both headings (seed 003)
            MeasurementKind(
                "pair_sighting",
                ("bearing", "heading_target", "heading_leader"),
                (0, 1, 2),
                needs_target="robot",
            ),
        )
    }
)
KIND_NAMES: tuple[str, ...] = tuple(KINDS)


def kind_code(name: str) -> int:
    """The integer code stored in :attr:`Measurements.kind` for the kind ``name``."""
    try:
        return KIND_NAMES.index(name)
    except ValueError:
        raise DataError(
            f"unknown measurement kind {name!r}; known: {', '.join(KIND_NAMES)}"
        ) from None


def _float_array(
    value: object, shape_tail: tuple[int, ...], where: str, *, nan_ok: bool = False
) -> Array:
    arr = checks.floats(value, where)
    if arr.ndim != 1 + len(shape_tail) or arr.shape[1:] != shape_tail:
        expected = "(N" + "".join(f", {d}" for d in shape_tail) + ")"
        raise DataError(f"{where}: expected shape {expected}, got {arr.shape}")
    bad = np.isinf(arr) if nan_ok else ~np.isfinite(arr)
    if bad.any():
        row = int(np.argwhere(bad)[0][0])
        raise DataError(f"{where}: non-finite value in row {row}")
    arr = np.array(arr, copy=True)
    arr.setflags(write=False)
    return arr


def _int_array(value: object, n: int, where: str) -> IntArray:
    raw = np.asarray(value)
    if raw.ndim != 1 or (raw.size and not np.issubdtype(raw.dtype, np.integer)):
        raise DataError(f"{where}: expected a 1-D integer array")
    if raw.shape[0] != n:
        raise DataError(f"{where}: {raw.shape[0]} rows but {n} timestamps")
    arr = np.array(raw, dtype=np.int64, copy=True)
    arr.setflags(write=False)
    return arr


def _check_times(t: Array, where: str, *, strict: bool) -> None:
    if t.size == 0:
        return
    d = np.diff(t)
    bad = d <= 0 if strict else d < 0
    if bad.any():
        row = int(np.argmax(bad)) + 1
        kind = "strictly increasing" if strict else "sorted (non-decreasing)"
        raise DataError(
            f"{where}: timestamps must be {kind}; row {row} has t={t[row]!r} after t={t[row - 1]!r}"
        )


@dataclass(frozen=True, kw_only=True)
class GroundTruth:
    """True poses of one robot: ``t (N,)`` strictly increasing, ``pose (N, 4)`` = (x, y, z, ψ).

    ``gap_s``: samples further apart than this enclose a gap of the recording (e.g. a motion
    capture dropout), across which :meth:`at` interpolates but :meth:`valid_at` says no.
    """

    t: Array
    pose: Array
    where: str = field(default="truth", compare=False, repr=False)
    gap_s: float = math.inf

    def __post_init__(self) -> None:
        t = _float_array(self.t, (), f"{self.where}.t")
        pose = _float_array(self.pose, (4,), f"{self.where}.pose")
        if pose.shape[0] != t.shape[0]:
            raise DataError(f"{self.where}: {t.shape[0]} timestamps but {pose.shape[0]} poses")
        if t.size < 2:
            raise DataError(f"{self.where}: at least two samples are needed, got {t.size}")
        _check_times(t, f"{self.where}.t", strict=True)
        gap = self.gap_s  # (a number > 0; inf, the default, is no gap at all)
        if isinstance(gap, bool) or not isinstance(gap, Real) or not gap > 0:
            raise DataError(f"{self.where}.gap_s: must be a number > 0, got {gap!r:.40}")
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "pose", pose)

    def valid_at(self, t: Array | float) -> NDArray[np.bool_]:
        """Whether each time ``t`` is a sample or lies between two samples at most ``gap_s``
        apart (a pose there is measured, not bridged over a gap or extrapolated); a NaN time is
        not. Times that are not numbers, or not 1-D: DataError."""
        tq = _query_times(t, self.where, nan_ok=True)
        hi = np.clip(np.searchsorted(self.t, tq, side="left"), 1, self.t.size - 1)
        inside = (tq >= self.t[0]) & (tq <= self.t[-1])
        bridged = self.t[hi] - self.t[hi - 1] <= self.gap_s
        sample = (self.t[hi] == tq) | (self.t[hi - 1] == tq)
        return np.asarray(inside & (bridged | sample))

    def at(self, t: Array | float) -> Array:
        """Poses interpolated at times ``t`` (linear in x, y, z; on the circle in ψ).

        Times outside ``[t[0], t[-1]]``, or NaN, raise :class:`DataError` (no extrapolation).
        """
        tq = _query_times(t, self.where)
        if tq.size and (tq.min() < self.t[0] - 1e-9 or tq.max() > self.t[-1] + 1e-9):
            raise DataError(
                f"{self.where}: query time outside the recorded span "
                f"[{self.t[0]:.6g}, {self.t[-1]:.6g}]: [{tq.min():.6g}, {tq.max():.6g}]"
            )
        out = np.empty((tq.size, 4))
        for j in range(3):
            out[:, j] = np.interp(tq, self.t, self.pose[:, j])
        out[:, 3] = circular_interp(tq, self.t, self.pose[:, 3], assume_sorted=True)
        return out


@dataclass(frozen=True, kw_only=True)
class Odometry:
    """Body-frame velocities of one robot: ``t (K,)``, ``velocity (K, 4)`` = (v_x, v_y, v_z, ω_z).

    ``velocity[k]`` applies over ``[t[k], t[k+1])``. ``sigma (4,)`` is the standard deviation of
    the white noise on each channel (0 for a channel known exactly, e.g. v_y of a unicycle). A
    robot that never reported odometry has ``K = 0`` and stands still.
    """

    t: Array
    velocity: Array
    sigma: Array
    where: str = field(default="odometry", compare=False, repr=False)

    def __post_init__(self) -> None:
        t = _float_array(self.t, (), f"{self.where}.t")
        vel = _float_array(self.velocity, (4,), f"{self.where}.velocity")
        sigma = _float_array(np.reshape(self.sigma, (1, -1)), (4,), f"{self.where}.sigma")[0]
        if vel.shape[0] != t.shape[0]:
            raise DataError(f"{self.where}: {t.shape[0]} timestamps but {vel.shape[0]} velocities")
        if np.any(sigma < 0):
            raise DataError(f"{self.where}.sigma: standard deviations must be ≥ 0, got {sigma}")
        _check_times(t, f"{self.where}.t", strict=True)
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "velocity", vel)
        object.__setattr__(self, "sigma", sigma)

    def held_at(self, t: Array | float) -> Array:
        """Zero-order-hold velocities at times ``t``: the last sample at or before each time.

        Times before the first sample get zero velocity (the robot has not reported motion yet);
        a NaN time is a :class:`DataError`.
        """
        tq = _query_times(t, self.where)
        idx = np.searchsorted(self.t, tq, side="right") - 1
        out = np.zeros((tq.size, 4))
        ok = idx >= 0
        out[ok] = self.velocity[idx[ok]]
        return out

    def stamp_at(self, t: Array | float) -> Array:
        """Time stamp of the sample held at each time ``t`` (NaN before the first sample)."""
        tq = _query_times(t, self.where)
        idx = np.searchsorted(self.t, tq, side="right") - 1
        out = np.full(tq.size, np.nan)
        ok = idx >= 0
        out[ok] = self.t[idx[ok]]
        return out


def _query_times(t: Array | float, where: str, *, nan_ok: bool = False) -> Array:
    """``t`` as a 1-D float array; a NaN time (which compares false with every bound, so it
    would pass any span check) unless ``nan_ok``, a time that is not a number or times of more
    than one axis are a DataError naming ``where``."""
    tq = np.atleast_1d(checks.floats(t, f"{where}: query times"))
    if tq.ndim != 1:
        raise DataError(f"{where}: query times must be a number or 1-D, got shape {tq.shape}")
    if not nan_ok and np.isnan(tq).any():
        raise DataError(f"{where}: a query time is NaN")
    return tq


@dataclass(frozen=True, kw_only=True)
class Measurements:
    """Every reading of a team, one row each, sorted by time (module docstring).

    ``t (M,)``; ``kind (M,)`` codes into :data:`KIND_NAMES`; ``observer``, ``target``,
    ``landmark``, ``origin (M,)`` integer indices; ``value (M, 3)`` and ``sigma (M, 3)`` with the
    columns beyond the kind's width NaN. ``origin`` defaults to ``target`` where the target is a
    robot and to :data:`ORIGIN_UNKNOWN` elsewhere. Indices are ≥ 0 but for the sentinels
    (``target``/``landmark`` −1, ``origin`` −1 or −2); any other negative index is refused.
    """

    t: Array
    kind: IntArray
    observer: IntArray
    target: IntArray
    value: Array
    sigma: Array
    landmark: IntArray | None = None
    origin: IntArray | None = None
    sensor: IntArray | None = None

    def __post_init__(self) -> None:
        t = _float_array(self.t, (), "measurements.t")
        n = t.shape[0]
        kind = _int_array(self.kind, n, "measurements.kind")
        observer = _int_array(self.observer, n, "measurements.observer")
        target = _int_array(self.target, n, "measurements.target")
        landmark = _int_array(
            np.full(n, NO_TARGET, dtype=np.int64) if self.landmark is None else self.landmark,
            n,
            "measurements.landmark",
        )
        sensor = _int_array(
            np.zeros(n, dtype=np.int64) if self.sensor is None else self.sensor,
            n,
            "measurements.sensor",
        )
        if np.any(sensor < 0):
            raise DataError(f"measurements.sensor: row {int(np.argmax(sensor < 0))} is < 0")
        default_origin = np.where(target >= 0, target, ORIGIN_UNKNOWN).astype(np.int64)
        origin = _int_array(
            default_origin if self.origin is None else self.origin, n, "measurements.origin"
        )
        value = _float_array(self.value, (VALUE_WIDTH,), "measurements.value", nan_ok=True)
        sigma = _float_array(self.sigma, (VALUE_WIDTH,), "measurements.sigma", nan_ok=True)
        for name, column in (("value", value), ("sigma", sigma)):
            if column.shape[0] != n:
                raise DataError(f"measurements.{name}: {column.shape[0]} rows but {n} timestamps")
        _check_times(t, "measurements.t", strict=False)
        bad_kind = (kind < 0) | (kind >= len(KIND_NAMES))
        if bad_kind.any():
            row = int(np.argmax(bad_kind))
            raise DataError(f"measurements.kind: row {row} has unknown kind code {kind[row]}")
        for code in np.unique(kind):
            _check_kind_rows(KINDS[KIND_NAMES[code]], kind == code, value, sigma, target, landmark)
        if np.any(observer < 0):
            raise DataError(f"measurements.observer: row {int(np.argmax(observer < 0))} is < 0")
        for name, ids, lowest, sentinels in (
            ("target", target, NO_TARGET, "−1 (no target)"),
            ("landmark", landmark, NO_TARGET, "−1 (no landmark)"),
            ("origin", origin, ORIGIN_UNKNOWN, "−1 (clutter) or −2 (unknown)"),
        ):
            below = ids < lowest
            if below.any():  # an estimator would read it as unknown without a word
                row = int(np.argmax(below))
                raise DataError(
                    f"measurements.{name}: row {row} is {int(ids[row])}; the only negative "
                    f"{name} is {sentinels}"
                )
        same = observer == target
        if same.any():
            raise DataError(f"measurements: row {int(np.argmax(same))} has observer == target")
        known = (target >= 0) | (landmark >= 0)
        if n > 1 and known.sum() > 1:
            rows = np.flatnonzero(known)
            key = np.stack(
                [t[rows], kind[rows], observer[rows], sensor[rows], target[rows], landmark[rows]],
                axis=1,
            )
            order = np.lexsort(key.T[::-1])
            dup = np.all(np.diff(key[order], axis=0) == 0, axis=1)
            if dup.any():
                row = int(rows[order[int(np.argmax(dup)) + 1]])
                raise DataError(
                    f"measurements: row {row} repeats (t, kind, observer, sensor, target, "
                    "landmark) of another row"
                )
        for name, arr in (
            ("t", t),
            ("kind", kind),
            ("observer", observer),
            ("target", target),
            ("landmark", landmark),
            ("origin", origin),
            ("sensor", sensor),
            ("value", value),
            ("sigma", sigma),
        ):
            object.__setattr__(self, name, arr)

    @property
    def size(self) -> int:
        return int(self.t.shape[0])

    def __len__(self) -> int:
        return self.size

    def select(self, mask: BoolArray | IntArray | slice) -> Measurements:
        """The rows picked by a boolean mask, an index array or a slice (order kept).

        Rows of a valid table taken in their order (a mask, a slice, or strictly increasing
        indices) form a valid table, so they are not checked again (the replay loop slices its
        table at every event); any other index array builds a new, checked table.

        A mask must have one entry per row; an index array must be 1-D and of integers in
        ``[−size, size)`` (negative indices count from the end, as in numpy). A scalar, a float
        index, an index out of range or a mask of another length is a :class:`DataError`.
        """
        assert self.landmark is not None and self.origin is not None and self.sensor is not None
        pick: slice | NDArray[Any]
        if isinstance(mask, slice):
            pick, ordered = mask, (mask.step or 1) > 0
        else:
            pick = np.asarray(mask)
            if pick.size == 0 and pick.ndim == 1:
                pick = pick.astype(np.int64)  # [] is float to numpy: no rows
            if pick.ndim != 1 or pick.dtype.kind not in "biu":
                raise DataError(
                    "measurements.select: expected a slice, a boolean mask or a 1-D integer "
                    f"index array, got {pick.dtype} of shape {pick.shape}"
                )
            if pick.dtype == np.bool_ and pick.shape != self.t.shape:
                raise DataError(f"measurements.select: mask of {pick.shape} for {self.size} rows")
            ordered = pick.dtype == np.bool_ or pick.size < 2 or bool(np.all(np.diff(pick) > 0))
        try:  # (numpy checks the index range; no pass of its own over the indices)
            columns = {name: getattr(self, name)[pick] for name in _MEASUREMENT_COLUMNS}
        except IndexError as exc:
            raise DataError(
                f"measurements.select: an index is out of range for {self.size} rows ({exc})"
            ) from None
        if not ordered:
            return Measurements(**columns)
        out = object.__new__(Measurements)
        for name, column in columns.items():
            column.setflags(write=False)
            object.__setattr__(out, name, column)
        return out

    def of_kind(self, *names: str) -> Measurements:
        """Only the rows of the named kinds."""
        return self.select(np.isin(self.kind, [kind_code(k) for k in names]))

    def kind_names(self) -> tuple[str, ...]:
        """The kind name of every row."""
        return tuple(KIND_NAMES[int(k)] for k in self.kind)

    def values(self, name: str) -> Array:
        """``(M, dim)`` values of the rows of kind ``name`` (the other columns dropped)."""
        return np.asarray(self.of_kind(name).value[:, : KINDS[name].dim])

    @staticmethod
    def concatenate(parts: Iterable[Measurements]) -> Measurements:
        """Rows of every part, sorted by time (stable: equal times keep the parts' order).

        ``parts`` is any iterable of tables (a generator is read once); anything else — a lone
        table, ``None``, a part that is not a :class:`Measurements` — is a :class:`DataError`.
        """
        if isinstance(parts, Measurements) or not isinstance(parts, Iterable):
            raise DataError(
                "measurements.concatenate: expected a sequence of Measurements tables, got "
                f"{type(parts).__name__}"
            )
        parts = tuple(parts)
        for i, part in enumerate(parts):
            if not isinstance(part, Measurements):
                raise DataError(
                    f"measurements.concatenate: part {i} is a {type(part).__name__}, "
                    "not a Measurements table"
                )
        if not parts:
            return empty_measurements()
        t = np.concatenate([p.t for p in parts])
        order = np.argsort(t, kind="stable")

        def cat(name: str) -> NDArray[Any]:
            return np.concatenate([getattr(p, name) for p in parts])[order]

        return Measurements(
            t=t[order],
            kind=cat("kind"),
            observer=cat("observer"),
            target=cat("target"),
            value=cat("value"),
            sigma=cat("sigma"),
            landmark=cat("landmark"),
            origin=cat("origin"),
            sensor=cat("sensor"),
        )


_MEASUREMENT_COLUMNS = (
    "t",
    "kind",
    "observer",
    "target",
    "value",
    "sigma",
    "landmark",
    "origin",
    "sensor",
)


def _check_kind_rows(
    spec: MeasurementKind,
    rows: BoolArray,
    value: Array,
    sigma: Array,
    target: IntArray,
    landmark: IntArray,
) -> None:
    """Validate the rows of one kind: used columns finite, the rest NaN, ranges in
    ``(0, MAX_SENSOR_RANGE_M]``, σ > 0."""
    where = f"measurements ({spec.name})"
    idx = np.flatnonzero(rows)
    used, unused = value[idx, : spec.dim], value[idx, spec.dim :]
    if not np.isfinite(used).all():
        row = int(idx[np.argwhere(~np.isfinite(used))[0][0]])
        raise DataError(f"{where}: row {row} has a non-finite {spec.fields} value")
    if unused.size and not np.isnan(unused).all():
        row = int(idx[np.argwhere(~np.isnan(unused))[0][0]])
        raise DataError(f"{where}: row {row} has values beyond the kind's {spec.dim} columns")
    for col in spec.positive:
        bad = ~(value[idx, col] > 0)
        if bad.any():
            raise DataError(f"{where}: row {int(idx[np.argmax(bad)])} has {spec.fields[col]} ≤ 0")
        far = value[idx, col] > MAX_SENSOR_RANGE_M  # a logging fault; it overflows a filter
        if far.any():
            raise DataError(
                f"{where}: row {int(idx[np.argmax(far)])} has {spec.fields[col]} "
                f"{value[idx[np.argmax(far)], col]:g} beyond {MAX_SENSOR_RANGE_M:g} m"
            )
    s = sigma[idx, : spec.dim]
    bad_sigma = ~np.isnan(s) & ~(s > 0)
    if bad_sigma.any():
        row = int(idx[np.argwhere(bad_sigma)[0][0]])
        raise DataError(f"{where}: row {row} has a standard deviation ≤ 0")
    if sigma[idx, spec.dim :].size and not np.isnan(sigma[idx, spec.dim :]).all():
        raise DataError(f"{where}: σ given beyond the kind's {spec.dim} columns")
    has_robot, has_landmark = target[idx] >= 0, landmark[idx] >= 0
    if (has_robot & has_landmark).any():
        row = int(idx[np.argmax(has_robot & has_landmark)])
        raise DataError(f"{where}: row {row} names both a robot and a landmark")
    if spec.needs_target == "robot" and not has_robot.all():
        row = int(idx[np.argmax(~has_robot)])
        raise DataError(f"{where}: row {row} needs a target robot")
    if spec.needs_target == "none" and (has_robot | has_landmark).any():
        row = int(idx[np.argmax(has_robot | has_landmark)])
        raise DataError(f"{where}: row {row} is absolute and must name no target")


def empty_measurements() -> Measurements:
    """A measurement table with no rows."""
    z = np.zeros(0, dtype=np.int64)
    return Measurements(
        t=np.zeros(0),
        kind=z,
        observer=z,
        target=z,
        value=np.zeros((0, VALUE_WIDTH)),
        sigma=np.zeros((0, VALUE_WIDTH)),
    )


def measurement_rows(
    kind: str,
    *,
    t: Array,
    observer: IntArray | int,
    value: Array,
    sigma: Array | None = None,
    target: IntArray | int = NO_TARGET,
    landmark: IntArray | int = NO_TARGET,
    origin: IntArray | None = None,
    sensor: IntArray | int = 0,
) -> Measurements:
    """A table of rows of one kind: ``value (M, dim)``, ``sigma (M, dim)`` or ``(dim,)``
    (NaN-padded to the table width); scalars broadcast to every row. An argument that is not
    of that shape, or an index that is not an integer, is a DataError naming it."""
    if not isinstance(kind, str):
        raise DataError(f"measurement_rows: kind {kind!r:.40} is not a kind's name")
    spec = KINDS[KIND_NAMES[kind_code(kind)]]  # an unknown name raises, naming the known ones

    def numbers(x: object, shape: tuple[int, ...], name: str, *, reshape: bool = False) -> Array:
        """``x`` as floats of ``shape``: reshaped (same size) or broadcast (from fewer)."""
        arr = checks.floats(x, f"measurement_rows: {name}")
        try:
            return arr.reshape(shape) if reshape else np.broadcast_to(arr, shape).copy()
        except ValueError as exc:
            raise DataError(f"measurement_rows: {name} is not {shape} numbers ({exc})") from None

    t = numbers(t, (-1,), "t", reshape=True)
    m = t.size
    padded = np.full((m, VALUE_WIDTH), np.nan)
    padded[:, : spec.dim] = numbers(value, (m, spec.dim), "value", reshape=True)
    s = np.full((m, VALUE_WIDTH), np.nan)
    if sigma is not None:
        s[:, : spec.dim] = numbers(sigma, (m, spec.dim), "sigma")

    def ints(x: IntArray | int, name: str) -> IntArray:
        arr = numbers(x, (m,), name)
        if not np.all(arr == np.round(arr)):
            raise DataError(f"measurement_rows: {name} must hold integer indices, got {x!r:.60}")
        return arr.astype(np.int64)

    return Measurements(
        t=t,
        kind=np.full(m, kind_code(kind), dtype=np.int64),
        observer=ints(observer, "observer"),
        target=ints(target, "target"),
        value=padded,
        sigma=s,
        landmark=ints(landmark, "landmark"),
        origin=None if origin is None else ints(origin, "origin"),
        sensor=ints(sensor, "sensor"),
    )


@dataclass(frozen=True)
class SkippedRow:
    """One example of a skipped row: 1-based line number, reason and the raw text."""

    line: int
    reason: str
    text: str


@dataclass(frozen=True)
class FileSkips:
    """What a loader did with the rows of one file: read = kept + skipped (by reason).

    The counts are integers ≥ 0, ``skipped`` a mapping of reasons to counts and ``examples``
    :class:`SkippedRow` items; anything else is a ConfigError naming the field."""

    file: str
    rows_read: int
    rows_kept: int
    skipped: Mapping[str, int] = field(default_factory=dict)
    examples: tuple[SkippedRow, ...] = ()

    def __post_init__(self) -> None:
        where = f"FileSkips({self.file!r:.60})"
        checks.count(self.rows_read, f"{where}.rows_read", low=0)
        checks.count(self.rows_kept, f"{where}.rows_kept", low=0)
        if not isinstance(self.skipped, Mapping):
            raise ConfigError(f"{where}.skipped: expected a mapping of reasons to counts")
        for reason, n in self.skipped.items():
            checks.count(n, f"{where}.skipped[{reason!r}]", low=0)
        for i, e in enumerate(self.examples):
            if not isinstance(e, SkippedRow):
                raise ConfigError(f"{where}.examples[{i}]: expected a SkippedRow, got {e!r:.40}")

    @property
    def n_skipped(self) -> int:
        return sum(self.skipped.values())

    def describe(self) -> str:
        """One line for logs and reports: counts by reason and the first examples."""
        if self.n_skipped == 0:
            return "no rows skipped"
        reasons = ", ".join(f"{n} {reason}" for reason, n in sorted(self.skipped.items()))
        first = "; ".join(f"line {e.line}: {e.text}" for e in self.examples)
        return f"{self.n_skipped} rows skipped: {reasons} (first: {first})"


@dataclass(frozen=True)
class SkipReport:
    """Rows read, kept and skipped per file and reason, with the first few examples
    (``files``: :class:`FileSkips` items, else a ConfigError)."""

    files: tuple[FileSkips, ...] = ()

    def __post_init__(self) -> None:
        for i, f in enumerate(self.files):
            if not isinstance(f, FileSkips):
                raise ConfigError(f"SkipReport.files[{i}]: expected FileSkips, got {f!r:.40}")

    @property
    def n_skipped(self) -> int:
        return sum(f.n_skipped for f in self.files)

    def skipped_by_reason(self) -> dict[str, int]:
        out: dict[str, int] = {}
        for f in self.files:
            for reason, n in f.skipped.items():
                out[reason] = out.get(reason, 0) + n
        return out

    def to_dict(self) -> dict[str, Any]:
        return {
            "rows_skipped": self.n_skipped,
            "by_reason": self.skipped_by_reason(),
            "files": {
                f.file: {
                    "rows_read": f.rows_read,
                    "rows_kept": f.rows_kept,
                    "skipped": dict(f.skipped),
                    "examples": [
                        {"line": e.line, "reason": e.reason, "text": e.text} for e in f.examples
                    ],
                }
                for f in self.files
            },
        }


def _items(value: object, where: str, what: str) -> tuple[Any, ...]:
    """``value`` — a sequence or any other iterable, a generator included — as a tuple;
    ``None``, a string, a mapping (whose keys it would iterate) or a non-iterable is a
    :class:`DataError` naming ``where``."""
    if isinstance(value, (str, bytes, Mapping)) or not isinstance(value, Iterable):
        raise DataError(f"{where}: expected a sequence of {what}, got {type(value).__name__}")
    return tuple(value)


def _landmarks(value: object) -> Array:
    """Landmark positions as a read-only ``(L, 3)`` array (an empty input: ``(0, 3)``)."""
    where = "recording.landmarks"
    raw = checks.floats(value, where)
    if raw.size == 0:
        raw = raw.reshape(0, 3)
    if raw.ndim != 2 or raw.shape[1] != 3:
        raise DataError(f"{where}: expected shape (L, 3) world positions, got {raw.shape}")
    return _float_array(raw, (3,), where)


@dataclass(frozen=True, kw_only=True)
class Recording:
    """What a team sensed (module docstring). Robots are indexed ``0 … n−1``.

    ``platforms[i]`` is ``"ground"`` or ``"aerial"``; ``odometry[i]`` and (if known)
    ``truth[i]`` belong to ``robots[i]``; ``landmarks (L, 3)`` are world positions indexed by
    the measurements' ``landmark`` column; ``source`` says where the recording came from.

    ``robots``, ``platforms``, ``odometry`` and ``truth`` may be any iterable (a list, a numpy
    array, a generator — read once) and are stored as tuples; ``None`` (but for ``truth``), a
    string, a mapping or a non-iterable is a :class:`DataError` naming the field, as are
    ``landmarks`` not of shape ``(L, 3)`` (an empty array of any shape means no landmarks),
    ``meta`` that is not a mapping and ``skips`` that is not a :class:`SkipReport`.
    """

    robots: tuple[str, ...]
    platforms: tuple[str, ...]
    odometry: tuple[Odometry, ...]
    measurements: Measurements
    truth: tuple[GroundTruth, ...] | None = None
    landmarks: Array = field(default_factory=lambda: np.zeros((0, 3)))
    source: str = ""
    meta: Mapping[str, Any] = field(default_factory=dict)
    skips: SkipReport = field(default_factory=SkipReport)

    def __post_init__(self) -> None:
        robots = tuple(str(r) for r in _items(self.robots, "recording.robots", "robot names"))
        if not robots:
            raise DataError("recording.robots: a recording needs at least one robot")
        if len(set(robots)) != len(robots):
            raise DataError(f"recording.robots: names must be unique, got {robots}")
        n = len(robots)
        platforms = _items(self.platforms, "recording.platforms", "platform names")
        odometry = _items(self.odometry, "recording.odometry", "Odometry streams")
        truth = None if self.truth is None else _items(self.truth, "recording.truth", "truths")
        if len(platforms) != n or len(odometry) != n:
            raise DataError(
                f"recording: {len(platforms)} platforms and {len(odometry)} odometry "
                f"streams for {n} robots"
            )
        for i, platform in enumerate(platforms):
            if not isinstance(platform, str) or platform not in PLATFORMS:
                raise DataError(
                    f"recording.platforms[{i}]: must be 'ground' or 'aerial', got {platform!r}"
                )
        for i, od in enumerate(odometry):
            if not isinstance(od, Odometry):
                raise DataError(
                    f"recording.odometry[{i}]: expected Odometry, got {type(od).__name__}"
                )
        if truth is not None:
            if len(truth) != n:
                raise DataError(f"recording.truth: {len(truth)} entries for {n} robots")
            for i, gt in enumerate(truth):
                if not isinstance(gt, GroundTruth):
                    raise DataError(
                        f"recording.truth[{i}]: expected GroundTruth, got {type(gt).__name__}"
                    )
        m = self.measurements
        if not isinstance(m, Measurements):
            raise DataError("recording.measurements: expected a Measurements table")
        if not isinstance(self.meta, Mapping):
            raise DataError(f"recording.meta: expected a mapping, got {type(self.meta).__name__}")
        if not isinstance(self.skips, SkipReport):
            raise DataError(
                f"recording.skips: expected a SkipReport, got {type(self.skips).__name__}"
            )
        landmarks = _landmarks(self.landmarks)
        assert m.landmark is not None and m.origin is not None
        for name, ids, limit in (
            ("observer", m.observer, n),
            ("target", m.target, n),
            ("landmark", m.landmark, landmarks.shape[0]),
            ("origin", m.origin, n),
        ):
            bad = ids >= limit
            if bad.any():
                row = int(np.argmax(bad))
                raise DataError(
                    f"measurements.{name}: row {row} names unknown index {int(ids[row])} "
                    f"(the recording has {limit})"
                )
        object.__setattr__(self, "robots", robots)
        object.__setattr__(self, "platforms", platforms)
        object.__setattr__(self, "odometry", odometry)
        object.__setattr__(self, "truth", truth)
        object.__setattr__(self, "landmarks", landmarks)
        object.__setattr__(self, "meta", MappingProxyType(dict(self.meta)))

    def __getstate__(self) -> dict[str, Any]:
        """Pickle support (recordings ship to Monte-Carlo workers): ``meta`` is stored as a
        plain dict, since its read-only view cannot be pickled."""
        state = dict(self.__dict__)
        state["meta"] = dict(self.meta)
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        for name, value in state.items():
            object.__setattr__(self, name, value)
        object.__setattr__(self, "meta", MappingProxyType(dict(state["meta"])))

    @property
    def n_robots(self) -> int:
        return len(self.robots)

    def index(self, robot: str | int) -> int:
        """Index of a robot given its name or index (DataError if unknown)."""
        if isinstance(robot, (int, np.integer)) and not isinstance(robot, bool):
            if 0 <= int(robot) < self.n_robots:
                return int(robot)
        elif robot in self.robots:
            return self.robots.index(robot)
        raise DataError(f"unknown robot {robot!r}; the recording has {', '.join(self.robots)}")

    @property
    def span(self) -> tuple[float, float]:
        """The time span covered by every robot's ground truth, or else by the data.

        Truth spans that do not all overlap (one robot's ends before another's starts) are a
        :class:`DataError` naming the two robots, never an inverted (empty) span.
        """
        if self.truth is not None:
            starts = [float(g.t[0]) for g in self.truth]
            ends = [float(g.t[-1]) for g in self.truth]
            t0, t1 = max(starts), min(ends)
            if t0 > t1:  # no instant at which every robot's truth is known
                late, early = int(np.argmax(starts)), int(np.argmin(ends))
                raise DataError(
                    f"recording {self.source!r}: the ground truth of {self.robots[late]!r} "
                    f"starts at {t0:.6g} s, after that of {self.robots[early]!r} ends at "
                    f"{t1:.6g} s; the robots' truth spans do not overlap, so there is no common "
                    "time span"
                )
            return t0, t1
        stamps = [od.t for od in self.odometry if od.t.size] + [self.measurements.t]
        t = np.concatenate(stamps) if stamps else np.zeros(0)
        if t.size == 0:
            raise DataError(f"recording {self.source!r}: no data, so no time span")
        return float(t.min()), float(t.max())

    def require_truth(self, what: str) -> tuple[GroundTruth, ...]:
        """The ground truth, or a :class:`DataError` saying that ``what`` needs it."""
        if self.truth is None:
            lacking = self.meta.get("robots_without_truth")
            detail = f" for robots {', '.join(lacking)}" if lacking else ""
            raise DataError(
                f"{what} needs ground truth of every robot; recording {self.source!r} has "
                f"none{detail}"
            )
        return self.truth

    def relative_truth(self, observer: str | int, observed: str | int, t: Array | float) -> Array:
        """True relative pose ``(x, y, z, φ)`` of ``observed`` in ``observer``'s body frame.

        ``p = Rz(ψ_l)ᵀ (p_c − p_l)``, ``φ = wrap(ψ_c − ψ_l)`` — the state of seed 000 Eq. 1
        (the 4-DOF ``⊖a ⊕ b`` of :func:`relloc.core.poses.relative`, vectorised over time).
        Returns shape ``(len(t), 4)``.
        """
        truth = self.require_truth("relative_truth")
        a = truth[self.index(observer)].at(t)
        b = truth[self.index(observed)].at(t)
        return relative_pose(a, b)


def _pose_pair(a: Array, b: Array, where: str) -> tuple[Array, Array, tuple[int, ...]]:
    """``a`` and ``b`` as 2-D arrays of 4-DOF poses and their broadcast shape ``(N, 4)``;
    a DataError naming ``where`` if either is not ``(4,)`` or ``(N, 4)`` or the row counts
    differ (other than 1). Only shapes are checked (these run at every step)."""
    a, b = np.atleast_2d(a), np.atleast_2d(b)
    (na, wa), (nb, wb) = a.shape[-2:], b.shape[-2:]
    if a.ndim != 2 or b.ndim != 2 or wa != 4 or wb != 4:
        raise DataError(
            f"{where}: poses are (x, y, z, ψ), shape (4,) or (N, 4); got {a.shape} and {b.shape}"
        )
    if na != nb and na != 1 and nb != 1:
        raise DataError(f"{where}: {na} poses against {nb}")
    return a, b, (max(na, nb), 4)


def relative_pose(a: Array, b: Array) -> Array:
    """Vectorised 4-DOF ``⊖a ⊕ b`` for poses ``(N, 4)``: ``b`` expressed in ``a``'s body frame.

    Either may be one pose ``(4,)`` (or ``(1, 4)``), applied to every row of the other; any
    other shape (a 3-wide SE(2) pose, a stack of more than two axes, row counts that differ) is
    a :class:`DataError`."""
    a, b, shape = _pose_pair(a, b, "relative_pose")
    d = b[:, :3] - a[:, :3]
    c, s = np.cos(a[:, 3]), np.sin(a[:, 3])
    out = np.empty(shape)
    out[:, 0] = c * d[:, 0] + s * d[:, 1]
    out[:, 1] = -s * d[:, 0] + c * d[:, 1]
    out[:, 2] = d[:, 2]
    out[:, 3] = wrap_angle(b[:, 3] - a[:, 3])
    return out


def compose_pose(a: Array, b: Array) -> Array:
    """Vectorised 4-DOF ``a ⊕ b`` for poses ``(N, 4)``: ``b``, given in ``a``'s body frame, in
    ``a``'s frame of reference (the inverse of :func:`relative_pose`: ``a ⊕ (⊖a ⊕ b) = b``);
    the heading is wrapped. Shapes as for :func:`relative_pose` (others: :class:`DataError`)."""
    a, b, shape = _pose_pair(a, b, "compose_pose")
    c, s = np.cos(a[:, 3]), np.sin(a[:, 3])
    out = np.empty(shape)
    out[:, 0] = a[:, 0] + c * b[:, 0] - s * b[:, 1]
    out[:, 1] = a[:, 1] + s * b[:, 0] + c * b[:, 1]
    out[:, 2] = a[:, 2] + b[:, 2]
    out[:, 3] = wrap_angle(a[:, 3] + b[:, 3])
    return out
