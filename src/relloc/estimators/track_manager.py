"""One observing robot's tracks of its teammates, whose membership changes over time.

Seed 000 §3.1 allows M observing and N observed robots whose numbers vary; §6.2 proposes that
when an observed robot leaves the field of view its track is kept (predicted only) for a
pre-defined window and deleted if the robot does not reappear, and that a robot seen again after
deletion gets a new track. :class:`TrackManager` does exactly that for one observing robot (its
``owner``); a team runs one manager per observing robot (:func:`managers_for`):

- a track per observed robot is **created** on the owner's first measurement of it, starting
  from an :class:`~relloc.estimators.initialisation.InitPolicy`;
- every live track is **predicted** with both robots' body velocities (the shared predict of
  :mod:`relloc.estimators.relative`);
- a measurement **updates** its track with the selected filter — PLKF, TEKF or
  bias-compensated PLKF (``bcplkf``);
- optionally, a track whose initial yaw is unknown starts as a bank of yaw hypotheses (a
  Gaussian sum over φ, :mod:`relloc.estimators.yaw_bank`) that is reweighted by every
  measurement and collapses to a single filter once one hypothesis dominates — this avoids the
  long stalls of a single filter started near the wrong yaw (seed 000 Table 1, case 4); while
  the bank lives, the track's belief is its heaviest hypothesis, from the instant it is created
  (so a prediction over a zero or 1e-16 s step, which one clock may take and another not,
  changes nothing);
- optionally (``gate_probability``), a measurement whose NIS exceeds ``χ²(3, p)`` under every
  live hypothesis of its track is **rejected** as an outlier, not fused, and counted
  (``rows_gated``); seed 000 fuses every measurement, so the gate is off by default. A rejected
  measurement does not refresh the track, so a track whose every measurement is rejected is
  deleted like an unseen one;
- a track with no update for longer than ``keep_window_s`` is **deleted**; the next measurement
  of that robot **re-creates** it.

The manager implements the estimator contract of :mod:`relloc.core.contract`, so
:func:`relloc.pipeline.replay.replay` (in-process) and a robot node (window by window) drive it
alike. At an event time ``t`` it is advanced, then measured (the owner's
``range_bearing_elevation`` rows of known targets, one at a time in row order), then stale
tracks are deleted as of ``t``. The deletion is done lazily — when the manager next moves on
(:meth:`TrackManager.advance`) or is asked what it holds (:meth:`TrackManager.beliefs`,
:meth:`TrackManager.take_events`) — which deletes exactly the tracks, and stamps the deletions
with exactly the times, that deleting after every event would: nothing changes a track between
the end of one event and the start of the next.

Beliefs are reported in frame ``relative_pose4`` (the observed robot's ``(x, y, z, φ)`` in the
owner's body frame, seed 000 Eq. 1) with the track's age; every update reports its NIS (3 degrees
of freedom) and the conditioning ``log10(λmax/λmin)`` of ``R`` and ``S`` (seed 000 §7.3).
Rows of the owner that the manager cannot use — another kind, an unknown target (unknown
correspondence or a landmark), no stated σ, beyond the gate — are counted by reason
(:meth:`TrackManager.take_counts`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from relloc.core.checks import probability
from relloc.core.contract import (
    Belief,
    EventKind,
    HeldOdometry,
    TrackEvent,
    UpdateRecord,
)
from relloc.core.gaussian import GaussianMixture
from relloc.core.kalman import Innovation, chi2_threshold
from relloc.core.recording import Measurements, Recording
from relloc.errors import ConfigError
from relloc.estimators.initialisation import InitContext, InitPolicy
from relloc.estimators.relative import (
    FRAME,
    MEASUREMENT_DOF,
    UPDATE_KINDS,
    FilterSettings,
    ObserverClock,
    is_relative_reading,
    predict_arrays,
    unfusable_reason,
)
from relloc.estimators.yaw_bank import (
    YawBankSettings,
    predict_yaw_bank,
    spread_yaw_bank,
    update_yaw_bank,
)
from relloc.metrics.conditioning import condition_log10_batch
from relloc.models.measurement import RangeBearingNoise
from relloc.models.motion import VelocityNoise

Array = NDArray[np.float64]


@dataclass(frozen=True, kw_only=True)
class TrackManagerSettings:
    """``filter``: ``plkf`` | ``tekf`` | ``bcplkf``; ``keep_window_s``: how long a track is
    predicted without measurements before deletion; ``pseudo_linear_covariance``:
    ``simplified`` (seed 000 Eq. 6) or ``full`` (Eqs. 4–5); ``init``: how tracks start;
    ``yaw_bank``: spread a track whose initial yaw is unknown into a bank of yaw hypotheses
    (:mod:`relloc.estimators.yaw_bank`), or ``None`` for a single filter per track;
    ``gate_probability``: reject a measurement whose NIS exceeds ``χ²(3, p)`` (module
    docstring), or ``None`` to fuse every measurement (seed 000)."""

    filter: str = "plkf"
    keep_window_s: float = 2.0
    pseudo_linear_covariance: Literal["simplified", "full"] = "simplified"
    init: InitPolicy = field(default_factory=InitPolicy)
    yaw_bank: YawBankSettings | None = None
    gate_probability: float | None = None

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
        if self.gate_probability is not None:
            probability(self.gate_probability, "gate_probability")

    @property
    def nis_gate(self) -> float:
        """The NIS beyond which a measurement is rejected (``inf`` without a gate)."""
        if self.gate_probability is None:
            return math.inf
        return chi2_threshold(MEASUREMENT_DOF, self.gate_probability)


@dataclass
class _Track:
    """A live track: its best estimate (the bank's heaviest hypothesis while the bank lives)
    and the bank."""

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
            self.bank = predict_yaw_bank(self.bank, u_l, u_c, dt, noise, where=where)
            self.mean, self.cov = self.bank.heaviest()

    def update(
        self, z: Array, bank_settings: YawBankSettings | None, gate: float, where: str
    ) -> Innovation | None:
        """Fuse ``z`` and return the innovation used, or return ``None`` and leave the track as
        it was when the NIS exceeds ``gate`` under every live hypothesis."""
        if self.bank is None or bank_settings is None:
            mean, cov, inn = self.settings.update_arrays(self.mean, self.cov, z, where=where)
            if inn.nis > gate:
                return None
            self.mean, self.cov = mean, cov
            return inn
        bank, inns = update_yaw_bank(self.bank, z, self.settings, bank_settings, where=where)
        if np.min(np.asarray(inns.nis)[self.bank.alive]) > gate:
            return None
        self.bank = bank
        k = int(bank.heaviest_index)
        self.mean, self.cov = bank.heaviest()
        if int(bank.alive.sum()) == 1:  # collapsed: a single filter from now on
            self.bank = None
        return Innovation(
            residual=inns.residual[k],
            cov=inns.cov[k],
            nis=float(np.asarray(inns.nis)[k]),
            meas_cov=inns.meas_cov[k],
        )


TruthFn = Callable[[int, float], Array]
"""``truth(j, t)``: the true relative pose of robot ``j`` in the owner's body frame at ``t`` —
only for the initialisation policies that start from the truth (seed 000 Table 1 cases 1–3)."""


class TrackManager(ObserverClock):
    """The tracks one robot (``owner``) holds of its teammates (module docstring).

    ``robots`` names the team (measurement indices index it); ``odometry_sigma[i]`` is robot
    i's body-velocity noise ``(σ_vx, σ_vy, σ_vz, σ_ω)``; ``truth`` feeds the policies that
    start from the true relative pose; ``rng`` the policies that draw random guesses.
    """

    def __init__(
        self,
        settings: TrackManagerSettings,
        *,
        owner: str,
        robots: Sequence[str],
        odometry_sigma: Sequence[Sequence[float] | Array],
        truth: TruthFn | None = None,
        rng: np.random.Generator | None = None,
    ) -> None:
        self.robots = tuple(robots)
        if owner not in self.robots:
            raise ConfigError(f"TrackManager: owner {owner!r} is not on the team {self.robots}")
        if len(odometry_sigma) != len(self.robots):
            raise ConfigError("odometry_sigma: one (σ_vx, σ_vy, σ_vz, σ_ω) per robot is required")
        self.settings = settings
        self.owner = owner
        self.name = settings.filter
        self._me = self.robots.index(owner)
        self._sigma = [tuple(float(s) for s in sig) for sig in odometry_sigma]
        self._start_clock()
        self._truth = truth
        self._rng = rng
        self._tracks: dict[int, _Track] = {}
        self._ever_tracked: set[int] = set()
        self._updates: list[UpdateRecord] = []
        self._events: list[TrackEvent] = []
        self._settings_cache: dict[tuple[int, tuple[float, ...]], FilterSettings] = {}
        self._gate = settings.nis_gate

    # ------------------------------------------------------------------ the contract
    def advance(self, t: float, odometry: HeldOdometry) -> None:
        """Delete the tracks stale at the previous event, then predict every live track to
        ``t`` with the body velocities ``odometry.velocity (n_robots, 4)`` held since."""
        t = float(t)
        dt = self._elapsed(t)
        if dt is None:
            return
        self._expire()
        if dt > 0.0:
            # One track at a time: the relative filter's scalar kernels are faster than numpy
            # on the handful of robots one observer tracks.
            when = f" predict at t={t:.3f}"
            u_l = odometry.velocity[self._me]
            for j, tr in self._tracks.items():
                tr.predict(u_l, odometry.velocity[j], dt, f"{self.owner}->{self.robots[j]}{when}")
        self.t = max(self._now("advance"), t)

    def measure(self, batch: Measurements) -> None:
        """Fuse the owner's ``range_bearing_elevation`` rows of known robots, in row order;
        count the owner's other rows by reason."""
        now = self._now("measure")
        for q in np.flatnonzero(batch.observer == self._me):
            reason = unfusable_reason(batch, int(q))
            if reason:
                self._count(reason)
                continue
            self._fuse(int(batch.target[q]), batch.value[q], batch.sigma[q], now)

    def beliefs(self) -> list[Belief]:
        """Every live track's belief now (stale tracks deleted first)."""
        now = self._now("beliefs")
        self._expire()
        return [
            Belief(
                subject=self.robots[j],
                frame=FRAME,
                mean=tr.mean.copy(),
                cov=tr.cov.copy(),
                age=now - tr.created_t,
            )
            for j, tr in self._tracks.items()
        ]

    def take_updates(self) -> list[UpdateRecord]:
        out, self._updates = self._updates, []
        return out

    def take_events(self) -> list[TrackEvent]:
        """Track events since the previous call (deletions as of the latest event included)."""
        if self.t is not None:
            self._expire()
        out, self._events = self._events, []
        return out

    # ------------------------------------------------------------------ internals
    def _filter_settings(self, j: int, sensor_sigma: Array) -> FilterSettings:
        key = (j, tuple(float(s) for s in sensor_sigma))
        fs = self._settings_cache.get(key)
        if fs is None:
            fs = FilterSettings(
                kind=self.settings.filter,  # type: ignore[arg-type]
                motion_noise=VelocityNoise(
                    observer=self._sigma[self._me],  # type: ignore[arg-type]
                    observed=self._sigma[j],  # type: ignore[arg-type]
                ),
                sensor_noise=RangeBearingNoise(
                    sigma_r=key[1][0], sigma_azimuth=key[1][1], sigma_elevation=key[1][2]
                ),
                pseudo_linear_covariance=self.settings.pseudo_linear_covariance,
            )
            self._settings_cache[key] = fs
        return fs

    def _fuse(self, j: int, value: Array, sigma: Array, now: float) -> None:
        """One measurement ``z = (r, θ, α)`` of robot ``j``, creating/re-creating its track."""
        z = np.asarray(value[:MEASUREMENT_DOF], dtype=float)
        sensor_sigma = np.asarray(sigma[:MEASUREMENT_DOF], dtype=float)
        settings = self._filter_settings(j, sensor_sigma)
        tr = self._tracks.get(j)
        if tr is None:
            tr = self._create(j, z, sensor_sigma, settings, now)
            if self.settings.init.uses_measurement:
                return
        tr.settings = settings
        label = f"{self.owner}->{self.robots[j]} at t={now:.3f}"
        inn = tr.update(z, self.settings.yaw_bank, self._gate, label)
        if inn is None:
            self._count("rows_gated")
            return
        tr.last_update_t = now
        cond = condition_log10_batch(np.stack([inn.meas_cov, inn.cov]))
        self._updates.append(
            UpdateRecord(
                t=now,
                subject=self.robots[j],
                nis=float(inn.nis),
                dof=MEASUREMENT_DOF,
                cond_r=float(cond[0]),
                cond_s=float(cond[1]),
                age=now - tr.created_t,
            )
        )

    def _create(
        self, j: int, z: Array, sensor_sigma: Array, settings: FilterSettings, now: float
    ) -> _Track:
        truth = self._truth(j, now) if self._truth is not None else None
        belief = self.settings.init(
            InitContext(z=z, sensor_sigma=sensor_sigma, truth=truth, rng=self._rng)
        )
        bank_settings = self.settings.yaw_bank
        bank = None
        if bank_settings is not None and math.sqrt(belief.cov[3, 3]) >= bank_settings.spread_above:
            bank = spread_yaw_bank(belief.mean, belief.cov, bank_settings)
        mean, cov = (belief.mean, belief.cov) if bank is None else bank.heaviest()
        tr = _Track(
            mean=mean.copy(),
            cov=cov.copy(),
            created_t=now,
            last_update_t=now,
            settings=settings,
            bank=bank,
        )
        self._tracks[j] = tr
        kind: EventKind = "recreated" if j in self._ever_tracked else "created"
        self._ever_tracked.add(j)
        self._events.append(TrackEvent(t=now, owner=self.owner, subject=self.robots[j], kind=kind))
        return tr

    def _expire(self) -> None:
        """Delete tracks not updated for more than ``keep_window_s`` (seed 000 §6.2)."""
        now = self._now("expire")
        window = self.settings.keep_window_s
        for j in [j for j, tr in self._tracks.items() if now - tr.last_update_t > window]:
            del self._tracks[j]
            self._events.append(
                TrackEvent(t=now, owner=self.owner, subject=self.robots[j], kind="deleted")
            )


DEFAULT_YAW_BANK = 12
"""Yaw hypotheses a track with unknown initial yaw starts with in ``relloc run``, ``team up``
and ``relloc node`` (0 = one filter, as in seed 000). :class:`TrackManagerSettings` alone
defaults to one filter."""


def default_tracker() -> TrackManagerSettings:
    """The tracker of ``relloc run`` (``TeamRunSettings()``), ``team up`` and ``relloc node``:
    the PLKF from the first measurement with :data:`DEFAULT_YAW_BANK` yaw hypotheses, keep
    window 2 s."""
    return TrackManagerSettings(yaw_bank=YawBankSettings(n_components=DEFAULT_YAW_BANK))


def managers_for(
    recording: Recording,
    settings: TrackManagerSettings,
    *,
    rng: np.random.Generator | None = None,
) -> list[TrackManager]:
    """One :class:`TrackManager` per robot that measures others with ``range_bearing_elevation``
    rows, in robot order, sharing ``rng`` (so a random initialisation draws in the order of the
    rows, which are sorted by time and observer).

    The policies that start from the truth get the recording's true relative poses (a
    simulation, or a dataset with ground truth).
    """
    m = recording.measurements
    observing = np.unique(m.observer[is_relative_reading(m.kind)])
    return [
        track_manager_of(recording, recording.robots[int(i)], settings, rng=rng) for i in observing
    ]


def track_manager_of(
    recording: Recording,
    owner: str,
    settings: TrackManagerSettings,
    *,
    rng: np.random.Generator | None = None,
) -> TrackManager:
    """The :class:`TrackManager` of robot ``owner`` of ``recording`` (see :func:`managers_for`)."""
    i = recording.index(owner)
    truth: TruthFn | None = None
    if settings.init.needs_truth and recording.truth is not None:

        def truth(j: int, t: float) -> Array:
            return recording.relative_truth(i, j, t)[0]

    return TrackManager(
        settings,
        owner=recording.robots[i],
        robots=recording.robots,
        odometry_sigma=[od.sigma for od in recording.odometry],
        truth=truth,
        rng=rng,
    )
