"""The one place that loads matplotlib: lazily, with the non-interactive ``Agg`` backend.

Experiments call :func:`pyplot` when they draw, so importing any relloc module never imports
matplotlib, and a missing ``plot`` extra raises :class:`relloc.errors.DependencyError`.
"""

from __future__ import annotations

import functools
from typing import Any

from relloc.errors import require


@functools.cache
def pyplot() -> Any:
    """Return ``matplotlib.pyplot`` with the ``Agg`` backend selected (once per process).

    >>> plt = pyplot()
    >>> plt.get_backend().lower()
    'agg'
    """
    matplotlib = require("matplotlib", "plot")
    matplotlib.use("Agg")
    return require("matplotlib.pyplot", "plot")
