"""Where a robot node's own sensor stream comes from — the live-source Python API.

A node reads *only its own* sensors: its body-velocity odometry and the inter-robot
measurements it makes. Every source answers the same two questions for a half-open window of
robot time ``[t0, t1)``:

- :meth:`SensorSource.odometry` → ``(stamps (n,), u (n, 4))`` samples
  ``u = (v_x, v_y, v_z, ω_z)``, each held until the next (zero-order hold, as in
  :class:`relloc.core.recording.Odometry`);
- :meth:`SensorSource.measurements` → :class:`MeasurementBatch` rows ``(t, target, z, σ)`` with
  ``z = (range, azimuth, elevation)`` in the robot's body frame (seed 000 Eq. 2).

Implementations:

- :class:`RecordingSource` — one robot's slice of a :class:`relloc.core.recording.Recording` (a
  simulated scenario or a dataset replay); deterministic.
- :class:`LiveSource` — for a real robot: driver threads push samples as they come
  (:meth:`LiveSource.push_odometry`, :meth:`LiveSource.push_measurement`) and the node pulls
  windows. Samples older than what the node already consumed are counted in ``late`` and
  dropped, never silently lost; non-finite or mis-shaped samples raise ``DataError`` at the push.

Example (a live robot)::

    source = LiveSource("robot3", odometry_sigma=(0.05, 0.0, 0.0, 0.05))
    # in the wheel-encoder thread:  source.push_odometry(t, (v, 0.0, 0.0, w))
    # in the camera/UWB thread:     source.push_measurement(t, "robot1", (r, az, el), (σr, σθ, σα))
    RobotNode(settings, source, ...).run()
"""

from __future__ import annotations

import threading
import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray

from relloc.core.recording import Measurements, Recording, kind_code, measurement_rows
from relloc.errors import DataError

Array = NDArray[np.float64]


@dataclass(frozen=True)
class MeasurementBatch:
    """Rows ``t (m,)``, ``targets`` (m robot ids), ``z (m, 3)``, ``sigma (m, 3)``, time-sorted."""

    t: Array
    targets: tuple[str, ...]
    z: Array
    sigma: Array

    @property
    def size(self) -> int:
        return int(self.t.shape[0])


class SensorSource(Protocol):
    """One robot's own sensor stream (see module docstring)."""

    robot: str
    odometry_sigma: Array
    """Standard deviation of the odometry noise per channel, ``(4,)``."""

    def odometry(self, t0: float, t1: float) -> tuple[Array, Array]: ...

    def measurements(self, t0: float, t1: float, *, inclusive: bool = False) -> MeasurementBatch:
        """Rows with ``t0 ≤ t < t1`` (``≤ t1`` with ``inclusive``: the run's last instant)."""
        ...


class RecordingSource:
    """One robot's own streams from a :class:`~relloc.core.recording.Recording`.

    The robot's readings travel as ``meas`` messages of range, azimuth and elevation of named
    teammates (seed 000 Eq. 2) with their stated σ; a recording in which the robot made other
    readings (another kind, of an unknown target, without σ) is a :class:`DataError` naming
    what it holds — unless ``all_readings``: then :meth:`rows` hands the node every reading the
    robot made, of any kind (seed 002's heights, ranges and bearings of unknown origin), and
    :meth:`measurements` the range/azimuth/elevation ones among them.
    """

    def __init__(self, recording: Recording, robot: str, *, all_readings: bool = False) -> None:
        self.robot = robot
        self._index = recording.index(robot)
        self.landmark_count = int(recording.landmarks.shape[0])
        """Landmarks of the team's map (a teammate's reading of another is refused)."""
        odo = recording.odometry[self._index]
        self._odo_t, self._odo_u = odo.t, odo.velocity
        self.odometry_sigma: Array = np.asarray(odo.sigma, dtype=float)
        m = recording.measurements
        mine = m.observer == self._index
        usable = (
            (m.kind == kind_code("range_bearing_elevation"))
            & (m.target >= 0)
            & np.all(np.isfinite(m.sigma), axis=1)
        )
        other = mine & ~usable
        if other.any() and not all_readings:
            kinds = sorted({m.kind_names()[int(q)] for q in np.flatnonzero(other)})
            raise DataError(
                f"{recording.source or 'recording'}: robot {robot!r} has {int(other.sum())} "
                f"readings a robot node cannot send (kinds {kinds}, no named target or no σ); "
                "the runtime carries range_bearing_elevation readings of teammates with their σ"
            )
        self._rows = m.select(mine)
        sent = mine & usable
        self._m_t = m.t[sent]
        self._m_targets = tuple(recording.robots[j] for j in m.target[sent])
        self._m_z = m.value[sent]
        self._m_sigma = m.sigma[sent]
        self.end_time = float(recording.span[1])

    def odometry(self, t0: float, t1: float) -> tuple[Array, Array]:
        lo, hi = np.searchsorted(self._odo_t, [t0, t1], side="left")
        return self._odo_t[lo:hi], self._odo_u[lo:hi]

    def measurements(self, t0: float, t1: float, *, inclusive: bool = False) -> MeasurementBatch:
        lo = np.searchsorted(self._m_t, t0, side="left")
        hi = np.searchsorted(self._m_t, t1, side="right" if inclusive else "left")
        return MeasurementBatch(
            self._m_t[lo:hi], self._m_targets[lo:hi], self._m_z[lo:hi], self._m_sigma[lo:hi]
        )

    def rows(self, t0: float, t1: float, *, inclusive: bool = False) -> Measurements:
        """The robot's own readings in the window as rows of the recording's table."""
        lo = np.searchsorted(self._rows.t, t0, side="left")
        hi = np.searchsorted(self._rows.t, t1, side="right" if inclusive else "left")
        return self._rows.select(slice(int(lo), int(hi)))


def batch_rows(batch: MeasurementBatch, roster: Sequence[str], robot: str) -> Measurements:
    """A :class:`MeasurementBatch` of ``robot`` as range/azimuth/elevation rows (robot indices
    in ``roster`` order); a target not on the roster is a :class:`DataError`."""
    unknown = sorted(set(batch.targets) - set(roster))
    if unknown:
        raise DataError(f"{robot}: readings of {unknown}, who are not on the roster {roster}")
    return measurement_rows(
        "range_bearing_elevation",
        t=batch.t,
        observer=list(roster).index(robot),
        target=np.array([list(roster).index(r) for r in batch.targets], dtype=np.int64),
        value=batch.z,
        sigma=batch.sigma,
    )


class LiveSource:
    """A thread-safe push buffer for a robot's live sensors (see module docstring)."""

    def __init__(self, robot: str, *, odometry_sigma: Sequence[float]) -> None:
        self.robot = robot
        sigma = np.asarray(odometry_sigma, dtype=float)
        if sigma.shape != (4,) or not np.all(np.isfinite(sigma)) or np.any(sigma < 0):
            raise DataError(f"LiveSource {robot}: odometry_sigma must be 4 finite values ≥ 0")
        self.odometry_sigma: Array = sigma
        self._lock = threading.Lock()
        self._odo: list[tuple[float, Array]] = []
        self._meas: list[tuple[float, str, Array, Array]] = []
        self._consumed_odo = -np.inf
        self._consumed_meas = -np.inf
        self.late = 0

    @staticmethod
    def _vector(value: ArrayLike, n: int, what: str) -> Array:
        arr = np.asarray(value, dtype=float)
        if arr.shape != (n,) or not np.all(np.isfinite(arr)):
            raise DataError(f"LiveSource: {what} must be {n} finite numbers, got {value!r}")
        return arr

    def push_odometry(self, t: float, u: ArrayLike) -> None:
        """Record the body velocity ``u = (v_x, v_y, v_z, ω_z)`` measured at robot time ``t``."""
        stamp = float(self._vector([t], 1, "t")[0])
        vel = self._vector(u, 4, "u")
        with self._lock:
            if stamp < self._consumed_odo or (self._odo and stamp <= self._odo[-1][0]):
                self.late += 1
                return
            self._odo.append((stamp, vel))

    def push_measurement(self, t: float, target: str, z: ArrayLike, sigma: ArrayLike) -> None:
        """Record a range/azimuth/elevation ``z`` of ``target`` with noise ``sigma``."""
        stamp = float(self._vector([t], 1, "t")[0])
        zv = self._vector(z, 3, "z")
        sv = self._vector(sigma, 3, "sigma")
        if zv[0] <= 0 or np.any(sv <= 0):
            raise DataError("LiveSource: range and sigma must be > 0")
        with self._lock:
            if stamp < self._consumed_meas:
                self.late += 1
                return
            self._meas.append((stamp, target, zv, sv))

    def odometry(self, t0: float, t1: float) -> tuple[Array, Array]:
        with self._lock:
            self._consumed_odo = max(self._consumed_odo, t1)
            take = [s for s in self._odo if t0 <= s[0] < t1]
            self._odo = [s for s in self._odo if s[0] >= t1]
        if not take:
            return np.zeros(0), np.zeros((0, 4))
        return np.array([s[0] for s in take]), np.stack([s[1] for s in take])

    def measurements(self, t0: float, t1: float, *, inclusive: bool = False) -> MeasurementBatch:
        def inside(m: tuple[float, str, Array, Array]) -> bool:
            return t0 <= m[0] <= t1 if inclusive else t0 <= m[0] < t1

        with self._lock:
            self._consumed_meas = max(self._consumed_meas, t1)
            take = sorted((m for m in self._meas if inside(m)), key=lambda m: m[0])
            self._meas = [m for m in self._meas if not inside(m) and m[0] >= t1]
        if not take:
            return MeasurementBatch(np.zeros(0), (), np.zeros((0, 3)), np.zeros((0, 3)))
        return MeasurementBatch(
            np.array([m[0] for m in take]),
            tuple(m[1] for m in take),
            np.stack([m[2] for m in take]),
            np.stack([m[3] for m in take]),
        )


class ReplayFeeder:
    """Plays one robot's recorded samples into a :class:`LiveSource` at the wall time they were
    recorded (a dataset replayed in real time through the live API): a thread pushes each
    odometry sample and reading at ``start + (t − t0)`` on the monotonic clock."""

    def __init__(self, recording: Recording, robot: str, live: LiveSource, *, t0: float) -> None:
        index = recording.index(robot)
        odo = recording.odometry[index]
        self._odo = [(float(t), u) for t, u in zip(odo.t, odo.velocity, strict=True)]
        m = recording.measurements
        mine = np.flatnonzero(
            (m.observer == index)
            & (m.kind == kind_code("range_bearing_elevation"))
            & (m.target >= 0)
        )
        self._meas = [
            (float(m.t[i]), recording.robots[int(m.target[i])], m.value[i], m.sigma[i])
            for i in mine
        ]
        self.live = live
        self.t0 = float(t0)
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    def start(self, start_wall: float) -> None:
        """Start pushing, with robot time ``t0`` at monotonic wall time ``start_wall``."""
        self._thread = threading.Thread(target=self._play, args=(start_wall,), daemon=True)
        self._thread.start()

    def stop(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=5.0)

    def _play(self, start_wall: float) -> None:
        events = sorted(
            [(t, 0, k) for k, (t, _) in enumerate(self._odo) if t >= self.t0]
            + [(t, 1, k) for k, (t, *_) in enumerate(self._meas) if t >= self.t0]
        )
        for t, which, k in events:
            wait = start_wall + (t - self.t0) - time.monotonic()
            if wait > 0 and self._stop.wait(wait):
                return
            if self._stop.is_set():
                return
            if which == 0:
                self.live.push_odometry(t, self._odo[k][1])
            else:
                _, target, z, sigma = self._meas[k]
                self.live.push_measurement(t, target, z, sigma)
