"""The :class:`Log`: what a team recorded, shared by the simulator and by dataset replays.

A log holds, for every robot of a team (indexed ``0 … n−1`` in :attr:`Log.robots`):

- :class:`GroundTruth` — true 4-DOF poses ``(x, y, z, ψ)`` in a common world frame over time
  (ψ is the yaw about the world z axis; ground robots move on planes, aerial robots hover, so
  roll and pitch are zero — seed 000 §3.1, condition 6);
- :class:`Odometry` — dead-reckoned body-frame velocities ``u = (v_x, v_y, v_z, ω_z)`` with their
  timestamps and the standard deviation of their noise; ``velocity[k]`` is held over
  ``[t[k], t[k+1])`` (zero-order hold), which is how both the simulator generates them and the
  filters consume them;

and one :class:`Measurements` table of inter-robot observations
``z = (r, θ, α)`` (range, azimuth, elevation of the observed robot in the observer's body frame,
seed 000 Eq. 2) with the time, observer and observed indices and the sensor's noise σ per row.

Every array is validated on construction (shapes, finite numbers, strictly increasing time for
truth and odometry, non-decreasing time for measurements with no duplicate (time, observer,
observed) rows, robot indices in range); violations raise :class:`relloc.errors.DataError`
naming the field and the first offending row.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from relloc.core.angles import circular_interp, wrap_angle
from relloc.errors import DataError

Array = NDArray[np.float64]
IntArray = NDArray[np.int64]

POSE_FIELDS = ("x", "y", "z", "yaw")
VELOCITY_FIELDS = ("v_x", "v_y", "v_z", "w_z")
MEASUREMENT_FIELDS = ("range", "azimuth", "elevation")


def _float_array(value: object, shape_tail: tuple[int, ...], where: str) -> Array:
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise DataError(f"{where}: not numeric ({exc})") from exc
    if arr.ndim != 1 + len(shape_tail) or arr.shape[1:] != shape_tail:
        expected = "(N" + "".join(f", {d}" for d in shape_tail) + ")"
        raise DataError(f"{where}: expected shape {expected}, got {arr.shape}")
    bad = ~np.isfinite(arr)
    if bad.any():
        row = int(np.argwhere(bad)[0][0])
        raise DataError(f"{where}: non-finite value in row {row}")
    arr = np.array(arr, copy=True)
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
    """True poses of one robot: ``t (N,)`` strictly increasing, ``pose (N, 4)`` = (x, y, z, ψ)."""

    t: Array
    pose: Array
    where: str = field(default="truth", compare=False, repr=False)

    def __post_init__(self) -> None:
        t = _float_array(self.t, (), f"{self.where}.t")
        pose = _float_array(self.pose, (4,), f"{self.where}.pose")
        if pose.shape[0] != t.shape[0]:
            raise DataError(f"{self.where}: {t.shape[0]} timestamps but {pose.shape[0]} poses")
        if t.size < 2:
            raise DataError(f"{self.where}: at least two samples are needed, got {t.size}")
        _check_times(t, f"{self.where}.t", strict=True)
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "pose", pose)

    def at(self, t: Array | float) -> Array:
        """Poses interpolated at times ``t`` (linear in x, y, z; on the circle in ψ).

        Times outside ``[t[0], t[-1]]`` raise :class:`DataError` (no extrapolation).
        """
        tq = np.atleast_1d(np.asarray(t, dtype=float))
        if tq.size and (tq.min() < self.t[0] - 1e-9 or tq.max() > self.t[-1] + 1e-9):
            raise DataError(
                f"{self.where}: query time outside the recorded span "
                f"[{self.t[0]:.6g}, {self.t[-1]:.6g}]: [{tq.min():.6g}, {tq.max():.6g}]"
            )
        out = np.empty((tq.size, 4))
        for j in range(3):
            out[:, j] = np.interp(tq, self.t, self.pose[:, j])
        out[:, 3] = circular_interp(tq, self.t, self.pose[:, 3])
        return out


@dataclass(frozen=True, kw_only=True)
class Odometry:
    """Body-frame velocities of one robot: ``t (K,)``, ``velocity (K, 4)`` = (v_x, v_y, v_z, ω_z).

    ``velocity[k]`` applies over ``[t[k], t[k+1])``. ``sigma (4,)`` is the standard deviation of
    the white noise on each channel (0 for a channel known exactly, e.g. v_y of a unicycle).
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
        if t.size < 1:
            raise DataError(f"{self.where}: no odometry samples")
        if np.any(sigma < 0):
            raise DataError(f"{self.where}.sigma: standard deviations must be ≥ 0, got {sigma}")
        _check_times(t, f"{self.where}.t", strict=True)
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "velocity", vel)
        object.__setattr__(self, "sigma", sigma)

    def held_at(self, t: Array | float) -> Array:
        """Zero-order-hold velocities at times ``t``: the last sample at or before each time.

        Times before the first sample get zero velocity (the robot has not reported motion yet).
        """
        tq = np.atleast_1d(np.asarray(t, dtype=float))
        idx = np.searchsorted(self.t, tq, side="right") - 1
        out = np.zeros((tq.size, 4))
        ok = idx >= 0
        out[ok] = self.velocity[idx[ok]]
        return out


@dataclass(frozen=True, kw_only=True)
class Measurements:
    """Inter-robot observations ``z = (r, θ, α)`` sorted by time.

    ``t (M,)``, ``observer (M,)`` and ``observed (M,)`` robot indices, ``z (M, 3)``,
    ``sigma (M, 3)`` = (σ_r, σ_θ, σ_α) of the sensor that produced each row.
    """

    t: Array
    observer: IntArray
    observed: IntArray
    z: Array
    sigma: Array

    def __post_init__(self) -> None:
        t = _float_array(self.t, (), "measurements.t")
        z = _float_array(self.z, (3,), "measurements.z")
        sigma = _float_array(self.sigma, (3,), "measurements.sigma")
        ids = []
        for name in ("observer", "observed"):
            raw = np.asarray(getattr(self, name))
            if raw.ndim != 1 or (raw.size and not np.issubdtype(raw.dtype, np.integer)):
                raise DataError(f"measurements.{name}: expected a 1-D integer array of robot ids")
            arr = np.array(raw, dtype=np.int64, copy=True)
            arr.setflags(write=False)
            ids.append(arr)
        n = t.shape[0]
        columns: tuple[tuple[str, np.ndarray], ...] = (
            ("z", z),
            ("sigma", sigma),
            ("observer", ids[0]),
            ("observed", ids[1]),
        )
        for name, column in columns:
            if column.shape[0] != n:
                raise DataError(f"measurements.{name}: {column.shape[0]} rows but {n} timestamps")
        if np.any(sigma <= 0):
            row = int(np.argwhere(sigma <= 0)[0][0])
            raise DataError(f"measurements.sigma: row {row} has a standard deviation ≤ 0")
        if np.any(z[:, 0] <= 0):
            row = int(np.argmax(z[:, 0] <= 0))
            raise DataError(f"measurements.z: row {row} has range ≤ 0")
        same = ids[0] == ids[1]
        if same.any():
            raise DataError(f"measurements: row {int(np.argmax(same))} has observer == observed")
        _check_times(t, "measurements.t", strict=False)
        if n > 1:
            key = np.stack([t, ids[0].astype(float), ids[1].astype(float)], axis=1)
            order = np.lexsort((key[:, 2], key[:, 1], key[:, 0]))
            dup = np.all(np.diff(key[order], axis=0) == 0, axis=1)
            if dup.any():
                row = int(order[int(np.argmax(dup)) + 1])
                raise DataError(
                    f"measurements: row {row} duplicates (t, observer, observed) of another row"
                )
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "z", z)
        object.__setattr__(self, "sigma", sigma)
        object.__setattr__(self, "observer", ids[0])
        object.__setattr__(self, "observed", ids[1])

    @property
    def size(self) -> int:
        return int(self.t.shape[0])

    def select(self, mask: NDArray[np.bool_]) -> Measurements:
        """The rows where ``mask`` is true (order kept)."""
        return Measurements(
            t=self.t[mask],
            observer=self.observer[mask],
            observed=self.observed[mask],
            z=self.z[mask],
            sigma=self.sigma[mask],
        )


def empty_measurements() -> Measurements:
    """A measurement table with no rows."""
    return Measurements(
        t=np.zeros(0),
        observer=np.zeros(0, dtype=np.int64),
        observed=np.zeros(0, dtype=np.int64),
        z=np.zeros((0, 3)),
        sigma=np.zeros((0, 3)),
    )


@dataclass(frozen=True, kw_only=True)
class Log:
    """A team's recording: robots, their truth and odometry, and inter-robot measurements.

    ``robots`` are unique names; ``kinds`` says ``"ground"`` or ``"aerial"`` per robot;
    ``truth[i]`` and ``odometry[i]`` belong to ``robots[i]``; measurement ids index ``robots``.
    ``source`` says where the log came from (e.g. ``"simulation seed 7"`` or a dataset path).
    """

    robots: tuple[str, ...]
    kinds: tuple[str, ...]
    truth: tuple[GroundTruth, ...]
    odometry: tuple[Odometry, ...]
    measurements: Measurements
    source: str = ""

    def __post_init__(self) -> None:
        robots = tuple(str(r) for r in self.robots)
        if not robots:
            raise DataError("log.robots: a log needs at least one robot")
        if len(set(robots)) != len(robots):
            raise DataError(f"log.robots: names must be unique, got {robots}")
        for name, items in (
            ("kinds", self.kinds),
            ("truth", self.truth),
            ("odometry", self.odometry),
        ):
            if len(items) != len(robots):
                raise DataError(f"log.{name}: {len(items)} entries for {len(robots)} robots")
        for i, kind in enumerate(self.kinds):
            if kind not in ("ground", "aerial"):
                raise DataError(f"log.kinds[{i}]: must be 'ground' or 'aerial', got {kind!r}")
        for i, (gt, od) in enumerate(zip(self.truth, self.odometry, strict=True)):
            if not isinstance(gt, GroundTruth):
                raise DataError(f"log.truth[{i}]: expected GroundTruth, got {type(gt).__name__}")
            if not isinstance(od, Odometry):
                raise DataError(f"log.odometry[{i}]: expected Odometry, got {type(od).__name__}")
        m = self.measurements
        if not isinstance(m, Measurements):
            raise DataError("log.measurements: expected a Measurements table")
        n = len(robots)
        for name in ("observer", "observed"):
            ids = getattr(m, name)
            bad = (ids < 0) | (ids >= n)
            if bad.any():
                row = int(np.argmax(bad))
                raise DataError(
                    f"measurements.{name}: row {row} names unknown robot id {int(ids[row])} "
                    f"(the log has {n} robots)"
                )
        object.__setattr__(self, "robots", robots)
        object.__setattr__(self, "kinds", tuple(self.kinds))
        object.__setattr__(self, "truth", tuple(self.truth))
        object.__setattr__(self, "odometry", tuple(self.odometry))

    @property
    def n_robots(self) -> int:
        return len(self.robots)

    def index(self, robot: str | int) -> int:
        """Index of a robot given its name or index (DataError if unknown)."""
        if isinstance(robot, (int, np.integer)):
            if 0 <= int(robot) < self.n_robots:
                return int(robot)
        elif robot in self.robots:
            return self.robots.index(robot)
        raise DataError(f"unknown robot {robot!r}; the log has {', '.join(self.robots)}")

    @property
    def span(self) -> tuple[float, float]:
        """The time span covered by every robot's ground truth."""
        start = max(float(g.t[0]) for g in self.truth)
        end = min(float(g.t[-1]) for g in self.truth)
        return start, end

    def relative_truth(self, observer: str | int, observed: str | int, t: Array | float) -> Array:
        """True relative pose ``(x, y, z, φ)`` of ``observed`` in ``observer``'s body frame.

        ``p = Rz(ψ_l)ᵀ (p_c − p_l)``, ``φ = wrap(ψ_c − ψ_l)`` — the state of seed 000 Eq. 1
        (the 4-DOF ``⊖a ⊕ b`` of :func:`relloc.core.poses.relative`, vectorised over time).
        Returns shape ``(len(t), 4)``.
        """
        a = self.truth[self.index(observer)].at(t)
        b = self.truth[self.index(observed)].at(t)
        return relative_pose(a, b)


def relative_pose(a: Array, b: Array) -> Array:
    """Vectorised 4-DOF ``⊖a ⊕ b`` for poses ``(N, 4)``: ``b`` expressed in ``a``'s body frame."""
    a = np.atleast_2d(a)
    b = np.atleast_2d(b)
    d = b[:, :3] - a[:, :3]
    c, s = np.cos(a[:, 3]), np.sin(a[:, 3])
    out = np.empty(np.broadcast_shapes(a.shape, b.shape))
    out[:, 0] = c * d[:, 0] + s * d[:, 1]
    out[:, 1] = -s * d[:, 0] + c * d[:, 1]
    out[:, 2] = d[:, 2]
    out[:, 3] = wrap_angle(b[:, 3] - a[:, 3])
    return out
