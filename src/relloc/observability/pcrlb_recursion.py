"""Posterior Cramér–Rao lower bound (PCRLB): the generic recursion (information form).

Tichavský, Muravchik & Nehorai (1998), "Posterior Cramér–Rao bounds for discrete-time
nonlinear filtering", IEEE TSP 46(5). For a system with additive Gaussian noise

    x_{k+1} = f_k(x_k) + w_k,  w_k ~ N(0, Q_k);      z_k = h_k(x_k) + v_k,  v_k ~ N(0, R_k)

the Fisher information ``J_k`` of the state (its inverse bounds the MSE matrix of *any*
estimator, ``E[(x̂_k − x_k)(x̂_k − x_k)ᵀ] ⪰ J_k⁻¹``) obeys their Eq. (21):

    J_{k+1} = D22_k − D21_k (J_k + D11_k)⁻¹ D12_k
    D11_k = E[F_kᵀ Q_k⁻¹ F_k],   D12_k = −E[F_kᵀ] Q_k⁻¹ = D21_kᵀ,
    D22_k = Q_k⁻¹ + E[H_{k+1}ᵀ R_{k+1}⁻¹ H_{k+1}],

with ``F_k = ∂f_k/∂x`` and ``H_k = ∂h_k/∂x`` evaluated at the *true* states and the
expectations taken over the true-trajectory distribution, approximated here by the mean over
``M`` Monte-Carlo true trajectories (``Q_k`` may differ per trajectory; the D-terms then
average ``F_kᵀQ_k⁻¹F_k``, ``F_kᵀQ_k⁻¹`` and ``Q_k⁻¹``). ``J_0 = P_0⁻¹ + E[H_0ᵀR_0⁻¹H_0]``
(information of the prior plus any measurement at step 0). Steps without a measurement
contribute zero measurement information.

With a single trajectory (``M = 1``) the expectations are point evaluations and the
recursion is algebraically identical (matrix inversion lemma) to the Riccati form

    J_{k+1} = (F_k J_k⁻¹ F_kᵀ + Q_k)⁻¹ + H_{k+1}ᵀ R_{k+1}⁻¹ H_{k+1},

i.e. the EKF covariance recursion evaluated on the true trajectory. That form is used for
``M = 1`` because it also holds for a *singular* ``Q_k`` (process noise entering through an
input matrix ``G`` of lower rank, e.g. a unicycle's two input noises on three states, or a
ground robot with noiseless vertical speed). The averaged information form needs every
``Q_k`` positive definite and says so (:class:`~relloc.errors.ModelError` naming the
trajectory and step) otherwise.

Public API (all arrays float64; ``n`` states, ``T`` steps, ``M`` true trajectories)
----------------------------------------------------------------------------------
``measurement_information(H, R) -> (..., n, n)``
    ``Hᵀ R⁻¹ H`` for stacks ``H (..., m, n)``, ``R (..., m, m)``.
``pcrlb_information(F, Q, meas_info, J0) -> (T, n, n)``
    The generic recursion. ``F, Q``: ``(T−1, n, n)`` or ``(M, T−1, n, n)``;
    ``meas_info``: ``(T, n, n)`` or ``(M, T, n, n)`` (zeros where nothing was measured);
    ``J0``: ``(n, n)`` prior information ``P_0⁻¹``. Returns ``J_k`` for ``k = 0..T−1``.
``pcrlb_covariance(J) -> (T, n, n)``
    The bound ``J_k⁻¹`` (PSD-checked inversion).
``pcrlb_ratio(errors, bound, *, start=0) -> (n,)``
    RMSE / sqrt(bound) per state: ``sqrt(Σ_k mean_runs e_k,i² / Σ_k B_k,ii)`` over steps
    ``k ≥ start``; ``errors (R, T, n)`` (angles already wrapped by the caller), ``bound
    (T, n, n)``. 1.0 is the physical limit; an efficient estimator approaches it from above.

Model wrappers and the public API are in :mod:`relloc.observability.pcrlb`
(``relative_pair_pcrlb`` for the seed-000 4-DOF pair and ``unicycle_team_pcrlb`` for a
cooperative unicycle team with bearing / range / pose measurements).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from relloc.core.linalg import cholesky, symmetrise
from relloc.errors import DataError, ModelError

Array = NDArray[np.float64]


def measurement_information(H: Array, R: Array) -> Array:
    """``Hᵀ R⁻¹ H`` for stacks ``H (..., m, n)`` and ``R (..., m, m)`` (R must be PD)."""
    H = np.asarray(H, dtype=float)
    R = np.asarray(R, dtype=float)
    if H.ndim < 2 or R.shape[-2:] != (H.shape[-2], H.shape[-2]):
        raise DataError(f"measurement_information: H {H.shape} and R {R.shape} do not match")
    L = cholesky(R, where="measurement noise R")
    W = np.linalg.solve(L, H)  # L⁻¹ H, so Hᵀ R⁻¹ H = Wᵀ W
    return symmetrise(np.swapaxes(W, -1, -2) @ W)


def _inverse_pd(A: Array, where: str) -> Array:
    L = cholesky(A, where=where)
    Linv = np.linalg.solve(L, np.broadcast_to(np.eye(A.shape[-1]), A.shape))
    return symmetrise(np.swapaxes(Linv, -1, -2) @ Linv)


def _check_inputs(F: Array, Q: Array, meas_info: Array, J0: Array) -> tuple[Array, ...]:
    F = np.asarray(F, dtype=float)
    Q = np.asarray(Q, dtype=float)
    I = np.asarray(meas_info, dtype=float)
    J0 = np.asarray(J0, dtype=float)
    if F.ndim == 3:
        F, Q, I = F[None], Q[None] if Q.ndim == 3 else Q, I[None] if I.ndim == 3 else I
    if F.ndim != 4 or Q.shape != F.shape:
        raise DataError(f"pcrlb: F {F.shape} and Q {Q.shape} must both be (M, T-1, n, n)")
    M, Tm1, n, _ = F.shape
    if F.shape[-1] != n or I.shape != (M, Tm1 + 1, n, n):
        raise DataError(
            f"pcrlb: meas_info has shape {I.shape}, expected {(M, Tm1 + 1, n, n)} "
            f"(one information matrix per step, F has {Tm1} transitions)"
        )
    if J0.shape != (n, n):
        raise DataError(f"pcrlb: J0 has shape {J0.shape}, expected {(n, n)}")
    for name, arr in (("F", F), ("Q", Q), ("meas_info", I), ("J0", J0)):
        if not np.all(np.isfinite(arr)):
            raise DataError(f"pcrlb: {name} contains NaN or inf")
    return F, symmetrise(Q), symmetrise(I), symmetrise(J0)


def pcrlb_information(F: Array, Q: Array, meas_info: Array, J0: Array) -> Array:
    """Fisher information ``J_k`` (``(T, n, n)``) by the Tichavský recursion (module doc).

    ``F``/``Q`` hold the transition Jacobian and process noise from step k to k+1 at the true
    state(s); ``meas_info[k]`` is ``H_kᵀR_k⁻¹H_k`` (summed over the measurements at step k, zero
    when none); ``J0`` is the prior information ``P_0⁻¹``.
    """
    F, Q, I, J0 = _check_inputs(F, Q, meas_info, J0)
    M, Tm1, n, _ = F.shape
    J = np.empty((Tm1 + 1, n, n))
    J[0] = J0 + I[:, 0].mean(axis=0)
    if M == 1:
        # Riccati form: exact for one trajectory and valid for singular Q (module doc).
        for k in range(Tm1):
            P = _inverse_pd(J[k], where=f"PCRLB information at step {k}")
            P_pred = F[0, k] @ P @ F[0, k].T + Q[0, k]
            J[k + 1] = (
                _inverse_pd(P_pred, where=f"PCRLB predicted bound at step {k + 1}") + I[0, k + 1]
            )
        return J
    for k in range(Tm1):
        try:
            Qinv = _inverse_pd(Q[:, k], where=f"process noise Q at step {k}")
        except ModelError:
            for m in range(M):  # name the first offending trajectory
                _inverse_pd(
                    Q[m, k],
                    where=f"process noise Q of trajectory {m} at step {k} (the averaged "
                    "PCRLB needs Q positive definite; use one trajectory for singular Q)",
                )
            raise
        Ft = np.swapaxes(F[:, k], -1, -2)
        D11 = (Ft @ Qinv @ F[:, k]).mean(axis=0)
        D12 = -(Ft @ Qinv).mean(axis=0)
        D22 = Qinv.mean(axis=0) + I[:, k + 1].mean(axis=0)
        S = symmetrise(J[k] + D11)
        L = cholesky(S, where=f"PCRLB J + D11 at step {k}")
        W = np.linalg.solve(L, D12)
        J[k + 1] = symmetrise(D22 - W.T @ W)
    return J


def pcrlb_covariance(J: Array) -> Array:
    """The bound ``J_k⁻¹`` for every step of ``J (T, n, n)``; ModelError if J is not PD."""
    J = np.asarray(J, dtype=float)
    out = np.empty_like(J)
    for k in range(J.shape[0]):
        out[k] = _inverse_pd(J[k], where=f"PCRLB information at step {k}")
    return out


def pcrlb_ratio(errors: Array, bound: Array, *, start: int = 0) -> Array:
    """RMSE over sqrt(PCRLB) per state, pooled over steps ``k ≥ start`` (module doc).

    ``errors``: ``(R, T, n)`` estimation errors of R Monte-Carlo runs (or ``(T, n)`` for one),
    angles already wrapped; ``bound``: ``(T, n, n)`` from :func:`pcrlb_covariance`.
    """
    e = np.asarray(errors, dtype=float)
    if e.ndim == 2:
        e = e[None]
    B = np.asarray(bound, dtype=float)
    if e.ndim != 3 or B.shape != (e.shape[1], e.shape[2], e.shape[2]):
        raise DataError(f"pcrlb_ratio: errors {e.shape} and bound {B.shape} do not match")
    if not 0 <= start < e.shape[1]:
        raise DataError(f"pcrlb_ratio: start={start} outside 0..{e.shape[1] - 1}")
    mse = np.nanmean(e[:, start:] ** 2, axis=0).sum(axis=0)
    var = np.diagonal(B[start:], axis1=-2, axis2=-1).sum(axis=0)
    if np.any(var <= 0):
        raise ModelError("pcrlb_ratio: the bound has a non-positive diagonal")
    return np.sqrt(mse / var)
