"""``relloc reproduce sharma2013``'s per-case statistics (``summarise``), its RPMG fractions
(``_rpmg_stats``, ``_edges_at``), the frame-NEES summary of three runs and the report's
sentences, on hand-made inputs whose every number is worked out below."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

from relloc.core.recording import Measurements, Odometry, Recording, measurement_rows
from relloc.experiments.sharma2013 import (
    CASES,
    _edges_at,
    _headline_text,
    _report,
    _rpmg_stats,
    departures,
    frame_nees_summary,
    headline_aware,
    summarise,
)

T = np.array([0.0, 0.5, 1.0, 1.5])


def _case_run(run: int) -> dict[str, Any]:
    """Two robots, four instants, identity covariance but 4·I at the last instant.

    Robot 1, both runs: error (0, 0, 0) at t0, (3, 0, 0) after: NEES 0, 9, 9, 9/4.
    Robot 2: run 0 no error; run 1 (0, 0, 0) at t0, (0, 3, 0) after: NEES 0, 9, 9, 9/4.
    """
    err = np.zeros((4, 2, 3))
    err[1:, 0, 0] = 3.0
    if run == 1:
        err[1:, 1, 1] = 3.0
    cov = np.broadcast_to(np.eye(3), (4, 2, 3, 3)).copy()
    cov[3] *= 4.0
    return {
        "errors": err,
        "cov": cov,
        "used": 10.0 * (run + 1),
        "rejected": float(run + 1),
        "frame_nees": None,
    }


def _results(block: str = "cases") -> list[dict[str, Any]]:
    return [{"t": T, block: {c: _case_run(r) for c in CASES}} for r in range(2)]


def test_case_statistics_of_two_runs_by_hand() -> None:
    c = summarise(_results(), 2)["no_landmark"]
    # mean squared planar error: robot 1 (0 + 9 + 9 + 9)/4 in both runs = 6.75;
    # robot 2 (0 + 27)/8 = 3.375; "mean" the RMS over the robots, √((6.75 + 3.375)/2) = 2.25
    assert c["pos_rmse_m"] == pytest.approx(
        {"1": math.sqrt(6.75), "2": math.sqrt(3.375), "mean": 2.25}
    )
    assert c["x_rmse_m"] == pytest.approx(
        {"1": math.sqrt(6.75), "2": 0.0, "mean": math.sqrt(3.375)}
    )
    assert c["y_rmse_m"] == pytest.approx(
        {"1": 0.0, "2": math.sqrt(3.375), "mean": math.sqrt(1.6875)}
    )
    assert c["heading_rmse_rad"] == {"1": 0.0, "2": 0.0, "mean": 0.0}
    # last instant: 9 (robot 1, twice), 0 and 9 (robot 2) → √(27/4)
    assert c["final_pos_err_m"] == pytest.approx(math.sqrt(6.75))
    # NEES 9 lies beyond χ²₃(0.95) = 7.81 (but not beyond χ²₃(0.99) = 11.34), 9/4 does not:
    # 4 samples of robot 1 and 2 of robot 2 beyond, of 16; run 0: 2 of 8, run 1: 4 of 8
    assert c["nees_pct_beyond"] == pytest.approx(37.5)
    assert c["nees_pct_beyond_per_run"] == pytest.approx([25.0, 50.0])
    # ANEES: (2·(9 + 9 + 2.25) + (9 + 9 + 2.25)) / 16 / 3
    assert c["anees"] == pytest.approx(60.75 / 16 / 3)
    # the run average: two runs at each of 4 instants × 2 robots
    band = c["nees_run_average"]
    assert band["runs"] == 2 and band["instants"] == 8
    # the error's RMS is 3·√3/2 at t1 and t3 (ratio 1), the 1σ bound √2 at t1, √8 at t3 (2)
    assert c["growth"] == pytest.approx({"error_ratio": 1.0, "sigma_ratio": 2.0})
    assert c["bounded"] is False
    assert (c["used"], c["rejected"]) == (15.0, 1.5)
    assert c["frame_nees"] is None


def test_frame_nees_summary_of_three_runs_with_one_dof() -> None:
    """Final values 5, 1, 0.5 of χ²(1): mean 6.5/3; one run beyond χ²₁(0.95) = 3.84; the band
    of a mean of three χ²₁ is that of χ²₃/3: [0.216/3, 9.348/3]. Along the run the mean (not
    the median) over the runs."""
    series = [(np.array([1.0, 5.0]), 1), (np.array([2.0, 1.0]), 1), (np.array([6.0, 0.5]), 1)]
    s = frame_nees_summary(series, np.array([30.0, 60.0]))
    assert s is not None
    assert s["mean"] == pytest.approx(6.5 / 3) and s["verdict"] == "consistent"
    assert s["band"] == pytest.approx([0.2158 / 3, 9.3484 / 3], abs=1e-4)
    assert s["pct_beyond"] == pytest.approx(100.0 / 3)
    assert s["along_the_run"]["mean_over_runs"] == pytest.approx([3.0, 6.5 / 3])


def _odometry() -> Odometry:
    return Odometry(t=np.array([0.0]), velocity=np.zeros((1, 4)), sigma=(0, 0, 0, 0))


def _team(rows: Measurements, n_landmarks: int) -> Recording:
    return Recording(
        robots=("1", "2", "3"),
        platforms=("ground",) * 3,
        odometry=(_odometry(),) * 3,
        measurements=rows,
        landmarks=np.zeros((n_landmarks, 3)),
    )


def _bearings(edges: list[tuple[float, int, int, int]]) -> Measurements:
    t, obs, tgt, lm = (np.array(v) for v in zip(*edges, strict=True))
    return measurement_rows("bearing", t=t, observer=obs, target=tgt, landmark=lm, value=0.0 * t)


def test_rpmg_fractions_over_the_detection_epochs() -> None:
    """Three robots, two landmarks. t = 1: 0→1, 1→2, 2→L0, 0→L1 (all one component);
    t = 2: 0→1, 1→L0 (robot 2 alone); t = 3: every robot sees L0 (robots joined through it, L1
    alone); t = 4: 1→0, 2→0, 0→L0, 0→L1 (all one component). Connected 3 of 4, β = 1 2 of 4."""
    rows = _bearings(
        [
            (1.0, 0, 1, -1),
            (1.0, 1, 2, -1),
            (1.0, 2, -1, 0),
            (1.0, 0, -1, 1),
            (2.0, 0, 1, -1),
            (2.0, 1, -1, 0),
            (3.0, 0, -1, 0),
            (3.0, 1, -1, 0),
            (3.0, 2, -1, 0),
            (4.0, 1, 0, -1),
            (4.0, 2, 0, -1),
            (4.0, 0, -1, 0),
            (4.0, 0, -1, 1),
        ]
    )
    rec = _team(rows, 2)
    assert _rpmg_stats(rec) == {"connected_fraction": 0.75, "beta_fraction": 0.5}
    assert _edges_at(rec, 4.0) == {"robots": [(1, 0), (2, 0)], "landmarks": [(0, 0), (0, 1)]}
    # one landmark: connected, but β(G) = 1 needs two landmarks
    one = _team(_bearings([(1.0, 0, 1, -1), (1.0, 1, 2, -1), (1.0, 2, -1, 0)]), 1)
    assert _rpmg_stats(one) == {"connected_fraction": 1.0, "beta_fraction": 0.0}
    # no detection at all: no epoch, both fractions 0 (no division by zero)
    none = _team(measurement_rows("range", t=[1.0], observer=0, target=1, value=[5.0]), 2)
    assert _rpmg_stats(none) == {"connected_fraction": 0.0, "beta_fraction": 0.0}


def _share(lo: float, hi: float) -> dict[str, Any]:
    return {"interval": [lo, hi], "verdict": "inconclusive"}


def test_headline_sentence_gives_each_runs_median_and_largest_share() -> None:
    """No filter meets the target (worst shares 12 and 11 %): the smaller one leads. Per-run
    shares 1, 2, 30 %: median 2, largest 30 (their mean would be 11)."""
    plain = {c: {"pos_rmse_m": {"mean": 1.0}} for c in ("no_landmark", "one_landmark")}

    def block(worst: float) -> dict[str, Any]:
        return {
            c: {
                "nees_pct_beyond": worst,
                "pos_rmse_m": {"mean": 0.9},
                "nees_beyond_interval": _share(2.0, 20.0),
                "nees_pct_beyond_per_run": [1.0, 2.0, 30.0],
                "frame_nees": {"mean": 3.1, "band": [2.19, 3.94], "verdict": "consistent"}
                if c == "no_landmark"
                else None,
            }
            for c in ("no_landmark", "one_landmark")
        }

    text = _headline_text(
        headline_aware(
            plain,
            {"cases_first_estimates": block(12.0), "cases_observability_constrained": block(11.0)},
        )
    )
    assert text.endswith(
        "; it does not meet it (no filter does). The target is judged on the shares themselves; "
        "their 95 % intervals (cluster means, each independent run one cluster) and verdicts: "
        "no landmark 2.0–20.0 inconclusive; one landmark 2.0–20.0 inconclusive. A run's own "
        "share (median, largest over the runs): no landmark 2.0 %, 30.0 %; one landmark "
        "2.0 %, 30.0 %. Along the unobservable directions (the runs' final frame NEES, below): "
        "no landmark mean 3.1 against 2.19–3.94, consistent."
    )


def test_report_states_the_band_the_rpmg_fractions_and_no_borderline_growth() -> None:
    cases = summarise(_results(), 2)
    for c in cases.values():
        c["observability_rank"] = {"rank": 3, "paper_rank": 3}
    aware = {
        b: summarise(_results(b), 2, b)
        for b in ("cases_first_estimates", "cases_observability_constrained")
    }
    scenario = {"duration_s": 2.0, "n_robots": 2, "speed_mps": 5.0, "sensing_range_m": 120.0}
    scenario |= {"ts_s": 0.1, "sigma_v": 0.2, "sigma_w": 0.2, "sigma_bearing": 0.1}
    summary = {
        "seed": 5,
        "runs": 2,
        "scenario": scenario,
        "rpmg": {"connected_fraction": 0.75, "beta_fraction": 0.5},
        "nees_on": "poses",
        "cases": cases,
        **aware,
        "observability_aware": headline_aware(cases, aware),
        "departures": departures(2.0, 2),
    }
    md = _report(summary, [])
    assert (
        "RPMG connected during 75.0 % of the measurement epochs; β(G) = 1 (every robot has a "
        "path to both landmarks) during 50.0 %." in md
    )
    # the 95 % band of a mean of two χ²₃ values: χ²₆(0.025, 0.975) / 2 = 1.237/2, 14.449/2
    assert "two-sided 95 % band of such a mean, [0.62, 7.22] for 2 runs" in md
    # growth ratios 1.0 and 2.0: neither within 0.05 of 1.2
    assert "Borderline" not in md
