"""Many relative filters of one observing robot, run side by side in a few numpy calls.

An observer may run dozens of relative filters over the same inputs: several observed robots,
several initialisations of each (seed 000 Table 1: 13 initial guesses × PLKF / TEKF / yaw bank),
several of its sensors (the four Table-2 settings of seed 000 §6, one sensor index each). They
share the observer's odometry and, per observed robot, that robot's odometry and readings; only
the prior, the update kind and the sensor differ. :class:`RelativeFilterBatch` holds them all,
one :class:`TrackSpec` each, and implements the estimator contract of
:mod:`relloc.core.contract`:

* :meth:`~RelativeFilterBatch.advance` — the shared predict (seed 000 Eq. 7)
  ``x⁻ = f_d(x, u_l, u_c, Δt)``, ``P⁻ = F P Fᵀ + G Σ_u Gᵀ`` of every filter in one batched call
  (:func:`relloc.estimators.relative.predict_arrays`) per velocity-noise model ``Σ_u`` (the
  owner's and the observed robot's odometry σ), with ``Δt`` the time since the previous event;
* :meth:`~RelativeFilterBatch.measure` — each ``range_bearing_elevation`` reading
  ``z = (r, θ, α)`` of the owner updates every filter of its (observed robot, sensor) in one
  batched call per *block* — the filters of one noise model, update kind and, for yaw banks,
  number of hypotheses (:meth:`relloc.estimators.relative.FilterSettings.update_arrays`,
  :func:`relloc.estimators.yaw_bank.update_yaw_bank`) — with the sensor noise the row states;
* :meth:`~RelativeFilterBatch.beliefs` — one :class:`~relloc.core.contract.Belief` per
  filter in frame ``relative_pose4`` with ``track`` = the spec's label; a yaw bank reports its
  highest-weight hypothesis and ``info["n_alive"]``, the hypotheses left;
* :meth:`~RelativeFilterBatch.take_updates` — per update and filter the NIS ``νᵀ S⁻¹ ν``
  (3 degrees of freedom) and ``log10`` condition numbers of ``R`` and ``S`` (seed 000 §7.3); a
  bank's are those of its best hypothesis after the update;
* :meth:`~RelativeFilterBatch.take_counts` — the owner's rows it did not fuse, by reason.

The filters are those of :mod:`relloc.estimators.relative` and
:mod:`relloc.estimators.yaw_bank`; batching changes none of their equations (the batch equals
one tracker per filter, tests/estimators/test_relative_batch.py). Every prior holds at the
first event time (the first :meth:`~RelativeFilterBatch.advance` only sets the clock).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from relloc.core.contract import Belief, HeldOdometry, UpdateRecord
from relloc.core.gaussian import GaussianMixture
from relloc.core.kalman import Innovation
from relloc.core.recording import Measurements
from relloc.errors import ConfigError, DataError
from relloc.estimators.relative import (
    FRAME,
    MEASUREMENT_DOF,
    UPDATE_KINDS,
    FilterSettings,
    ObserverClock,
    UpdateKind,
    predict_arrays,
    unfusable_reason,
)
from relloc.estimators.yaw_bank import YawBankSettings, spread_yaw_bank, update_yaw_bank
from relloc.metrics.conditioning import condition_log10_batch
from relloc.models.measurement import PseudoLinearCovariance, RangeBearingNoise
from relloc.models.motion import VelocityNoise

Array = NDArray[np.float64]
IntArray = NDArray[np.int64]


@dataclass(frozen=True, kw_only=True)
class TrackSpec:
    """One filter of the batch.

    ``label`` names its track (:attr:`Belief.track`; unique per subject); ``subject`` the
    observed robot; ``sensor`` which of the owner's sensors it fuses (the ``sensor`` column of
    the measurements); ``kind`` the update (``plkf``, ``bcplkf``, ``tekf``); ``prior_mean (4,)``
    and ``prior_cov (4, 4)`` its belief at the first event; ``bank``: start a yaw bank
    (:mod:`relloc.estimators.yaw_bank`, pseudo-linear updates only) from that prior.
    """

    label: str
    subject: str
    kind: UpdateKind
    prior_mean: Array
    prior_cov: Array
    sensor: int = 0
    bank: bool = False

    def __post_init__(self) -> None:
        where = f"TrackSpec {self.subject}#{self.label}"
        if self.kind not in UPDATE_KINDS:
            raise ConfigError(f"{where}: kind must be one of {UPDATE_KINDS}, got {self.kind!r}")
        if self.bank and self.kind == "tekf":
            raise ConfigError(f"{where}: a yaw bank runs pseudo-linear updates, not 'tekf'")
        if isinstance(self.sensor, bool) or not isinstance(self.sensor, (int, np.integer)):
            raise ConfigError(f"{where}: sensor must be an integer, got {self.sensor!r}")
        if self.sensor < 0:
            raise ConfigError(f"{where}: sensor must be ≥ 0, got {self.sensor}")
        mean = np.asarray(self.prior_mean, dtype=float)
        cov = np.asarray(self.prior_cov, dtype=float)
        if mean.shape != (4,) or cov.shape != (4, 4):
            raise ConfigError(
                f"{where}: prior must be (4,) and (4, 4), got {mean.shape}, {cov.shape}"
            )
        if not (np.isfinite(mean).all() and np.isfinite(cov).all()):
            raise ConfigError(f"{where}: prior contains NaN or inf")
        object.__setattr__(self, "sensor", int(self.sensor))
        object.__setattr__(self, "prior_mean", mean)
        object.__setattr__(self, "prior_cov", cov)


@dataclass
class _Block:
    """Filters updated together: one subject, sensor and update kind; plain filters or banks
    of ``K`` hypotheses (``weights (banks, K)``). ``rows`` index the group's arrays."""

    subject: int
    sensor: int
    kind: UpdateKind
    specs: list[int]
    rows: IntArray
    weights: Array | None = None


@dataclass
class _Group:
    """Every filter of one velocity-noise model: one predict call per event."""

    noise: VelocityNoise
    means: Array
    covs: Array
    row_subject: IntArray
    single_subject: int | None
    blocks: list[_Block] = field(default_factory=list)


@dataclass(frozen=True)
class _PendingUpdates:
    """One batched update of a block at ``t``: per filter (``specs``) its NIS and ``R``, ``S``."""

    t: float
    age: float
    subject: str
    specs: list[int]
    nis: Array
    meas_cov: Array
    cov: Array


class RelativeFilterBatch(ObserverClock):
    """The relative filters ``specs`` of robot ``owner`` (module docstring).

    ``robots`` names the team (the indices of :class:`HeldOdometry` and of the measurements);
    ``odometry_sigma[i]`` is robot ``i``'s body-velocity noise ``(σ_vx, σ_vy, σ_vz, σ_ω)``;
    ``bank`` how yaw banks spread and reduce; ``pseudo_linear_covariance`` the PLKF's ``R``.
    """

    def __init__(
        self,
        specs: Sequence[TrackSpec],
        *,
        owner: str,
        robots: Sequence[str],
        odometry_sigma: Sequence[ArrayLike],
        bank: YawBankSettings | None = None,
        pseudo_linear_covariance: PseudoLinearCovariance = "simplified",
        name: str = "relative_filters",
    ) -> None:
        self.robots = tuple(robots)
        if owner not in self.robots:
            raise ConfigError(
                f"RelativeFilterBatch: owner {owner!r} is not on the team {self.robots}"
            )
        if len(odometry_sigma) != len(self.robots):
            raise ConfigError(
                f"RelativeFilterBatch: {len(odometry_sigma)} odometry σ for "
                f"{len(self.robots)} robots"
            )
        if not specs:
            raise ConfigError("RelativeFilterBatch: no filters given")
        self.owner = owner
        self.name = name
        self.specs = tuple(specs)
        self.bank_settings = bank or YawBankSettings()
        self.pseudo_linear_covariance = pseudo_linear_covariance
        self._me = self.robots.index(owner)
        self._sigma = [tuple(float(s) for s in np.reshape(sig, -1)) for sig in odometry_sigma]
        self._subjects = [self._subject_index(s) for s in self.specs]
        self._groups = self._build_groups()
        self._blocks_of: dict[tuple[int, int], list[tuple[_Group, _Block]]] = {}
        for g in self._groups:
            for b in g.blocks:
                self._blocks_of.setdefault((b.subject, b.sensor), []).append((g, b))
        self._settings: dict[tuple[str, VelocityNoise, tuple[float, ...]], FilterSettings] = {}
        self._start_clock()
        self._t0 = 0.0
        self._pending: list[_PendingUpdates] = []

    # ------------------------------------------------------------------ building
    def _subject_index(self, spec: TrackSpec) -> int:
        if spec.subject not in self.robots:
            raise ConfigError(
                f"TrackSpec {spec.label!r}: subject {spec.subject!r} is not on the team "
                f"{self.robots}"
            )
        j = self.robots.index(spec.subject)
        if j == self._me:
            raise ConfigError(f"TrackSpec {spec.label!r}: the owner cannot track itself")
        return j

    def _build_groups(self) -> list[_Group]:
        """Stack the filters: rows grouped by noise model, blocks by (subject, sensor, kind,
        bank size); a bank takes ``K`` consecutive rows."""
        seen: set[tuple[str, str]] = set()
        members: dict[VelocityNoise, list[int]] = {}
        for i, (spec, j) in enumerate(zip(self.specs, self._subjects, strict=True)):
            if (spec.subject, spec.label) in seen:
                raise ConfigError(f"TrackSpec: label {spec.label!r} repeats for {spec.subject!r}")
            seen.add((spec.subject, spec.label))
            noise = VelocityNoise.of(self._sigma[self._me], self._sigma[j])
            members.setdefault(noise, []).append(i)
        return [self._build_group(noise, idx) for noise, idx in members.items()]

    def _build_group(self, noise: VelocityNoise, members: list[int]) -> _Group:
        means: list[Array] = []
        covs: list[Array] = []
        subjects: list[int] = []
        blocks: dict[tuple[int, int, str, bool, int], _Block] = {}
        row = 0
        for i in members:
            spec, j = self.specs[i], self._subjects[i]
            if spec.bank:
                b = spread_yaw_bank(spec.prior_mean, spec.prior_cov, self.bank_settings)
                k, m, P = b.weights.shape[-1], b.means, b.covs
            else:
                k, m, P = 1, spec.prior_mean[None, :], spec.prior_cov[None, :, :]
            key = (j, spec.sensor, spec.kind, spec.bank, k)
            block = blocks.setdefault(
                key, _Block(j, spec.sensor, spec.kind, [], np.zeros(0, dtype=np.int64))
            )
            block.specs.append(i)
            block.rows = np.concatenate([block.rows, np.arange(row, row + k)])
            means.append(np.asarray(m, dtype=float))
            covs.append(np.asarray(P, dtype=float))
            subjects.extend([j] * k)
            row += k
        for (_, _, _, is_bank, k), block in blocks.items():
            if is_bank:
                block.weights = np.ones((len(block.specs), k))
        distinct = set(subjects)
        return _Group(
            noise=noise,
            means=np.concatenate(means),
            covs=np.concatenate(covs),
            row_subject=np.asarray(subjects, dtype=np.int64),
            single_subject=distinct.pop() if len(distinct) == 1 else None,
            blocks=list(blocks.values()),
        )

    # ------------------------------------------------------------------ the contract
    def advance(self, t: float, odometry: HeldOdometry) -> None:
        """Predict every filter from the previous event to ``t`` with the body velocities
        ``odometry.velocity (n_robots, 4)`` held since (the first call only sets the clock)."""
        t = float(t)
        dt = self._elapsed(t)
        if dt is None:
            self._t0 = t
            return
        velocity = np.asarray(odometry.velocity, dtype=float)
        if velocity.shape != (len(self.robots), 4):
            raise DataError(
                f"RelativeFilterBatch.advance: odometry of shape {velocity.shape} for "
                f"{len(self.robots)} robots"
            )
        if dt > 0.0:
            where = f"{self.owner}: predict to t={t:.3f}"
            u_l = velocity[self._me]
            for g in self._groups:
                if g.single_subject is None:
                    u_c = velocity[g.row_subject]
                else:
                    u_c = velocity[g.single_subject]
                g.means, g.covs = predict_arrays(
                    g.means, g.covs, u_l, u_c, dt, g.noise, where=where
                )
        self.t = max(self._now("advance"), t)

    def measure(self, batch: Measurements) -> None:
        """Fuse the owner's ``range_bearing_elevation`` rows of tracked (robot, sensor) pairs in
        row order; count the owner's other rows by reason."""
        self._now("measure")
        assert batch.sensor is not None
        for q in np.flatnonzero(batch.observer == self._me).tolist():
            reason = self._unusable(batch, q)
            if reason:
                self._count(reason)
                continue
            j, s = int(batch.target[q]), int(batch.sensor[q])
            z = np.asarray(batch.value[q, :MEASUREMENT_DOF])
            sigma = batch.sigma[q, :MEASUREMENT_DOF]
            sensor_noise = RangeBearingNoise(
                sigma_r=float(sigma[0]),
                sigma_azimuth=float(sigma[1]),
                sigma_elevation=float(sigma[2]),
            )
            for g, block in self._blocks_of[(j, s)]:
                self._update_block(g, block, z, sensor_noise)

    def beliefs(self) -> list[Belief]:
        """Every filter's belief now, in spec order (a bank: its best hypothesis)."""
        age = self._now("beliefs") - self._t0
        out: list[Belief | None] = [None] * len(self.specs)
        for g in self._groups:
            for block in g.blocks:
                if block.weights is None:
                    mean, cov = g.means[block.rows], g.covs[block.rows]
                    info: list[Mapping[str, float]] = [{}] * len(block.specs)
                else:
                    bank = self._bank(g, block)
                    mean, cov = bank.heaviest()
                    info = [{"n_alive": float(n)} for n in bank.alive.sum(axis=-1)]
                for n, i in enumerate(block.specs):
                    spec = self.specs[i]
                    out[i] = Belief(
                        subject=spec.subject,
                        frame=FRAME,
                        mean=mean[n],
                        cov=cov[n],
                        age=age,
                        info=info[n],
                        track=spec.label,
                    )
        return [b for b in out if b is not None]

    def take_updates(self) -> list[UpdateRecord]:
        """The updates since the previous call, in the order they were made."""
        pending, self._pending = self._pending, []
        if not pending:
            return []
        matrices = [p.meas_cov for p in pending] + [p.cov for p in pending]
        cond = condition_log10_batch(np.concatenate(matrices)).tolist()
        n = len(cond) // 2
        cond_r, cond_s = cond[:n], cond[n:]
        out: list[UpdateRecord] = []
        for p in pending:
            for nis, i in zip(p.nis.tolist(), p.specs, strict=True):
                k = len(out)
                out.append(
                    UpdateRecord(
                        t=p.t,
                        subject=p.subject,
                        nis=nis,
                        dof=MEASUREMENT_DOF,
                        cond_r=cond_r[k],
                        cond_s=cond_s[k],
                        age=p.age,
                        track=self.specs[i].label,
                    )
                )
        return out

    # ------------------------------------------------------------------ internals
    def _unusable(self, batch: Measurements, q: int) -> str:
        """Why row ``q`` of the owner cannot be fused (empty if it can): the relative filters'
        rule (:func:`relloc.estimators.relative.unfusable_reason`), or no track of its
        (target, sensor)."""
        assert batch.sensor is not None
        reason = unfusable_reason(batch, q)
        if not reason and (int(batch.target[q]), int(batch.sensor[q])) not in self._blocks_of:
            return "rows_of_untracked_target_or_sensor"
        return reason

    def _filter_settings(
        self, kind: UpdateKind, noise: VelocityNoise, sensor: RangeBearingNoise
    ) -> FilterSettings:
        key = (kind, noise, (sensor.sigma_r, sensor.sigma_azimuth, sensor.sigma_elevation))
        fs = self._settings.get(key)
        if fs is None:
            fs = FilterSettings(
                kind=kind,
                motion_noise=noise,
                sensor_noise=sensor,
                pseudo_linear_covariance=self.pseudo_linear_covariance,
            )
            self._settings[key] = fs
        return fs

    def _bank(self, g: _Group, block: _Block) -> GaussianMixture:
        assert block.weights is not None
        nb, k = block.weights.shape
        return GaussianMixture(
            means=g.means[block.rows].reshape(nb, k, 4),
            covs=g.covs[block.rows].reshape(nb, k, 4, 4),
            weights=block.weights,
        )

    def _update_block(self, g: _Group, block: _Block, z: Array, sensor: RangeBearingNoise) -> None:
        """One batched update of every filter of ``block`` with ``z = (r, θ, α)``."""
        settings = self._filter_settings(block.kind, g.noise, sensor)
        where = (
            f"{self.owner}->{self.robots[block.subject]} (sensor {block.sensor}) at t={self.t:.3f}"
        )
        if block.weights is None:
            rows = block.rows
            mean, cov, inn = settings.update_arrays(g.means[rows], g.covs[rows], z, where=where)
            g.means[rows] = mean
            g.covs[rows] = cov
            self._log(block, inn)
            return
        nb, k = block.weights.shape
        bank, inn = update_yaw_bank(self._bank(g, block), z, settings, self.bank_settings)
        g.means[block.rows] = bank.means.reshape(nb * k, 4)
        g.covs[block.rows] = bank.covs.reshape(nb * k, 4, 4)
        block.weights = bank.weights
        pick = np.arange(nb), bank.heaviest_index
        self._log(
            block,
            Innovation(
                residual=inn.residual[pick],
                cov=inn.cov[pick],
                nis=np.asarray(inn.nis)[pick],
                meas_cov=inn.meas_cov[pick],
            ),
        )

    def _log(self, block: _Block, inn: Innovation) -> None:
        """Keep the update of every filter of ``block`` (``inn`` batched over them) for
        :meth:`take_updates`, which conditions all ``R`` and ``S`` kept in one call."""
        now = self._now("measure")
        self._pending.append(
            _PendingUpdates(
                t=now,
                age=now - self._t0,
                subject=self.robots[block.subject],
                specs=block.specs,
                nis=np.asarray(inn.nis, dtype=float).reshape(-1),
                meas_cov=np.asarray(inn.meas_cov),
                cov=np.asarray(inn.cov),
            )
        )
