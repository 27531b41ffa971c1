"""A pair whose observer never reads its robot has no row in the tables: ``relloc run`` names
it (``pairs_never_read`` in summary.json, a note in report.md) instead of dropping it silently."""

from __future__ import annotations

import json

from test_pair_figure_names import SCENARIO

from relloc.cli import main

# the two-observer team with bravo also observing alpha, through a sensor of 1 m range: over
# its 8 s bravo stays more than 3 m from alpha (near (2, 2); bravo on its square from (6, 3))
# and from the drone (3 m up)
_BRAVO = SCENARIO.index('name = "bravo"')
SHORT_SIGHTED = SCENARIO[:_BRAVO] + SCENARIO[_BRAVO:].replace(
    'observes = ["drone"]', 'observes = ["alpha", "drone"]', 1
).replace("max_range = 20.0", "max_range = 1.0", 1)


def test_a_pair_never_read_is_named_in_the_summary_and_the_report(tmp_path):
    assert SHORT_SIGHTED.count("max_range = 1.0") == 1 and '"alpha", "drone"' in SHORT_SIGHTED
    scenario = tmp_path / "short.toml"
    scenario.write_text(SHORT_SIGHTED)
    out = tmp_path / "out"
    argv = ["run", str(scenario), "--out", str(out), "--runs", "1", "--executor", "serial"]
    assert main([*argv, "--no-plots", "--quiet"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert set(summary["pairs"]) == {"alpha->bravo", "alpha->drone"}
    assert summary["pairs_never_read"] == ["bravo->alpha", "bravo->drone"]
    assert "or range): bravo->alpha, bravo->drone." in (out / "report.md").read_text()


def test_the_default_team_reads_every_pair(tmp_path):
    out = tmp_path / "out"
    argv = ["run", "--out", str(out), "--runs", "1", "--duration", "6", "--executor", "serial"]
    assert main([*argv, "--no-plots", "--quiet"]) == 0
    assert json.loads((out / "summary.json").read_text())["pairs_never_read"] == []
    assert "Never read" not in (out / "report.md").read_text()
