"""A pair whose observer never reads its robot has no row in the tables: ``relloc run`` names
it (``pairs_never_read`` in summary.json, a note in report.md) instead of dropping it silently."""

from __future__ import annotations

import json

from relloc.cli import main

# alpha observes bravo (360°, 20 m); bravo observes alpha with a 1 m range, and over 8 s the
# two stay more than 3 m apart (alpha near (2, 2), bravo on its square from (6, 3))
SCENARIO = """
name = "short-sighted"
duration_s = 8.0
propagation_rate_hz = 50.0

[arena]
x = [0.0, 12.0]
y = [0.0, 12.0]
z = [-0.5, 4.0]

[[robots]]
name = "alpha"
kind = "ground"
height = 0.0
initial_pose = [2.0, 2.0, 0.7854]
[robots.motion]
type = "velocity"
mean = [0.1, 0.0, 0.0, 0.0]
amplitude = [0.05, 0.0, 0.0, 0.1]
period_s = [20.0, 10.0, 10.0, 12.0]
phase_rad = [0.0, 0.0, 0.0, 0.0]
[robots.sensor]
rate_hz = 5.0
max_range = 20.0

[[robots]]
name = "bravo"
kind = "ground"
height = 0.0
[robots.motion]
type = "waypoints"
points = [[6.0, 3.0], [9.0, 6.0], [6.0, 9.0], [3.0, 6.0]]
speed = 0.3
closed = true
[robots.sensor]
rate_hz = 5.0
max_range = 1.0
"""


def test_a_pair_never_read_is_named_in_the_summary_and_the_report(tmp_path):
    scenario = tmp_path / "short.toml"
    scenario.write_text(SCENARIO)
    out = tmp_path / "out"
    argv = ["run", str(scenario), "--out", str(out), "--runs", "1", "--executor", "serial"]
    assert main([*argv, "--no-plots", "--quiet"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert set(summary["pairs"]) == {"alpha->bravo"}
    assert summary["pairs_never_read"] == ["bravo->alpha"]
    assert "or range): bravo->alpha." in (out / "report.md").read_text()


def test_the_default_team_reads_every_pair(tmp_path):
    out = tmp_path / "out"
    argv = ["run", "--out", str(out), "--runs", "1", "--duration", "6", "--executor", "serial"]
    assert main([*argv, "--no-plots", "--quiet"]) == 0
    assert json.loads((out / "summary.json").read_text())["pairs_never_read"] == []
    assert "Never read" not in (out / "report.md").read_text()
