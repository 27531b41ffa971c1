"""Edge cases of the team report (:mod:`relloc.pipeline.team_report`) on hand-built scores:
a pair never in steady state, a single run, a track that never converges or converges late,
run 0 without true paths, the NEES figure of several runs, and report.md's optional lines."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from relloc.core.contract import TrackEvent
from relloc.pipeline import team_report
from relloc.pipeline.evaluation import SeriesEvaluation
from relloc.pipeline.team_report import (
    RunResult,
    not_used_note,
    pair_figure_stems,
    report_markdown,
    spread_rows,
    summarise,
    summary_rows,
)

T = np.arange(11) * 0.5  # 0 … 5 s at 2 Hz


def _evaluation(
    error: Any,
    *,
    t: np.ndarray = T,
    nees: float = 4.0,
    update_t: Any = None,
    owner: str = "a",
    subject: str = "b",
    track: str = "",
) -> SeriesEvaluation:
    """One scored series: ``error`` per record (rows of x, y, z, φ, or one row for every
    record), unit σ, a constant NEES, track age counted from the first record."""
    k = t.size
    err = np.broadcast_to(np.asarray(error, dtype=float), (k, 4)).copy()
    upd = t.copy() if update_t is None else np.asarray(update_t, dtype=float)
    m = upd.size
    return SeriesEvaluation(
        owner=owner,
        subject=subject,
        track=track,
        platform="ground",
        frame="relative_pose4",
        t=t,
        error=err,
        sigma=np.ones((k, 4)),
        nees=np.full(k, nees),
        age=t - t[0],
        cond_p=np.zeros(k),
        update_t=upd,
        update_age=upd - t[0],
        nis=np.full(m, 3.0),
        nis_dof=np.full(m, 3),
        cond_r=np.zeros(m),
        cond_s=np.zeros(m),
    )


def _one_run(*evaluations: SeriesEvaluation, events: tuple[TrackEvent, ...] = ()) -> RunResult:
    return RunResult(evaluations=evaluations, events=events)


def _row(rows: list[list[Any]], label: str) -> list[Any]:
    return next(r for r in rows if r[0] == label)


def test_a_pair_never_in_steady_state_has_no_rmse_spread_and_prints_dashes() -> None:
    """Every record younger than settle_s: no run has a steady-state RMSE, so the spread
    counts 0 runs with NaN figures, and the spread table shows dashes, not numbers."""
    s = summarise([_one_run(_evaluation([0.3, 0.4, 0.0, 0.0]))], settle_s=100.0, record_rate_hz=2.0)
    pair = s["pairs"]["a->b"]
    assert pair["samples"] == 0
    for key in ("position_rmse_over_runs", "yaw_rmse_over_runs"):
        spread = pair[key]
        assert spread["runs"] == 0
        assert math.isnan(spread["mean"]) and math.isnan(spread["std"])
        assert all(math.isnan(v) for v in spread["interval95"])
    _, rows = spread_rows(s)
    assert _row(rows, "a->b")[1:5] == ["— ± —", "—–—", "— ± —", "—–—"]
    assert _row(rows, "team (all pairs)")[1:5] == ["— ± —", "—–—", "— ± —", "—–—"]


def test_one_run_has_no_std_no_run_average_verdict_and_a_point_interval() -> None:
    """One run with a constant (0.3, 0.4) m position error and 0.2 rad yaw error: RMSE 0.5 m
    and 0.2 rad, no std (ddof 1 needs two runs), the 95 % interval of one value is that value,
    and no run-averaged NEES (it needs two runs) — the table says so with dashes."""
    s = summarise([_one_run(_evaluation([0.3, 0.4, 0.0, 0.2]))], settle_s=0.0, record_rate_hz=2.0)
    pair = s["pairs"]["a->b"]
    assert pair["position_rmse_m"] == pytest.approx(0.5)
    assert pair["yaw_rmse_rad"] == pytest.approx(0.2)
    spread = pair["position_rmse_over_runs"]
    assert spread["runs"] == 1
    assert spread["mean"] == pytest.approx(0.5)
    assert math.isnan(spread["std"])
    assert spread["interval95"] == pytest.approx([0.5, 0.5])
    for key in (
        "nees_run_average_in_band_percent",
        "nees_run_average_band",
        "nees_run_average_verdict",
        "nees_run_average_blocks_short",
    ):
        assert key not in pair
    headers, rows = summary_rows(s)
    row = dict(zip(headers, _row(rows, "a->b"), strict=True))
    assert row["avg NEES in band %"] is None
    assert row["its verdict"] == "—"
    _, rows = spread_rows(s)
    assert _row(rows, "a->b")[1:5] == ["0.5 ± —", "0.5–0.5", "0.2 ± —", "0.2–0.2"]


@pytest.mark.parametrize(
    ("nees", "in_band", "verdict"),
    [(4.0, 100.0, "consistent"), (20.0, 0.0, "over-confident"), (0.5, 0.0, "conservative")],
)
def test_two_runs_state_the_run_average_verdict(nees: float, in_band: float, verdict: str) -> None:
    """From two runs on (the other side of the above) the run-averaged NEES has a band and a
    verdict. The average of two χ²(4) draws is χ²(8)/2, so its 95 % band is
    [χ²₈(0.025)/2, χ²₈(0.975)/2] = [2.1797/2, 17.5345/2]; a constant NEES of 4 lies inside it at
    every record, 20 above it and 0.5 below. 11 records make the verdict's blocks short, and
    the summary says so (blocks_short)."""
    runs = [_one_run(_evaluation([0.1, 0.0, 0.0, 0.0], nees=nees)) for _ in range(2)]
    pair = summarise(runs, settle_s=0.0, record_rate_hz=2.0)["pairs"]["a->b"]
    assert pair["nees_run_average_band"] == pytest.approx([2.17973 / 2, 17.53455 / 2], rel=1e-5)
    assert pair["nees_run_average_in_band_percent"] == in_band
    assert pair["nees_run_average_verdict"] == verdict
    assert pair["nees_run_average_blocks_short"] is True


def test_a_track_that_never_settles_counts_no_converged_run() -> None:
    """A 0.5 m error to the end never enters the 0.1 bounds: 0 of 1 runs converged and the
    time and update columns are dashes in report.md."""
    s = summarise([_one_run(_evaluation([0.5, 0.0, 0.0, 0.0]))], settle_s=0.0, record_rate_hz=2.0)
    conv = s["pairs"]["a->b"]["convergence"]
    assert (conv["runs"], conv["runs_converged"]) == (1, 0)
    assert all(math.isnan(conv[k]) for k in ("median_time_s", "max_time_s", "median_updates"))
    _, rows = spread_rows(s)
    assert _row(rows, "a->b")[5:7] == ["0/1", "— (—)"]
    md = report_markdown(s, [], title="t")
    assert "| a->b | 0.5 ± — | 0.5–0.5 | 0 ± — | 0–0 | 0/1 | — (—) | — |" in md


def test_convergence_counts_time_and_updates_to_the_first_record_inside_for_good() -> None:
    """Run 1 is outside the bounds until t = 1.5 s and inside from t = 2 s; run 2 is inside
    from its first record. Times 2 s and 0 s (median 1 s, max 2 s); updates at 0.75 s and
    1.75 s and 3.75 s: run 1 counts the two up to 2 s, run 2 none up to 0 s (median 1)."""
    late = np.zeros((T.size, 4))
    late[T <= 1.5, 0] = 0.5
    updates = [0.75, 1.75, 3.75]
    runs = [
        _one_run(_evaluation(late, update_t=updates)),
        _one_run(_evaluation([0.0, 0.0, 0.0, 0.0], update_t=updates)),
    ]
    conv = summarise(runs, settle_s=0.0, record_rate_hz=2.0)["pairs"]["a->b"]["convergence"]
    assert conv["runs_converged"] == 2
    assert conv["median_time_s"] == pytest.approx(1.0)
    assert conv["max_time_s"] == pytest.approx(2.0)
    assert conv["median_updates"] == pytest.approx(1.0)


def test_run_zero_without_true_paths_draws_no_trajectory_figure(tmp_path: Path) -> None:
    from relloc.plotting.setup import pyplot

    run0 = _one_run(_evaluation([0.1, 0.0, 0.0, 0.0]))
    assert run0.paths is None
    plt = pyplot()
    assert team_report._trajectory_figure(plt, tmp_path, run0, arena=None, views=None) == []
    assert not (tmp_path / "trajectories.png").exists()


def test_the_nees_figure_of_two_runs_draws_their_average_against_its_band(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Run 1's NEES is 2 at every record, run 2's is 6: the top panel draws their 2-run
    average, 4, with the band of a 2-run average (n_runs = 2); one run alone draws its own
    values against the single-run bound (n_runs = 1)."""
    from relloc.plotting import consistency
    from relloc.plotting.setup import pyplot

    calls: list[tuple[np.ndarray, np.ndarray, int, int]] = []

    draw = consistency.plot_chi2_series

    def record(ax: Any, t: Any, values: Any, dof: int, **kw: Any) -> None:
        calls.append((np.asarray(t), np.asarray(values), dof, kw.get("n_runs", 1)))
        draw(ax, t, values, dof, **kw)  # and draws it

    monkeypatch.setattr(consistency, "plot_chi2_series", record)
    plt = pyplot()
    runs = [
        _one_run(_evaluation([0.1, 0.0, 0.0, 0.0], nees=2.0)),
        _one_run(_evaluation([0.1, 0.0, 0.0, 0.0], nees=6.0)),
    ]
    team_report._nees_nis_figure(plt, tmp_path, runs, settle_s=0.0, rate=2.0)
    t, values, dof, n = calls[0]  # the NEES panel; calls[1] is the NIS panel
    assert (dof, n) == (4, 2)
    assert values.size == T.size
    assert np.allclose(values, 4.0)

    calls.clear()
    team_report._nees_nis_figure(plt, tmp_path, runs[1:], settle_s=1.0, rate=2.0)
    t, values, dof, n = calls[0]
    assert (dof, n) == (4, 1)
    assert np.allclose(t, T[T >= 1.0])
    assert np.allclose(values, 6.0)


def test_report_lists_noise_settings_an_off_gate_and_says_when_there_are_no_events() -> None:
    s = summarise([_one_run(_evaluation([0.1, 0.0, 0.0, 0.0]))], settle_s=0.0, record_rate_hz=2.0)
    s = {
        "scenario": "hand",
        "gate_probability": None,
        "odometry_sigma": {"a": [0.05, 0.0, 0.02, 0.05], "b": [0.1, 0.0, 0.0, 0.1]},
        "sensor_sigma": {"a": [0.0068, 0.0036, 0.0036]},
        **s,
    }
    md = report_markdown(s, [], title="hand")
    lines = md.splitlines()
    assert "- **gate_probability**: off" in lines
    i = lines.index("- **odometry noise σ (v_x, v_y, v_z, ω_z)** per robot:")
    assert lines[i + 1 : i + 3] == ["  - a: [0.05, 0.0, 0.02, 0.05]", "  - b: [0.1, 0.0, 0.0, 0.1]"]
    assert "- **sensor σ (r, θ, α)**: {'a': [0.0068, 0.0036, 0.0036]}" in lines
    assert "No track events." in lines
    assert "## Notes" not in lines


def test_report_without_noise_settings_has_no_noise_lines() -> None:
    s = summarise([_one_run(_evaluation([0.1, 0.0, 0.0, 0.0]))], settle_s=0.0, record_rate_hz=2.0)
    md = report_markdown(s, [], title="hand")
    assert "odometry noise σ" not in md
    assert "sensor σ" not in md
    assert "gate_probability" not in md


def test_run_zero_events_are_tabled_in_the_report() -> None:
    events = (TrackEvent(t=0.5, owner="a", subject="b", kind="created"),)
    s = summarise(
        [_one_run(_evaluation([0.1, 0.0, 0.0, 0.0]), events=events)],
        settle_s=0.0,
        record_rate_hz=2.0,
    )
    md = report_markdown(s, [], title="hand")
    assert "| 0.5 | a | b | created |" in md
    assert "No track events." not in md


def test_readings_not_used_with_zero_counts_add_no_note() -> None:
    assert not_used_note({}) == []
    assert not_used_note({"gated": 0, "unknown_target": 0}) == []
    assert not_used_note({"gated": 0, "unknown_target": 3}) == [
        "Readings the trackers did not use, over all runs, by reason: 3 unknown_target."
    ]
    s = summarise([_one_run(_evaluation([0.1, 0.0, 0.0, 0.0]))], settle_s=0.0, record_rate_hz=2.0)
    md = report_markdown({**s, "rows_not_used": {"gated": 0}}, [], title="hand")
    assert "## Notes" not in md
    md = report_markdown(s, [], title="hand", notes=["a note"])
    assert "## Notes\n\n- a note" in md


def test_figure_stems_that_clash_after_sanitising_are_numbered() -> None:
    """``a b`` and ``a_b`` both become ``a_b``; the second and third get ``_2`` and ``_3``."""
    pairs = [
        _evaluation([0.0] * 4, owner="a b", subject="c"),
        _evaluation([0.0] * 4, owner="a_b", subject="c"),
        _evaluation([0.0] * 4, owner="a.b", subject="c"),
        _evaluation([0.0] * 4, owner="a", subject="c", track="t 1"),
    ]
    assert pair_figure_stems(pairs) == ["a_b_c", "a_b_c_2", "a_b_c_3", "a_c__t_1"]


def test_a_pair_tracked_in_one_of_two_runs_is_drawn_against_the_single_run_bound(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """a->b only in run 1 (NEES 2), a->c in both (NEES 6 and 6): the NEES panel draws b's own
    values as one run's (n_runs = 1) and c's average over both runs (n_runs = 2); the pair's
    summary has no run-averaged verdict (one run of it)."""
    from relloc.plotting import consistency
    from relloc.plotting.setup import pyplot

    drawn: dict[str, tuple[np.ndarray, int]] = {}

    draw = consistency.plot_chi2_series

    def record(ax: Any, t: Any, values: Any, dof: int, **kw: Any) -> None:
        if dof == 4:
            drawn[kw["label"]] = (np.asarray(values), kw.get("n_runs", 1))
        draw(ax, t, values, dof, **kw)  # and draws it

    monkeypatch.setattr(consistency, "plot_chi2_series", record)
    b = _evaluation([0.1, 0.0, 0.0, 0.0], nees=2.0)
    c = _evaluation([0.1, 0.0, 0.0, 0.0], nees=6.0, subject="c")
    runs = [_one_run(b, c), _one_run(c)]
    team_report._nees_nis_figure(pyplot(), tmp_path, runs, settle_s=0.0, rate=2.0)
    assert drawn["b"][1] == 1 and np.allclose(drawn["b"][0], 2.0)
    assert drawn["c"][1] == 2 and np.allclose(drawn["c"][0], 6.0)
    pairs = summarise(runs, settle_s=0.0, record_rate_hz=2.0)["pairs"]
    assert "nees_run_average_verdict" not in pairs["a->b"]
    assert "nees_run_average_verdict" in pairs["a->c"]
    assert pairs["a->b"]["convergence"]["runs"] == 1
    assert pairs["a->c"]["convergence"]["runs"] == 2
