"""``relloc run``'s settings checks and report notes (:mod:`relloc.experiments.team_run`) on
hand-built scenarios and summaries: refused run counts and seeds, pairs never read and their
note, and the sensor views drawn on the trajectory figure."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import pytest

from relloc.errors import ConfigError
from relloc.experiments.team_run import (
    TeamRunSettings,
    never_read_note,
    pairs_never_read,
    sensor_views,
    write_run_report,
)
from relloc.pipeline.montecarlo import MAX_RUNS
from relloc.sim.scenario import Arena, RobotSpec, Scenario, SensorSpec, VelocityMotion


def _scenario(*, observes: tuple[str, ...] | None = None, description: str = "") -> Scenario:
    """a (360°, unlimited range) sees b and c; b (90°, 4 m) sees a; c has no sensor; the arena
    is 3 m × 4 m, so its diagonal is 5 m."""
    still = VelocityMotion()
    return Scenario(
        name="hand",
        description=description,
        arena=Arena(x=(0.0, 3.0), y=(0.0, 4.0)),
        robots=(
            RobotSpec(
                name="a",
                kind="ground",
                motion=still,
                initial_pose=(0.5, 0.5, 0.0),
                sensor=SensorSpec(max_range=math.inf),
                observes=observes,
            ),
            RobotSpec(
                name="b",
                kind="ground",
                motion=still,
                initial_pose=(2.5, 0.5, 0.0),
                sensor=SensorSpec(fov_deg=90.0, max_range=4.0),
            ),
            RobotSpec(name="c", kind="ground", motion=still, initial_pose=(1.5, 3.5, 0.0)),
        ),
    )


def _summary(*pairs: tuple[str, str]) -> dict[str, Any]:
    return {"pairs": {f"{o}->{s}": {"observer": o, "observed": s} for o, s in pairs}}


@pytest.mark.parametrize("runs", [0, MAX_RUNS + 1, True, 2.0, "3"])
def test_a_run_count_outside_one_to_the_maximum_or_not_an_integer_is_refused(runs: Any) -> None:
    with pytest.raises(ConfigError) as err:
        TeamRunSettings(runs=runs)
    assert str(err.value) == f"--runs: must be an integer in 1…{MAX_RUNS}, got {runs!r}"


@pytest.mark.parametrize("seed", [-1, False, 1.0, "7"])
def test_a_negative_or_non_integer_seed_is_refused(seed: Any) -> None:
    with pytest.raises(ConfigError) as err:
        TeamRunSettings(seed=seed)
    assert str(err.value) == f"--seed: must be an integer ≥ 0, got {seed!r}"


def test_the_extreme_run_counts_and_seed_zero_are_accepted() -> None:
    assert TeamRunSettings(runs=1, seed=0).runs == 1
    assert TeamRunSettings(runs=MAX_RUNS).runs == MAX_RUNS


def test_every_sensor_pair_no_run_tracked_is_named_in_scenario_order() -> None:
    sc = _scenario()
    assert pairs_never_read(sc, _summary(("a", "b"))) == ["a->c", "b->a", "b->c"]
    assert pairs_never_read(sc, _summary(("a", "b"), ("a", "c"), ("b", "a"), ("b", "c"))) == []


def test_a_robot_limited_to_its_observes_list_is_not_blamed_for_the_others() -> None:
    sc = _scenario(observes=("b",))
    assert pairs_never_read(sc, _summary(("a", "b"))) == ["b->a", "b->c"]


def test_the_never_read_note_names_the_pairs_and_is_absent_when_none() -> None:
    assert never_read_note([]) == []
    assert never_read_note(["a->c", "b->a"]) == [
        "Never read in any run, so not in the tables (the observed robot stayed outside the "
        "observer's field of view or range): a->c, b->a."
    ]


def test_sensor_views_draw_an_unlimited_range_to_the_arena_diagonal() -> None:
    assert sensor_views(_scenario()) == {"a": (360.0, 5.0), "b": (90.0, 4.0)}


def test_the_report_notes_the_description_and_the_pairs_never_read(tmp_path: Path) -> None:
    """Without plots: report.md's notes are the scenario's description, the never-read pairs
    and the no-figures line, in that order."""
    team = {
        k: 0.1
        for k in (
            "position_rmse_m",
            "yaw_rmse_rad",
            "anees",
            "nees_percent_beyond",
            "anis",
            "nis_percent_beyond",
        )
    }
    summary = {"runs": 1, "settle_s": 0.0, "record_rate_hz": 2.0, "pairs": {}, "team": team}
    summary["pairs_never_read"] = ["b->a"]
    sc = _scenario(description="Three robots, one blind.")
    written = write_run_report(sc, summary, [], tmp_path, plots=False)
    assert [p.name for p in written] == ["summary.json", "report.md"]
    md = (tmp_path / "report.md").read_text()
    assert md.startswith("# relloc run — hand\n")
    notes = md.split("## Notes\n\n", 1)[1].split("\n\n## Figures", 1)[0].splitlines()
    assert notes == [
        "- Three robots, one blind.",
        "- Never read in any run, so not in the tables (the observed robot stayed outside the "
        "observer's field of view or range): b->a.",
        "- Figures were not drawn (--no-plots, or matplotlib is not installed).",
    ]


def test_run_scenario_writes_its_summary_and_names_the_robot_out_of_range(tmp_path: Path) -> None:
    """One 2 s run of a (sensor reaching 2 m) beside b, 1 m ahead, and c, about 3.2 m away:
    a->c is never read, so it is in the summary's pairs_never_read and in report.md's notes;
    summary.json holds the returned summary."""
    import json

    from relloc.experiments.team_run import run_scenario

    still = VelocityMotion()
    sc = Scenario(
        name="tiny",
        duration_s=2.0,
        arena=Arena(x=(0.0, 3.0), y=(0.0, 4.0)),
        robots=(
            RobotSpec(
                name="a",
                kind="ground",
                motion=still,
                initial_pose=(0.5, 0.5, 0.0),
                sensor=SensorSpec(max_range=2.0),
            ),
            RobotSpec(name="b", kind="ground", motion=still, initial_pose=(1.5, 0.5, 0.0)),
            RobotSpec(name="c", kind="ground", motion=still, initial_pose=(1.5, 3.5, 0.0)),
        ),
    )
    settings = TeamRunSettings(runs=1, executor="serial", quiet=True, settle_s=0.5)
    summary, results = run_scenario(sc, settings, tmp_path / "out")
    assert list(summary["pairs"]) == ["a->b"]
    assert summary["pairs_never_read"] == ["a->c"]
    assert "export" not in summary
    assert len(results) == 1
    written = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert written["pairs_never_read"] == ["a->c"]
    assert written["scenario"] == "tiny" and written["runs"] == 1
    md = (tmp_path / "out" / "report.md").read_text()
    assert md.startswith("# relloc run — tiny\n")
    assert (
        "- Never read in any run, so not in the tables (the observed robot stayed outside the "
        "observer's field of view or range): a->c." in md
    )
