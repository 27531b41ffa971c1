"""Posterior Cramér–Rao lower bound (PCRLB) for relloc's scenarios — the public API.

How well can *any* estimator do? The PCRLB ``B_k = J_k⁻¹`` bounds the MSE matrix of every
unbiased estimator, ``E[(x̂_k − x_k)(x̂_k − x_k)ᵀ] ⪰ B_k``. ``J_k`` follows the recursion of
Tichavský, Muravchik & Nehorai (1998), implemented generically in
:mod:`relloc.observability.pcrlb_recursion` (see there for the equations, the Monte-Carlo
averaging and the single-trajectory Riccati form used for singular process noise). This module
builds its inputs (``F_k``, ``Q_k``, ``Σ HᵀR⁻¹H``) from the *true* trajectory with the very
numeric models the estimators use, and re-exports the generic functions.

Functions
---------
``relative_pair_pcrlb(true_states, u_obs, u_tgt, dt, measurement_mask, *, sigma_r,
sigma_theta, sigma_alpha, velocity_noise, P0, measured=("range", "azimuth", "elevation"))
-> (T, 4, 4)``
    Seed-000 4-DOF relative pair, state ``(x, y, z, φ)`` of the observed robot in the
    observer's body frame. ``true_states (T, 4)``; ``u_obs``, ``u_tgt (T, 4)`` body velocities
    ``(v_x, v_y, v_z, ω_z)`` of observer and observed robot (``u[k]`` drives step k → k+1, the
    last row is unused); ``dt`` a float or ``(T−1,)`` step lengths; ``measurement_mask (T,)``
    bool, True where a range/azimuth/elevation measurement was taken at step k. A leading
    Monte-Carlo dimension ``(M, T, …)`` on states, inputs and (optionally) the mask averages the
    expectations over M true trajectories. ``velocity_noise``:
    :class:`relloc.models.motion.VelocityNoise` (``Q_k = G_k Σ_u G_kᵀ`` via
    :func:`relloc.models.motion.relative_jacobians`); the measurement information uses the
    nonlinear Jacobian :func:`relloc.models.measurement.range_bearing_jacobian` with
    ``R = diag(σ_r², σ_θ², σ_α²)`` restricted to ``measured``. The pseudo-linear filter sees
    the same raw measurements, so one bound serves the PLKF and the EKF. ``P0 (4, 4)`` is the
    prior covariance (the filter's initial covariance). Returns the bound ``B_k`` per step;
    ``sqrt(diag B_k)`` is the smallest RMSE reachable per state.
``unicycle_team_pcrlb(true_poses, u, dt, rows, *, input_sigma, P0) -> (T, 3n, 3n)``
    Cooperative team of ``n`` unicycles (seed 001): ``true_poses (T, n, 3)`` (or ``(M, T, n,
    3)``), ``u (T, n, 2)`` = ``(v, ω)`` per robot, ``dt`` float or ``(T−1,)``, ``rows``: T
    :class:`relloc.models.planar_measurement.ScalarRows` (bearing / range / GPS-pose rows taken
    at each step; only their structure and ``sigma`` are used), ``input_sigma`` ``(2,)`` or
    ``(n, 2)`` odometry σ of ``(v, ω)``, ``P0 (3n, 3n)``.
``pcrlb_ratio(errors, bound, *, start=0) -> (n,)``
    RMSE / sqrt(bound) per state, ``sqrt(Σ_k mean_runs e²_{k,i} / Σ_k B_{k,ii})`` over steps
    ``k ≥ start``; ``errors (R, T, n)`` with angles already wrapped. 1.0 is the physical limit.
``pcrlb_information``, ``pcrlb_covariance``, ``measurement_information``
    The generic recursion (re-exported from :mod:`.pcrlb_recursion`).

Example (seed-000 reproduction)::

    from relloc.observability.pcrlb import relative_pair_pcrlb, pcrlb_ratio
    B = relative_pair_pcrlb(X_true, u_l, u_c, dt, has_meas, sigma_r=σr, sigma_theta=σθ,
                            sigma_alpha=σα, velocity_noise=noise, P0=P0)
    ratio = pcrlb_ratio(errors, B, start=burn_in)   # per (x, y, z, φ)
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from relloc.core.linalg import cholesky
from relloc.errors import DataError, ModelError
from relloc.models.measurement import MEASUREMENT_NAMES, range_bearing_jacobian
from relloc.models.motion import VelocityNoise, process_noise, relative_jacobians
from relloc.models.planar_measurement import ScalarRows, linearise_rows
from relloc.models.unicycle import unicycle_jacobians
from relloc.observability.pcrlb_recursion import (
    measurement_information,
    pcrlb_covariance,
    pcrlb_information,
    pcrlb_ratio,
)

__all__ = [
    "measurement_information",
    "pcrlb_covariance",
    "pcrlb_information",
    "pcrlb_ratio",
    "relative_pair_pcrlb",
    "unicycle_team_pcrlb",
]

Array = NDArray[np.float64]


def _step_lengths(dt: float | ArrayLike, T: int) -> Array:
    if T < 1:
        raise DataError("PCRLB: the trajectory has no steps (T = 0); give at least one state")
    d = np.asarray(dt, dtype=float)
    d = np.full(T - 1, float(d)) if d.ndim == 0 else d.reshape(-1)
    if d.shape != (T - 1,) or not np.all(np.isfinite(d)) or np.any(d < 0):
        raise DataError(f"PCRLB: dt must be a float or {T - 1} finite step lengths ≥ 0")
    return d


def _with_runs(a: ArrayLike, tail: tuple[int, ...], name: str) -> Array:
    arr = np.asarray(a, dtype=float)
    if arr.ndim == len(tail) + 1:
        arr = arr[None]
    if arr.ndim != len(tail) + 2 or arr.shape[2:] != tail:
        raise DataError(f"PCRLB: {name} has shape {arr.shape}, expected (T, *{tail}) or (M, T, …)")
    if not np.all(np.isfinite(arr)):
        raise DataError(f"PCRLB: {name} contains NaN or inf")
    return arr


def _prior_information(P0: ArrayLike, n: int) -> Array:
    """``P0⁻¹``; ``P0`` must be finite and positive definite (a ModelError naming P0)."""
    P = np.asarray(P0, dtype=float)
    if P.shape != (n, n):
        raise DataError(f"PCRLB: P0 has shape {P.shape}, expected {(n, n)}")
    cholesky(P, where="the prior covariance P0")  # names P0, not "measurement noise R"
    return measurement_information(np.eye(n), P)


def relative_pair_pcrlb(
    true_states: ArrayLike,
    u_obs: ArrayLike,
    u_tgt: ArrayLike,
    dt: float | ArrayLike,
    measurement_mask: ArrayLike,
    *,
    sigma_r: float,
    sigma_theta: float,
    sigma_alpha: float,
    velocity_noise: VelocityNoise,
    P0: ArrayLike,
    measured: Sequence[str] = MEASUREMENT_NAMES,
) -> Array:
    """PCRLB ``(T, 4, 4)`` of the seed-000 relative pair (see the module docstring).

    A measured step where the Jacobian is not finite (``ρ = √(x² + y²) = 0``: azimuth and
    elevation have no gradient there) is a :class:`ModelError` naming the step; at unmeasured
    steps the state is not used for information and any ρ is fine.
    """
    X = _with_runs(true_states, (4,), "true_states")
    M, T = X.shape[:2]
    U_l = _with_runs(u_obs, (4,), "u_obs")
    U_c = _with_runs(u_tgt, (4,), "u_tgt")
    if U_l.shape != X.shape or U_c.shape != X.shape:
        raise DataError(f"PCRLB: inputs {U_l.shape}/{U_c.shape} must match states {X.shape}")
    mask = np.asarray(measurement_mask, dtype=bool)
    if mask.shape not in ((T,), (M, T)):
        raise DataError(f"PCRLB: measurement_mask has shape {mask.shape}, expected {(T,)}")
    mask = np.broadcast_to(mask, (M, T))
    unknown = [m for m in measured if m not in MEASUREMENT_NAMES]
    if unknown or not measured:
        raise DataError(f"PCRLB: measured must be a non-empty subset of {MEASUREMENT_NAMES}")
    rows = [MEASUREMENT_NAMES.index(m) for m in measured]
    sig = np.array([sigma_r, sigma_theta, sigma_alpha], dtype=float)
    if not np.all(np.isfinite(sig) & (sig > 0)):
        raise DataError(f"PCRLB: sensor sigmas must be finite and > 0, got {sig}")
    steps = _step_lengths(dt, T)

    if T > 1 and np.all(steps == steps[0]):  # one batched call over all steps
        F, G = relative_jacobians(X[:, :-1], U_l[:, :-1], U_c[:, :-1], float(steps[0]))
        Q = process_noise(G, velocity_noise)
    else:
        F = np.empty((M, T - 1, 4, 4))
        Q = np.empty((M, T - 1, 4, 4))
        for k in range(T - 1):
            F[:, k], G = relative_jacobians(X[:, k], U_l[:, k], U_c[:, k], float(steps[k]))
            Q[:, k] = process_noise(G, velocity_noise)
    with np.errstate(divide="ignore", invalid="ignore"):  # ρ = 0: checked just below
        H = range_bearing_jacobian(X)[..., rows, :]
    singular = mask & ~np.isfinite(H).all(axis=(-2, -1))
    if singular.any():
        m, k = (int(v) for v in np.argwhere(singular)[0])
        why = (
            "horizontal distance ρ = √(x² + y²) = 0 (robot straight above/below or co-located), "
            "where azimuth and elevation have no gradient; leave that step out of "
            "measurement_mask or measure range only"
            if np.hypot(X[m, k, 0], X[m, k, 1]) ** 2 == 0.0
            else "the position is beyond double precision (ρ² under- or overflows)"
        )
        raise ModelError(
            f"PCRLB: the {'/'.join(measured)} Jacobian is not finite at step {k} "
            f"(trajectory {m}), state {X[m, k].tolist()}: {why}"
        )
    H = np.where(mask[..., None, None], H, 0.0)  # unmeasured steps: no information (HᵀR⁻¹H = 0)
    R = np.diag(sig[rows] ** 2)
    info = measurement_information(H, np.broadcast_to(R, (*H.shape[:-2], len(rows), len(rows))))
    J = pcrlb_information(F, Q, info, _prior_information(P0, 4))
    return pcrlb_covariance(J)


def unicycle_team_pcrlb(
    true_poses: ArrayLike,
    u: ArrayLike,
    dt: float | ArrayLike,
    rows: Sequence[ScalarRows],
    *,
    input_sigma: ArrayLike,
    P0: ArrayLike,
) -> Array:
    """PCRLB ``(T, 3n, 3n)`` of a cooperative unicycle team (see the module docstring)."""
    X = np.asarray(true_poses, dtype=float)
    if X.ndim == 3:
        X = X[None]
    if X.ndim != 4 or X.shape[-1] != 3 or not np.all(np.isfinite(X)):
        raise DataError(f"PCRLB: true_poses has shape {X.shape}, expected finite (T, n, 3)")
    M, T, n, _ = X.shape
    U = np.asarray(u, dtype=float)
    U = U[None] if U.ndim == 3 else U
    if U.shape != (M, T, n, 2) or not np.all(np.isfinite(U)):
        raise DataError(f"PCRLB: u has shape {U.shape}, expected finite {(M, T, n, 2)}")
    if len(rows) != T:
        raise DataError(f"PCRLB: rows has {len(rows)} entries, expected one per step ({T})")
    sig = np.broadcast_to(np.asarray(input_sigma, dtype=float), (n, 2))
    if not np.all(np.isfinite(sig) & (sig >= 0)):
        raise DataError("PCRLB: input_sigma must be finite and ≥ 0")
    steps = _step_lengths(dt, T)

    N = 3 * n
    F = np.zeros((M, T - 1, N, N))
    Q = np.zeros((M, T - 1, N, N))
    # per-robot blocks (M, T−1, n, 3, ·): one batched call per distinct step length
    Fi = np.empty((M, T - 1, n, 3, 3))
    Gi = np.empty((M, T - 1, n, 3, 2))
    for d in np.unique(steps):
        at = np.flatnonzero(steps == d)
        Fi[:, at], Gi[:, at] = unicycle_jacobians(X[:, at], U[:, at], float(d))
    Qi = (Gi * sig[:, None, :] ** 2) @ np.swapaxes(Gi, -1, -2)
    for i in range(n):
        F[:, :, 3 * i : 3 * i + 3, 3 * i : 3 * i + 3] = Fi[:, :, i]
        Q[:, :, 3 * i : 3 * i + 3, 3 * i : 3 * i + 3] = Qi[:, :, i]
    info = np.zeros((M, T, N, N))
    for k, batch in enumerate(rows):
        if batch.size == 0:
            continue
        for m in range(M):
            Hk = linearise_rows(X[m, k], batch).dense_jacobian(n)
            info[m, k] = measurement_information(Hk, np.diag(np.asarray(batch.sigma) ** 2))
    J = pcrlb_information(F, Q, info, _prior_information(P0, N))
    return pcrlb_covariance(J)
