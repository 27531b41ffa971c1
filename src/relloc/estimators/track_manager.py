"""Tracks of many (observer, observed) pairs whose membership changes over time.

Seed 000 §3.1 allows M observing and N observed robots whose numbers vary; §6.2 proposes that
when an observed robot leaves the field of view its track is kept (predicted only) for a
pre-defined window and deleted if the robot does not reappear, and that a robot seen again after
deletion gets a new track. :class:`TrackManager` does exactly that:

- a track per (observer, observed) pair is **created** on the first measurement of the pair,
  starting from an :class:`~relloc.estimators.initialisation.InitPolicy`;
- every live track is **predicted** with both robots' body velocities (the shared predict of
  :mod:`relloc.estimators.relative`);
- a measurement **updates** its pair's track with the selected filter — PLKF, TEKF or
  bias-compensated PLKF (``bcplkf``);
- optionally, a track whose initial yaw is unknown starts as a bank of yaw hypotheses (a
  Gaussian sum over φ, :mod:`relloc.estimators.yaw_bank`) that is reweighted by every
  measurement and collapses to a single filter once one hypothesis dominates — this avoids the
  long stalls of a single filter started near the wrong yaw (seed 000 Table 1, case 4);
- a track with no update for longer than ``keep_window_s`` is **deleted**; the next measurement
  of the pair **re-creates** it.

The manager records each live track's belief on a regular grid, the NIS and the conditioning
``log10(λmax/λmin)`` of ``R`` and ``S`` at every update, and the track events, and returns them as
:class:`TeamEstimates` — plain arrays that can be shipped between processes and scored against
ground truth by :mod:`relloc.experiments.team_run`. :func:`track_log` runs a manager over a
whole :class:`~relloc.sim.log.Log`.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from relloc.core.gaussian import Gaussian, GaussianMixture
from relloc.core.kalman import Innovation
from relloc.errors import ConfigError
from relloc.estimators.initialisation import InitContext, InitPolicy
from relloc.estimators.relative import UPDATE_KINDS, FilterSettings, predict_arrays
from relloc.estimators.yaw_bank import (
    YawBankSettings,
    predict_yaw_bank,
    spread_yaw_bank,
    update_yaw_bank,
)
from relloc.metrics.conditioning import condition_log10_batch
from relloc.models.measurement import RangeBearingNoise
from relloc.models.motion import VelocityNoise
from relloc.sim.log import Log, Measurements

Array = NDArray[np.float64]
EventKind = Literal["created", "deleted", "recreated"]

_TIME_TOL = 1e-9


@dataclass(frozen=True, kw_only=True)
class TrackManagerSettings:
    """``filter``: ``plkf`` | ``tekf`` | ``bcplkf``; ``keep_window_s``: how long a track is
    predicted without measurements before deletion; ``pseudo_linear_covariance``:
    ``simplified`` (seed 000 Eq. 6) or ``full`` (Eqs. 4–5); ``init``: how tracks start;
    ``yaw_bank``: spread a track whose initial yaw is unknown into a bank of yaw hypotheses
    (:mod:`relloc.estimators.yaw_bank`), or ``None`` for a single filter per track."""

    filter: str = "plkf"
    keep_window_s: float = 2.0
    pseudo_linear_covariance: Literal["simplified", "full"] = "simplified"
    init: InitPolicy = field(default_factory=InitPolicy)
    yaw_bank: YawBankSettings | None = None

    def __post_init__(self) -> None:
        if self.filter not in UPDATE_KINDS:
            raise ConfigError(
                f"filter: must be one of {', '.join(UPDATE_KINDS)}, got {self.filter!r}"
            )
        w = self.keep_window_s
        if isinstance(w, bool) or not isinstance(w, (int, float)) or not 0.0 <= w < np.inf:
            raise ConfigError(f"keep_window_s: must be a finite number ≥ 0, got {w!r}")
        if self.pseudo_linear_covariance not in ("simplified", "full"):
            raise ConfigError(
                "pseudo_linear_covariance: must be 'simplified' or 'full', "
                f"got {self.pseudo_linear_covariance!r}"
            )
        if not isinstance(self.init, InitPolicy):
            raise ConfigError("init: expected an InitPolicy")
        if self.yaw_bank is not None and not isinstance(self.yaw_bank, YawBankSettings):
            raise ConfigError("yaw_bank: expected YawBankSettings or None")


@dataclass(frozen=True)
class TrackEvent:
    """A change in the set of tracks: ``kind`` is created, deleted or recreated."""

    t: float
    observer: str
    observed: str
    kind: EventKind


@dataclass(frozen=True, kw_only=True)
class PairEstimates:
    """One pair's recorded beliefs and updates.

    ``t (K,)``, ``mean (K, 4)``, ``cov (K, 4, 4)`` on the recording grid while a track exists;
    ``age (K,)`` seconds since the track was (re)created; ``update_t (U,)``,
    ``update_age (U,)``, ``nis (U,)``, ``cond_r (U,)``, ``cond_s (U,)`` at each measurement
    update.
    """

    observer: str
    observed: str
    t: Array
    mean: Array
    cov: Array
    age: Array
    update_t: Array
    update_age: Array
    nis: Array
    cond_r: Array
    cond_s: Array

    @property
    def label(self) -> str:
        return f"{self.observer}->{self.observed}"


@dataclass(frozen=True, kw_only=True)
class TeamEstimates:
    """What a team's trackers produced: per-pair series and the track events, in pair order."""

    filter: str
    pairs: tuple[PairEstimates, ...]
    events: tuple[TrackEvent, ...]

    def pair(self, observer: str, observed: str) -> PairEstimates:
        for p in self.pairs:
            if (p.observer, p.observed) == (observer, observed):
                return p
        raise ConfigError(f"no estimates for pair {observer}->{observed}")


@dataclass
class _Track:
    """A live track: its best estimate and, while several yaw hypotheses live, the bank."""

    mean: Array
    cov: Array
    created_t: float
    last_update_t: float
    settings: FilterSettings
    bank: GaussianMixture | None = None

    def predict(self, u_l: Array, u_c: Array, dt: float, where: str) -> None:
        noise = self.settings.motion_noise
        if self.bank is None:
            self.mean, self.cov = predict_arrays(
                self.mean, self.cov, u_l, u_c, dt, noise, where=where
            )
        else:
            self.bank = predict_yaw_bank(self.bank, u_l, u_c, dt, noise)
            self.mean, self.cov = self.bank.heaviest()

    def update(self, z: Array, bank_settings: YawBankSettings | None, where: str) -> Innovation:
        if self.bank is None or bank_settings is None:
            self.mean, self.cov, inn = self.settings.update_arrays(
                self.mean, self.cov, z, where=where
            )
            return inn
        self.bank, inns = update_yaw_bank(self.bank, z, self.settings, bank_settings)
        k = int(self.bank.heaviest_index)
        self.mean, self.cov = self.bank.heaviest()
        if int(self.bank.alive.sum()) == 1:  # collapsed: a single filter from now on
            self.bank = None
        return Innovation(
            residual=inns.residual[k],
            cov=inns.cov[k],
            nis=float(np.asarray(inns.nis)[k]),
            meas_cov=inns.meas_cov[k],
        )


@dataclass
class _Recorder:
    t: list[float] = field(default_factory=list)
    mean: list[Array] = field(default_factory=list)
    cov: list[Array] = field(default_factory=list)
    age: list[float] = field(default_factory=list)
    update_t: list[float] = field(default_factory=list)
    update_age: list[float] = field(default_factory=list)
    nis: list[float] = field(default_factory=list)
    cond_r: list[float] = field(default_factory=list)
    cond_s: list[float] = field(default_factory=list)


TruthFn = Callable[[int, int, float], Array]


class TrackManager:
    """Create, predict, update and delete the tracks of a team (see module docstring).

    ``robots`` names the robots (ids are indices into it); ``odometry_sigma[i]`` is robot i's
    body-velocity noise ``(σ_vx, σ_vy, σ_vz, σ_ω)``. ``truth_fn(observer, observed, t)`` gives the
    true relative pose for policies that need it (simulation); ``rng`` is for policies that
    draw random guesses.
    """

    def __init__(
        self,
        settings: TrackManagerSettings,
        *,
        robots: Sequence[str],
        odometry_sigma: Sequence[Sequence[float] | Array],
        t0: float,
        truth_fn: TruthFn | None = None,
        rng: np.random.Generator | None = None,
    ) -> None:
        if len(odometry_sigma) != len(robots):
            raise ConfigError("odometry_sigma: one (σ_vx, σ_vy, σ_vz, σ_ω) per robot is required")
        self.settings = settings
        self.robots = tuple(robots)
        self._sigma = [tuple(float(s) for s in sig) for sig in odometry_sigma]
        self.t = float(t0)
        self._truth_fn = truth_fn
        self._rng = rng
        self._tracks: dict[tuple[int, int], _Track] = {}
        self._records: dict[tuple[int, int], _Recorder] = {}
        self._events: list[TrackEvent] = []
        self._settings_cache: dict[tuple[int, int, tuple[float, ...]], FilterSettings] = {}

    # ------------------------------------------------------------------ state
    @property
    def live_pairs(self) -> tuple[tuple[int, int], ...]:
        return tuple(self._tracks)

    def belief(self, observer: int, observed: int) -> Gaussian:
        tr = self._tracks[(observer, observed)]
        return Gaussian(mean=tr.mean, cov=tr.cov)

    def _label(self, key: tuple[int, int]) -> str:
        return f"{self.robots[key[0]]}->{self.robots[key[1]]}"

    def _filter_settings(self, key: tuple[int, int], sensor_sigma: Array) -> FilterSettings:
        ck = (key[0], key[1], tuple(float(s) for s in sensor_sigma))
        fs = self._settings_cache.get(ck)
        if fs is None:
            fs = FilterSettings(
                kind=self.settings.filter,  # type: ignore[arg-type]
                motion_noise=VelocityNoise(
                    observer=self._sigma[key[0]],  # type: ignore[arg-type]
                    observed=self._sigma[key[1]],  # type: ignore[arg-type]
                ),
                sensor_noise=RangeBearingNoise(
                    sigma_r=ck[2][0], sigma_azimuth=ck[2][1], sigma_elevation=ck[2][2]
                ),
                pseudo_linear_covariance=self.settings.pseudo_linear_covariance,
            )
            self._settings_cache[ck] = fs
        return fs

    # ------------------------------------------------------------------ steps
    def advance(self, t: float, velocities: Array) -> None:
        """Predict every live track from :attr:`t` to ``t`` with body velocities
        ``velocities (n_robots, 4)`` held over the interval."""
        dt = float(t) - self.t
        if dt < -_TIME_TOL:
            raise ConfigError(f"TrackManager.advance: time went backwards ({self.t} -> {t})")
        if dt > 0.0:
            # One pair at a time: the relative filter's scalar kernels are faster than numpy
            # on the handful of pairs a robot tracks.
            where = f"predict at t={t:.3f}"
            for (i, j), tr in self._tracks.items():
                tr.predict(velocities[i], velocities[j], dt, where)
        self.t = max(self.t, float(t))

    def measure(self, observer: int, observed: int, z: Array, sensor_sigma: Array) -> None:
        """Fuse a measurement taken at :attr:`t`, creating/re-creating the track if needed."""
        key = (int(observer), int(observed))
        z = np.asarray(z, dtype=float)
        sensor_sigma = np.asarray(sensor_sigma, dtype=float)
        settings = self._filter_settings(key, sensor_sigma)
        tr = self._tracks.get(key)
        if tr is None:
            truth = self._truth_fn(key[0], key[1], self.t) if self._truth_fn else None
            belief = self.settings.init(
                InitContext(z=z, sensor_sigma=sensor_sigma, truth=truth, rng=self._rng)
            )
            bank_settings = self.settings.yaw_bank
            bank = None
            if bank_settings is not None and math.sqrt(belief.cov[3, 3]) >= (
                bank_settings.spread_above
            ):
                bank = spread_yaw_bank(belief.mean, belief.cov, bank_settings)
            tr = _Track(
                mean=belief.mean.copy(),
                cov=belief.cov.copy(),
                created_t=self.t,
                last_update_t=self.t,
                settings=settings,
                bank=bank,
            )
            self._tracks[key] = tr
            kind: EventKind = "recreated" if key in self._records else "created"
            self._records.setdefault(key, _Recorder())
            self._events.append(
                TrackEvent(
                    t=self.t, observer=self.robots[key[0]], observed=self.robots[key[1]], kind=kind
                )
            )
            if self.settings.init.uses_measurement:
                return
        tr.settings = settings
        inn = tr.update(z, self.settings.yaw_bank, f"{self._label(key)} at t={self.t:.3f}")
        tr.last_update_t = self.t
        rec = self._records[key]
        rec.update_t.append(self.t)
        rec.update_age.append(self.t - tr.created_t)
        rec.nis.append(float(inn.nis))
        cond = condition_log10_batch(np.stack([inn.meas_cov, inn.cov]))
        rec.cond_r.append(float(cond[0]))
        rec.cond_s.append(float(cond[1]))

    def expire(self) -> None:
        """Delete tracks not updated for more than ``keep_window_s`` (seed 000 §6.2)."""
        window = self.settings.keep_window_s
        for key in [k for k, tr in self._tracks.items() if self.t - tr.last_update_t > window]:
            del self._tracks[key]
            self._events.append(
                TrackEvent(
                    t=self.t,
                    observer=self.robots[key[0]],
                    observed=self.robots[key[1]],
                    kind="deleted",
                )
            )

    def snapshot(self) -> None:
        """Record every live track's belief at :attr:`t`."""
        for key, tr in self._tracks.items():
            rec = self._records[key]
            rec.t.append(self.t)
            rec.mean.append(tr.mean.copy())
            rec.cov.append(tr.cov.copy())
            rec.age.append(self.t - tr.created_t)

    def replay(
        self, times: Array, held: Array, measurements: Measurements, record_times: Array
    ) -> None:
        """The event loop shared by :func:`track_log` and the runtime nodes.

        For every event time ``times[k]`` (increasing, none before :attr:`t`): predict to it
        with the velocities ``held[k] (n_robots, 4)`` in force since the previous event, fuse
        the ``measurements`` (sorted by time) stamped up to it and not fused yet, delete stale
        tracks, and record the beliefs if it is one of the ``record_times`` (each of which must
        be among the event times).
        """
        is_record = np.zeros(len(times), dtype=bool)
        is_record[np.searchsorted(times, np.asarray(record_times) - _TIME_TOL)] = True
        ends = np.searchsorted(measurements.t, np.asarray(times) + _TIME_TOL, side="right")
        done = 0
        for k, t in enumerate(times):
            self.advance(float(t), held[k])
            for q in range(done, int(ends[k])):
                self.measure(
                    int(measurements.observer[q]),
                    int(measurements.observed[q]),
                    measurements.z[q],
                    measurements.sigma[q],
                )
            done = int(ends[k])
            self.expire()
            if is_record[k]:
                self.snapshot()

    def results(self) -> TeamEstimates:
        """The recorded series of every pair ever tracked, in (observer, observed) order."""
        pairs = []
        for key in sorted(self._records):
            r = self._records[key]
            pairs.append(
                PairEstimates(
                    observer=self.robots[key[0]],
                    observed=self.robots[key[1]],
                    t=np.asarray(r.t, dtype=float),
                    mean=np.asarray(r.mean, dtype=float).reshape(-1, 4),
                    cov=np.asarray(r.cov, dtype=float).reshape(-1, 4, 4),
                    age=np.asarray(r.age, dtype=float),
                    update_t=np.asarray(r.update_t, dtype=float),
                    update_age=np.asarray(r.update_age, dtype=float),
                    nis=np.asarray(r.nis, dtype=float),
                    cond_r=np.asarray(r.cond_r, dtype=float),
                    cond_s=np.asarray(r.cond_s, dtype=float),
                )
            )
        return TeamEstimates(
            filter=self.settings.filter, pairs=tuple(pairs), events=tuple(self._events)
        )


def _merge_times(*arrays: Array) -> Array:
    t = np.unique(np.concatenate(arrays))
    if t.size < 2:
        return t
    keep = np.concatenate([[True], np.diff(t) > _TIME_TOL])
    return t[keep]


def track_log(
    log: Log,
    settings: TrackManagerSettings,
    *,
    record_rate_hz: float = 10.0,
    rng: np.random.Generator | None = None,
    use_truth: bool = True,
) -> TeamEstimates:
    """Run a :class:`TrackManager` over a whole log.

    Events are the union of every robot's odometry times, the measurement times and a recording
    grid at ``record_rate_hz`` within the span covered by ground truth. Between two events every
    track is predicted with the velocities each robot reported last (zero-order hold); at an
    event the measurements of that instant are fused, stale tracks are deleted and, on the
    recording grid, beliefs are recorded. ``use_truth`` lets truth-based initialisation
    policies see the true relative pose (simulations and datasets with ground truth).
    """
    if not (np.isfinite(record_rate_hz) and record_rate_hz > 0):
        raise ConfigError(f"record_rate_hz: must be > 0, got {record_rate_hz}")
    t0, t1 = log.span
    n_rec = int(np.floor((t1 - t0) * record_rate_hz + _TIME_TOL))
    record_times = t0 + np.arange(n_rec + 1) / record_rate_hz
    m = log.measurements
    in_span = (m.t >= t0 - _TIME_TOL) & (m.t <= t1 + _TIME_TOL)
    m = m.select(in_span)
    odo_times = [od.t[(od.t > t0) & (od.t < t1)] for od in log.odometry]
    times = _merge_times(np.array([t0, t1]), record_times, m.t, *odo_times)
    times = times[(times >= t0 - _TIME_TOL) & (times <= t1 + _TIME_TOL)]
    held = np.stack([od.held_at(times + _TIME_TOL) for od in log.odometry], axis=1)

    def truth_fn(i: int, j: int, t: float) -> Array:
        return log.relative_truth(i, j, t)[0]

    manager = TrackManager(
        settings,
        robots=log.robots,
        odometry_sigma=[od.sigma for od in log.odometry],
        t0=float(times[0]),
        truth_fn=truth_fn if use_truth else None,
        rng=rng,
    )
    # velocity in force up to each event: the one held at the previous event (none before t0)
    manager.replay(times, np.concatenate([held[:1], held[:-1]]), m, record_times)
    return manager.results()
