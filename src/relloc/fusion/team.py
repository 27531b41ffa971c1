"""A team of distributed fusers run at their own rates (seed 002 §II-B and Fig. 1).

Every sensing robot runs a :class:`~relloc.estimators.gaussian_sum.GaussianSumFuser`. Time
advances on the filter grid (paper: 20 Hz): every step predicts all fusers with the measured
body velocities; a direct scan (paper: 10 Hz) is fused when the filter clock reaches its time
stamp; every ``fusion_period`` seconds (paper: 1 Hz) all fusers broadcast their equivalent
measurements (Eq. 8) and then fuse what the others sent (mutual and indirect fusion).

:class:`TeamData` is what the simulator (:mod:`relloc.sim.multihypothesis`) and the dataset
replays (:mod:`relloc.experiments.mrclam_association`) produce; :class:`TeamTrace` records, at
every direct scan, the dominant track of every filter and the true origin of the bearing it
used (for the wrong-association rate).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from relloc.errors import ConfigError, DataError
from relloc.estimators.gaussian_sum import GaussianSumFuser, GaussianSumSettings, predict_fusers

Array = NDArray[np.float64]
IntArray = NDArray[np.int64]

#: ``TeamTrace.assoc_origin`` value when the dominant track used no bearing at that scan.
NO_BEARING = -2
#: ``DirectScan.origins`` / ``TeamTrace.assoc_origin`` value of a clutter bearing.
CLUTTER = -1


@dataclass(frozen=True)
class DirectScan:
    """What one sensing robot measured at one instant (indices are robot indices).

    ``heights[j]`` and ``ranges[j]`` (known correspondence) are NaN when not measured (and at
    the observer's own index). ``bearings`` (m, 2) or (m, 1) have unknown correspondence;
    ``origins`` (m,) is the robot that produced each bearing (``CLUTTER`` for clutter) and is
    used only to score associations, never by the filter.
    """

    time: float
    observer: int
    heights: Array
    ranges: Array
    bearings: Array
    origins: IntArray


@dataclass(frozen=True)
class TeamData:
    """Inputs of a team run.

    ``times`` (T,) is the filter grid (strictly increasing); ``velocities`` (T, n, 4) the
    measured body velocities held over ``[t_k, t_{k+1})``; ``scans`` sorted by time, each
    time stamp on the grid; ``truth`` (T, n, 4) world poses ``(x, y, z, ψ)`` when known.
    """

    times: Array
    velocities: Array
    sensing: tuple[int, ...]
    scans: tuple[DirectScan, ...]
    truth: Array | None = None

    def __post_init__(self) -> None:
        t = np.asarray(self.times, dtype=float)
        if t.ndim != 1 or t.size < 2 or not np.all(np.diff(t) > 0.0):
            raise DataError("TeamData.times: needs ≥ 2 strictly increasing time stamps")
        v = np.asarray(self.velocities, dtype=float)
        if v.ndim != 3 or v.shape[0] != t.size or v.shape[2] != 4:
            raise DataError(f"TeamData.velocities: expected (T, n, 4), got {v.shape}")
        if not np.isfinite(v).all():
            raise DataError("TeamData.velocities: non-finite values")
        n = v.shape[1]
        if any(not 0 <= s < n for s in self.sensing) or len(set(self.sensing)) != len(self.sensing):
            raise DataError(f"TeamData.sensing: distinct robot indices in [0, {n}) required")
        last = -np.inf
        for k, scan in enumerate(self.scans):
            if scan.time < last:
                raise DataError(f"TeamData.scans[{k}]: time {scan.time} goes backwards")
            if scan.observer not in self.sensing:
                raise DataError(f"TeamData.scans[{k}]: observer {scan.observer} is not sensing")
            if scan.heights.shape != (n,) or scan.ranges.shape != (n,):
                raise DataError(f"TeamData.scans[{k}]: heights/ranges need shape ({n},)")
            if scan.bearings.shape[0] != scan.origins.shape[0]:
                raise DataError(f"TeamData.scans[{k}]: one origin per bearing is required")
            last = scan.time
        if self.truth is not None and np.asarray(self.truth).shape != (t.size, n, 4):
            raise DataError(f"TeamData.truth: expected ({t.size}, {n}, 4)")
        object.__setattr__(self, "times", t)
        object.__setattr__(self, "velocities", v)

    @property
    def n_robots(self) -> int:
        """Number of robots in the team."""
        return int(self.velocities.shape[1])


@dataclass(frozen=True, kw_only=True)
class TeamRunSettings:
    """Rates and switches of a team run.

    ``fusion_period``: seconds between broadcasts (paper: 1 s); ``sharing``: mutual and
    indirect fusion on/off.
    """

    fusion_period: float = 1.0
    sharing: bool = True

    def __post_init__(self) -> None:
        if not (np.isfinite(self.fusion_period) and self.fusion_period > 0.0):
            raise ConfigError(f"TeamRunSettings.fusion_period must be > 0: {self.fusion_period}")


@dataclass(frozen=True)
class TeamTrace:
    """Dominant track of every filter at every direct scan of its observer.

    Arrays are indexed ``[scan, target]`` for the scans of one observer; ``mean`` (S, n, 4),
    ``cov`` (S, n, 4, 4), ``weight`` / ``components`` / ``confirmed`` / ``assoc_origin`` (true
    origin of the bearing the dominant track used) / ``joint_origin`` (true origin of the bearing
    the fuser's joint decision gave the teammate) (S, n). Entries of the observer itself and of
    filters without tracks are NaN / 0 / False / ``NO_BEARING``.
    """

    observer: int
    times: Array
    scan_index: IntArray
    mean: Array
    cov: Array
    weight: Array
    components: IntArray
    confirmed: NDArray[np.bool_]
    assoc_origin: IntArray
    joint_origin: IntArray
    bearing_origin_present: NDArray[np.bool_]


#: The per-scan arrays :func:`_record` appends and :func:`_finish` stacks: the array fields of
#: :class:`TeamTrace`, under their own names.
_TRACE_FIELDS = (
    "times",
    "scan_index",
    "mean",
    "cov",
    "weight",
    "components",
    "confirmed",
    "assoc_origin",
    "joint_origin",
    "bearing_origin_present",
)


def _fuser_for(robot: int, n: int, settings: GaussianSumSettings) -> GaussianSumFuser:
    return GaussianSumFuser(robot, [j for j in range(n) if j != robot], settings)


def run_team(
    data: TeamData, settings: GaussianSumSettings, run: TeamRunSettings
) -> dict[int, TeamTrace]:
    """Run every sensing robot's fuser over ``data``; returns one trace per observer."""
    n = data.n_robots
    fusers = {i: _fuser_for(i, n, settings) for i in data.sensing}
    rec: dict[int, dict[str, list[object]]] = {
        i: {field: [] for field in _TRACE_FIELDS} for i in data.sensing
    }
    scan_ptr = 0
    scans = data.scans
    next_fusion = run.fusion_period
    grid = data.times
    for k in range(grid.size):
        if k > 0:
            dt = float(grid[k] - grid[k - 1])
            u = data.velocities[k - 1]
            predict_fusers(
                list(fusers.values()),
                [u[i] for i in fusers],
                [np.delete(u, i, axis=0) for i in fusers],
                dt,
            )
        while scan_ptr < len(scans) and scans[scan_ptr].time <= grid[k] + 1e-9:
            scan = scans[scan_ptr]
            scan_ptr += 1
            fus = fusers[scan.observer]
            others = [j for j in range(n) if j != scan.observer]
            fus.direct_scan(scan.heights[others], scan.ranges[others], scan.bearings)
            _record(rec[scan.observer], fus, scan, others, k)
        if run.sharing and grid[k] - grid[0] >= next_fusion - 1e-9:
            next_fusion += run.fusion_period
            messages = [m for fus in fusers.values() for m in fus.broadcast()]
            for i, fus in fusers.items():
                for msg in messages:
                    if msg.sender != i:
                        fus.fuse(msg)
    return {i: _finish(i, rec[i], n) for i in data.sensing}


def _record(
    rec: dict[str, list[object]],
    fus: GaussianSumFuser,
    scan: DirectScan,
    others: list[int],
    k: int,
) -> None:
    """Append the dominant track of every filter of ``fus`` after direct scan ``k`` to ``rec``."""
    n = len(others) + 1
    mean = np.full((n, 4), np.nan)
    cov = np.full((n, 4, 4), np.nan)
    weight = np.zeros(n)
    components = np.zeros(n, dtype=np.int64)
    confirmed = np.zeros(n, dtype=bool)
    assoc_origin = np.full(n, NO_BEARING, dtype=np.int64)
    joint_origin = np.full(n, NO_BEARING, dtype=np.int64)
    present = np.zeros(n, dtype=bool)
    for local, j in enumerate(others):
        present[j] = bool(np.any(scan.origins == j))
        if fus.last_decision[local] >= 0:
            joint_origin[j] = int(scan.origins[fus.last_decision[local]])
        s = fus.summary(j)
        if s is None:
            continue
        mean[j], cov[j], weight[j] = s.belief.mean, s.belief.cov, s.weight
        components[j], confirmed[j] = s.components, s.confirmed
        if s.assoc >= 0:
            assoc_origin[j] = int(scan.origins[s.assoc])
    row: dict[str, object] = {
        "times": scan.time,
        "scan_index": k,
        "mean": mean,
        "cov": cov,
        "weight": weight,
        "components": components,
        "confirmed": confirmed,
        "assoc_origin": assoc_origin,
        "joint_origin": joint_origin,
        "bearing_origin_present": present,
    }
    for field in _TRACE_FIELDS:
        rec[field].append(row[field])


def _finish(observer: int, rec: dict[str, list[object]], n: int) -> TeamTrace:
    def arr(key: str, dtype: type, shape: tuple[int, ...]) -> NDArray:  # type: ignore[type-arg]
        return np.array(rec[key], dtype=dtype) if rec[key] else np.zeros((0, *shape), dtype)

    return TeamTrace(
        observer=observer,
        times=arr("times", float, ()),
        scan_index=arr("scan_index", np.int64, ()),
        mean=arr("mean", float, (n, 4)),
        cov=arr("cov", float, (n, 4, 4)),
        weight=arr("weight", float, (n,)),
        components=arr("components", np.int64, (n,)),
        confirmed=arr("confirmed", bool, (n,)),
        assoc_origin=arr("assoc_origin", np.int64, (n,)),
        joint_origin=arr("joint_origin", np.int64, (n,)),
        bearing_origin_present=arr("bearing_origin_present", bool, (n,)),
    )
