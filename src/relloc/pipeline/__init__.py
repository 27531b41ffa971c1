"""The one pipeline: Recording → replay(recording, estimators) → Estimates → evaluate.

- :mod:`relloc.pipeline.contract` — the estimator contract every estimator implements;
- :mod:`relloc.pipeline.replay` — the one event loop;
- :mod:`relloc.pipeline.estimates` — the one estimates record;
- :mod:`relloc.pipeline.frames` — named state layouts and their truth;
- :mod:`relloc.pipeline.evaluation` — errors, RMSE, NEES/NIS and their χ² bands, convergence;
- :mod:`relloc.pipeline.montecarlo` — independent runs on any executor;
- :mod:`relloc.pipeline.output` — ``summary.json``, ``report.md`` and figures;
- :mod:`relloc.pipeline.team_report` — the relative-localisation team report (``relloc run``,
  ``relloc team up``).
"""

from relloc.pipeline.contract import Belief, Estimator, HeldOdometry, TrackEvent, UpdateRecord
from relloc.pipeline.estimates import BeliefSeries, Estimates, Recorder, UpdateSeries
from relloc.pipeline.evaluation import SeriesEvaluation, accuracy_and_consistency, evaluate
from relloc.pipeline.replay import replay, run_events

__all__ = [
    "Belief",
    "BeliefSeries",
    "Estimates",
    "Estimator",
    "HeldOdometry",
    "Recorder",
    "SeriesEvaluation",
    "TrackEvent",
    "UpdateRecord",
    "UpdateSeries",
    "accuracy_and_consistency",
    "evaluate",
    "replay",
    "run_events",
]
