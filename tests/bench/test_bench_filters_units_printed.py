"""`relloc bench filters` prints the unit of its throughput rows.

Rich read the label's "[pair-updates/s]" as a markup tag and dropped it, so the console showed
"batched PLKF, 1000 pairs   930,716" with no unit.
"""

from __future__ import annotations

import pytest

from relloc.bench.filters import _print_table


def test_throughput_rows_keep_their_unit(capsys: pytest.CaptureFixture[str]) -> None:
    result = {
        "per_update_us": {
            "plkf": 13.0,
            "tekf": 13.0,
            "filterpy_ekf": 245.0,
            "filterpy_ekf_algebra_only": 22.0,
        },
        "ratio_vs_filterpy": 18.8,
        "ratio_vs_filterpy_algebra_only": 1.7,
        "batched_pair_updates_per_s": 900000.0,
        "loop_pair_updates_per_s": 57000.0,
        "batched_speedup_vs_loop": 15.8,
        "setup": {"pairs": 1000},
        "machine": {"load_average_1min": 1.0},
    }
    _print_table(result)
    out = capsys.readouterr().out
    assert out.count("[pair-updates/s]") == 2
    assert "900,000" in out and "57,000" in out
