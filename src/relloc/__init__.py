"""relloc — relative and cooperative localization of heterogeneous multi-robot teams.

Every estimator runs on one pipeline::

    Recording ──▶ replay(recording, estimators) ──▶ Estimates ──▶ evaluate(estimates, recording)

The public API, importable from ``relloc`` itself (loaded on first use: importing relloc runs
nothing and loads no optional dependency):

- inputs — :class:`Recording` (what a team sensed: per-robot :class:`Odometry`, one
  :class:`Measurements` table of readings of the kinds in :data:`KINDS`, optional
  :class:`GroundTruth`, landmarks, the loader's skip report), :func:`measurement_rows`;
  :func:`simulate` a scenario (:func:`load_scenario`, :func:`default_scenario`);
  :func:`load_mrclam` and :func:`mrclam_recording` for any folder in MRCLAM layout;
- estimators, all implementing the one contract :class:`Estimator` (``advance`` with
  :class:`HeldOdometry`, ``measure`` a batch, ``beliefs`` → :class:`Belief`, ``outbox`` /
  ``receive`` teammates' messages): :class:`TrackManager` (seed 000 relative tracking: PLKF,
  TEKF, bias-compensated PLKF, yaw bank, track keep/delete, set by
  :class:`TrackManagerSettings`; one per observing robot, :func:`managers_for`),
  :class:`CooperativeEstimator` (seed 001 team EIF / joint EKF), :class:`GaussianSumEstimator`
  (seed 002, one leader's multi-hypothesis fuser), :class:`SwitchingEkf` (seed 003, one
  follower's switching multi-rate EKF);
- the loop — :func:`replay` (any recording through any estimators) and :func:`run_events`
  (the same loop, window by window, as robot nodes run it);
- results — :class:`Estimates` (:class:`BeliefSeries` and :class:`UpdateSeries` per owner and
  subject), :func:`evaluate` → :class:`SeriesEvaluation` (errors with angles wrapped, NEES,
  NIS, conditioning), :func:`accuracy_and_consistency` (RMSE, ±3σ, ANEES, % beyond χ² bounds),
  :func:`nees_band_check` (run-averaged NEES against its 95 % band), :func:`convergence_time`.

Subpackages by role: :mod:`relloc.core` (the recording, the estimator contract, the event loop,
the estimates record, beliefs, pose algebra, the Kalman core), :mod:`relloc.models`,
:mod:`relloc.estimators`, :mod:`relloc.association`, :mod:`relloc.fusion`,
:mod:`relloc.control`, :mod:`relloc.geometry`; :mod:`relloc.sim` and :mod:`relloc.datasets`
(inputs), :mod:`relloc.calibration` (error models fitted on a stated window);
:mod:`relloc.pipeline` (replay, evaluation, Monte Carlo, outputs); :mod:`relloc.metrics`,
:mod:`relloc.observability`, :mod:`relloc.plotting`; :mod:`relloc.experiments` (seed
reproductions), :mod:`relloc.bench`, :mod:`relloc.runtime` (one process per robot over Zenoh),
:mod:`relloc.cli`; :mod:`relloc.errors`.
"""

from __future__ import annotations

import importlib
from typing import Any

__version__ = "0.1.0"

#: Public name → the module that defines it.
_API: dict[str, str] = {
    "GroundTruth": "relloc.core.recording",
    "KINDS": "relloc.core.recording",
    "Measurements": "relloc.core.recording",
    "Odometry": "relloc.core.recording",
    "Recording": "relloc.core.recording",
    "measurement_rows": "relloc.core.recording",
    "simulate": "relloc.sim.simulate",
    "load_scenario": "relloc.sim.scenario",
    "default_scenario": "relloc.sim.scenario",
    "load_mrclam": "relloc.datasets.mrclam",
    "Belief": "relloc.core.contract",
    "Estimator": "relloc.core.contract",
    "HeldOdometry": "relloc.core.contract",
    "TrackManager": "relloc.estimators.track_manager",
    "GaussianSumEstimator": "relloc.fusion.gaussian_sum_estimator",
    "SwitchingEkf": "relloc.estimators.switching_ekf",
    "TrackManagerSettings": "relloc.estimators.track_manager",
    "managers_for": "relloc.estimators.track_manager",
    "replay": "relloc.pipeline.replay",
    "run_events": "relloc.core.events",
    "BeliefSeries": "relloc.core.estimates",
    "Estimates": "relloc.core.estimates",
    "UpdateSeries": "relloc.core.estimates",
    "SeriesEvaluation": "relloc.pipeline.evaluation",
    "accuracy_and_consistency": "relloc.pipeline.evaluation",
    "convergence_time": "relloc.pipeline.evaluation",
    "evaluate": "relloc.pipeline.evaluation",
    "nees_band_check": "relloc.pipeline.evaluation",
}

__all__ = sorted(_API)


def __getattr__(name: str) -> Any:
    """Load a public name from its module on first use (PEP 562)."""
    module = _API.get(name)
    if module is None:
        raise AttributeError(f"module 'relloc' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *_API})
