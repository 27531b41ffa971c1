"""Formation control of a follower UGV from its own relative estimate (seed 003, §4).

Follower R_i keeps the leader at a desired relative position ``r_des`` (``r = p_0 − p_i``),
either fixed in the common frame F_G (``frame="global"``, the paper's experiments:
``r_1^des = [0.5, 0.5]``) or fixed in the leader's body frame (``frame="leader"``, a hexagon that
turns with the leader): ``r_des = R(θ_0) c``.

Since ``ṙ = v_0 e(θ_0) − v_i e(θ_i)``, asking for ``ṙ = ṙ_des − k (r − r_des)`` gives the
follower's desired planar velocity (leader-velocity feed-forward, as the paper recommends for
arcs)::

    w = v_0 e(θ_0) − ṙ_des + k (r − r_des),   ṙ_des = ω_0 R(θ_0) [−c_y, c_x]  (leader frame)

which a unicycle tracks with ``v = ‖w‖ cos Δ``, ``ω = k_θ Δ``, ``Δ = wrap(∠w − θ_i)``, both
saturated. Everything is evaluated at the *estimates* ``r̂, θ̂_i, θ̂_0``, so estimation error
becomes formation error.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from relloc.core.angles import wrap_angle
from relloc.errors import ConfigError

Array = NDArray[np.float64]
Frame = Literal["global", "leader"]


@dataclass(frozen=True, kw_only=True)
class FormationSettings:
    """Gains and limits of the follower controller."""

    gain: float = 0.6
    heading_gain: float = 2.0
    v_max: float = 0.35
    w_max: float = 1.5

    def __post_init__(self) -> None:
        for name in ("gain", "heading_gain", "v_max", "w_max"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0.0):
                raise ConfigError(f"FormationSettings.{name}: must be > 0, got {value!r}")


def desired_relative(offset: Array, theta0: float, frame: Frame) -> Array:
    """``r_des``: ``offset`` itself (global) or ``R(θ_0) offset`` (leader frame)."""
    c = np.asarray(offset, dtype=float)
    if frame == "global":
        return c.copy()
    if frame == "leader":
        ct, st = math.cos(theta0), math.sin(theta0)
        return np.array([ct * c[0] - st * c[1], st * c[0] + ct * c[1]])
    raise ConfigError(f"formation frame: 'global' or 'leader', got {frame!r}")


def formation_command(
    estimate: Array,
    offset: Array,
    frame: Frame,
    leader_u: tuple[float, float],
    settings: FormationSettings,
) -> tuple[float, float]:
    """Unicycle command ``(v_i, ω_i)`` of a follower from its estimate ``[r_x, r_y, θ_i, θ_0]``."""
    x = np.asarray(estimate, dtype=float)
    th_i, th_0 = float(x[2]), float(x[3])
    v0, w0 = leader_u
    r_des = desired_relative(offset, th_0, frame)
    r_des_dot = w0 * np.array([-r_des[1], r_des[0]]) if frame == "leader" else np.zeros(2)
    w = v0 * np.array([math.cos(th_0), math.sin(th_0)]) - r_des_dot
    w = w + settings.gain * (x[:2] - r_des)
    speed = float(np.hypot(w[0], w[1]))
    if speed < 1e-9:
        return 0.0, 0.0
    delta = float(wrap_angle(math.atan2(w[1], w[0]) - th_i))
    v = min(speed * math.cos(delta), settings.v_max)
    v = max(v, -settings.v_max)
    omega = max(-settings.w_max, min(settings.w_max, settings.heading_gain * delta))
    return v, omega


@dataclass(frozen=True, kw_only=True)
class FormationController:
    """The followers' formation controller: follower ``R_i`` (i = 1..N) holds ``offsets[i-1]``
    (in ``frame``) from its own estimate, with :func:`formation_command`."""

    offsets: tuple[tuple[float, float], ...]
    frame: Frame
    settings: FormationSettings = field(default_factory=FormationSettings)

    def __post_init__(self) -> None:
        if not self.offsets:
            raise ConfigError("FormationController.offsets: need at least one follower")
        desired_relative(np.zeros(2), 0.0, self.frame)  # raises on an unknown frame

    def command(
        self, follower: int, estimate: Array, leader_u: tuple[float, float]
    ) -> tuple[float, float]:
        """Follower ``R_follower``'s command (``1 ≤ follower ≤ N``) from its own estimate
        ``[r_x, r_y, θ_i, θ_0]`` (what its own process computes)."""
        if not 1 <= follower <= len(self.offsets):
            raise ConfigError(
                f"FormationController: follower {follower} outside 1..{len(self.offsets)}"
            )
        off = np.array(self.offsets[follower - 1])
        return formation_command(estimate, off, self.frame, leader_u, self.settings)

    def commands(self, estimates: Array, leader_u: tuple[float, float]) -> Array:
        """``(N, 2)`` commands ``(v_i, ω_i)`` from the followers' estimates ``(N, 4)``
        ``[r_x, r_y, θ_i, θ_0]`` and the leader's broadcast command ``(v_0, ω_0)``."""
        x = np.asarray(estimates, dtype=float)
        if x.shape != (len(self.offsets), 4):
            raise ConfigError(
                f"FormationController: estimates of shape {x.shape} for "
                f"{len(self.offsets)} followers (expected ({len(self.offsets)}, 4))"
            )
        return np.array([self.command(i, x[i - 1], leader_u) for i in range(1, len(x) + 1)])
