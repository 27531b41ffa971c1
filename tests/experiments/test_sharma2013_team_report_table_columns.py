"""`relloc team up sharma2013` writes report.md whose agent table has as many header cells as
separator cells: the header "max |Δ| vs in-process" held two bare pipes, which split it into
three cells (8 header cells over a 6-column separator), so the table rendered broken."""

from __future__ import annotations

from relloc.experiments.sharma2013_team import report_markdown


def _cells(line: str) -> int:
    """Cells of a markdown table row, an escaped pipe (\\|) not splitting one."""
    return line.replace("\\|", "").count("|") - 1


def test_agent_table_header_has_one_cell_per_column() -> None:
    agent = {
        "pos_rmse_m": 4.6,
        "heading_rmse_rad": 0.05,
        "max_abs_mean_diff": 1.25,
        "max_abs_cov_diff": 3.5,
        "readings_late": 0,
        "readings_refiltered": 0,
    }
    summary = {
        "experiment": "sharma2013",
        "case": "two_landmarks",
        "runs": 1,
        "seed": 0,
        "tolerance": 1e-9,
        "agreement": {
            "max_abs_diff": 3.5,
            "records_missing": 0,
            "perfect_network": False,
            "within_tolerance": False,
        },
        "per_run": [
            {
                "run": 0,
                "in_process": {"pos_rmse_m": 4.5, "heading_rmse_rad": 0.05},
                "agents": {"1": agent},
                "rejoined": [],
            }
        ],
    }
    lines = report_markdown(summary).splitlines()
    sep = next(i for i, line in enumerate(lines) if line.startswith("|---"))
    header, separator, row = lines[sep - 1], lines[sep], lines[sep + 2]
    assert _cells(header) == _cells(separator) == _cells(row) == 6
    assert "| agent 1 | 4.6 | 0.05 | 3.5 |" in row  # the larger of the mean and covariance Δ
