"""Joint extended Kalman filter over a team of unicycles (covariance form).

State: ``X = [X_1ᵀ … X_nᵀ]ᵀ`` with ``X_i = (x_i, y_i, ψ_i)`` (seed 001 §2.1), covariance ``P``
(3n × 3n). It is the moment-form twin of the extended information filter in
:mod:`relloc.estimators.eif`: given the same linearisation points both produce the same
estimate (tested in ``tests/cooperative``).

Prediction. The team transition is block-diagonal (each robot moves on its own inputs), so a
prediction over any interval is described by per-robot blocks ``F_i`` (3 × 3) and
``Q_i = Σ_k Φ_{i,k} B_{i,k} Q_{u,k} B_{i,k}ᵀ Φ_{i,k}ᵀ`` (input noise through ``B``, seed 001
Eqs. 5, 8, 9, accumulated exactly over many odometry steps, see
:mod:`relloc.estimators.cooperative`):

    P⁺ = F P Fᵀ + diag(Q_1 … Q_n),   F = diag(F_1 … F_n)              (seed 001 Eq. 5)

computed block-wise in ``O(n²)`` instead of the dense ``O(n³)`` product.

Update (all rows of one epoch at once, linearised at the prior mean), the Joseph-form
:func:`relloc.core.kalman.kalman_update`:

    S = H P Hᵀ + R,  K = P Hᵀ S⁻¹,  X⁺ = X + K ν,  P⁺ = (I − K H) P (I − K H)ᵀ + K R Kᵀ.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from relloc.core.gaussian import Gaussian
from relloc.core.kalman import kalman_update
from relloc.core.linalg import symmetrise
from relloc.errors import ModelError
from relloc.models.planar_measurement import LinearisedRows

Array = NDArray[np.float64]


def propagate_team_covariance(P: Array, F_blocks: Array, Q_blocks: Array) -> Array:
    """``F P Fᵀ + diag(Q)`` for block-diagonal ``F = diag(F_blocks)``, ``F_blocks (n,3,3)``, or
    a dense ``F_blocks (3n,3n)`` (the observability-constrained transition couples robots)."""
    n = Q_blocks.shape[0]
    if F_blocks.ndim == 2:
        FPF = (F_blocks @ P @ F_blocks.T).reshape(n, 3, n, 3)
    else:
        P4 = P.reshape(n, 3, n, 3)
        FP = np.einsum("iab,ibjc->iajc", F_blocks, P4)
        FPF = np.einsum("iajc,jdc->iajd", FP, F_blocks)
    idx = np.arange(n)
    FPF[idx, :, idx, :] += Q_blocks
    return symmetrise(FPF.reshape(3 * n, 3 * n))


def check_blocks(n: int, mean_pred: Array, F_blocks: Array, Q_blocks: Array) -> None:
    """Shape and finiteness checks shared by both joint filters' predictions."""
    dense = (3 * n, 3 * n)
    if (
        mean_pred.shape != (3 * n,)
        or F_blocks.shape not in ((n, 3, 3), dense)
        or Q_blocks.shape != (n, 3, 3)
    ):
        raise ModelError(
            f"team prediction: expected mean ({3 * n},), F blocks ({n},3,3) or dense {dense} and "
            f"Q blocks ({n},3,3); got "
            f"{mean_pred.shape}, {F_blocks.shape}, {Q_blocks.shape}"
        )
    if not (np.isfinite(mean_pred).all() and np.isfinite(F_blocks).all()):
        raise ModelError("team prediction: non-finite predicted mean or Jacobian")
    if not np.isfinite(Q_blocks).all():
        raise ModelError("team prediction: non-finite process noise")


def ekf_predict(belief: Gaussian, mean_pred: Array, F_blocks: Array, Q_blocks: Array) -> Gaussian:
    """Joint EKF prediction to the mean ``mean_pred`` (propagated by the motion model)."""
    n = belief.dim // 3
    check_blocks(n, mean_pred, F_blocks, Q_blocks)
    return Gaussian(mean=mean_pred, cov=propagate_team_covariance(belief.cov, F_blocks, Q_blocks))


def ekf_update(belief: Gaussian, rows: LinearisedRows) -> Gaussian:
    """Joint EKF update with every row of an epoch (residuals already at the prior mean)."""
    m = rows.residual.shape[0]
    if m == 0:
        return belief
    n = belief.dim // 3
    H = rows.dense_jacobian(n)
    R = np.diag(rows.sigma**2)
    mean, cov, _ = kalman_update(
        belief.mean, belief.cov, rows.residual, H, R, where="joint EKF update"
    )
    return Gaussian(mean=mean, cov=cov)


class _Moments(Protocol):
    """A team belief that holds its mean ``(3n,)`` and covariance ``(3n, 3n)``."""

    @property
    def dim(self) -> int: ...

    @property
    def mean(self) -> Array: ...

    @property
    def cov(self) -> Array: ...


class TeamMoments:
    """The team's mean and covariance read from a joint filter's ``belief`` (both
    :class:`JointEkf` and :class:`relloc.estimators.eif.ExtendedInformationFilter` keep them)."""

    belief: _Moments

    def mean(self) -> Array:
        """Team mean as ``(n, 3)``."""
        return self.belief.mean.reshape(-1, 3)

    def covariance(self) -> Array:
        """Joint covariance ``(3n, 3n)`` (for the EIF ``Y⁻¹``, from its last factorisation)."""
        return self.belief.cov


@dataclass
class JointEkf(TeamMoments):
    """Thin stateful wrapper around :func:`ekf_predict` / :func:`ekf_update`."""

    belief: Gaussian

    def predict(self, mean_pred: Array, F_blocks: Array, Q_blocks: Array) -> None:
        self.belief = ekf_predict(self.belief, mean_pred.reshape(-1), F_blocks, Q_blocks)

    def update(self, rows: LinearisedRows) -> None:
        self.belief = ekf_update(self.belief, rows)
