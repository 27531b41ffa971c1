"""Centralised extended information filter (EIF) for a team of unicycles (seed 001 §2.1).

The filter's state is the information pair ``Y = P⁻¹`` and ``y = Y X̂`` (seed 001 Eqs. 3–4),
together with the mean ``X̂`` that the motion model propagates (seed 001 Eq. 7). Its covariance
``P = Y⁻¹`` is kept alongside because it comes out of the same factorisation and is needed for
χ² gating and reporting.

Prediction (seed 001 Eqs. 5–7), with block-diagonal ``F`` and accumulated input noise
``Q_i = B_i Q_{u,i} B_iᵀ`` (blocks as in :mod:`relloc.estimators.joint_ekf`):

    Y(k+1|k) = (F Y(k|k)⁻¹ Fᵀ + B Q Bᵀ)⁻¹,    y(k+1|k) = Y(k+1|k) X̂(k+1|k).

Update, summing over every edge of the current RPMG (and landmark / absolute-pose rows), each
scalar row with Jacobian ``H_r`` (non-zero only in the observer's and the observed robot's
blocks), noise ``σ_r`` and innovation ``μ_r = z_r − h_r(X̂(k+1|k))`` (seed 001 Eq. 10):

    Y(k+1|k+1) = Y(k+1|k) + Σ_r H_rᵀ σ_r⁻² H_r
    y(k+1|k+1) = y(k+1|k) + Σ_r H_rᵀ σ_r⁻² (μ_r + H_r X̂(k+1|k)).

Sparsity: each row adds to at most four 3 × 3 blocks of ``Y``, so the information update is
``O(m)`` in the number of rows ``m`` (a scatter-add), independent of the team size; only
recovering ``X̂ = Y⁻¹ y`` and ``P`` costs one Cholesky factorisation of ``Y`` per epoch, and the
prediction is paid once per measurement epoch however many odometry steps it spans.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg
from numpy.typing import NDArray

from relloc.core.gaussian import Gaussian, InformationState
from relloc.core.linalg import cholesky, symmetrise
from relloc.errors import ModelError
from relloc.estimators.joint_ekf import TeamMoments, check_blocks, propagate_team_covariance
from relloc.models.planar_measurement import LinearisedRows

Array = NDArray[np.float64]


@dataclass(frozen=True)
class TeamInformation:
    """EIF belief: information pair, the mean it encodes and the matching covariance."""

    info: InformationState
    mean: Array
    cov: Array

    @property
    def dim(self) -> int:
        return int(self.mean.size)

    @staticmethod
    def from_gaussian(belief: Gaussian) -> TeamInformation:
        """Convert a moment-form prior ``N(X̂, P)``."""
        info = belief.to_information()
        return TeamInformation(info=info, mean=belief.mean.copy(), cov=belief.cov.copy())


def _inverse_spd(A: Array, where: str) -> Array:
    """``A⁻¹`` (symmetrised) of an exactly symmetric positive definite ``A``: LAPACK ``potrs``
    on its Cholesky factor and the identity (what ``scipy.linalg.cho_solve`` calls, without
    its per-call argument handling)."""
    L = cholesky(A, where=where, symmetric=True)
    inv, info = scipy.linalg.lapack.dpotrs(L, np.eye(A.shape[0]), lower=1)
    if info != 0:
        raise ModelError(f"{where}: LAPACK potrs failed (info {info})")
    return symmetrise(inv)


def eif_predict(
    belief: TeamInformation, mean_pred: Array, F_blocks: Array, Q_blocks: Array
) -> TeamInformation:
    """EIF prediction (seed 001 Eqs. 5–7) to the propagated mean ``mean_pred (3n,)``."""
    n = belief.dim // 3
    check_blocks(n, mean_pred, F_blocks, Q_blocks)
    P_pred = propagate_team_covariance(belief.cov, F_blocks, Q_blocks)
    Y_pred = _inverse_spd(P_pred, "EIF prediction F Y⁻¹ Fᵀ + B Q Bᵀ")
    info = InformationState.from_symmetric(Y_pred @ mean_pred, Y_pred)
    return TeamInformation(info=info, mean=np.array(mean_pred, dtype=float), cov=P_pred)


def information_increment(rows: LinearisedRows, mean: Array, n: int) -> tuple[Array, Array]:
    """``(Σ H_rᵀ σ⁻² H_r, Σ H_rᵀ σ⁻² (μ_r + H_r X̂))`` by block scatter-add (seed 001 update)."""
    blocks, idx = rows.blocks, rows.block_index
    w = 1.0 / rows.sigma**2
    safe = np.maximum(idx, 0)
    X = mean.reshape(n, 3)
    HX = np.einsum("rpa,rpa->r", blocks, X[safe])
    s = w * (rows.residual + HX)
    dY = np.zeros((n, n, 3, 3))
    outer = np.einsum("r,rpa,rqb->rpqab", w, blocks, blocks)
    for p in range(2):
        for q in range(2):
            np.add.at(dY, (safe[:, p], safe[:, q]), outer[:, p, q])
    dy = np.zeros((n, 3))
    for p in range(2):
        np.add.at(dy, safe[:, p], blocks[:, p, :] * s[:, None])
    return dY.transpose(0, 2, 1, 3).reshape(3 * n, 3 * n), dy.reshape(-1)


def eif_update(belief: TeamInformation, rows: LinearisedRows) -> TeamInformation:
    """EIF update with every row of an epoch (residuals at the prior mean)."""
    if rows.residual.shape[0] == 0:
        return belief
    n = belief.dim // 3
    dY, dy = information_increment(rows, belief.mean, n)
    Y = symmetrise(belief.info.info_matrix + dY)
    y = belief.info.info_vector + dy
    P = _inverse_spd(Y, "EIF information matrix after update")
    mean = P @ y
    if not np.isfinite(mean).all():
        raise ModelError("EIF update produced a non-finite mean")
    return TeamInformation(info=InformationState.from_symmetric(y, Y), mean=mean, cov=P)


@dataclass
class ExtendedInformationFilter(TeamMoments):
    """Thin stateful wrapper around :func:`eif_predict` / :func:`eif_update`."""

    belief: TeamInformation

    @staticmethod
    def from_prior(prior: Gaussian) -> ExtendedInformationFilter:
        return ExtendedInformationFilter(TeamInformation.from_gaussian(prior))

    def predict(self, mean_pred: Array, F_blocks: Array, Q_blocks: Array) -> None:
        self.belief = eif_predict(self.belief, mean_pred.reshape(-1), F_blocks, Q_blocks)

    def update(self, rows: LinearisedRows) -> None:
        self.belief = eif_update(self.belief, rows)
