"""Every top-level key of an experiment's summary.json is named in its module docstring (the
README: "keys are documented in the experiment module's docstring"), on the small runs other
tests already make: sharma2013 as in ``test_export_hooks`` (5 s runs, one run, symbolic ranks
off), mrclam-cl on the synthetic MRCLAM-layout folder of ``tests/cooperative`` and tiers-uwb on
the two stretches of the real bag that ``test_tiers_uwb`` cuts. The other experiments' smallest
runs take longer; their docstrings are checked by hand. ``relloc run``'s keys (top, pair, team)
are checked against :mod:`relloc.pipeline.team_report`'s docstring on an 8 s run."""

from __future__ import annotations

import importlib
import importlib.util
import json
import re
from pathlib import Path

import pytest

from relloc.cli import main
from relloc.experiments import registry

HERE = Path(__file__).parent


def named_in(doc: str | None) -> set[str]:
    """The identifiers inside the ``literal`` spans of docstring ``doc``."""
    spans = re.findall(r"``(.+?)``", doc or "", flags=re.S)
    return {word for span in spans for word in re.findall(r"[A-Za-z_][A-Za-z0-9_]*", span)}


def undocumented(name: str, out: Path) -> list[str]:
    summary = json.loads((out / "summary.json").read_text())
    named = named_in(importlib.import_module(registry.EXPERIMENTS[name]).__doc__)
    return [key for key in summary if key not in named]


def test_relloc_run(tmp_path: Path) -> None:
    """``relloc run``'s keys, at the top, per pair and for the team, are named in the team
    report's docstring (which the README points to)."""
    from relloc.pipeline import team_report

    out = tmp_path / "r"
    argv = ["run", "--out", str(out), "--runs", "2", "--duration", "8", "--executor", "serial",
            "--settle", "2", "--quiet", "--no-plots"]  # fmt: skip
    assert main(argv) == 0
    summary = json.loads((out / "summary.json").read_text())
    named = named_in(team_report.__doc__)
    keys = [*summary, *next(iter(summary["pairs"].values())), *summary["team"]]
    assert [key for key in keys if key not in named] == []


def test_sharma2013(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from relloc.experiments import sharma2013

    monkeypatch.setattr(sharma2013, "DURATION_S", 5.0)
    out = tmp_path / "s"
    argv = ["reproduce", "sharma2013", "--out", str(out), "--runs", "1", "--executor", "serial",
            "--quiet"]  # fmt: skip
    assert main(argv) == 0
    assert undocumented("sharma2013", out) == []


def test_mrclam_cl(tmp_path: Path) -> None:
    spec = importlib.util.spec_from_file_location(
        "cooperative_fixtures", HERE.parent / "cooperative" / "conftest.py"
    )
    assert spec is not None and spec.loader is not None
    fixtures = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(fixtures)
    folder = fixtures.write_mrclam_folder(tmp_path / "Synthetic", duration=12.0)
    out = tmp_path / "m"
    argv = ["reproduce", "mrclam-cl", "--out", str(out), "--dataset", str(folder), "--executor",
            "serial", "--quiet"]  # fmt: skip
    assert main(argv) == 0
    assert undocumented("mrclam-cl", out) == []


def test_tiers_uwb(tmp_path: Path) -> None:
    pytest.importorskip("rosbags", reason="extra 'ros' is not installed")
    from test_tiers_uwb import TIERS, cut

    if not TIERS.is_dir():
        pytest.skip(f"TIERS bags not found at {TIERS} (outside the workspace)")
    src = TIERS / "relative_case4_test1"
    calibration = cut(src, tmp_path / "first", 0.0, 8.0)
    scored = cut(src, tmp_path / "second", 20.0, 26.0)
    out = tmp_path / "t"
    argv = ["reproduce", "tiers-uwb", "--out", str(out), "--bag", str(scored), "--map",
            "tiers_relative", "--calibrate-on", str(calibration), "--quiet"]  # fmt: skip
    assert main(argv) == 0
    assert undocumented("tiers-uwb", out) == []
