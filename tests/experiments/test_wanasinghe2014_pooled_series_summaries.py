"""The summary blocks of ``relloc reproduce wanasinghe2014`` that pool scored series
(:mod:`relloc.experiments.wanasinghe2014`), on hand-written evaluations: the accuracy's ±3σ
share as a fraction over every update and its run-averaged NEES band over every instant (none
with one draw), the odometry-noise sweep's σ and its steady state (a third of a short run),
and the replay's radial bias over the steady state and the NEES share's clustering (runs and
time blocks: the draws replay one recording), and the RMSE ÷ √PCRLB over the steady state
only."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest
from test_wanasinghe2014_replay_parts_by_hand import _replay_data as replay_parts_data

from relloc.calibration.odometry import OdometryModelFit
from relloc.calibration.window import CalibrationWindow
from relloc.experiments.wanasinghe2014 import (
    Wanasinghe2014Config,
    accuracy_summary,
    odometry_noise_summary,
    pcrlb_summary,
    replay_summary,
)
from relloc.experiments.wanasinghe2014_mrclam import (
    InflationFit,
    PairResponse,
    ReplayData,
    ReplaySettings,
    ReplayTrack,
)
from relloc.experiments.wanasinghe2014_sim import SimSettings, true_pair_inputs
from relloc.pipeline.evaluation import SeriesEvaluation
from relloc.sim.scenario import default_scenario

REPLAY = ReplaySettings(dataset=Path("unused"))


def _evaluation(t: np.ndarray, x: np.ndarray, phi: np.ndarray, nees: np.ndarray):
    """A relative-pose series scored at ``t`` (age = t), errors ``x`` and ``φ`` (y = z = 0),
    σ = 1 for every state."""
    k = t.size
    error = np.zeros((k, 4))
    error[:, 0], error[:, 3] = x, phi
    return SeriesEvaluation(
        owner="observer",
        subject="aerial1",
        track="accuracy",
        platform="aerial",
        frame="relative_pose4",
        t=t,
        error=error,
        sigma=np.ones((k, 4)),
        nees=nees,
        age=t,
        cond_p=np.ones(k),
        update_t=t,
        update_age=t,
        nis=np.ones(k),
        nis_dof=np.full(k, 3),
        cond_r=np.ones(k),
        cond_s=np.ones(k),
    )


T4 = np.array([0.0, 5.0, 10.0, 15.0])


def test_accuracy_share_inside_three_sigma_is_a_fraction_and_the_band_uses_every_instant() -> None:
    """x errors 0, 1, 4, 0 with σ = 1: three of four inside ±3σ → 0.75 (not 75). The NEES
    averaged over the two draws is judged at all 4 instants (settle 0, not the accuracy's
    10 s steady state); one draw has no such band."""
    config = Wanasinghe2014Config(replay=REPLAY)
    ev = _evaluation(T4, np.array([0.0, 1.0, 4.0, 0.0]), np.zeros(4), np.full(4, 4.0))
    draw = {"accuracy": dict.fromkeys(config.sim.targets, ev)}
    out, series = accuracy_summary([draw, draw], config)
    acc = out["aerial1"]
    assert acc["inside_3sigma"] == {"x": 0.75, "y": 1.0, "z": 1.0, "phi": 1.0}
    assert acc["updates"] == 4 and acc["paper"] == {
        "position_rmse_m": [0.05, 0.1],
        "yaw_rmse_rad": [0.075, 0.1],
    }
    assert acc["run_averaged_nees"]["runs"] == 2
    assert acc["run_averaged_nees"]["instants"] == 4
    assert series["aerial1"]["errors"].shape == (2, 4, 4)
    single, _ = accuracy_summary([draw], config)
    assert single["aerial1"]["run_averaged_nees"] is None


def _replay_data() -> ReplayData:
    """The replay-parts recording with a calibration and an inflation fit."""
    window = CalibrationWindow(200.0, 360.0, "hand")
    fit = InflationFit(
        k=1.5,
        met=True,
        target_percent=5.0,
        grid=(1.0, 1.5),
        yaw_percent_beyond=(9.0, 4.0),
        samples=10,
        stretches=(window,),
        stretches_in_window=1,
        draws=1,
        seed=3,
    )
    team = OdometryModelFit(
        calibration_window=window,
        latency_s=0.25,
        time_constant_s=0.5,
        scale_v=(1.1, 1.0),
        scale_w=(0.9, 1.2),
        q_v0=1e-4,
        k_v=1e-3,
        q_w0=1e-4,
        k_w=1e-3,
        k_wv=0.0,
        odometry_window_s=1.0,
    )
    return dataclasses.replace(
        replay_parts_data(),
        calibration=team,
        pair_scales=((1.1, 0.9), (1.0, 1.2)),
        inflation=fit,
        response=PairResponse(window),
    )


def test_the_sweep_rows_state_the_scaled_sigma_and_score_after_a_third_of_the_run() -> None:
    """Scales 1 and 4 of the observer's σ_v = σ_ω = 0.05; a 15 s sweep run scores from
    min(10 s, 15/3 = 5 s): yaw errors 9, 3, 0, 0 rad at 0, 5, 10, 15 s → √(9/3) = √3 rad."""
    config = Wanasinghe2014Config(replay=REPLAY, sweep_scales=(1.0, 4.0), sweep_duration_s=15.0)
    ev = _evaluation(T4, np.zeros(4), np.array([9.0, 3.0, 0.0, 0.0]), np.ones(4))
    draw = dict.fromkeys(config.sim.targets, ev)
    data = dict.fromkeys(("calibrated", "raw", "truth_velocity"), _replay_data())
    out = odometry_noise_summary(config, [[draw], [draw]], data)
    rows = out["sweep"]
    assert [(r["scale"], r["sigma_v"], r["sigma_w"]) for r in rows] == [
        (1.0, 0.05, 0.05),
        (4.0, 0.2, 0.2),
    ]
    assert rows[1]["yaw_rmse_rad"]["ground2"] == pytest.approx(math.sqrt(3.0))
    assert out["sweep_duration_s"] == 15.0
    assert out["team"]["observer"] == {"sigma_v": 0.05, "sigma_vz": 0.02, "sigma_w": 0.05}
    cal = out["replay_calibration"]
    assert (cal["latency_s"], cal["time_constant_s"]) == (0.25, 0.5)
    assert cal["scale_v"] == {"1": 1.1, "3": 1.0} and cal["scale_w"] == {"1": 0.9, "3": 1.2}
    assert cal["noise_inflation"]["k"] == 1.5


def test_the_sweep_scales_the_observers_sigma_wherever_it_is_listed() -> None:
    """The observer listed after aerial1, whose σ_v = σ_ω = 0.3: the sweep still scales the
    observer's 0.05 (×2 → 0.1), not the first robot's."""
    base = default_scenario()
    observer, aerial1, *rest = base.robots
    noisy = dataclasses.replace(
        aerial1, odometry=dataclasses.replace(aerial1.odometry, sigma_v=0.3, sigma_w=0.3)
    )
    scenario = dataclasses.replace(base, robots=(noisy, observer, *rest))
    config = Wanasinghe2014Config(
        replay=REPLAY, sweep_scales=(2.0,), sim=SimSettings(scenario=scenario)
    )
    ev = _evaluation(T4, np.zeros(4), np.zeros(4), np.ones(4))
    draw = dict.fromkeys(config.sim.targets, ev)
    data = dict.fromkeys(("calibrated", "raw", "truth_velocity"), _replay_data())
    (row,) = odometry_noise_summary(config, [[draw]], data)["sweep"]
    assert (row["sigma_v"], row["sigma_w"]) == (0.1, 0.1)


def test_the_replay_radial_bias_is_over_the_steady_state_and_the_share_clusters_two_ways() -> None:
    """Two draws of one recording, 40 updates 1 s apart, steady state from 30 s: radial errors
    1 m before it and 0.5 m (draw 0) / 0.3 m (draw 1) in it → bias 0.4 m, not pooled with the
    first 30 s. The NEES share's interval clusters by the runs and by time blocks."""
    t = np.arange(40.0)
    config = dataclasses.replace(Wanasinghe2014Config(replay=REPLAY), replay_steady_state_s=30.0)
    draws = []
    for late in (0.5, 0.3):
        ev = _evaluation(t, np.zeros(40), np.zeros(40), np.where(t % 7 == 0, 12.0, 3.0))
        radial = np.where(t >= 30.0, late, 1.0)
        track = ReplayTrack(evaluation=ev, radial=radial)
        draws.append(
            {c: {"PLKF": track, "yaw bank": track} for c in ("case1", "case2", "case3", "case4")}
        )
    _, _, table4, bias, series = replay_summary(draws, config, "raw")
    assert bias["case1"]["PLKF"]["radial_bias_m"] == pytest.approx(0.4)
    assert bias["case3"]["yaw bank"]["radial_bias_m"] == pytest.approx(0.4)
    share = table4["case1"]["nees_beyond_interval"]
    assert share["clustering"] == "runs and time blocks"
    # NEES 12 > χ²(4, 0.95) = 9.49 at t = 35 of the steady state 30 … 39: 1 of 10 per draw
    assert table4["case1"]["nees_percent_beyond"] == pytest.approx(10.0)
    assert series["case2"]["PLKF"]["radial"].shape == (2, 40)


def test_the_pcrlb_ratio_pools_the_steady_state_only() -> None:
    """A 12 s team: errors of 1000 before the 10 s steady state and none in it give a ratio of
    exactly 0 for every robot and state (the early errors must not count), and the bound is
    returned at each of the 120 updates."""
    sim = SimSettings(scenario=dataclasses.replace(default_scenario(), duration_s=12.0))
    config = Wanasinghe2014Config(replay=REPLAY, sim=sim, steady_state_s=10.0)
    t = np.round(np.arange(1, 121) * 0.1, 10)  # the 10 Hz updates 0.1 … 12 s
    errors = np.where((t < 10.0)[None, :, None], 1000.0, 0.0) * np.ones((2, 120, 4))
    acc = {robot: {"t": t, "errors": errors} for robot in sim.targets}
    ratios, bounds = pcrlb_summary(config, acc)
    assert ratios == {robot: dict.fromkeys(("x", "y", "z", "phi"), 0.0) for robot in sim.targets}
    assert bounds["aerial1"].shape == (120, 4) and np.all(bounds["aerial1"] > 0)


def test_the_pcrlb_inputs_are_the_commands_on_the_grid_with_the_last_repeated() -> None:
    """aerial2 starts at (7.5, 10, 1.5) with yaw 0.5; the observer at (5, 2.5) facing +y: in
    its frame (7.5, −2.5, 1.5) and φ = 0.5 − π/2. It flies sideways at 0.35 m/s and bobs
    0.2 m over 12 s (vertical rate 0.2·2π/12 at t = 0, falling after)."""
    sim = SimSettings(scenario=dataclasses.replace(default_scenario(), duration_s=2.0))
    t, truth, u_l, u_c = true_pair_inputs(sim, "aerial2")
    assert t.shape == (201,) and truth.shape == u_l.shape == u_c.shape == (201, 4)
    np.testing.assert_allclose(truth[0], [7.5, -2.5, 1.5, 0.5 - math.pi / 2], atol=1e-9)
    assert math.hypot(u_c[0, 0], u_c[0, 1]) == pytest.approx(0.35, abs=1e-6)
    assert u_c[0, 2] == pytest.approx(0.2 * 2 * math.pi / 12, abs=1e-6)
    assert u_c[1, 2] < u_c[0, 2]  # each row is its own step's command
    np.testing.assert_array_equal(u_c[-1], u_c[-2])  # the last row drives no step
    np.testing.assert_array_equal(u_l[-1], u_l[-2])
