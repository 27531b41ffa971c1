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

Inputs. Offsets are settings (:class:`~relloc.errors.ConfigError` naming the offset): finite,
each follower at least :data:`MIN_SEPARATION_M` from the leader and from every other follower.
The estimate and the leader's command arrive at every tick (:class:`~relloc.errors.DataError`
naming them): finite, positions within :data:`~relloc.core.limits.MAX_ABS_POSITION_M`, the
command within :data:`~relloc.core.limits.MAX_SPEED_M_S` and
:data:`~relloc.core.limits.MAX_YAW_RATE_RAD_S`. A command is never computed from a NaN.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from relloc.core import checks
from relloc.core.angles import wrap_angle
from relloc.core.limits import MAX_ABS_POSITION_M, MAX_SPEED_M_S, MAX_YAW_RATE_RAD_S
from relloc.errors import ConfigError, DataError, RellocError

Array = NDArray[np.float64]
Frame = Literal["global", "leader"]

MIN_SEPARATION_M = 0.1
"""Least distance (m) between two places of a formation — the leader's and a follower's, or two
followers': closer, the robots collide and their markers overlap."""
MAX_GAIN = 1e6
"""Largest controller gain (1/s): any gain beyond it saturates every command already, and the
bound keeps ``k (r − r_des)`` finite for every admissible estimate."""


def formation_offsets(offsets: object, where: str) -> tuple[tuple[float, float], ...]:
    """``offsets`` (follower ``i``'s desired ``r = p_0 − p_i``, ``i = 1..N``, ``N ≥ 1``) as float
    pairs, each finite and within ``MAX_ABS_POSITION_M``, no follower within
    :data:`MIN_SEPARATION_M` of the leader (``r = 0``) or of another follower; else ConfigError
    naming ``where[i]``. The distances do not depend on the frame the offsets are in."""
    offsets = checks.sequence(offsets, where, "a list of [x, y] offsets")
    if len(offsets) == 0:
        raise ConfigError(f"{where}: need at least one follower")
    out: list[tuple[float, float]] = []
    for i, off in enumerate(offsets):
        at = f"{where}[{i}]"
        off = checks.sequence(off, at, "two numbers [x, y]", length=2)
        x, y = (
            checks.number(v, f"{at}[{k}]", low=-MAX_ABS_POSITION_M, high=MAX_ABS_POSITION_M)
            for k, v in enumerate(off)
        )
        if math.hypot(x, y) < MIN_SEPARATION_M:
            raise ConfigError(
                f"{at}: follower {i + 1} sits on the leader (closer than {MIN_SEPARATION_M:g} m)"
            )
        for j, (xj, yj) in enumerate(out):
            if math.hypot(x - xj, y - yj) < MIN_SEPARATION_M:
                raise ConfigError(
                    f"{at}: follower {i + 1} sits on follower {j + 1} (closer than "
                    f"{MIN_SEPARATION_M:g} m)"
                )
        out.append((x, y))
    return tuple(out)


@dataclass(frozen=True, kw_only=True)
class FormationSettings:
    """Gains and limits of the follower controller: each a finite number > 0, the gains at most
    :data:`MAX_GAIN`, ``v_max`` at most ``MAX_SPEED_M_S`` and ``w_max`` at most
    ``MAX_YAW_RATE_RAD_S`` (ConfigError naming the field)."""

    gain: float = 0.6
    heading_gain: float = 2.0
    v_max: float = 0.35
    w_max: float = 1.5

    def __post_init__(self) -> None:
        for name, high in (
            ("gain", MAX_GAIN),
            ("heading_gain", MAX_GAIN),
            ("v_max", MAX_SPEED_M_S),
            ("w_max", MAX_YAW_RATE_RAD_S),
        ):
            checks.number(
                getattr(self, name), f"FormationSettings.{name}", low=0.0, open_low=True, high=high
            )


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
    """Unicycle command ``(v_i, ω_i)`` of a follower from its estimate ``[r_x, r_y, θ_i, θ_0]``.

    ``offset`` must be two finite numbers (ConfigError); the estimate and the leader's command
    ``(v_0, ω_0)`` must be finite and within the module's bounds (DataError naming which).
    """
    x = _finite_vector(estimate, 4, "estimate [r_x, r_y, θ_i, θ_0]")
    if np.any(np.abs(x[:2]) > MAX_ABS_POSITION_M):
        raise DataError(
            f"estimate: relative position {x[:2]} beyond {MAX_ABS_POSITION_M:g} m "
            "(MAX_ABS_POSITION_M)"
        )
    _finite_vector(offset, 2, "formation offset", ConfigError)
    v0, w0 = _finite_vector(leader_u, 2, "leader command (v_0, ω_0)")
    if abs(v0) > MAX_SPEED_M_S or abs(w0) > MAX_YAW_RATE_RAD_S:
        raise DataError(
            f"leader command (v_0, ω_0): ({v0:g}, {w0:g}) beyond ({MAX_SPEED_M_S:g} m/s, "
            f"{MAX_YAW_RATE_RAD_S:g} rad/s)"
        )
    th_i, th_0 = float(x[2]), float(x[3])
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


def _finite_vector(
    value: object, size: int, what: str, error: type[RellocError] = DataError
) -> Array:
    """``value`` as ``size`` finite floats, or ``error`` naming ``what``."""
    x = checks.floats(value, what, error)
    if x.shape != (size,) or not np.all(np.isfinite(x)):
        raise error(f"{what}: expected {size} finite numbers, got {value!r:.60}")
    return x


@dataclass(frozen=True, kw_only=True)
class FormationController:
    """The followers' formation controller: follower ``R_i`` (i = 1..N) holds ``offsets[i-1]``
    (in ``frame``) from its own estimate, with :func:`formation_command`. ``offsets`` are
    checked by :func:`formation_offsets`."""

    offsets: tuple[tuple[float, float], ...]
    frame: Frame
    settings: FormationSettings = field(default_factory=FormationSettings)

    def __post_init__(self) -> None:
        formation_offsets(self.offsets, "FormationController.offsets")
        desired_relative(np.zeros(2), 0.0, self.frame)  # raises on an unknown frame
        if not isinstance(self.settings, FormationSettings):
            raise ConfigError(
                f"FormationController.settings: expected FormationSettings, got "
                f"{type(self.settings).__name__}"
            )

    def command(
        self, follower: int, estimate: Array, leader_u: tuple[float, float]
    ) -> tuple[float, float]:
        """Follower ``R_follower``'s command (``1 ≤ follower ≤ N``) from its own estimate
        ``[r_x, r_y, θ_i, θ_0]`` (what its own process computes); a bad estimate or leader
        command is a DataError naming the follower."""
        checks.count(follower, "FormationController: follower")
        if follower > len(self.offsets):
            raise ConfigError(
                f"FormationController: follower {follower} outside 1..{len(self.offsets)}"
            )
        off = np.array(self.offsets[follower - 1])
        try:
            return formation_command(estimate, off, self.frame, leader_u, self.settings)
        except DataError as exc:
            raise DataError(f"FormationController follower {follower}: {exc}") from None
