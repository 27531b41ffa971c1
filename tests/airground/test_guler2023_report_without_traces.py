"""``relloc reproduce guler2023``'s figures and report.md for scenarios that kept no run-0
traces (``_figures`` and ``_report`` of :mod:`relloc.experiments.guler2023`): such a scenario
gets no traces or estimates figure and no figure line in the report, while the sweep and
UWB-noise figures are still drawn."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from test_guler2023_report_sentences_by_hand import UWB_NOISE_FIT

from relloc.calibration.uwb import fit_uwb_noise
from relloc.datasets.uwb import load_uwb_csv
from relloc.experiments import guler2023

CAPTION_TAIL = "(run 0); background = detected pair (red: none, dark: several)"


def _band() -> dict[str, Any]:
    return {
        "verdict": "consistent",
        "blocks_short": False,
        "in_band_percent": 95.0,
        "below_band_percent": 2.0,
        "above_band_percent": 3.0,
    }


def _block(**extra: Any) -> dict[str, Any]:
    axes = {"x": 0.04, "y": 0.05}
    return {
        "runs": 2,
        "rmse_m": {"R_1": axes},
        "rmse_m_max_over_runs": {"R_1": axes},
        "rmse_m_mean": 0.045,
        "rmse_m_worst": 0.05,
        "formation_rmse_m": {"R_1": axes},
        "formation_rmse_m_worst": 0.06,
        "mode_fraction": {"sw1": 0.5, "sw2": 0.3, "sw3": 0.2},
        "anees_position": 1.1,
        "nees_run_average": _band(),
        "mean_nis_per_dof": {"range": 1.0, "camera": 0.9},
        "triangle_refusals": 0,
        "gate_rejections": {"range": {"rejected": 3}},
        "meets_paper_bound": True,
        **extra,
    }


def _point(label: str, value: float) -> dict[str, Any]:
    return {label: value, **_block()}


def _summary() -> dict[str, Any]:
    return {
        "seed": 3,
        "runs": {"one_drone": 2, "two_drones": 2, "formation": 2, "sweep_point": 2},
        "uwb_noise_fit": UWB_NOISE_FIT,
        "one_drone": _block(),
        "two_drones": _block(),
        "formation": _block(),
        "ablation_uwb_link_bias": _block(),
        "ablation_no_gate": _block(),
        "ablation_white_range_model": _block(),
        "sweep_dwell_time": {"parameter": "dwell_s", "points": [_point("dwell_s", 4.0)]},
        "sweep_drones": {"parameter": "drones", "points": [_point("drones", 2)]},
        "formation_size": {
            "derived_side_m": 0.7,
            "points": [
                {"side_m": 0.7, "headline": True, "one_drone": _block(), "two_drones": _block()}
            ],
        },
        "camera_noise": {"bearing_sigma_rad": 0.015, "heading_sigma_rad": 0.025, "source": "s"},
        "sweep_camera_noise": {
            "parameter": "scale",
            "points": [
                {"scale": 1.0, "bearing_sigma_rad": 0.015, "heading_sigma_rad": 0.025, **_block()}
            ],
        },
        "departures": ["d"],
    }


def _figure_lines(md: str) -> list[str]:
    return [line for line in md.splitlines() if line.startswith("![") and CAPTION_TAIL in line]


def test_the_report_links_trace_figures_only_for_scenarios_that_have_them() -> None:
    files = {
        "uwb_noise": "uwb_noise.png",
        "sweeps": "sweeps.png",
        "traces_two_drones": "traces_two_drones.png",
        "estimates_two_drones": "estimates_two_drones.png",
    }
    md = guler2023._report(_summary(), files)
    assert _figure_lines(md) == [
        f"![two_drones: traces {CAPTION_TAIL}](traces_two_drones.png)",
        f"![two_drones: estimates {CAPTION_TAIL}](estimates_two_drones.png)",
    ]
    assert "one_drone: traces" not in md and "formation: estimates" not in md


def test_a_report_without_any_traces_has_no_trace_figure_but_keeps_the_others() -> None:
    md = guler2023._report(_summary(), {"uwb_noise": "uwb_noise.png", "sweeps": "sweeps.png"})
    assert _figure_lines(md) == []
    assert "](uwb_noise.png)" in md and "](sweeps.png)" in md
    assert md.rstrip().endswith("## Departures from the paper\n\n- d")


def test_scenarios_without_traces_get_no_figures_but_sweeps_and_uwb_noise_are_drawn(
    tmp_path: Path, shared_uwb_csv: Path
) -> None:
    rec = load_uwb_csv(shared_uwb_csv)
    fit = fit_uwb_noise(rec, guler2023.whole_recording(rec))
    traces: dict[str, Any] = {"one_drone": None, "two_drones": None, "formation": None}
    files = guler2023._figures(tmp_path, traces, _summary(), rec, fit)
    assert files == {"sweeps": "sweeps.png", "uwb_noise": "uwb_noise.png"}
    assert sorted(p.name for p in tmp_path.iterdir()) == ["sweeps.png", "uwb_noise.png"]
