"""Track formation for one Gaussian-sum filter (seed 002 §II-D.3 and Eq. 13).

Every track ``h`` (mixture component with weight ``w_h``) of the filter ``GSF^(i,j)`` that
tracks teammate ``j`` branches, for one sensor's measurement set ``Z = {z_1 … z_m}``, into

* a **false-alarm** track (association ``A_0``: none of the measurements is ``j``) with weight
  ``w_h (1 − P_D P_G)``;
* one **detected** track per measurement ``z_r`` inside the track's gate (association
  ``A_r``), Kalman-updated, with the likelihood weight of Eq. 7 divided by the density ``κ``
  of measurements that are *not* ``j`` (clutter and the other teammates; the fuser evaluates
  it per measurement, see :mod:`relloc.estimators.gaussian_sum`)::

      w_{h,r} = w_h · P_D · N(z_r; ẑ_h, S_h) / κ;

  dividing by ``κ`` is Reid's single-target MHT weighting and makes the detected weight a
  likelihood *ratio*, so it can be normalised together with the dimensionless false-alarm
  and birth weights (Eq. 7 gives only the likelihood factor);
* one **new** track per measurement that lies outside the gate of every track, with birth
  probability ``P_B`` (Eq. 13).  Tracks are *not* born from in-gate measurements: every track of
  ``GSF^(i,j)`` is the same robot ``j``, so that would only duplicate hypotheses. A new track's
  prior over the measurement space is uniform, so its measurement likelihood is ``1/V``
  (``V``: volume of the measurement space); like a detected track it is divided by ``κ``.

Birth (Eq. 13), from range ``r`` (known correspondence), a bearing ``(α, β)`` of unknown
correspondence and the height difference ``h``::

    m = [r cos β cos α, r cos β sin α, r sin β, 0],   P = diag(0.1, 0.1, 0.05, 4π)
    w = P_B · (1/V_r) · N(h; r sin β, P₃₃) · P_D / (V κ).

Every factor is the predictive density of one measurement under the hypothesis "teammate ``j``
is somewhere new" (a uniform prior over the measurement space), so that it can be compared
with the densities an existing track gets for the same measurements: the range is uniform on
``[0, V_r]`` (density ``1/V_r``; an existing track gets ``N(r; r̂, S_r)``), the height, given
the range and the bearing, is ``N(h; r sin β, P₃₃)`` (Eq. 13; an existing track gets
``N(h; ẑ, S_h)``) and the bearing is uniform over its space (``1/V``, divided by ``κ`` like a
detection). The yaw, unobservable from one measurement, starts at 0 with variance 4π (almost
uniform over a turn).
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from relloc.core.checks import count, number, positive
from relloc.errors import ConfigError, DataError

Array = NDArray[np.float64]


@dataclass(frozen=True, kw_only=True)
class FormationSettings:
    """Probabilities of track formation and the Eq. 13 birth covariance.

    Attributes:
        p_detect: detection probability ``P_D`` of the sensor.
        p_gate: gate probability ``P_G``.
        p_birth: birth probability ``P_B`` of a new track.
        birth_variances: diagonal of the birth covariance ``(σ²_x, σ²_y, σ²_z, σ²_φ)``.
        birth_yaw_components: ``K``; 1 is Eq. 13's single component (yaw 0, variance σ²_φ);
            ``K > 1`` splits every new track into ``K`` components at yaw ``2πk/K`` with
            standard deviation ``π/K`` and weight ``w/K`` (a Gaussian sum over the unknown yaw,
            as :mod:`relloc.estimators.yaw_bank`), so that no update is linearised about a yaw
            that is far from the truth.
    """

    p_detect: float = 0.95
    p_gate: float = 0.95
    p_birth: float = 0.5
    birth_variances: tuple[float, float, float, float] = (0.1, 0.1, 0.05, 4.0 * np.pi)
    birth_yaw_components: int = 8

    def __post_init__(self) -> None:
        """Every field is checked with :mod:`relloc.core.checks`: a value of the wrong type (a
        string, ``None``, a ``bool``, a float ``birth_yaw_components``) or out of its range is a
        ConfigError naming the field."""
        for name in ("p_detect", "p_gate", "p_birth"):
            number(
                getattr(self, name), f"FormationSettings.{name}", low=0.0, high=1.0, open_low=True
            )
        if self.p_gate >= 1.0:
            raise ConfigError("FormationSettings.p_gate must be < 1 (a gate needs a threshold)")
        values = self.birth_variances
        if (
            isinstance(values, str)
            or not isinstance(values, Iterable)
            or len(vs := tuple(values)) != 4
        ):
            raise ConfigError(
                f"FormationSettings.birth_variances needs 4 positive values, got {values!r:.60}"
            )
        bv = tuple(positive(v, f"FormationSettings.birth_variances[{i}]") for i, v in enumerate(vs))
        object.__setattr__(self, "birth_variances", bv)
        if count(self.birth_yaw_components, "FormationSettings.birth_yaw_components") > 64:
            raise ConfigError(
                "FormationSettings.birth_yaw_components must lie in [1, 64], got "
                f"{self.birth_yaw_components}"
            )


def _detection(settings: FormationSettings, p_detect: float | Array | None) -> Array:
    """``P_D`` of this scan: ``p_detect`` when given (scalar or per item), else the setting."""
    return np.asarray(settings.p_detect if p_detect is None else p_detect, dtype=float)


def formation_weights(
    weights: Array,
    likelihood: Array,
    gated: NDArray[np.bool_],
    settings: FormationSettings,
    false_density: float | Array,
    p_detect: float | Array | None = None,
) -> tuple[Array, Array]:
    """Unnormalised weights of false-alarm and detected tracks (module docstring).

    Args:
        weights: prior track weights ``w_h`` (K,).
        likelihood: ``N(z_r; ẑ_h, S_h)`` (K, m).
        gated: ``True`` where measurement ``r`` is inside the gate of track ``h`` (K, m).
        settings: formation probabilities.
        false_density: density ``κ`` of measurements not originating from the target (> 0),
            a scalar or one value per (track, measurement) pair (K, m).
        p_detect: ``P_D`` for this scan, a scalar or one value per track (K,), each in
            ``[0, 1]`` (else ConfigError: a NaN or a value above 1 would give NaN or negative
            weights); ``None``: ``settings.p_detect``.

    Returns:
        ``(w_false_alarm (K,), w_detected (K, m))`` with zeros outside the gate.
    """
    kappa = np.asarray(false_density, dtype=float)
    if not (np.all(np.isfinite(kappa)) and np.all(kappa > 0.0)):
        raise ConfigError(f"formation_weights: false_density must be > 0, got {kappa}")
    pd = _detection(settings, p_detect)
    if not np.all((pd >= 0.0) & (pd <= 1.0)):
        raise ConfigError(f"formation_weights: p_detect must lie in [0, 1], got {pd}")
    w_fa = weights * (1.0 - pd * settings.p_gate)
    w_det = np.where(gated, (weights * pd)[:, None] * likelihood / kappa, 0.0)
    return w_fa, w_det


def birth_tracks(
    r: Array | float,
    alpha: Array,
    beta: Array,
    h: Array | float,
    settings: FormationSettings,
    *,
    volume: float,
    range_volume: float,
    false_density: float | Array,
    p_detect: float | Array | None = None,
) -> tuple[Array, Array, Array]:
    """New tracks of Eq. 13 for bearings ``(α_k, β_k)`` with ranges ``r_k`` and heights ``h_k``.

    ``r`` and ``h`` are scalars or one value per bearing (several teammates at once).
    ``volume`` is the volume ``V`` of the bearing space, ``range_volume`` the extent ``V_r`` (m)
    of the range space and ``false_density`` the density ``κ`` (scalar or one value per
    bearing); ``p_detect`` is ``P_D`` (scalar or per bearing; ``None``: ``settings.p_detect``).
    Returns ``(means (mK, 4), covs (mK, 4, 4), weights (mK,))``, the ``K =
    settings.birth_yaw_components`` yaw components of each bearing consecutive. Shapes that do
    not match and values that are not finite are a DataError (the estimator passes only
    finite, positive ranges).
    """
    kappa = np.asarray(false_density, dtype=float)
    if not (volume > 0.0 and range_volume > 0.0 and np.all(kappa > 0.0)):
        raise ConfigError(
            "birth_tracks: volume, range_volume and false_density must be > 0: "
            f"{volume}, {range_volume}, {false_density}"
        )
    alpha = np.asarray(alpha, dtype=float).reshape(-1)
    beta = np.asarray(beta, dtype=float).reshape(-1)
    try:
        beta, r, h = (
            np.broadcast_to(np.asarray(v, dtype=float), alpha.shape) for v in (beta, r, h)
        )
    except ValueError:
        raise DataError(
            f"birth_tracks: {alpha.size} azimuths need as many elevations, and ranges and heights "
            f"as scalars or one per bearing; got shapes {np.shape(beta)}, {np.shape(r)}, "
            f"{np.shape(h)}"
        ) from None
    if not np.isfinite(np.concatenate([alpha, beta, r, h])).all():
        raise DataError("birth_tracks: a bearing, range or height is NaN or infinite")
    cb = np.cos(beta)
    means = np.stack(
        [r * cb * np.cos(alpha), r * cb * np.sin(alpha), r * np.sin(beta), np.zeros_like(alpha)],
        axis=-1,
    )
    covs = np.broadcast_to(np.diag(settings.birth_variances), (alpha.size, 4, 4)).copy()
    var_z = settings.birth_variances[2]
    height_density = np.exp(-0.5 * (h - r * np.sin(beta)) ** 2 / var_z) / np.sqrt(
        2.0 * np.pi * var_z
    )
    weights = (
        settings.p_birth
        * height_density
        / range_volume
        * _detection(settings, p_detect)
        / (volume * kappa)
    )
    K = settings.birth_yaw_components
    if K == 1:
        return means, covs, weights
    means = np.repeat(means, K, axis=0)
    means[:, 3] = np.tile(2.0 * np.pi * np.arange(K) / K, alpha.size)
    covs = np.repeat(covs, K, axis=0)
    covs[:, 3, 3] = (np.pi / K) ** 2
    return means, covs, np.repeat(weights / K, K)
