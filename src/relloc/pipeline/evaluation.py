"""The one evaluation: estimates against the truth of a recording, and their pooled figures.

:func:`evaluate` scores every belief series of an :class:`~relloc.core.estimates.Estimates`
against the recording's ground truth in the series' frame (:mod:`relloc.pipeline.frames`):

- error ``e = x̂ − x`` with the frame's angles wrapped to [−π, π), the filter's standard
  deviations ``σ_i = √P_ii``, NEES ``eᵀ P⁻¹ e`` (seed 000 Eq. 33) and the conditioning
  ``log10(λmax/λmin)`` of ``P`` (seed 000 Eq. 36), at every record time;
- and, per measurement update, the NIS with its degrees of freedom and the conditioning of
  ``R`` and ``S`` as the estimator reported them.

:func:`accuracy_and_consistency` pools evaluations (runs, pairs) over their steady-state samples
(track age ≥ ``settle_s``): RMSE of position, yaw and every state; the share of errors inside
±3σ; ANEES and the share of NEES beyond the single-run bound ``χ²(n, 0.95)`` (about 5 % for a
consistent filter), with its 95 % interval by cluster means (the samples of one run are
correlated in time: time blocks of one run, the runs when they are independent, both when they
replay one recording; :func:`relloc.metrics.consistency.percent_beyond_interval`); ANIS and the
share of NIS beyond ``χ²(m, 0.95)``.
:func:`run_averaged_nees` gives the NEES averaged over *independent runs at one instant* — the
only average whose 95 % band (:func:`relloc.metrics.consistency.mean_chi2_band`) is valid;
time-correlated samples of one run pooled as if independent give a band far too narrow.
:func:`convergence_time` is the first record time after which an error stays below a threshold.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from relloc.core.checks import number, positive
from relloc.core.estimates import BeliefSeries, Estimates, UpdateSeries, series_label
from relloc.core.events import TIME_TOL
from relloc.core.recording import Recording
from relloc.errors import ConfigError, DataError, ModelError
from relloc.metrics.conditioning import condition_log10_batch
from relloc.metrics.consistency import (
    anees,
    chi2_upper,
    nees,
    percent_beyond,
    percent_beyond_interval,
    run_average_band,
)
from relloc.metrics.errors import state_errors
from relloc.pipeline.frames import frame

Array = NDArray[np.float64]
IntArray = NDArray[np.int64]


@dataclass(frozen=True, kw_only=True)
class SeriesEvaluation:
    """One (owner, subject) series scored in one run.

    ``t (K,)``, ``error (K, n)`` (angles wrapped), ``sigma (K, n)``, ``nees (K,)``, ``age (K,)``,
    ``cond_p (K,)``; per update ``update_t``, ``update_age``, ``nis``, ``nis_dof``, ``cond_r``,
    ``cond_s``. ``platform`` is the subject's (``ground``/``aerial``).
    """

    owner: str
    subject: str
    track: str
    platform: str
    frame: str
    t: Array
    error: Array
    sigma: Array
    nees: Array
    age: Array
    cond_p: Array
    update_t: Array
    update_age: Array
    nis: Array
    nis_dof: IntArray
    cond_r: Array
    cond_s: Array

    @property
    def label(self) -> str:
        return series_label((self.owner, self.subject, self.track))


def series_errors(series: BeliefSeries, recording: Recording) -> Array:
    """``x̂ − x`` of every record of ``series`` against the recording's truth in the series'
    frame (angles wrapped), ``(T, dim)``.

    A mean or track age that is not finite would make every pooled figure NaN (or drop the
    record from the steady state) without a word: ModelError naming the series and the first
    such record. A truth the recording cannot give (an unknown owner or subject, a time beyond
    its ground truth) is a DataError naming the series."""
    f = frame(series.frame)
    if series.mean.shape[1:] != (f.dim,):
        raise ConfigError(
            f"{series.label}: frame {f.name} has {f.dim} states, the series {series.mean.shape}"
        )
    if series.t.size == 0:
        return np.zeros((0, f.dim))
    finite = np.isfinite(series.mean).all(axis=1) & np.isfinite(series.age)
    if not finite.all():
        k = int(np.argmin(finite))
        raise ModelError(
            f"{series.label}: belief at t={series.t[k]:g} has a mean or age that is not finite"
        )
    try:
        truth = f.truth(recording, series.owner, series.subject, series.t)
    except DataError as exc:  # an owner or subject the recording lacks, a time beyond its truth
        raise DataError(f"{series.label}: {exc}") from exc
    return state_errors(series.mean, truth, f.angles)


def position_rmse(err: Array, frame_name: str) -> float:
    """RMSE of the position part of errors ``(N, dim)`` in frame ``frame_name`` (NaN if none)."""
    if not err.size:
        return float("nan")
    position = list(frame(frame_name).position)
    return float(np.sqrt(np.mean(np.sum(err[:, position] ** 2, axis=1))))


def evaluate_series(
    series: BeliefSeries, updates: UpdateSeries, recording: Recording
) -> SeriesEvaluation:
    """Score one belief series (and its updates) against the recording's truth; a covariance
    that NEES or conditioning cannot use is a ModelError naming the series."""
    err = series_errors(series, recording)
    empty = series.t.size == 0
    try:
        nees_ = np.zeros(0) if empty else nees(err, series.cov)
        cond_p = np.zeros(0) if empty else condition_log10_batch(series.cov)
    except ModelError as exc:
        raise ModelError(f"{series.label}: {exc}") from exc
    return SeriesEvaluation(
        owner=series.owner,
        subject=series.subject,
        track=series.track,
        platform=recording.platforms[recording.index(series.subject)],
        frame=series.frame,
        t=series.t,
        error=err,
        sigma=np.sqrt(np.diagonal(series.cov, axis1=1, axis2=2)),
        nees=nees_,
        age=series.age,
        cond_p=cond_p,
        update_t=updates.t,
        update_age=updates.age,
        nis=updates.nis,
        nis_dof=updates.dof,
        cond_r=updates.cond_r,
        cond_s=updates.cond_s,
    )


def evaluate(
    estimates: Estimates, recording: Recording, *, at_updates: bool = False
) -> tuple[SeriesEvaluation, ...]:
    """Score every belief series of ``estimates`` (in their order).

    With ``at_updates`` each series is scored only at its own update times — the belief just
    after each measurement update, which must have been recorded at those events — so that the
    per-record arrays (error, σ, NEES, …) and the per-update ones (NIS, …) align one to one.
    """
    out = []
    for s in estimates.beliefs:
        updates = estimates.updates_of(*s.key)
        out.append(evaluate_series(at_times(s, updates.t) if at_updates else s, updates, recording))
    return tuple(out)


def at_times(series: BeliefSeries, t: Array) -> BeliefSeries:
    """The records of ``series`` at the times ``t`` (each must be a record time, within
    :data:`TIME_TOL`; ConfigError otherwise, for a NaN time too)."""
    t = np.asarray(t, dtype=float)
    idx = np.clip(np.searchsorted(series.t, t - TIME_TOL), 0, max(series.t.size - 1, 0))
    if t.size and (series.t.size == 0 or not np.all(np.abs(series.t[idx] - t) <= TIME_TOL)):
        raise ConfigError(f"{series.label}: not recorded at every requested time")
    return dataclasses.replace(
        series,
        t=series.t[idx],
        mean=series.mean[idx],
        cov=series.cov[idx],
        age=series.age[idx],
        info={k: v[idx] for k, v in series.info.items()},
    )


def _normalised_mean(values: Array, dof: IntArray) -> float:
    """``mean(v) / n`` for one dof ``n`` (ANEES, ANIS); ``mean(v / n)`` for mixed dofs."""
    if values.size == 0:
        return float("nan")
    if np.all(dof == dof[0]):
        return anees(values, int(dof[0]))
    return anees(values / dof, 1)


def _percent_beyond_bound(values: Array, dof: IntArray, p: float = 0.95) -> float:
    if values.size == 0:
        return float("nan")
    if np.all(dof == dof[0]):
        return percent_beyond(values, chi2_upper(int(dof[0]), p))
    dofs, which = np.unique(dof, return_inverse=True)
    bounds = np.array([chi2_upper(int(d), p) for d in dofs])[which]
    return float(100.0 * np.mean(values > bounds))


def accuracy_and_consistency(
    evaluations: Sequence[SeriesEvaluation],
    *,
    settle_s: float,
    runs: Sequence[int] | None = None,
    shared_recording: bool = False,
) -> dict[str, Any]:
    """Pooled accuracy and consistency of evaluations in one frame (module docstring).

    ``runs``: the run of each evaluation (omitted: all of one run); ``shared_recording``: the
    runs replay one recording (fresh measurement noise on the same odometry) rather than being
    independent. Keys: ``samples``, ``position_rmse_m``, ``yaw_rmse_rad``, ``rmse`` and
    ``within_3sigma_percent`` per state, ``anees``, ``nees_bound``, ``nees_percent_beyond``,
    ``nees_beyond_interval`` (that share's interval by cluster means — time blocks of one
    run, the independent runs, or both ways for runs of one recording —,
    :func:`relloc.metrics.consistency.percent_beyond_interval`, with its verdict), ``anis``,
    ``nis_dof`` (the most common NIS dof; 0 without NIS), ``nis_bound`` (its χ² 0.95 bound),
    ``nis_percent_beyond`` (each NIS against the bound of its own dof).
    """
    if not evaluations:
        raise ConfigError("accuracy_and_consistency: nothing to pool")
    number(settle_s, "accuracy_and_consistency: settle_s", low=0.0)
    if runs is not None and len(runs) != len(evaluations):
        raise ConfigError(
            f"accuracy_and_consistency: {len(runs)} run indices for {len(evaluations)} "
            "evaluations; one per evaluation"
        )
    frames = {e.frame for e in evaluations}
    if len(frames) != 1:
        raise ConfigError(f"accuracy_and_consistency: mixed frames {sorted(frames)}")
    f = frame(frames.pop())
    n = f.dim
    steady = [e.age >= settle_s for e in evaluations]
    err = np.concatenate([e.error[s] for e, s in zip(evaluations, steady, strict=True)]).reshape(
        -1, n
    )
    sig = np.concatenate([e.sigma[s] for e, s in zip(evaluations, steady, strict=True)]).reshape(
        -1, n
    )
    ne = np.concatenate([e.nees[s] for e, s in zip(evaluations, steady, strict=True)])
    ne_t = np.concatenate([e.t[s] for e, s in zip(evaluations, steady, strict=True)])
    ne_run = (
        None
        if runs is None
        else np.repeat(np.asarray(runs, dtype=np.int64), [int(np.sum(s)) for s in steady])
    )
    nees_share = percent_beyond_interval(
        ne, ne_t, chi2_upper(n, 0.95), runs=ne_run, shared_recording=shared_recording
    )
    keep_nis = [e.update_age >= settle_s for e in evaluations]
    ni = np.concatenate([e.nis[k] for e, k in zip(evaluations, keep_nis, strict=True)])
    ni_dof = np.concatenate(
        [e.nis_dof[k] for e, k in zip(evaluations, keep_nis, strict=True)]
    ).astype(np.int64)
    nan = float("nan")
    common_dof = int(np.bincount(ni_dof).argmax()) if ni_dof.size else 0
    return {
        "samples": int(err.shape[0]),
        "position_rmse_m": position_rmse(err, f.name),
        "yaw_rmse_rad": float(np.sqrt(np.mean(err[:, f.yaw] ** 2)))
        if err.size and f.yaw is not None
        else nan,
        "rmse": {
            s: float(np.sqrt(np.mean(err[:, i] ** 2))) if err.size else nan
            for i, s in enumerate(f.states)
        },
        "within_3sigma_percent": {
            s: float(100.0 * np.mean(np.abs(err[:, i]) <= 3.0 * sig[:, i])) if err.size else nan
            for i, s in enumerate(f.states)
        },
        "anees": anees(ne, n),
        "nees_bound": chi2_upper(n, 0.95),
        "nees_percent_beyond": nees_share.percent,
        "nees_beyond_interval": nees_share.to_dict(),
        "anis": _normalised_mean(ni, ni_dof),
        "nis_dof": common_dof,
        "nis_bound": chi2_upper(common_dof, 0.95) if common_dof else nan,
        "nis_percent_beyond": _percent_beyond_bound(ni, ni_dof),
    }


def _grid_cells(run: SeriesEvaluation, t0: float, rate_hz: float) -> IntArray:
    """The cell ``k`` of each record of ``run`` on the grid ``t0 + k / rate_hz``; ConfigError
    naming the run for a record off the grid (by more than :data:`TIME_TOL`) or two records in
    one cell, either of which means that ``rate_hz`` is not the record rate."""
    cell = (run.t - t0) * rate_hz
    nearest = np.rint(cell)
    off = ~(np.abs(cell - nearest) <= TIME_TOL * rate_hz)  # (a NaN time is off too)
    if off.any():
        raise ConfigError(
            f"{run.label}: record at t={run.t[off][0]} is off the {rate_hz} Hz grid from t={t0}"
        )
    idx = nearest.astype(np.int64)
    if np.unique(idx).size != idx.size:
        raise ConfigError(f"{run.label}: two records in one cell of the {rate_hz} Hz grid")
    return idx


def steady_nees_table(
    runs: Sequence[SeriesEvaluation], *, rate_hz: float, settle_s: float
) -> tuple[Array, Array]:
    """The NEES of independent runs at the record times where every run has a steady-state
    sample: ``(t, table (R, T))``. The records lie on a grid at ``rate_hz`` from the first
    record of any run, one per cell (:func:`_grid_cells`); ``rate_hz`` finite and > 0,
    ``settle_s`` finite and ≥ 0 (ConfigError otherwise)."""
    positive(rate_hz, "steady_nees_table: rate_hz")
    number(settle_s, "steady_nees_table: settle_s", low=0.0)
    t0 = min((float(r.t.min()) for r in runs if r.t.size), default=0.0)
    idx = [_grid_cells(r, t0, rate_hz) for r in runs]
    width = max((int(i.max()) + 1 for i in idx if i.size), default=0)
    table = np.full((len(runs), width), np.nan)
    for k, (r, i) in enumerate(zip(runs, idx, strict=True)):
        steady = r.age >= settle_s
        table[k, i[steady]] = r.nees[steady]
    full = np.all(np.isfinite(table), axis=0)
    t = t0 + np.arange(width) / rate_hz
    return t[full], table[:, full]


def run_averaged_nees(
    runs: Sequence[SeriesEvaluation], *, rate_hz: float, settle_s: float
) -> tuple[Array, Array, int]:
    """NEES averaged over independent runs at each record time where every run has a
    steady-state sample: ``(t, mean_nees, n_runs)`` (:func:`steady_nees_table`)."""
    t, table = steady_nees_table(runs, rate_hz=rate_hz, settle_s=settle_s)
    return t, table.mean(axis=0), len(runs)


def nees_band_check(
    runs: Sequence[SeriesEvaluation], *, rate_hz: float, settle_s: float, p: float = 0.95
) -> dict[str, Any]:
    """Share of record times at which the run-averaged NEES lies inside its two-sided ``p``
    band (about ``100 p`` % for a consistent filter), and the verdict of
    :func:`relloc.metrics.consistency.run_average_band`; needs ≥ 2 independent runs."""
    if len(runs) < 2:
        raise ConfigError("nees_band_check: needs at least two independent runs")
    _, table = steady_nees_table(runs, rate_hz=rate_hz, settle_s=settle_s)
    return run_average_band(table, frame(runs[0].frame).dim, p)


def convergence_time(evaluation: SeriesEvaluation, thresholds: Sequence[float]) -> float | None:
    """Seconds from the series' first record until every state's ``|error|`` stays below its
    threshold for good (``None`` if it never settles). Each threshold must be a finite number
    > 0 (ConfigError naming it): a NaN or one ≤ 0 is never reached, and would read as a run
    that never converged."""
    th = np.asarray(thresholds, dtype=float).reshape(-1)
    if th.size != evaluation.error.shape[1]:
        raise ConfigError(
            f"convergence_time: {th.size} thresholds for {evaluation.error.shape[1]} states"
        )
    for i, x in enumerate(th):
        positive(x, f"convergence_time: thresholds[{i}]")
    if evaluation.t.size == 0:
        return None
    above = ~np.all(np.abs(evaluation.error) < th, axis=1)
    if not above.any():
        return 0.0
    last = int(np.flatnonzero(above)[-1])
    if last == above.size - 1:
        return None
    return float(evaluation.t[last + 1] - evaluation.t[0])
