"""``relloc reproduce wanasinghe2014-pairs`` (:mod:`relloc.experiments.wanasinghe2014_pairs`)
from hand-built replay summaries: a pair's row takes each figure from the key the module
docstring names, the tally counts the yaw and NEES targets (not the position one), and
report.md states the tally, the median and range over the pairs, each cell's verdict mark
and RMSE ÷ bound."""

from __future__ import annotations

from typing import Any

from relloc.experiments.wanasinghe2014_pairs import (
    _median_range,
    build_report,
    default_pairs,
    pair_row,
    tally,
)

CASES = ("case1", "case2", "case3", "case4")


def _part(yaw: dict[str, float], nees: dict[str, float], position_ok: bool) -> dict[str, Any]:
    """The keys of :func:`replay_results` a pair's row reads; raw yaw = 2 × calibrated, raw
    NEES = calibrated + 30, the calibrated bound = yaw / 2, the truth-velocity bound 0.01·i."""
    verdicts = {"case1": "consistent", "case2": "over-confident", "case3": "conservative"}
    table3: dict[str, Any] = {"windows": {"calibration": {"start_s": 180.0, "end_s": 900.0}}}
    table3["windows"]["scored"] = {"start_s": 17.78, "end_s": 177.78}
    table4: dict[str, Any] = {}
    for kind, scale, shift in (("calibrated", 1.0, 0.0), ("raw", 2.0, 30.0)):
        table3[kind] = {
            c: {"phi": {"rmse_mean": scale * yaw[c], "rmse_per_draw": [scale * yaw[c]]}}
            for c in CASES
        }
        table4[kind] = {
            c: {
                "nees_percent_beyond": nees[c] + shift,
                "nees_beyond_interval": {"verdict": verdicts.get(c, "inconclusive")},
            }
            for c in CASES
        }
    targets = {
        c: {
            "yaw_ok": yaw[c] <= 0.10,
            "nees_ok": nees[c] <= 10.0,
            "position_ok": position_ok,
            "position_rmse_m": 0.05,
            "raw_position_rmse_m": 0.08,
            "yaw_bound_rad": yaw[c] / 2,
        }
        for c in CASES
    }
    walk = {w: {"calibrated": {"yaw_random_walk_rad": v}} for w, v in (("calibration", 0.4),)}
    walk["scored"] = {"calibrated": {"yaw_random_walk_rad": 0.3}}
    return {
        "table3": table3,
        "table4": table4,
        "replay_targets": targets,
        "replay_pcrlb": {
            "truth_velocity": {c: {"phi": 0.01 * (i + 1)} for i, c in enumerate(CASES)}
        },
        "turn_rate_residual": {"residual": {"relative": walk}},
        "replay": {"steady_state_range_m": {"mean": 3.46, "max": 5.0}},
    }


GOOD = dict.fromkeys(CASES, 0.08)
NEES_OK = dict.fromkeys(CASES, 4.0)


def _rows() -> list[dict[str, Any]]:
    """1 → 3 meets yaw and NEES in every case but not the position target; 2 → 4 meets them
    in case 1 only (case 2 misses the yaw, cases 3–4 the NEES)."""
    mixed_yaw = {**GOOD, "case2": 0.3}
    mixed_nees = {**NEES_OK, "case3": 12.0, "case4": 40.0}
    return [
        pair_row(1, 3, _part(GOOD, NEES_OK, position_ok=False)),
        pair_row(2, 4, _part(mixed_yaw, mixed_nees, position_ok=True)),
    ]


def test_a_pair_row_takes_each_figure_from_its_key() -> None:
    row = _rows()[1]
    assert (row["observer"], row["observed"], row["steady_state_range_m"]) == (2, 4, 3.46)
    assert row["relative_yaw_random_walk_rad"] == {"calibration": 0.4, "scored": 0.3}
    assert row["windows"]["scored"] == {"start_s": 17.78, "end_s": 177.78}
    c2 = row["cases"]["case2"]
    assert c2["calibrated"]["yaw_rmse_rad"] == 0.3 and c2["raw"]["yaw_rmse_rad"] == 0.6
    assert c2["calibrated"]["position_rmse_m"] == 0.05 and c2["raw"]["position_rmse_m"] == 0.08
    assert c2["raw"]["nees_percent_beyond"] == 34.0
    assert (c2["yaw_bound_rad"], c2["truth_velocity_yaw_bound_rad"]) == (0.15, 0.02)
    assert (c2["yaw_ok"], c2["nees_ok"], c2["position_ok"], c2["met"]) == (False, True, True, False)
    assert row["cases"]["case1"]["met"] is True
    assert _rows()[0]["cases"]["case1"]["met"] is False  # the position target missed


def test_the_tally_counts_the_yaw_and_nees_targets() -> None:
    assert tally(_rows()) == {
        "cells": 8,
        "cells_meeting_yaw_and_nees": 5,
        "pairs": 2,
        "pairs_meeting_every_case": 1,
        "per_case": {"case1": 2, "case2": 1, "case3": 1, "case4": 1},
    }


def test_default_pairs_of_four_robots() -> None:
    """Each robot observes the next two (cyclic): 4 robots give 8 ordered pairs, each once."""
    assert default_pairs([10, 20, 30, 40]) == (
        (10, 20),
        (10, 30),
        (20, 30),
        (20, 40),
        (30, 40),
        (30, 10),
        (40, 10),
        (40, 20),
    )


def _summary() -> dict[str, Any]:
    rows = _rows()
    return {
        "dataset": "/data/MRCLAM_Dataset6",
        "seed": 7,
        "runs": 5,
        "seeds": {"replay": 8, "replay_noise_inflation": 13},
        "loader": None,
        "paper": {c: {"yaw_rmse_rad": 0.03, "nees_percent_beyond": 1.0} for c in CASES},
        "pairs": rows,
        "skipped": [],
        "tally": tally(rows),
    }


def test_the_pairs_report_states_the_tally_medians_marks_and_ratios() -> None:
    report = build_report(_summary(), {}, elapsed_s=12.0)
    assert "Met in **5 of 8** pair-cases; **1 of 2** pairs meet them in every case." in report
    # case 2 over the two pairs: yaw 0.08 and 0.3 (median 0.19), NEES 4 and 4
    assert "| case2 | 0.190 (0.080–0.300) | 0.03 | 4.0 (4.0–4.0) | 1 | 1 of 2 |" in report
    # calibrated cells: ✓ where both targets hold, the verdict mark after the NEES share
    assert "| 2 → 4 | 3.5 m | 0.080 / 4.0 ✓ | 0.300 / 4.0↑ | 0.080 / 12.0↓ | 0.080 / 40.0? |" in (
        report
    )
    # raw cells: never ✓
    assert "| 1 → 3 | 3.5 m | 0.160 / 34.0 | 0.160 / 34.0↑ | 0.160 / 34.0↓ | 0.160 / 34.0? |" in (
        report
    )
    # the bound table: calibrated bounds, truth-velocity range, RMSE ÷ bound = 2
    assert (
        "| 2 → 4 | 0.040 / 0.150 / 0.040 / 0.040 | 0.010–0.040 | 2.00 / 2.00 / 2.00 / 2.00 |"
        in (report)
    )
    assert "| case4 | 0.080 (0.080–0.080) | 0.03 | 22.0 (4.0–40.0) | 1 | 1 of 2 |" in report
    assert "| 1 → 3 | 180.00–900.00 | 17.78–177.78 | 0.400 / 0.300 |" in report


def test_the_paper_table_cell_is_the_median_and_the_range() -> None:
    """0.1, 0.2 and 0.9: median 0.20 (the mean would be 0.40), range 0.10–0.90."""
    assert _median_range([0.9, 0.1, 0.2], 2) == "0.20 (0.10–0.90)"
