"""Many relative filters of one observing robot, run side by side in a few numpy calls.

The seed-000 reproduction runs, on each Monte-Carlo draw, dozens of filters over the same
inputs: the four observed robots of the team, the Table-1 initialisations (13 guesses x
PLKF / TEKF / yaw bank), the four Table-2 sensor settings of the MRCLAM replay. They share the
observer's odometry and, per observed robot, the observed robot's odometry and its
measurements; only the prior and the update differ. This module stacks them so that each
propagation step is one batched predict per velocity-noise model
(:func:`relloc.estimators.relative.predict_arrays`) and each measurement one batched update per
filter kind (:meth:`relloc.estimators.relative.FilterSettings.update_arrays`) or per group of
yaw banks (:func:`relloc.estimators.yaw_bank.update_yaw_bank`). The filters themselves are
those of :mod:`relloc.estimators.relative` and :mod:`relloc.estimators.yaw_bank`; nothing here
changes their equations.

Time convention: ``u_l[k]``, ``u_c[k]`` drive the step ``t_k → t_{k+1}`` (zero-order hold);
a measurement with ``step = s`` is taken at ``t_s``, i.e. after ``s`` predict steps.
"""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from relloc.core.gaussian import GaussianMixture
from relloc.core.kalman import Innovation
from relloc.errors import ConfigError, DataError
from relloc.estimators.relative import FilterSettings, UpdateKind, predict_arrays
from relloc.estimators.yaw_bank import YawBankSettings, spread_yaw_bank, update_yaw_bank
from relloc.metrics.conditioning import condition_log10_batch
from relloc.metrics.consistency import nees
from relloc.metrics.errors import state_errors
from relloc.models.measurement import RangeBearingNoise
from relloc.models.motion import VelocityNoise

Array = NDArray[np.float64]
IntArray = NDArray[np.int64]


@dataclass(frozen=True)
class TargetStream:
    """One observed robot (or one sensor setting of it) as the observer sees it.

    ``u_c (T, 4)`` the observed robot's body-velocity inputs; ``noise`` the velocity noise of
    the pair (observer and observed σ); ``sensor`` the range/bearing noise; measurement ``j``
    is ``z[j]`` taken at grid step ``step[j]`` where the true relative pose is ``truth[j]``.
    """

    name: str
    u_c: Array
    noise: VelocityNoise
    sensor: RangeBearingNoise
    step: IntArray
    z: Array
    truth: Array

    def __post_init__(self) -> None:
        m = len(self.step)
        if self.z.shape != (m, 3) or self.truth.shape != (m, 4):
            raise DataError(
                f"target {self.name}: {m} steps but z {self.z.shape}, truth {self.truth.shape}"
            )
        if m and np.any(np.diff(self.step) <= 0):
            raise DataError(f"target {self.name}: measurement steps must be strictly increasing")


@dataclass(frozen=True)
class PairStreams:
    """The observer's inputs ``u_l (T, 4)`` on a grid of step ``dt`` and its targets."""

    dt: float
    u_l: Array
    targets: tuple[TargetStream, ...]

    def __post_init__(self) -> None:
        T = self.u_l.shape[0]
        for tgt in self.targets:
            if tgt.u_c.shape != (T, 4):
                raise DataError(f"target {tgt.name}: u_c {tgt.u_c.shape}, expected {(T, 4)}")
            if len(tgt.step) and (tgt.step[0] < 1 or tgt.step[-1] > T):
                raise DataError(f"target {tgt.name}: measurement steps outside 1..{T}")

    @property
    def n_steps(self) -> int:
        """Propagation steps ``T``."""
        return int(self.u_l.shape[0])


@dataclass(frozen=True, kw_only=True)
class TrackSpec:
    """One filter to run: its target, update kind, prior and whether it is a yaw bank.

    ``detail`` records σ, NEES, NIS and conditioning besides the errors.
    """

    target: int
    kind: UpdateKind
    prior_mean: Array
    prior_cov: Array
    bank: bool = False
    detail: bool = False


#: Per-update series recorded for a ``detail`` track besides the errors.
DETAIL_FIELDS: tuple[str, ...] = ("sigma", "nees", "nis", "cond_p", "cond_r", "cond_s")


@dataclass
class TrackRecord:
    """What a filter produced at each of its target's measurements (after the update).

    ``errors (M, 4)`` (yaw wrapped); ``detail`` (``detail`` tracks only): ``sigma (M, 4)``,
    ``nees``, ``nis``, ``cond_p``, ``cond_r``, ``cond_s`` ``(M,)`` (log10 condition numbers of
    P⁺, R and S); ``n_alive (M,)`` hypotheses left in a yaw bank.
    """

    errors: Array
    detail: dict[str, Array] = field(default_factory=dict)
    n_alive: Array | None = None


@dataclass
class _Block:
    """Rows of one noise group updated together: same target, same kind, plain or bank."""

    target: int
    kind: UpdateKind
    specs: list[int]
    rows: IntArray
    weights: Array | None = None
    detail: NDArray[np.bool_] = field(default_factory=lambda: np.zeros(0, dtype=bool))


@dataclass
class _Group:
    """All rows sharing one velocity-noise model (one predict call per step)."""

    noise: VelocityNoise
    means: Array
    covs: Array
    row_target: IntArray
    blocks: list[_Block]
    single_target: int | None = None


def _build_groups(
    streams: PairStreams, specs: Sequence[TrackSpec], bank_settings: YawBankSettings
) -> list[_Group]:
    by_noise: dict[VelocityNoise, list[int]] = defaultdict(list)
    for i, s in enumerate(specs):
        if not 0 <= s.target < len(streams.targets):
            raise ConfigError(f"track {i}: target {s.target} is not one of the streams")
        if s.bank and s.kind == "tekf":
            raise ConfigError(f"track {i}: a yaw bank runs pseudo-linear updates, not 'tekf'")
        by_noise[streams.targets[s.target].noise].append(i)
    groups = []
    for noise, members in by_noise.items():
        means: list[Array] = []
        covs: list[Array] = []
        targets: list[int] = []
        blocks: dict[tuple[int, str, bool, int], _Block] = {}
        row = 0
        for i in members:
            s = specs[i]
            if s.bank:
                bank = spread_yaw_bank(s.prior_mean, s.prior_cov, bank_settings)
                k = bank.weights.shape[-1]
                m, P = bank.means, bank.covs
            else:
                k = 1
                m, P = s.prior_mean[None, :], s.prior_cov[None, :, :]
            key = (s.target, s.kind, s.bank, k)
            block = blocks.setdefault(key, _Block(s.target, s.kind, [], np.zeros(0, np.int64)))
            block.specs.append(i)
            block.rows = np.concatenate([block.rows, np.arange(row, row + k)])
            means.append(np.asarray(m, dtype=float))
            covs.append(np.asarray(P, dtype=float))
            targets.extend([s.target] * k)
            row += k
        for (_, _, is_bank, k), block in blocks.items():
            block.detail = np.array([specs[i].detail for i in block.specs])
            if is_bank:
                block.weights = np.ones((len(block.specs), k))
        groups.append(
            _Group(
                noise=noise,
                means=np.concatenate(means),
                covs=np.concatenate(covs),
                row_target=np.asarray(targets, dtype=np.int64),
                blocks=list(blocks.values()),
                single_target=_members_target(specs, members),
            )
        )
    return groups


def _members_target(specs: Sequence[TrackSpec], members: Sequence[int]) -> int | None:
    """The one target all ``members`` track, or ``None`` if they track several."""
    targets = {specs[i].target for i in members}
    return targets.pop() if len(targets) == 1 else None


def _record(
    records: list[TrackRecord],
    block: _Block,
    m_idx: int,
    mean: Array,
    cov: Array,
    innovation: Innovation,
    truth: Array,
    n_alive: Array | None,
) -> None:
    err = state_errors(mean, np.broadcast_to(truth, mean.shape))
    for n, i in enumerate(block.specs):
        records[i].errors[m_idx] = err[n]
        alive_series = records[i].n_alive
        if n_alive is not None and alive_series is not None:
            alive_series[m_idx] = n_alive[n]
    det = block.detail
    if not det.any():
        return
    values = {
        "sigma": np.sqrt(np.diagonal(cov[det], axis1=-2, axis2=-1)),
        "nees": nees(err[det], cov[det]),
        "nis": np.asarray(innovation.nis)[det],
        "cond_p": condition_log10_batch(cov[det]),
        "cond_r": condition_log10_batch(innovation.meas_cov[det]),
        "cond_s": condition_log10_batch(innovation.cov[det]),
    }
    for n, i in enumerate(np.asarray(block.specs)[det].tolist()):
        for name, series in records[i].detail.items():
            series[m_idx] = values[name][n]


def _update_block(
    group: _Group,
    block: _Block,
    target: TargetStream,
    m_idx: int,
    records: list[TrackRecord],
    bank_settings: YawBankSettings,
) -> None:
    settings = FilterSettings(kind=block.kind, motion_noise=group.noise, sensor_noise=target.sensor)
    z = target.z[m_idx]
    where = f"{target.name}, measurement {m_idx}"
    if block.weights is None:
        rows = block.rows
        mean, cov, inn = settings.update_arrays(group.means[rows], group.covs[rows], z, where=where)
        group.means[rows] = mean
        group.covs[rows] = cov
        _record(records, block, m_idx, mean, cov, inn, target.truth[m_idx], None)
        return
    nb, k = block.weights.shape
    bank = GaussianMixture(
        means=group.means[block.rows].reshape(nb, k, 4),
        covs=group.covs[block.rows].reshape(nb, k, 4, 4),
        weights=block.weights,
    )
    bank, inn = update_yaw_bank(bank, z, settings, bank_settings)
    group.means[block.rows] = bank.means.reshape(nb * k, 4)
    group.covs[block.rows] = bank.covs.reshape(nb * k, 4, 4)
    block.weights = bank.weights
    mean, cov = bank.heaviest()
    best = bank.heaviest_index
    pick = np.arange(nb), best
    best_inn = Innovation(
        residual=inn.residual[pick],
        cov=inn.cov[pick],
        nis=np.asarray(inn.nis)[pick],
        meas_cov=inn.meas_cov[pick],
    )
    alive = bank.alive.sum(axis=-1)
    _record(records, block, m_idx, mean, cov, best_inn, target.truth[m_idx], alive)


def run_tracks(
    streams: PairStreams,
    specs: Sequence[TrackSpec],
    bank_settings: YawBankSettings | None = None,
) -> list[TrackRecord]:
    """Run every filter of ``specs`` over ``streams``; one :class:`TrackRecord` per spec.

    Records hold one row per measurement of the spec's target (the state after that update).
    """
    settings = bank_settings or YawBankSettings()
    groups = _build_groups(streams, specs, settings)
    records = []
    for spec in specs:
        m = len(streams.targets[spec.target].step)
        detail = {}
        if spec.detail:
            detail = {
                name: np.full((m, 4) if name == "sigma" else m, np.nan) for name in DETAIL_FIELDS
            }
        records.append(
            TrackRecord(
                errors=np.full((m, 4), np.nan),
                detail=detail,
                n_alive=np.full(m, np.nan) if spec.bank else None,
            )
        )
    # measurements due after each step: step -> [(target, index)]
    due: dict[int, list[tuple[int, int]]] = defaultdict(list)
    for j, tgt in enumerate(streams.targets):
        for m, s in enumerate(tgt.step.tolist()):
            due[int(s)].append((j, m))
    u_c_all = np.stack([t.u_c for t in streams.targets])  # (targets, T, 4)
    for k in range(streams.n_steps):
        u_l = streams.u_l[k]
        for g in groups:
            if g.single_target is not None:
                u_c = u_c_all[g.single_target, k]
            else:
                u_c = u_c_all[g.row_target, k]
            g.means, g.covs = predict_arrays(g.means, g.covs, u_l, u_c, streams.dt, g.noise)
        for j, m in due.get(k + 1, ()):
            for g in groups:
                for block in g.blocks:
                    if block.target == j:
                        _update_block(g, block, streams.targets[j], m, records, settings)
    return records
