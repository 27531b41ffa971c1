"""The run limit of :func:`relloc.pipeline.montecarlo.spawn_seeds` is inclusive ("1…MAX_RUNS"):
checked with the limit lowered, since a million seed sequences take seconds to spawn."""

from __future__ import annotations

import pytest

from relloc.errors import ConfigError
from relloc.pipeline import montecarlo


def test_exactly_max_runs_is_accepted_one_more_is_refused(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(montecarlo, "MAX_RUNS", 3)
    seeds = montecarlo.spawn_seeds(7, 3)
    assert [s.spawn_key for s in seeds] == [(0,), (1,), (2,)]
    with pytest.raises(ConfigError, match=r"runs: must be in 1…3, got 4"):
        montecarlo.spawn_seeds(7, 4)
