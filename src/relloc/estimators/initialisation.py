"""How a relative-pose track starts: the initial Gaussian over ``RelPose4 = (x, y, z, φ)``.

Seed 000 §5.1 compares four initialisations (its Table 1 cases):

1. **known pose** — the initial relative pose is accurately known;
2. **known position, unknown yaw** — the position is known, the relative yaw is not;
3. **known yaw, unknown position** — the yaw is known, the position is a random guess;
4. **fully unknown** — an arbitrary pose inside the observing robot's field of view.

A fifth, practical policy starts from the **first measurement**: the position is the
measured point, the yaw unknown (what a robot without ground truth does).

Unknown quantities get the moments of a uniform distribution over their range, so the prior
covers the truth without being arbitrarily wide: a yaw uniform on the circle has σ = π/√3;
a position coordinate uniform on ``[−R, R]`` (R = the sensor's maximum range) has σ = R/√3.

The first-measurement position is ``p = r u_r(θ, α)`` with
``u_r = (cθ cα, sθ cα, sα)``; its covariance is ``J diag(σ_r², σ_θ², σ_α²) Jᵀ`` with
``J = ∂p/∂(r, θ, α) = [u_r, r cα u_θ, r u_α]`` (``u_θ = (−sθ, cθ, 0)``,
``u_α = (−cθ sα, −sθ sα, cα)``), i.e. the inverse of seed 000 Eq. 2 linearised at the
measurement.

The policies are frozen dataclasses called with an :class:`InitContext` (the track's first
measurement, the sensor's σ, and — in simulation only — the true relative pose); the pure
functions beneath them can be used directly.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from relloc.core.checks import number, positive
from relloc.core.gaussian import Gaussian
from relloc.errors import ConfigError

Array = NDArray[np.float64]

#: σ of a yaw uniform on the circle, π/√3.
SIGMA_UNKNOWN_YAW = math.pi / math.sqrt(3.0)


def _diag(sigma_position: float, sigma_yaw: float) -> Array:
    return np.diag([sigma_position**2] * 3 + [sigma_yaw**2])


def known_pose(
    truth: ArrayLike,
    *,
    sigma_position: float = 0.02,
    sigma_yaw: float = 0.02,
    rng: np.random.Generator | None = None,
) -> Gaussian:
    """Case 1: ``N(x₀, P₀)`` around the true pose, ``P₀ = diag(σ_p², σ_p², σ_p², σ_φ²)``.

    With ``rng`` the mean is drawn from ``N(truth, P₀)`` so the initial error is consistent with
    ``P₀``; without it the mean is the truth itself.
    """
    P = _diag(sigma_position, sigma_yaw)
    mean = np.asarray(truth, dtype=float).reshape(4)
    if rng is not None:
        mean = mean + np.sqrt(np.diag(P)) * rng.standard_normal(4)
    return Gaussian(mean=mean, cov=P)


def known_position_unknown_yaw(
    truth: ArrayLike,
    yaw_guess: float,
    *,
    sigma_position: float = 0.02,
    sigma_yaw: float = SIGMA_UNKNOWN_YAW,
) -> Gaussian:
    """Case 2: the true position, a yaw guess with the σ of a yaw unknown on the circle."""
    mean = np.asarray(truth, dtype=float).reshape(4).copy()
    mean[3] = yaw_guess
    return Gaussian(mean=mean, cov=_diag(sigma_position, sigma_yaw))


def known_yaw_unknown_position(
    truth: ArrayLike,
    position_guess: ArrayLike,
    *,
    sigma_position: float,
    sigma_yaw: float = 0.02,
) -> Gaussian:
    """Case 3: a position guess with a wide σ, the true yaw."""
    mean = np.asarray(truth, dtype=float).reshape(4).copy()
    mean[:3] = np.asarray(position_guess, dtype=float).reshape(3)
    return Gaussian(mean=mean, cov=_diag(sigma_position, sigma_yaw))


def fully_unknown(
    pose_guess: ArrayLike, *, sigma_position: float, sigma_yaw: float = SIGMA_UNKNOWN_YAW
) -> Gaussian:
    """Case 4: an arbitrary pose guess with wide position and yaw uncertainty."""
    mean = np.asarray(pose_guess, dtype=float).reshape(4)
    return Gaussian(mean=mean, cov=_diag(sigma_position, sigma_yaw))


def from_first_measurement(
    z: ArrayLike,
    sensor_sigma: ArrayLike,
    *,
    yaw_guess: float = 0.0,
    sigma_yaw: float = SIGMA_UNKNOWN_YAW,
) -> Gaussian:
    """Position from the first ``z = (r, θ, α)`` (inverse of seed 000 Eq. 2), yaw unknown."""
    r, th, al = np.asarray(z, dtype=float).reshape(3)
    s_r, s_th, s_al = np.asarray(sensor_sigma, dtype=float).reshape(3)
    ct, st, ca, sa = math.cos(th), math.sin(th), math.cos(al), math.sin(al)
    u_r = np.array([ct * ca, st * ca, sa])
    u_t = np.array([-st, ct, 0.0])
    u_a = np.array([-ct * sa, -st * sa, ca])
    J = np.column_stack([u_r, r * ca * u_t, r * u_a])
    cov = np.zeros((4, 4))
    cov[:3, :3] = (J * np.array([s_r, s_th, s_al]) ** 2) @ J.T
    cov[3, 3] = sigma_yaw**2
    return Gaussian(mean=np.append(r * u_r, yaw_guess), cov=cov)


def pose_in_fov(
    rng: np.random.Generator,
    *,
    fov_deg: float,
    range_limits: tuple[float, float],
    elevation_fov_deg: float = 0.0,
) -> Array:
    """A random pose inside a field of view: range, azimuth, elevation and yaw uniform."""
    r = rng.uniform(*range_limits)
    th = rng.uniform(-0.5, 0.5) * math.radians(fov_deg)
    al = rng.uniform(-0.5, 0.5) * math.radians(elevation_fov_deg)
    return np.array(
        [
            r * math.cos(al) * math.cos(th),
            r * math.cos(al) * math.sin(th),
            r * math.sin(al),
            rng.uniform(-math.pi, math.pi),
        ]
    )


def poses_spread_in_fov(
    n: int, *, fov_deg: float, range_limits: tuple[float, float], height: float = 0.0
) -> Array:
    """``n`` deterministic poses spread over a horizontal field of view (seed 000 case 4 uses 13).

    Azimuths are evenly spaced across the view, ranges alternate between ⅓ and ⅔ of the range
    interval, heights are ``height`` and yaws are evenly spaced on the circle, so the set covers
    near/far, left/right and every heading.
    """
    if n < 1:
        raise ConfigError(f"n: must be ≥ 1, got {n}")
    half = 0.5 * math.radians(min(fov_deg, 359.0))
    th = np.linspace(-half, half, n) if n > 1 else np.zeros(1)
    lo, hi = range_limits
    rho = np.where(np.arange(n) % 2 == 0, lo + (hi - lo) / 3.0, lo + 2.0 * (hi - lo) / 3.0)
    yaw = -math.pi + (np.arange(n) + 0.5) * 2.0 * math.pi / n
    return np.column_stack([rho * np.cos(th), rho * np.sin(th), np.full(n, height), yaw])


# --------------------------------------------------------------------------- policies


@dataclass(frozen=True, kw_only=True)
class InitContext:
    """What a policy may use when a track is created.

    ``z`` the first measurement ``(r, θ, α)``; ``sensor_sigma`` ``(σ_r, σ_θ, σ_α)``;
    ``truth`` the true relative pose (simulation only, ``None`` otherwise); ``rng`` for
    policies that draw a random guess.
    """

    z: Array
    sensor_sigma: Array
    truth: Array | None = None
    rng: np.random.Generator | None = None

    def require_truth(self, policy: str) -> Array:
        if self.truth is None:
            raise ConfigError(
                f"initialisation {policy!r} needs the true relative pose, which only a simulation "
                "or a dataset with ground truth provides; use 'measurement' instead"
            )
        return self.truth

    def require_rng(self, policy: str) -> np.random.Generator:
        if self.rng is None:
            raise ConfigError(f"initialisation {policy!r} draws a random guess and needs an rng")
        return self.rng


@dataclass(frozen=True, kw_only=True)
class FieldOfView:
    """Where an arbitrary initial guess is drawn: horizontal FOV and range interval."""

    fov_deg: float = 120.0
    range_limits: tuple[float, float] = (0.3, 15.0)
    elevation_fov_deg: float = 0.0

    def __post_init__(self) -> None:
        number(self.fov_deg, "FieldOfView.fov_deg", low=0.0, high=360.0, open_low=True)
        number(self.elevation_fov_deg, "FieldOfView.elevation_fov_deg", low=0.0, high=180.0)
        limits = self.range_limits
        if not isinstance(limits, (tuple, list)) or len(limits) != 2:
            raise ConfigError(f"range_limits: need (min, max), got {limits!r:.60}")
        lo, hi = (number(v, "FieldOfView.range_limits") for v in limits)
        if not (0.0 <= lo < hi):
            raise ConfigError(f"range_limits: need 0 ≤ min < max < ∞, got {self.range_limits}")
        object.__setattr__(self, "range_limits", (lo, hi))

    @property
    def sigma_position(self) -> float:
        """σ of a coordinate uniform on ``[−R, R]``, R = the maximum range: R/√3."""
        return self.range_limits[1] / math.sqrt(3.0)


@dataclass(frozen=True, kw_only=True)
class InitPolicy:
    """An initialisation policy; ``name`` is one of :data:`POLICY_NAMES`.

    ``uses_measurement`` tells the track manager whether the first measurement is already
    inside the initial belief (then it must not be fused again).
    """

    name: str = "measurement"
    sigma_known_position: float = 0.02
    sigma_known_yaw: float = 0.02
    fov: FieldOfView = field(default_factory=FieldOfView)

    def __post_init__(self) -> None:
        if self.name not in POLICY_NAMES:
            raise ConfigError(f"init: must be one of {', '.join(POLICY_NAMES)}, got {self.name!r}")
        positive(self.sigma_known_position, "InitPolicy.sigma_known_position")
        positive(self.sigma_known_yaw, "InitPolicy.sigma_known_yaw")

    @property
    def uses_measurement(self) -> bool:
        return self.name == "measurement"

    @property
    def needs_truth(self) -> bool:
        """Whether the policy starts from the true relative pose (seed 000 cases 1–3)."""
        return self.name in _TRUTH_POLICIES

    def __call__(self, ctx: InitContext) -> Gaussian:
        return _POLICIES[self.name](self, ctx)


def _known(p: InitPolicy, ctx: InitContext) -> Gaussian:
    return known_pose(
        ctx.require_truth(p.name),
        sigma_position=p.sigma_known_position,
        sigma_yaw=p.sigma_known_yaw,
        rng=ctx.rng,
    )


def _known_position(p: InitPolicy, ctx: InitContext) -> Gaussian:
    truth = ctx.require_truth(p.name)
    yaw = ctx.require_rng(p.name).uniform(-math.pi, math.pi)
    return known_position_unknown_yaw(truth, yaw, sigma_position=p.sigma_known_position)


def _random_guess(p: InitPolicy, ctx: InitContext) -> Array:
    f = p.fov
    return pose_in_fov(
        ctx.require_rng(p.name),
        fov_deg=f.fov_deg,
        range_limits=f.range_limits,
        elevation_fov_deg=f.elevation_fov_deg,
    )


def _known_yaw(p: InitPolicy, ctx: InitContext) -> Gaussian:
    truth = ctx.require_truth(p.name)
    guess = _random_guess(p, ctx)
    return known_yaw_unknown_position(
        truth, guess[:3], sigma_position=p.fov.sigma_position, sigma_yaw=p.sigma_known_yaw
    )


def _unknown(p: InitPolicy, ctx: InitContext) -> Gaussian:
    return fully_unknown(_random_guess(p, ctx), sigma_position=p.fov.sigma_position)


def _measurement(p: InitPolicy, ctx: InitContext) -> Gaussian:
    return from_first_measurement(ctx.z, ctx.sensor_sigma)


_POLICIES: dict[str, Callable[[InitPolicy, InitContext], Gaussian]] = {
    "known": _known,
    "known-position": _known_position,
    "known-yaw": _known_yaw,
    "unknown": _unknown,
    "measurement": _measurement,
}

#: Names accepted by :class:`InitPolicy` (and ``relloc run --init``).
POLICY_NAMES: tuple[str, ...] = tuple(_POLICIES)
_TRUTH_POLICIES = frozenset({"known", "known-position", "known-yaw"})
