"""Range-only (UWB) localization: a relative pair from range and both robots' odometry, and a
whole team from ranges alone with a constant-velocity motion prior.

Both implement the estimator contract (:mod:`relloc.core.contract`), so
:func:`relloc.pipeline.replay.replay` drives them over any recording with ``range`` rows.

:class:`RangePairBank` — seed 000's relative state ``x = (x, y, z, φ)`` of ``subject`` in the
``owner``'s body frame (Eq. 1) with the shared predict of :mod:`relloc.estimators.relative`
(both robots' body velocities), measured by the range ``h(x) = √(x² + y² + z²)`` only. From an
unknown start a single range fixes neither the bearing nor the relative yaw, so the track starts,
at the first range ``r₀``, as a Gaussian sum of ``n_bearing × n_yaw`` EKFs placed on the circle
of radius ``r₀`` in the owner's plane (bearings ``2πk/n_bearing``, yaws ``2πm/n_yaw − π``, each
with a radial σ of the range's, a tangential σ of half the spacing, ``r₀·π/n_bearing``, but no
less than the range's, and a yaw σ of ``π/n_yaw``). Each
range updates every component (EKF, ``H = xᵀ/‖x‖`` on the position) and reweights it by its
likelihood ``N(ν; 0, S)``; the belief is the moment-matched mixture (yaws aligned before
averaging). Whether the pair is observable at all from range and these motions is a property of
the trajectory: the experiment asks :mod:`relloc.observability`.

:class:`RangeTeamFilter` — every robot not declared an anchor has the state ``(x, y, v_x, v_y)``
in the world plane, predicted by the constant-velocity model ``F = [[I, dt I], [0, I]]`` with
white acceleration of spectral density ``q`` (``Q = q [[dt³/3 I, dt²/2 I], [dt²/2 I, dt I]]``);
anchors (and static radios of known position, the recording's landmarks) are fixed points.
A range between two points ``p_i, p_j`` is the planar ``h = ‖p_i − p_j‖`` (``H`` rows
``±(p_i − p_j)ᵀ/h``); each is χ²-gated and applied on its own (Joseph form). Without anchors
the team is localized up to a rigid motion only (scored after alignment); the initial positions
come from the caller (e.g. classical multidimensional scaling of the first ranges).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from relloc.association.mixture_reduction import merge_moments
from relloc.core.checks import count, number, positive, probability
from relloc.core.contract import Belief, HeldOdometry, Silent, UpdateRecord
from relloc.core.events import elapsed
from relloc.core.kalman import chi2_threshold, gated_update, kalman_update
from relloc.core.recording import NO_TARGET, Measurements, kind_code
from relloc.errors import ConfigError, DataError
from relloc.estimators.relative import FRAME as RELATIVE_FRAME
from relloc.estimators.relative import check_cov, check_finite, predict_arrays
from relloc.models.motion import VelocityNoise

Array = NDArray[np.float64]

RANGE = kind_code("range")
#: Frame of the team filter's beliefs: a robot's planar world position.
TEAM_FRAME = "world_position2"


# ----------------------------------------------------------------------------------------------
# A relative pair from range and odometry
# ----------------------------------------------------------------------------------------------


@dataclass(frozen=True, kw_only=True)
class RangePairSettings:
    """``n_bearing × n_yaw`` components; ``sigma_range`` used where a row states no σ (m);
    ``sigma_z`` the prior σ of the height difference (m); ``gate`` the χ² probability beyond
    which a range is rejected by every component (``None``: no gate)."""

    n_bearing: int = 12
    n_yaw: int = 8
    sigma_range: float = 0.1
    sigma_z: float = 0.3
    gate: float | None = 0.999

    def __post_init__(self) -> None:
        for name in ("n_bearing", "n_yaw"):
            count(getattr(self, name), f"RangePairSettings.{name}")
        for name in ("sigma_range", "sigma_z"):
            positive(getattr(self, name), f"RangePairSettings.{name}")
        if self.gate is not None:
            probability(self.gate, "RangePairSettings.gate")


class RangePairBank(Silent):
    """``owner``'s belief of ``subject`` from ranges and both odometries (module docstring)."""

    name = "range_pair"

    def __init__(
        self,
        owner: int,
        subject: int,
        robots: Sequence[str],
        noise: VelocityNoise,
        settings: RangePairSettings,
    ) -> None:
        self.owner_index, self.subject_index = owner, subject
        self.owner, self.subject = robots[owner], robots[subject]
        self.noise, self.settings = noise, settings
        self.t: float | None = None
        self.started: float | None = None
        self.means = np.zeros((0, 4))
        self.covs = np.zeros((0, 4, 4))
        self.log_w = np.zeros(0)
        self._updates: list[UpdateRecord] = []
        self._gated = 0

    def advance(self, t: float, odometry: HeldOdometry) -> None:
        dt = elapsed(self.t, t, f"{self.owner}->{self.subject} RangePairBank.advance")
        if dt is not None and self.means.shape[0] and dt > 0:
            u = odometry.velocity
            self.means, self.covs = predict_arrays(
                self.means,
                self.covs,
                np.broadcast_to(u[self.owner_index], self.means.shape),
                np.broadcast_to(u[self.subject_index], self.means.shape),
                dt,
                self.noise,
                where=f"{self.owner}->{self.subject}",
            )
        self.t = t

    def _start(self, r0: float, sigma: float) -> None:
        s = self.settings
        bearing = 2 * np.pi * np.arange(s.n_bearing) / s.n_bearing
        yaw = 2 * np.pi * np.arange(s.n_yaw) / s.n_yaw - np.pi
        b, y = (a.ravel() for a in np.meshgrid(bearing, yaw, indexing="ij"))
        k = b.size
        self.means = np.stack([r0 * np.cos(b), r0 * np.sin(b), np.zeros(k), y], axis=1)
        radial, tangential = np.cos(b), np.sin(b)
        sr, st = sigma, max(r0 * np.pi / s.n_bearing, sigma)
        covs = np.zeros((k, 4, 4))
        covs[:, 0, 0] = sr**2 * radial**2 + st**2 * tangential**2
        covs[:, 1, 1] = sr**2 * tangential**2 + st**2 * radial**2
        covs[:, 0, 1] = covs[:, 1, 0] = (sr**2 - st**2) * radial * tangential
        covs[:, 2, 2] = s.sigma_z**2
        covs[:, 3, 3] = (np.pi / s.n_yaw) ** 2
        self.covs = covs
        self.log_w = np.full(k, -math.log(k))
        self.started = self.t

    def measure(self, batch: Measurements) -> None:
        rows = np.flatnonzero(
            (batch.kind == RANGE)
            & (
                ((batch.observer == self.owner_index) & (batch.target == self.subject_index))
                | ((batch.observer == self.subject_index) & (batch.target == self.owner_index))
            )
        )
        for q in rows:
            sigma = float(batch.sigma[q, 0])
            sigma = self.settings.sigma_range if not math.isfinite(sigma) else sigma
            self._update(float(batch.t[q]), float(batch.value[q, 0]), sigma)

    def _update(self, t: float, r: float, sigma: float) -> None:
        if not self.means.shape[0]:
            self._start(r, sigma)
            return
        p = self.means[:, :3]
        h = np.linalg.norm(p, axis=1)
        if np.any(h < 1e-6):
            raise DataError(f"{self.owner}->{self.subject}: a hypothesis reached range 0 at t={t}")
        H = np.zeros((h.size, 1, 4))
        H[:, 0, :3] = p / h[:, None]
        R = np.full((h.size, 1, 1), sigma**2)
        nu = (r - h)[:, None]
        mean, cov, inn = kalman_update(self.means, self.covs, nu, H, R, where=self.owner)
        S = inn.cov[:, 0, 0]
        nis = np.asarray(inn.nis, dtype=float)
        gate = self.settings.gate
        if gate is not None and float(nis.min()) > chi2_threshold(1, gate):
            self._gated += 1  # an outlier for every hypothesis: rejected, counted
            return
        self.means, self.covs = mean, cov
        self.log_w = self.log_w - 0.5 * (nis + np.log(2 * np.pi * S))
        self.log_w -= self.log_w.max()
        best = int(np.argmax(self.log_w))
        self._updates.append(
            UpdateRecord(
                t=t,
                subject=self.subject,
                nis=float(nis[best]),
                dof=1,
                cond_r=0.0,
                cond_s=0.0,
                age=t - (self.started or t),
            )
        )

    def mixture(self) -> tuple[Array, Array, Array]:
        """Components' means ``(K, 4)``, covariances and normalised weights."""
        w = np.exp(self.log_w - self.log_w.max())
        return self.means, self.covs, w / w.sum()

    def beliefs(self) -> list[Belief]:
        if not self.means.shape[0]:
            return []
        means, covs, w = self.mixture()
        group = np.argsort(-w).astype(np.int64)
        mean, cov, _ = merge_moments(means, covs, w, group, angle_index=3)
        age = (self.t or 0.0) - (self.started or 0.0)
        return [
            Belief(
                subject=self.subject,
                frame=RELATIVE_FRAME,
                mean=mean,
                cov=cov,
                age=age,
                info={"top_weight": float(w.max())},
            )
        ]

    def take_updates(self) -> list[UpdateRecord]:
        out, self._updates = self._updates, []
        return out

    def take_counts(self) -> dict[str, int]:
        """Ranges rejected by the gate since the previous call (``ranges_gated``)."""
        out = {"ranges_gated": self._gated} if self._gated else {}
        self._gated = 0
        return out


# ----------------------------------------------------------------------------------------------
# A team from ranges alone
# ----------------------------------------------------------------------------------------------


@dataclass(frozen=True, kw_only=True)
class RangeTeamSettings:
    """``q`` the acceleration spectral density (m²/s³) of the constant-velocity prior;
    ``sigma_position``/``sigma_velocity`` the initial σ around the given start; ``sigma_range``
    where a row states none; ``gate`` the χ² probability of the per-range gate."""

    q: float = 0.05
    sigma_position: float = 0.5
    sigma_velocity: float = 0.2
    sigma_range: float = 0.1
    gate: float | None = 0.999

    def __post_init__(self) -> None:
        for name in ("q", "sigma_position", "sigma_velocity", "sigma_range"):
            positive(getattr(self, name), f"RangeTeamSettings.{name}")
        if self.gate is not None:
            probability(self.gate, "RangeTeamSettings.gate")


@dataclass
class _Counts:
    used: int = 0
    gated: int = 0
    between_anchors: int = 0
    unknown_target: int = 0
    other: int = 0


class RangeTeamFilter(Silent):
    """Every free robot's planar position from the team's ranges (module docstring).

    ``initial (n, 2)`` start positions of every robot (those of anchors are their fixed
    positions); ``anchors`` the robot indices held fixed; ``landmarks (L, ≥2)`` fixed points
    named by the rows' ``landmark`` column.
    """

    name = "range_team"
    owner = "team"

    def __init__(
        self,
        robots: Sequence[str],
        initial: Array,
        settings: RangeTeamSettings,
        *,
        anchors: Sequence[int] = (),
        landmarks: Array | None = None,
        start: float | None = None,
    ) -> None:
        self.robots = tuple(robots)
        initial = np.asarray(initial, dtype=float)
        if initial.shape != (len(self.robots), 2) or not np.isfinite(initial).all():
            raise ConfigError(
                f"RangeTeamFilter: initial positions must be finite ({len(robots)}, 2)"
            )
        self.settings = settings
        self.anchors = tuple(sorted(set(int(a) for a in anchors)))
        self.free = [i for i in range(len(self.robots)) if i not in self.anchors]
        self.slot = {r: k for k, r in enumerate(self.free)}
        self.fixed = initial.copy()
        self.landmarks = np.zeros((0, 2)) if landmarks is None else np.asarray(landmarks)[:, :2]
        n = len(self.free)
        self.x = np.zeros(4 * n)
        P = np.zeros((4 * n, 4 * n))
        for k, r in enumerate(self.free):
            self.x[4 * k : 4 * k + 2] = initial[r]
            P[4 * k : 4 * k + 2, 4 * k : 4 * k + 2] = np.eye(2) * settings.sigma_position**2
            P[4 * k + 2 : 4 * k + 4, 4 * k + 2 : 4 * k + 4] = np.eye(2) * settings.sigma_velocity**2
        self.P = P
        self.t = start
        self.started = start
        self.counts = _Counts()
        self._updates: list[UpdateRecord] = []

    def advance(self, t: float, odometry: HeldOdometry) -> None:
        del odometry  # a range-only team has no odometry: the motion prior is constant velocity
        dt = elapsed(self.t, t, "RangeTeamFilter.advance")
        if dt is None:
            self.t = self.started = t
            return
        if dt > 0 and self.free:
            q = self.settings.q
            F1 = np.array([[1.0, 0, dt, 0], [0, 1.0, 0, dt], [0, 0, 1.0, 0], [0, 0, 0, 1.0]])
            a, b, c = dt**3 / 3, dt**2 / 2, dt
            Q1 = q * np.array([[a, 0, b, 0], [0, a, 0, b], [b, 0, c, 0], [0, b, 0, c]])
            n = len(self.free)
            F = np.kron(np.eye(n), F1)
            self.x = F @ self.x
            self.P = F @ self.P @ F.T + np.kron(np.eye(n), Q1)
        self.t = t

    def _point(self, robot: int, landmark: int) -> tuple[Array, int | None]:
        """Position of one end of a range and its state slot (``None`` when fixed)."""
        if robot >= 0:
            if robot in self.slot:
                k = self.slot[robot]
                return self.x[4 * k : 4 * k + 2], k
            return self.fixed[robot], None
        return self.landmarks[landmark], None

    def measure(self, batch: Measurements) -> None:
        assert batch.landmark is not None
        for q in range(batch.size):
            if batch.kind[q] != RANGE:
                self.counts.other += 1
                continue
            if batch.target[q] == NO_TARGET and batch.landmark[q] == NO_TARGET:
                self.counts.unknown_target += 1  # a radio of unknown identity or place
                continue
            pi, ki = self._point(int(batch.observer[q]), -1)
            pj, kj = self._point(int(batch.target[q]), int(batch.landmark[q]))
            if ki is None and kj is None:
                self.counts.between_anchors += 1
                continue
            d = pi - pj
            h = float(np.hypot(d[0], d[1]))
            if h < 1e-6:
                self.counts.other += 1
                continue
            H = np.zeros((1, self.x.size))
            if ki is not None:
                H[0, 4 * ki : 4 * ki + 2] = d / h
            if kj is not None:
                H[0, 4 * kj : 4 * kj + 2] -= d / h
            sigma = float(batch.sigma[q, 0])
            sigma = self.settings.sigma_range if not math.isfinite(sigma) else sigma
            R = np.array([[sigma**2]])
            nu = np.array([float(batch.value[q, 0]) - h])
            x, P, inn, ok = gated_update(
                self.x, self.P, nu, H, R, self.settings.gate, where="range team"
            )
            if not ok:
                self.counts.gated += 1
                continue
            self.x, self.P = x, P
            self.counts.used += 1
            subject = self.robots[
                int(batch.observer[q]) if ki is not None else int(batch.target[q])
            ]
            self._updates.append(
                UpdateRecord(
                    t=float(batch.t[q]),
                    subject=subject,
                    nis=float(inn.nis),
                    dof=1,
                    cond_r=0.0,
                    cond_s=0.0,
                    age=float(batch.t[q]) - (self.started or 0.0),
                )
            )

    def beliefs(self) -> list[Belief]:
        age = (self.t or 0.0) - (self.started or 0.0)
        return [
            Belief(
                subject=self.robots[r],
                frame=TEAM_FRAME,
                mean=self.x[4 * k : 4 * k + 2],
                cov=self.P[4 * k : 4 * k + 2, 4 * k : 4 * k + 2],
                age=age,
            )
            for r, k in self.slot.items()
        ]

    def take_updates(self) -> list[UpdateRecord]:
        out, self._updates = self._updates, []
        return out

    def take_counts(self) -> dict[str, int]:
        c, self.counts = self.counts, _Counts()
        return {
            "ranges_used": c.used,
            "ranges_gated": c.gated,
            "ranges_between_fixed_points": c.between_anchors,
            "rows_of_unknown_target": c.unknown_target,
            "rows_not_used": c.other,
        }


class RelativeDeadReckoning(Silent):
    """The baseline a user tries first for a pair: both odometries integrated from a given start
    ``(t, mean, cov)`` of the relative state, with the shared predict and no measurement.

    The start is checked where it comes in: a finite time (else :class:`ConfigError`), a mean
    ``(4,)`` and a covariance ``(4, 4)`` of finite entries (else :class:`DataError` naming the
    pair). A NaN start time would make every later ``t > t_start`` false and freeze the belief;
    a NaN mean would be reported as a belief until the first prediction.
    """

    name = "odometry_alone"

    def __init__(
        self,
        owner: int,
        subject: int,
        robots: Sequence[str],
        noise: VelocityNoise,
        start: tuple[float, Array, Array],
    ) -> None:
        self.owner_index, self.subject_index = owner, subject
        self.owner, self.subject = robots[owner], robots[subject]
        self.noise = noise
        self._where = f"{self.owner}->{self.subject}"
        self.t = number(start[0], f"RelativeDeadReckoning {self._where}: start time")
        self.started = self.t
        mean = check_finite("start mean", start[1], 4, self._where)
        if mean.shape != (4,):
            raise DataError(f"{self._where}: start mean must have shape (4,), got {mean.shape}")
        cov = check_cov(start[2], self._where)
        if cov.shape != (4, 4):
            raise DataError(f"{self._where}: start covariance must be (4, 4), got {cov.shape}")
        self.mean, self.cov = mean.copy(), cov.copy()

    def advance(self, t: float, odometry: HeldOdometry) -> None:
        dt = elapsed(self.t, t, f"RelativeDeadReckoning {self._where}")
        if dt > 0:
            u = odometry.velocity
            self.mean, self.cov = predict_arrays(
                self.mean,
                self.cov,
                u[self.owner_index],
                u[self.subject_index],
                dt,
                self.noise,
                where=self._where,
            )
            self.t = t

    def measure(self, batch: Measurements) -> None:
        del batch  # odometry alone: readings are ignored

    def beliefs(self) -> list[Belief]:
        return [
            Belief(
                subject=self.subject,
                frame=RELATIVE_FRAME,
                mean=self.mean,
                cov=self.cov,
                age=self.t - self.started,
            )
        ]
