"""The summary statistics of ``relloc reproduce wanasinghe2014``
(:mod:`relloc.experiments.wanasinghe2014`) on tiny hand-written error series, every expected
value worked out by hand: Table 3's mean/std over the steady state of the RMSE over draws and
each draw's RMSE, Table 1's updates to converge (censored at updates + 1) with the yaw bank's
speed-up and acceptance, the readings of the case-4 φ count, the replay targets at their
edges, and the seed of the noise-inflation fit."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from relloc.experiments.wanasinghe2014 import (
    Wanasinghe2014Config,
    _convergence_stats,
    _table3_entry,
    inflation_seed,
    replay_targets,
    table1_best_summary,
    table1_readings,
    table1_summary,
)
from relloc.experiments.wanasinghe2014_mrclam import ReplaySettings

NAN = float("nan")


def test_table3_is_the_mean_and_std_over_the_steady_state_of_the_rmse_over_draws() -> None:
    """Two draws, four updates, the first before the steady state (its 100 m / 7 rad error
    must not count). x: both draws 3, 0, 4 → RMSE curve 3, 0, 4: mean 7/3, std √26/3 (not its
    variance 26/9, not the median 3); y: 1 everywhere; z: a missing (NaN) update is skipped;
    φ: one draw at 1 rad, the other at 0 → curve √½ flat, per draw 1 and 0."""
    E = np.zeros((2, 4, 4))
    E[:, :, 0] = [100.0, 3.0, 0.0, 4.0]
    E[:, :, 1] = 1.0
    E[:, :, 2] = [0.0, 2.0, NAN, 2.0]
    E[0, :, 3] = [7.0, 1.0, 1.0, 1.0]
    E[1, :, 3] = [7.0, 0.0, 0.0, 0.0]
    ss = np.array([False, True, True, True])
    entry = _table3_entry(E, ss, "case3")
    assert entry["x"]["rmse_mean"] == pytest.approx(7 / 3)
    assert entry["x"]["rmse_std"] == pytest.approx(math.sqrt(26) / 3)
    assert entry["x"]["rmse_per_draw"] == pytest.approx([5 / math.sqrt(3)] * 2)
    assert (entry["y"]["rmse_mean"], entry["y"]["rmse_std"]) == (pytest.approx(1.0), 0.0)
    assert entry["z"]["rmse_mean"] == pytest.approx(2.0)
    assert entry["z"]["rmse_per_draw"] == pytest.approx([2.0, 2.0])
    assert entry["phi"]["rmse_mean"] == pytest.approx(math.sqrt(0.5))
    assert entry["phi"]["rmse_std"] == pytest.approx(0.0, abs=1e-12)
    assert entry["phi"]["rmse_per_draw"] == pytest.approx([1.0, 0.0])
    # seed 000 Table 3, case (3): φ 0.0443 (0.0820), x 0.0266 (0.0227)
    assert (entry["phi"]["paper_rmse"], entry["phi"]["paper_std"]) == (0.0443, 0.0820)
    assert (entry["x"]["paper_rmse"], entry["x"]["paper_std"]) == (0.0266, 0.0227)


def test_updates_to_converge_count_a_guess_that_never_settles_as_updates_plus_one() -> None:
    """Three guesses, five updates, threshold 1: x settles after update 2, after update 1 and
    never (→ 6): mean 3, median 2, worst 6, one not converged."""
    curves = np.full((3, 5, 4), 0.5)
    curves[0, 0, 0] = 2.0
    curves[2, :, 0] = 2.0
    stats, missed = _convergence_stats(curves, np.ones(4))
    assert stats["x"] == {"mean": 3.0, "median": 2.0, "worst": 6}
    assert missed == {"x": 1, "y": 0, "z": 0, "phi": 0}
    assert stats["phi"] == {"mean": 1.0, "median": 1.0, "worst": 1}


def _series(settle_after: int, n: int) -> np.ndarray:
    """Error 1 (above both thresholds) for ``settle_after − 1`` updates, then 0; never settles
    (error 1 throughout) when ``settle_after`` is 0."""
    e = np.ones(n)
    if settle_after:
        e[settle_after - 1 :] = 0.0
    return e


def _team(counts: dict[str, dict[str, list[int]]], n: int) -> list[dict[str, Any]]:
    """One draw whose case-c filter f settles, per guess, after ``counts[c][f]`` updates (every
    state alike); the known-pose filters at 0.1 (Eq. 32 threshold 0.105)."""
    table1: dict[str, dict[str, np.ndarray]] = {
        "case1": {f: np.full((1, n, 4), 0.1) for f in ("PLKF", "TEKF")}
    }
    for case, filters in counts.items():
        table1[case] = {
            f: np.stack([np.repeat(_series(k, n)[:, None], 4, axis=1) for k in ks])
            for f, ks in filters.items()
        }
    return [{"table1": table1}]


def _counts(plkf: list[int], bank: list[int]) -> dict[str, dict[str, list[int]]]:
    tekf = [0] * len(plkf)
    return {
        "case2": {"PLKF": plkf, "TEKF": tekf, "bank": bank},
        "case3": {"PLKF": plkf, "TEKF": tekf},
        "case4": {"PLKF": plkf, "TEKF": tekf, "bank": bank},
    }


def test_the_yaw_banks_speed_up_is_the_plkfs_mean_over_the_banks() -> None:
    """PLKF guesses settle after 9 and 15 updates (mean 12), the bank's after 12 and 4 (mean
    8): speed-up 1.5; the bank's worst is exactly 12, which meets "≤ 12"."""
    team = _team(_counts([9, 15], [12, 4]), n=20)
    table1, missed, thresholds, _ = table1_summary(team)
    assert thresholds["PLKF"]["paper_rule"]["phi"] == pytest.approx(0.105)
    assert table1["case4"]["TEKF"]["paper_rule"]["x"] == {"mean": 21.0, "median": 21.0, "worst": 21}
    assert missed["case4"]["TEKF"]["fixed"]["phi"] == 2
    best = table1_best_summary(team, table1, thresholds)
    assert best["case4"]["speedup_vs_plkf"]["fixed"]["phi"] == pytest.approx(1.5)
    assert best["case4"]["paper_rule"]["phi"]["mean"] == 8.0
    assert best["case3"]["speedup_vs_plkf"]["paper_rule"]["x"] == 1.0  # the bank is the PLKF
    accept = best["acceptance"]
    assert accept["case4_fixed_phi_worst"] == 12 and accept["case4_fixed_phi_worst_le_12"]
    assert accept["case4_paper_rule_ok"] and accept["case4_plkf_paper_rule_phi_mean"] == 12.0


def test_the_eq32_acceptance_is_twelve_updates_or_a_third_of_the_plkf() -> None:
    """Bank mean 14 (> 12): accepted against a PLKF mean of 42 (a third is 14), refused
    against 30 (a third is 10, although 14 is under half of it)."""
    for plkf, ok in ((42, True), (30, False)):
        team = _team(_counts([plkf, plkf], [14, 14]), n=50)
        table1, _, thresholds, _ = table1_summary(team)
        accept = table1_best_summary(team, table1, thresholds)["acceptance"]
        assert accept["case4_paper_rule_phi_mean"] == 14.0
        assert accept["case4_paper_rule_ok"] is ok, plkf
        assert accept["case4_fixed_phi_worst_le_12"] is False


def test_the_readings_of_the_case4_yaw_count() -> None:
    """One draw, three guesses, threshold 0.5. Guesses 0 and 2 sit at 0.2 (settle and first
    dip at 1, initial yaw error under π/2); guess 1 starts at 3 rad (not within π/2), dips at
    update 2, rises to 0.9 at update 3 and settles after update 4. Stays below: mean of 1, 4,
    1 = 2; first below: mean of 1, 2, 1 = 4/3; the RMSE pooled over the guesses is
    √((0.81 + 0.08)/3) ≈ 0.545 > 0.5 at update 3, so it settles after update 4; within π/2:
    the mean of 1 and 1."""
    phi = np.array([[0.2] * 5, [3.0, 0.1, 0.9, 0.1, 0.1], [0.2] * 5])
    E = np.zeros((3, 5, 4))  # one draw: (guesses, updates, states)
    E[..., 3] = phi
    team = [{"table1": {"case4": {"PLKF": E, "TEKF": E}}}]
    thresholds = {f: {"paper_rule": {"phi": 0.5}} for f in ("PLKF", "TEKF")}
    out = table1_readings(team, thresholds)
    expected = {
        "stays_below": 2.0,
        "first_below": 4 / 3,
        "pooled_guesses": 4.0,
        "yaw_within_half_pi": 1.0,
        "guesses_within_half_pi": 2,
        "guesses": 3,
    }
    for filt, paper in (("PLKF", 12), ("TEKF", 263)):  # seed 000 Table 1, case 4, φ
        assert out[filt] == {**expected, "first_below": pytest.approx(4 / 3), "paper": paper}


def _targets_summary(yaw: float, nees: float, bound: float) -> dict[str, Any]:
    def t3(x: float, y: float, z: float, phi: float) -> dict[str, Any]:
        return {
            s: {"rmse_mean": v} for s, v in zip(("x", "y", "z", "phi"), (x, y, z, phi), strict=True)
        }

    return {
        "table3": {
            "calibrated": {"case1": t3(0.1, 0.2, 0.3, yaw)},
            "raw": {"case1": t3(0.3, 0.1, 0.2, 0.5)},
        },
        "table4": {"calibrated": {"case1": {"nees_percent_beyond": nees}}},
        "replay_pcrlb": {"calibrated": {"case1": {"phi": bound}}},
    }


def test_replay_targets_hold_at_their_limits_and_fail_just_beyond() -> None:
    """Yaw 0.10 rad, NEES 10 %, bound 0.10 rad and a position (mean of x, y, z: 0.2 m) equal
    to the raw one all meet their targets; a hair beyond, none does."""
    at = replay_targets(_targets_summary(0.10, 10.0, 0.10))["case1"]
    assert at == {
        "yaw_rmse_rad": 0.10,
        "yaw_ok": True,
        "nees_percent_beyond": 10.0,
        "nees_ok": True,
        "position_rmse_m": pytest.approx(0.2),
        "raw_position_rmse_m": pytest.approx(0.2),
        "position_ok": True,
        "yaw_bound_rad": 0.10,
        "yaw_bound_ok": True,
    }
    beyond = _targets_summary(0.1001, 10.01, 0.1001)
    beyond["table3"]["calibrated"]["case1"]["z"]["rmse_mean"] = 0.31
    out = replay_targets(beyond)["case1"]
    assert not (out["yaw_ok"] or out["nees_ok"] or out["yaw_bound_ok"] or out["position_ok"])
    assert out["position_rmse_m"] == pytest.approx(0.61 / 3)


def test_the_noise_inflation_seed_follows_the_sweep_seeds() -> None:
    """Team S, replay S + 1, sweep S + 2 … S + 5 with the default four scales, inflation
    S + 6 (the pairs experiment documents S + 6); two scales move it to S + 4."""
    replay = ReplaySettings(dataset=Path("unused"))
    assert inflation_seed(100, Wanasinghe2014Config(replay=replay)) == 106
    two = Wanasinghe2014Config(replay=replay, sweep_scales=(1.0, 3.0))
    assert inflation_seed(100, two) == 104
