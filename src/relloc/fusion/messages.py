"""Equivalent-measurement messages broadcast between fusers (seed 002 Eq. 8).

At the communication rate a fuser ``i`` broadcasts, for every teammate ``j`` it tracks, the
tracks of ``GSF^(i,j)``::

    ^{eq}Z^{ij} = ⋃_h { m_h(k|k), P_h(k|k), m_h(k|k−f), P_h(k|k−f), w_h(k|k) },

where ``m_h(k|k−f), P_h(k|k−f)`` is the track as it was at the previous broadcast, propagated
to now by the prediction only; the receiver uses the pair to remove the information it already
holds (information de-correlation, Eqs. 10 and 12).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from relloc.core.checks import count, floats, number
from relloc.core.linalg import symmetric_within
from relloc.errors import ConfigError, DataError

Array = NDArray[np.float64]

#: Size of a track's state ``(x, y, z, φ)``.
STATE_DIM = 4


@dataclass(frozen=True, kw_only=True)
class EquivalentMeasurement:
    """The tracks of ``GSF^(sender, subject)`` at ``time`` (Eq. 8).

    ``means``/``prior_means`` (K, 4) and ``covs``/``prior_covs`` (K, 4, 4) are the current and
    the previous-broadcast-propagated tracks; ``weights`` (K,) sum to one. ``sender`` and
    ``subject`` are robot indices (integers ≥ 0) and ``time`` a finite number
    (:mod:`relloc.core.checks`), else DataError.

    Every covariance must be symmetric (:func:`relloc.core.linalg.symmetric_within`: a
    Cholesky factorisation reads one triangle only). The
    weights must sum to a finite total (normalised by an infinite one, all would be 0).

    Every covariance must be positive definite with a determinant that is > 0 in floating
    point (its Cholesky factor ``L`` exists and ``det P = (Π diag L)² > 0``), else DataError:
    the receiver scores a track with Gaussian densities (``e^{−γ/2}/√det(2πP)`` for a birth),
    which a singular or numerically degenerate ``P`` (a point mass) makes infinite;
    normalised, that weight is NaN and would empty the receiver's filter.
    """

    sender: int
    subject: int
    time: float
    means: Array
    covs: Array
    prior_means: Array
    prior_covs: Array
    weights: Array

    def __post_init__(self) -> None:
        sender, subject, time = (f"{v!r:.20}" for v in (self.sender, self.subject, self.time))
        where = f"EquivalentMeasurement({sender}→{subject} at t={time})"
        try:
            count(self.sender, f"{where}: sender", low=0)
            count(self.subject, f"{where}: subject", low=0)
            number(self.time, f"{where}: time")
        except ConfigError as exc:
            raise DataError(str(exc)) from exc
        if self.sender == self.subject:
            raise DataError(f"{where}: sender and subject must differ")
        means = np.atleast_2d(floats(self.means, f"{where}: means"))
        k = means.shape[0]
        arrays = {
            "means": (means, (k, STATE_DIM)),
            "covs": (floats(self.covs, f"{where}: covs"), (k, STATE_DIM, STATE_DIM)),
            "prior_means": (
                np.atleast_2d(floats(self.prior_means, f"{where}: prior_means")),
                (k, STATE_DIM),
            ),
            "prior_covs": (
                floats(self.prior_covs, f"{where}: prior_covs"),
                (k, STATE_DIM, STATE_DIM),
            ),
            "weights": (floats(self.weights, f"{where}: weights").reshape(-1), (k,)),
        }
        for name, (arr, shape) in arrays.items():
            if arr.shape != shape:
                raise DataError(f"{where}: {name} has shape {arr.shape}, expected {shape}")
            if not np.all(np.isfinite(arr)):
                raise DataError(f"{where}: {name} holds non-finite values")
            object.__setattr__(self, name, arr)
        for name in ("covs", "prior_covs"):
            try:
                L = np.linalg.cholesky(arrays[name][0])
                # det P = (Π diag L)²: 0 when det P underflows
                regular = bool(np.all(np.prod(np.diagonal(L, 0, -2, -1), axis=-1) ** 2 > 0.0))
            except np.linalg.LinAlgError:
                regular = False
            if not regular:
                raise DataError(f"{where}: {name} must be positive definite with a determinant > 0")
            if not symmetric_within(arrays[name][0]):
                raise DataError(f"{where}: {name} must be symmetric")
        w = arrays["weights"][0]
        if k == 0 or np.any(w < 0.0) or not 0.0 < w.sum() < np.inf:
            raise DataError(
                f"{where}: needs ≥ 1 track with non-negative weights summing to a finite total > 0"
            )
        object.__setattr__(self, "weights", w / w.sum())

    @property
    def size(self) -> int:
        """Number of tracks in the message."""
        return int(self.weights.size)
