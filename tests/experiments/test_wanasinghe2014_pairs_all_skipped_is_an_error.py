"""`relloc reproduce wanasinghe2014-pairs --pair 1,2` on a run too short for that pair's windows
replayed nothing, wrote a report of empty tables ("0 of 0") and exited 0 with no word on the
console. When every pair is skipped the experiment must fail with a DataError (exit 3) naming
each pair's reason; report.md still records it."""

from __future__ import annotations

from pathlib import Path

import pytest
from mrclam_synthetic import truth_ending_before
from wanasinghe_small import small_config

from relloc.errors import DataError
from relloc.experiments.wanasinghe2014_pairs import run_pairs


def test_every_pair_skipped_raises_data_error(mrclam_run6_cut, tmp_path: Path) -> None:
    short = mrclam_run6_cut(tmp_path / "MRCLAM_short")
    truth_ending_before(short, 3, 8.0)  # robot 3's ground truth: its first 8 s only
    out = tmp_path / "out"
    with pytest.raises(DataError, match=r"no pair of .* could be replayed; 1 → 3: .*share only"):
        run_pairs(small_config(short), [(1, 3)], out, seed=3, executor="serial", quiet=True)
    assert "## Skipped pairs" in (out / "report.md").read_text()
