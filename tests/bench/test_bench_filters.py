"""``relloc bench filters`` on a tiny workload: the keys exist and the compared filters agree.

Speed itself is not asserted here (no timed unit tests); the benchmark checks inside ``run``
that relloc's TEKF equals filterpy's EKF on the same model and that batched equals looped.
"""

import math

import pytest

from relloc.bench.filters import BenchSize, run
from relloc.errors import ConfigError

pytest.importorskip("filterpy", reason="filterpy (extra 'bench') is needed for this benchmark")


def test_tiny_run_reports_every_key() -> None:
    result = run(quiet=True, size=BenchSize(steps=30, pairs=12, batch_steps=5, repeats=1))
    assert set(result["per_update_us"]) >= {"plkf", "tekf", "filterpy_ekf"}
    for key in ("ratio_vs_filterpy", "batched_pair_updates_per_s", "batched_speedup_vs_loop"):
        assert math.isfinite(result[key]) and result[key] > 0
    assert result["setup"]["max_difference_tekf_vs_filterpy"] < 1e-8
    assert result["setup"]["max_difference_batched_vs_loop"] < 1e-8


def test_bad_size_names_the_field() -> None:
    with pytest.raises(ConfigError, match="pairs"):
        BenchSize(pairs=0)
    with pytest.raises(ConfigError, match="batch_steps"):
        BenchSize(steps=5, batch_steps=5)
