"""Validation gates for measurement-to-track association (seed 002 §II-D.2).

A measurement ``z`` falls inside the gate of a track with predicted measurement ``ẑ`` and
innovation covariance ``S`` when the squared Mahalanobis distance

    d² = (z − ẑ)ᵀ S⁻¹ (z − ẑ)  ≤  γ,      γ = F⁻¹_{χ²(n_z)}(P_G),

so that a correct measurement is kept with probability ``P_G`` (the *gate probability*). The
threshold is :func:`relloc.core.kalman.chi2_threshold`, the one χ² gate of every filter.

Modified gate for tracks whose yaw is still (close to) uniform. A new track starts with yaw
variance 4π (seed 002 Eq. 13), and the linearised prediction of such a track turns the
yaw-induced position uncertainty into a thin ellipse tangent to the teammate's velocity, while
the true set of positions reachable in ``τ`` seconds is a disc of radius ``|v_j| τ`` around the
yaw-free prediction (seed 002 Fig. 3). For tracks whose yaw standard deviation exceeds a
threshold the gate therefore adds the covariance of that disc, ``(|v_j| τ)²·I₂`` on the
horizontal position, mapped into measurement space with the measurement Jacobian ``H``:

    S_gate = S + H_xy (|v_j| τ)² H_xyᵀ.

This enlarges the gate only where the linearisation is known to be wrong and leaves the
Kalman update itself untouched.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from relloc.core.checks import number, positive, probability
from relloc.errors import ModelError

Array = NDArray[np.float64]


@dataclass(frozen=True, kw_only=True)
class GateSettings:
    """Gate probability and the modified gate for uniform-yaw tracks.

    Attributes:
        p_gate: probability ``P_G`` that a correct measurement lies inside the gate.
        yaw_sigma_uniform: yaw standard deviation (rad) above which a track counts as having
            an (almost) uniform yaw and gets the modified gate.
        horizon: time ``τ`` (s) over which the unknown yaw can displace the track (the
            interval between direct-fusion scans).
        p_birth_exclusion: probability of the wider gate around every track inside which no
            new track is born (a correct measurement falls outside the update gate with
            probability 1 − P_G; without this margin each such miss would start a duplicate
            track with uniform yaw on top of the existing one).
    """

    p_gate: float = 0.95
    yaw_sigma_uniform: float = 0.5
    horizon: float = 0.1
    p_birth_exclusion: float = 0.9999

    def __post_init__(self) -> None:
        """Every field is checked with :mod:`relloc.core.checks`: a value of the wrong type (a
        string, ``None``, a ``bool``) or out of its range is a ConfigError naming the field."""
        p_gate = probability(self.p_gate, "GateSettings.p_gate")
        positive(self.yaw_sigma_uniform, "GateSettings.yaw_sigma_uniform")
        number(
            self.p_birth_exclusion,
            "GateSettings.p_birth_exclusion",
            low=p_gate,
            high=1.0,
            open_high=True,
        )
        number(self.horizon, "GateSettings.horizon", low=0.0)


def mahalanobis_batch(nu: Array, S: Array) -> Array:
    """Squared Mahalanobis distances for stacks: ``nu`` (..., n), ``S`` (..., n, n) → (...).

    A singular ``S`` (no gate exists) is a ModelError, not numpy's ``LinAlgError``."""
    try:
        sol = np.linalg.solve(S, nu[..., None])[..., 0]
    except np.linalg.LinAlgError as exc:
        raise ModelError(
            f"mahalanobis_batch: an innovation covariance is singular ({exc})"
        ) from exc
    return np.einsum("...i,...i->...", nu, sol)


def modified_gate_covariance(
    S: Array, H: Array, yaw_var: Array, speed: Array, settings: GateSettings
) -> Array:
    """Innovation covariance used for gating (module docstring).

    Args:
        S: innovation covariances (K, n_z, n_z).
        H: measurement Jacobians (K, n_z, 4) with respect to (x, y, z, φ).
        yaw_var: yaw variances of the tracks (K,).
        speed: horizontal speed |v_j| of the tracked teammate (K,) in m/s.
        settings: gate settings.
    """
    uniform = yaw_var > settings.yaw_sigma_uniform**2
    if not np.any(uniform):
        return S
    radius2 = np.where(uniform, (speed * settings.horizon) ** 2, 0.0)
    Hxy = H[..., :2]
    return S + radius2[:, None, None] * (Hxy @ np.swapaxes(Hxy, -1, -2))
