"""``relloc reproduce mrclam-association --mcap/--tum``: every robot's dominant tracks of its
teammates, in its body frame, on a small synthetic MRCLAM-layout folder."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from test_mrclam_association import _synthetic_folder, short_windows

from relloc.cli import main

pytest.importorskip("mcap", reason="extra 'ros' is not installed")


@pytest.mark.slow
def test_mrclam_association_exports_every_robots_tracks(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    folder = _synthetic_folder(tmp_path / "data", np.random.default_rng(0))
    short_windows(monkeypatch)
    out = tmp_path / "out"
    code = main(
        ["reproduce", "mrclam-association", "--out", str(out), "--dataset", str(folder),
         "--runs", "1", "--quiet",
         "--mcap", str(tmp_path / "a.mcap"), "--tum", str(tmp_path / "tum")]
    )  # fmt: skip
    assert code == 0
    export = json.loads((out / "summary.json").read_text())["export"]
    pairs = {f"{a}->{b}" for a in "123" for b in "123" if a != b}
    assert set(export["series"]) == pairs
    for label, s in export["series"].items():
        owner = label.split("->")[0]
        assert s["frame_id"] == f"r{owner}/base_link"
        assert s["records_with_truth"] == s["records"] > 0
        assert np.isfinite(s["position_rmse_m"])  # from an unknown start: transient included
        assert export["mcap"]["topics"][s["topic"]] == s["records"]
        assert Path(export["tum"]["pairs"][label]["truth"]).is_file()
