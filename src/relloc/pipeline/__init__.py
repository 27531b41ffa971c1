"""The one pipeline: Recording → replay(recording, estimators) → Estimates → evaluate.

Built on the contract of :mod:`relloc.core.contract`, the loop of :mod:`relloc.core.events` and
the record of :mod:`relloc.core.estimates`:

- :mod:`relloc.pipeline.replay` — a whole recording through any estimators;
- :mod:`relloc.pipeline.frames` — named state layouts and their truth;
- :mod:`relloc.pipeline.evaluation` — errors, RMSE, NEES/NIS and their χ² bands, convergence;
- :mod:`relloc.pipeline.montecarlo` — independent runs on any executor;
- :mod:`relloc.pipeline.output` — ``summary.json``, ``report.md`` and figures;
- :mod:`relloc.pipeline.team_report` — the relative-localisation team report (``relloc run``,
  ``relloc team up``);
- :mod:`relloc.pipeline.export` — estimates as an MCAP file (Foxglove, ``ros2 bag play``) and
  TUM files (evo): ``--mcap`` / ``--tum``.
"""
