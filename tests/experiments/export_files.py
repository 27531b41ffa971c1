"""What ``--tum DIR`` / ``--mcap FILE`` wrote, read back against the ``export`` section of the
same run's summary.json (:mod:`relloc.pipeline.export`)."""

from __future__ import annotations

from collections import Counter
from pathlib import Path
from typing import Any

import numpy as np
import pytest

TUM_HEADER = "# timestamp tx ty tz qx qy qz qw"


def _tum_rows(path: Path) -> np.ndarray:
    lines = path.read_text().splitlines()
    assert lines[0] == TUM_HEADER, path
    rows = np.array([[float(v) for v in line.split()] for line in lines[1:]]).reshape(-1, 8)
    assert np.all(np.diff(rows[:, 0]) > 0), path  # one pose per stamp, in time order
    np.testing.assert_allclose(np.linalg.norm(rows[:, 4:], axis=1), 1.0, rtol=0, atol=1e-12)
    return rows


def check_tum(export: dict[str, Any], directory: Path) -> None:
    """Every series has its estimate file (one row per exported record) and its truth file (one
    row per record with truth) under ``directory``, and the position RMSE between the two (what
    ``evo_ape tum`` reports unaligned) is the series' ``position_rmse_m``."""
    tum = export["tum"]
    assert Path(tum["dir"]) == directory
    assert set(tum["pairs"]) == set(export["series"]) and export["series"]
    for label, pair in tum["pairs"].items():
        s = export["series"][label]
        estimate = Path(pair["estimate"])
        assert estimate.parent.parent == directory and estimate.suffix == ".tum", label
        est = _tum_rows(estimate)
        assert est.shape[0] == pair["poses"] == s["records"] > 0, label
        if s["records_with_truth"] == 0:
            assert pair["truth"] is None, label
            continue
        truth = _tum_rows(Path(pair["truth"]))
        assert truth.shape[0] == s["records_with_truth"], label
        known = np.isin(est[:, 0], truth[:, 0])
        assert known.sum() == truth.shape[0], label
        err = est[known, 1:4] - truth[:, 1:4]
        rmse = float(np.sqrt(np.mean(np.sum(err**2, axis=1))))
        assert rmse == pytest.approx(s["position_rmse_m"], rel=1e-9, abs=1e-12), label


def check_mcap(export: dict[str, Any], path: Path) -> None:
    """The file is the one the summary names, of its size, with the messages per topic it
    states, and one estimate message per exported record of every series."""
    from mcap.reader import make_reader

    m = export["mcap"]
    assert Path(m["path"]) == path and path.stat().st_size == m["bytes"]
    with open(path, "rb") as f:
        reader = make_reader(f)
        topics = Counter(channel.topic for _, channel, _ in reader.iter_messages())
    assert dict(topics) == m["topics"] and sum(topics.values()) == m["messages"]
    for label, s in export["series"].items():
        assert topics[s["topic"]] == s["records"] > 0, label
