"""Planar (SE(2)) measurement models for cooperative localization of unicycle teams.

Poses are ``(x, y, ψ)``; a target is a point ``(x_j, y_j)`` (another robot's position or a
known landmark). With ``Δx = x_j − x_i``, ``Δy = y_j − y_i``, ``q = Δx² + Δy²``, ``ρ = √q``:

- bearing (seed 001 Eq. 2): ``η_ij = atan2(Δy, Δx) − ψ_i`` (wrapped to [−π, π)), with

      ∂η/∂(x_i, y_i, ψ_i) = ( Δy/q, −Δx/q, −1 ),   ∂η/∂(x_j, y_j) = ( −Δy/q, Δx/q );

- range: ``ρ_ij = √q`` with ``∂ρ/∂(x_i, y_i, ψ_i) = (−Δx/ρ, −Δy/ρ, 0)``,
  ``∂ρ/∂(x_j, y_j) = (Δx/ρ, Δy/ρ)``;
- GPS-like absolute pose: ``h(X_i) = X_i``, ``H = I₃`` (heading residual wrapped);
- range bias of the camera (:func:`range_bias_features`): the measured range reads
  ``ρ + b(η, ρ)`` with ``b = c · (1, η, η², ρ, ρη²)``, a smooth function of where the target
  sits in the image and how far it is (the coefficients are fitted by
  :mod:`relloc.calibration.camera`).

All functions accept a leading batch dimension. The joint (team) form used by the cooperative
filters is a stack of *scalar rows* (:class:`ScalarRows`): every row depends on at most two robot
blocks (observer and observed robot), so the joint Jacobian ``H`` (m × 3n) is stored as
``(m, 2, 3)`` blocks plus their block indices — the sparsity the information filter exploits
(seed 001, update step: ``Y⁺ = Y + Σ Hᵢⱼᵀ σ⁻² Hᵢⱼ`` touches only the (i, j) blocks).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from relloc.core.angles import wrap_angle
from relloc.errors import ModelError

Array = NDArray[np.float64]
IntArray = NDArray[np.int64]

_MIN_SEPARATION_SQ = 1e-12


class RowKind:
    """What a scalar measurement row observes: plain ``int`` codes (not an ``IntEnum``: numpy
    compares an array with a plain int several times faster, and the filters compare row kinds
    at every epoch)."""

    BEARING = 0
    RANGE = 1
    POSE_X = 2
    POSE_Y = 3
    POSE_HEADING = 4


ANGULAR_KINDS = (RowKind.BEARING, RowKind.POSE_HEADING)


def _deltas(observer: Array, target_xy: Array) -> tuple[Array, Array, Array]:
    observer = np.asarray(observer, dtype=float)
    target_xy = np.asarray(target_xy, dtype=float)
    dx = target_xy[..., 0] - observer[..., 0]
    dy = target_xy[..., 1] - observer[..., 1]
    q = dx * dx + dy * dy
    if (q < _MIN_SEPARATION_SQ).any():
        raise ModelError("planar measurement: observer and target coincide (bearing undefined)")
    return dx, dy, q


def bearing(observer: Array, target_xy: Array) -> Array:
    """Bearing ``η = atan2(Δy, Δx) − ψ`` of a point seen from a pose, wrapped to [−π, π)."""
    dx, dy, _ = _deltas(observer, target_xy)
    psi = np.asarray(observer, dtype=float)[..., 2]
    return np.asarray(wrap_angle(np.arctan2(dy, dx) - psi), dtype=float)


def bearing_jacobians(observer: Array, target_xy: Array) -> tuple[Array, Array]:
    """``(∂η/∂observer (…,3), ∂η/∂target_xy (…,2))`` of :func:`bearing`."""
    dx, dy, q = _deltas(observer, target_xy)
    H_obs = np.stack([dy / q, -dx / q, -np.ones_like(q)], axis=-1)
    H_tgt = np.stack([-dy / q, dx / q], axis=-1)
    return H_obs, H_tgt


def planar_range(observer: Array, target_xy: Array) -> Array:
    """Euclidean range ``ρ = √(Δx² + Δy²)``."""
    _, _, q = _deltas(observer, target_xy)
    return np.sqrt(q)


def range_jacobians(observer: Array, target_xy: Array) -> tuple[Array, Array]:
    """``(∂ρ/∂observer (…,3), ∂ρ/∂target_xy (…,2))`` of :func:`planar_range`."""
    dx, dy, q = _deltas(observer, target_xy)
    r = np.sqrt(q)
    H_obs = np.stack([-dx / r, -dy / r, np.zeros_like(r)], axis=-1)
    H_tgt = np.stack([dx / r, dy / r], axis=-1)
    return H_obs, H_tgt


def range_bearing(observer: Array, target_xy: Array) -> Array:
    """``(ρ, η)`` stacked on the last axis, shape ``(…, 2)``."""
    return np.stack([planar_range(observer, target_xy), bearing(observer, target_xy)], axis=-1)


def range_bearing_jacobians(observer: Array, target_xy: Array) -> tuple[Array, Array]:
    """``(∂(ρ,η)/∂observer (…,2,3), ∂(ρ,η)/∂target_xy (…,2,2))``."""
    Ro, Rt = range_jacobians(observer, target_xy)
    Bo, Bt = bearing_jacobians(observer, target_xy)
    return np.stack([Ro, Bo], axis=-2), np.stack([Rt, Bt], axis=-2)


#: Regressors of the camera's range-bias model ``b(η, ρ) = c · (1, η, η², ρ, ρη²)``.
RANGE_BIAS_FEATURES = ("1", "η", "η²", "ρ", "ρη²")


def range_bias_features(bearing: Array, rng: Array) -> Array:
    """Regressors ``(1, η, η², ρ, ρ η²)`` of the range-bias model, shape ``(…, 5)``."""
    return np.stack([np.ones_like(bearing), bearing, bearing**2, rng, rng * bearing**2], axis=-1)


@dataclass(frozen=True)
class ScalarRows:
    """A batch of scalar measurement rows on a team of robots (one joint update epoch).

    Fields (``m`` rows):

    - ``kind``: :class:`RowKind` per row;
    - ``observer``: index of the observing robot (the pose's robot for POSE_* rows);
    - ``target``: index of the observed robot, or −1 for a landmark / absolute pose row;
    - ``landmark_xy``: ``(m, 2)`` known landmark position (ignored unless ``target == −1`` on a
      BEARING/RANGE row);
    - ``z``: measured value; ``sigma``: its standard deviation (diagonal R, ``R = diag(σ²)``);
    - ``group``: rows sharing a group id are gated together (e.g. the range and bearing of one
      detection, or the three rows of one GPS fix).
    """

    kind: IntArray
    observer: IntArray
    target: IntArray
    landmark_xy: Array
    z: Array
    sigma: Array
    group: IntArray

    def __post_init__(self) -> None:
        z = np.asarray(self.z)
        if z.ndim != 1:
            raise ModelError(f"ScalarRows.z: expected shape (m,), got {z.shape}")
        m = z.shape[0]
        for name in ("kind", "observer", "target", "sigma", "group"):
            if np.asarray(getattr(self, name)).shape != (m,):
                raise ModelError(f"ScalarRows.{name}: expected shape ({m},)")
        for name in ("kind", "observer", "target", "group"):
            column = np.asarray(getattr(self, name))
            if m and column.dtype.kind not in "iu":  # a float index would be truncated or refused
                raise ModelError(f"ScalarRows.{name}: expected integers, got {column.dtype}")
        if np.asarray(self.landmark_xy).shape != (m, 2):
            raise ModelError(f"ScalarRows.landmark_xy: expected shape ({m}, 2)")
        if not np.isfinite(self.z).all() or not (np.asarray(self.sigma) > 0).all():
            raise ModelError("ScalarRows: z must be finite and sigma > 0")

    @property
    def size(self) -> int:
        return int(np.asarray(self.z).shape[0])

    def select(self, keep: NDArray[np.bool_]) -> ScalarRows:
        """The rows where ``keep`` is true."""
        return ScalarRows(
            kind=self.kind[keep],
            observer=self.observer[keep],
            target=self.target[keep],
            landmark_xy=self.landmark_xy[keep],
            z=self.z[keep],
            sigma=self.sigma[keep],
            group=self.group[keep],
        )

    @staticmethod
    def concatenate(parts: list[ScalarRows]) -> ScalarRows:
        """Stack several row batches (group ids are kept as given)."""
        if not parts:
            return empty_rows()
        return ScalarRows(
            kind=np.concatenate([p.kind for p in parts]),
            observer=np.concatenate([p.observer for p in parts]),
            target=np.concatenate([p.target for p in parts]),
            landmark_xy=np.concatenate([p.landmark_xy for p in parts]),
            z=np.concatenate([p.z for p in parts]),
            sigma=np.concatenate([p.sigma for p in parts]),
            group=np.concatenate([p.group for p in parts]),
        )


def empty_rows() -> ScalarRows:
    """A batch with no rows."""
    return ScalarRows(
        kind=np.zeros(0, dtype=np.int64),
        observer=np.zeros(0, dtype=np.int64),
        target=np.zeros(0, dtype=np.int64),
        landmark_xy=np.zeros((0, 2)),
        z=np.zeros(0),
        sigma=np.ones(0),
        group=np.zeros(0, dtype=np.int64),
    )


@dataclass(frozen=True)
class LinearisedRows:
    """Rows linearised at a team mean ``X (n, 3)``.

    ``residual`` = z − h(X) (angles wrapped); ``blocks (m, 2, 3)``: the non-zero 1×3 blocks of
    each joint Jacobian row, at robot indices ``block_index (m, 2)`` (−1 = no second block);
    ``sigma`` as in the rows.
    """

    residual: Array
    blocks: Array
    block_index: IntArray
    sigma: Array
    group: IntArray

    def dense_jacobian(self, n_robots: int) -> Array:
        """The joint Jacobian ``H (m, 3n)`` (used by the covariance-form EKF)."""
        m = self.residual.shape[0]
        H = np.zeros((m, n_robots, 3))
        rows = np.arange(m)
        for b in range(2):
            idx = self.block_index[:, b]
            ok = idx >= 0
            H[rows[ok], idx[ok], :] += self.blocks[ok, b, :]
        return H.reshape(m, 3 * n_robots)


def linearise_rows(X: Array, rows: ScalarRows) -> LinearisedRows:
    """Evaluate residuals and sparse Jacobian blocks of ``rows`` at the team mean ``X (n, 3)``
    (another shape, or ``rows`` not a :class:`ScalarRows`: ModelError)."""
    X = np.asarray(X, dtype=float)
    if X.ndim != 2 or X.shape[1] != 3 or not isinstance(rows, ScalarRows):
        raise ModelError(
            f"linearise_rows: expected a team mean (n, 3) and ScalarRows, got {X.shape} and "
            f"{type(rows).__name__}"
        )
    n = X.shape[0]
    m = rows.size
    if m and (rows.observer.min() < 0 or rows.observer.max() >= n or rows.target.max() >= n):
        raise ModelError(f"linearise_rows: robot index out of range for a team of {n}")
    kind = rows.kind
    obs = X[rows.observer] if m else np.zeros((0, 3))
    robot_target = rows.target >= 0
    tgt_xy = np.where(robot_target[:, None], X[np.maximum(rows.target, 0), :2], rows.landmark_xy)
    h = np.zeros(m)
    blocks = np.zeros((m, 2, 3))
    block_index = np.full((m, 2), -1, dtype=np.int64)
    block_index[:, 0] = rows.observer

    rel = (kind == RowKind.BEARING) | (kind == RowKind.RANGE)
    if rel.any():
        block_index[rel, 1] = np.where(robot_target[rel], rows.target[rel], -1)
    # each relative kind evaluated on its own rows only (most epochs carry one kind)
    for k, value, jacobians in (
        (RowKind.BEARING, bearing, bearing_jacobians),
        (RowKind.RANGE, planar_range, range_jacobians),
    ):
        sel = kind == k
        if sel.any():
            o, t = obs[sel], tgt_xy[sel]
            h[sel] = value(o, t)
            H_obs, H_tgt = jacobians(o, t)
            blocks[sel, 0, :] = H_obs
            blocks[sel, 1, :2] = H_tgt
    for k, col in ((RowKind.POSE_X, 0), (RowKind.POSE_Y, 1), (RowKind.POSE_HEADING, 2)):
        sel = kind == k
        h[sel] = obs[sel, col]
        blocks[sel, 0, col] = 1.0
    residual = rows.z - h
    angular = (kind == RowKind.BEARING) | (kind == RowKind.POSE_HEADING)
    residual[angular] = np.asarray(wrap_angle(residual[angular]), dtype=float)
    blocks[block_index[:, 1] < 0, 1, :] = 0.0
    return LinearisedRows(
        residual=residual,
        blocks=blocks,
        block_index=block_index,
        sigma=np.asarray(rows.sigma, dtype=float),
        group=np.asarray(rows.group, dtype=np.int64),
    )
