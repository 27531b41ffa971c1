"""report.md's consistency paragraph names the NIS bound the table's NIS>χ²₉₅ column used.

`relloc run BAG --map MAP` tracks UWB ranges (one number per reading, NIS bound χ²(1, 0.95) =
3.84), yet the paragraph said χ²(3, 0.95) = 7.81, the bound of a range/azimuth/elevation
reading. The paragraph follows the team's ``nis_dof``, the most common NIS dimension.
"""

from __future__ import annotations

from relloc.pipeline.team_report import report_markdown


def _summary(nis_dof: int, nis_bound: float) -> dict[str, object]:
    team = {
        "samples": 10,
        "position_rmse_m": 0.5,
        "yaw_rmse_rad": 0.1,
        "anees": 1.0,
        "nees_percent_beyond": 5.0,
        "anis": 1.0,
        "nis_percent_beyond": 5.0,
        "nees_bound": 9.487729036781154,
        "nis_dof": nis_dof,
        "nis_bound": nis_bound,
    }
    return {"settle_s": 5.0, "runs": 1, "pairs": {}, "team": team, "events_run0": []}


def test_a_range_only_report_states_the_one_dof_nis_bound() -> None:
    text = report_markdown(_summary(1, 3.841458820694124), [], title="bag")
    assert "χ²(1, 0.95) = 3.84" in text
    assert "χ²(3, 0.95) = 7.81" not in text


def test_a_range_bearing_report_keeps_the_three_dof_nis_bound() -> None:
    text = report_markdown(_summary(3, 7.814727903251179), [], title="scenario")
    assert "χ²(3, 0.95) = 7.81" in text
    assert "χ²(4, 0.95) = 9.49" in text


def test_a_report_without_nis_names_no_bound_of_its_own() -> None:
    text = report_markdown(_summary(0, float("nan")), [], title="bag")
    assert "(each NIS against χ² of its reading's dimension)" in text
