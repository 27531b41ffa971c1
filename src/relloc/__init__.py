"""relloc — relative and cooperative localization of heterogeneous multi-robot teams.

Importing relloc runs nothing and loads no optional dependency. Subpackages by role:

- inputs: :mod:`relloc.datasets` (recorded data), :mod:`relloc.sim` (simulated teams);
- models and math: :mod:`relloc.core`, :mod:`relloc.models`, :mod:`relloc.geometry`;
- estimation: :mod:`relloc.estimators` (filters), :mod:`relloc.association` (data association),
  :mod:`relloc.fusion` (beliefs shared between robots), :mod:`relloc.control` (team motion);
- analysis: :mod:`relloc.metrics`, :mod:`relloc.observability`, :mod:`relloc.plotting`;
- running: :mod:`relloc.experiments` (seed reproductions), :mod:`relloc.bench`,
  :mod:`relloc.runtime` (one process per robot), :mod:`relloc.cli` (the ``relloc`` command);
- :mod:`relloc.errors`: the exceptions relloc raises on purpose.
"""

__version__ = "0.1.0"
