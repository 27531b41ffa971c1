"""CLI smoke tests of ``relloc reproduce desilva2015`` / ``mrclam-association`` and the bench."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from relloc.cli import main
from relloc.experiments import desilva2015


@pytest.mark.slow
@pytest.mark.parametrize("sensing", [None, "P2,L2"])
def test_reproduce_desilva2015_smoke(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, sensing: str | None
) -> None:
    # shortened runs: the experiment's constants are module level on purpose
    monkeypatch.setattr(desilva2015, "DURATION_S", 3.0)
    monkeypatch.setattr(desilva2015, "STEADY_FROM_S", 1.0)
    monkeypatch.setattr(desilva2015, "FINAL_WINDOW_S", 1.0)
    monkeypatch.setattr(desilva2015, "KIDNAP", (3, 1.5, 3.0, -2.0, 2.0))
    out = tmp_path / "ds"
    code = main(
        [
            "reproduce",
            "desilva2015",
            "--out",
            str(out),
            "--runs",
            "1",
            "--seed",
            "7",
            "--executor",
            "serial",
            "--quiet",
            *(["--sensing", sensing] if sensing else []),
        ]
    )
    assert code == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["experiment"] == "desilva2015" and summary["seed"] == 7
    sensing_names = ["L1", "L2"] if sensing is None else ["L2", "P2"]
    assert summary["settings"]["sensing"] == sensing_names
    assert summary["settings"]["paper_sensing"] == ["L1", "L2"]
    observers = {pair.split("->")[0] for pair in summary["success_rate"]["per_pair"]}
    assert observers == set(sensing_names)
    for key in (
        "success_rate",
        "clutter_sweep",
        "pd_sweep",
        "wrong_association_rate",
        "no_sharing",
        "time_to_first_confirmed_s",
        "hypotheses",
        "kidnapped",
        "consistency",
        "covariance_intersection",
        "mutual_confirmed",
    ):
        assert key in summary
    assert set(summary["clutter_sweep"]) == {"1", "10", "100", "1000"}
    assert set(summary["pd_sweep"]) == {"0.95", "0.8", "0.6"}
    assert 0.0 <= summary["success_rate"]["overall"] <= 1.0
    assert summary["consistency"]["anees"] > 0.0
    # each sweep point is its own scenario: λ × k clutter, the given P_D
    lam = summary["settings"]["expected_clutter_per_scan"]
    for k, point in summary["clutter_sweep"].items():
        assert point["expected_clutter_per_scan"] == pytest.approx(int(k) * lam), k
    assert {k: p["p_detect"] for k, p in summary["pd_sweep"].items()} == {
        "0.95": 0.95,
        "0.8": 0.8,
        "0.6": 0.6,
    }
    # the paper's constants as stated in the module docstring
    settings = summary["settings"]
    assert (settings["p_birth"], settings["p_gate"]) == (0.5, 0.95)
    assert settings["rates_hz"] == {"filter": 20, "direct": 10, "mutual_indirect": 1}
    assert summary["success_rate"]["paper"] == 1.0
    assert summary["consistency"]["ideal"] == {"anees": 1.0, "nees_percent_beyond_chi2_95": 5.0}
    # what the RMSE is taken over: the scans with a dominant track, said as a share
    scored = summary["rmse_scored_percent"]
    assert set(scored["per_pair"]) == set(summary["success_rate"]["per_pair"])
    assert all(0.0 <= v <= 100.0 for v in [scored["overall"], *scored["per_pair"].values()])
    report = (out / "report.md").read_text()
    assert "with a dominant track to take them over (%)" in report
    team_note = "the paper's leaders" if sensing is None else "`--sensing`; an extension"
    assert f"Sensing robots: {', '.join(sensing_names)} ({team_note}" in report
    for fig in summary["figures"].values():
        assert (out / fig).is_file() and fig in report


def test_reproduce_rejects_bad_runs(tmp_path: Path) -> None:
    assert main(["reproduce", "desilva2015", "--out", str(tmp_path), "--runs", "0"]) == 2
