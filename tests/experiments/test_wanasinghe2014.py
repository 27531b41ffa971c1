"""A small seeded run of the seed-000 reproduction on a truncated MRCLAM-layout copy.

The run is the real pipeline (simulation, Table 1 with the yaw bank, MRCLAM replay, sweep,
PCRLB, figures, report) with a reduced internal configuration: a 6 s team, 3 initial guesses,
2 draws, a 10 s replay window of a truncated copy of MRCLAM run 6 written into ``tmp_path``.
"""

from __future__ import annotations

import dataclasses
import json
import math
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
from export_files import check_mcap, check_tum
from wanasinghe_small import small_config

from relloc.calibration.odometry import ground_truth_velocities
from relloc.calibration.window import CalibrationWindow
from relloc.datasets.mrclam import load_mrclam
from relloc.errors import ConfigError, DataError
from relloc.experiments.registry import ReproduceArgs
from relloc.experiments.wanasinghe2014 import (
    Wanasinghe2014Config,
    run_reproduction,
    table1_best_summary,
    table1_summary,
)
from relloc.experiments.wanasinghe2014_mrclam import (
    TABLE2,
    ReplaySettings,
    _epochs,
    _inflated_by,
    prepare_replay,
    prepare_replays,
    replay_pcrlb,
    replay_recording,
    replay_task,
    spread_stretches,
)
from relloc.experiments.wanasinghe2014_paper import PAPER_TABLE1, RULES, STATES
from relloc.experiments.wanasinghe2014_report import _bias_nees_text
from relloc.experiments.wanasinghe2014_sim import SimSettings, team_task
from relloc.models.measurement import range_bearing
from relloc.pipeline.export import ExportRequest
from relloc.sim.scenario import default_scenario


@pytest.fixture(scope="module")
def small_dataset(tmp_path_factory: pytest.TempPathFactory, mrclam_run6_cut) -> Path:
    """Barcodes, landmarks and the first 45 s of robots 1-3 of run 6."""
    return mrclam_run6_cut(tmp_path_factory.mktemp("mrclam") / "MRCLAM_short")


@pytest.fixture(scope="module")
def medium_dataset(tmp_path_factory: pytest.TempPathFactory, mrclam_run6_cut) -> Path:
    """The first 200 s: a 60 s scored window and the rest to calibrate on."""
    return mrclam_run6_cut(tmp_path_factory.mktemp("mrclam") / "MRCLAM_200s", keep_s=200.0)


def test_small_reproduction_on_another_mrclam_folder(
    small_dataset: Path, tmp_path: Path, states_skipped_rows: Callable[..., bool]
) -> None:
    out = tmp_path / "out"
    export = ExportRequest(tum=tmp_path / "tum", mcap=tmp_path / "w.mcap")  # --tum, --mcap
    summary = run_reproduction(
        small_config(small_dataset), out, seed=11, executor="serial", quiet=True, export=export
    )
    on_disk = json.loads((out / "summary.json").read_text())
    # the exported run: the accuracy filters of team draw 0, every observed robot's series
    exported = on_disk["export"]
    assert exported["run"].startswith("team draw 0 of 2 (seed 11): ")
    assert set(exported["series"]) == {f"observer->{r}#accuracy" for r in summary["accuracy"]}
    assert {s["settle_s"] for s in exported["series"].values()} == {
        small_config(small_dataset).steady_state_s
    }
    check_tum(exported, tmp_path / "tum")
    check_mcap(exported, tmp_path / "w.mcap")
    assert on_disk["seed"] == 11 and on_disk["runs"] == 2
    for key in ("accuracy", "table1", "table1_best", "table3", "table4", "pcrlb_ratio"):
        assert key in on_disk
    # accuracy of the four observed robots
    assert set(summary["accuracy"]) == {"aerial1", "aerial2", "ground1", "ground2"}
    for acc in summary["accuracy"].values():
        assert 0 < acc["position_rmse_m"] < 0.5 and 0 < acc["yaw_rmse_rad"] < 0.5
        assert set(acc["inside_3sigma"]) == set(STATES)
        assert acc["paper"]["position_rmse_m"] == [0.05, 0.1]
    # table1[case][filter][rule][state] = {mean, median, worst}, paper values alongside
    for case in ("case2", "case3", "case4"):
        for filt in ("PLKF", "TEKF"):
            entry = summary["table1"][case][filt]
            assert entry["paper"] == PAPER_TABLE1[case][filt]
            for rule in RULES:
                for state in STATES:
                    cell = entry[rule][state]
                    assert set(cell) == {"mean", "median", "worst"}
                    assert 1 <= cell["mean"] <= cell["worst"]
    # the yaw bank's fixed-rule acceptance (issue 2): yaw inside 0.1 rad within 12 updates for
    # every guess (the Eq.-32 guard needs a longer team: test_yaw_bank_meets_the_eq32_rule)
    assert summary["table1_best"]["case4"]["fixed"]["phi"]["worst"] <= 12
    # Tables 3-4 on the truncated copy: calibrated and raw odometry, calibrated on the rest of
    # the recording after the scored window (disjoint windows, both stated)
    assert summary["replay"]["dataset"] == str(small_dataset)
    # the pair's horizontal range in the steady state, from the dataset's ground truth
    start, end = summary["replay"]["window_s"]
    t = np.arange(start + summary["replay"]["steady_state_after_s"], end, 0.01)
    obs, tgt = (load_mrclam(small_dataset).robot(r).groundtruth.at(t) for r in (1, 3))
    apart = np.hypot(tgt.x - obs.x, tgt.y - obs.y)
    spread = summary["replay"]["steady_state_range_m"]
    assert spread["mean"] == pytest.approx(float(np.mean(apart)), rel=1e-2)
    assert spread["max"] == pytest.approx(float(np.max(apart)), rel=1e-2)
    assert f"{spread['mean']:.2f} m apart on average" in (out / "report.md").read_text()
    # the rows the loader skipped are stated in report.md too, not only in summary.json
    skipped = summary["replay"]["loader"]["n_skipped"]
    assert states_skipped_rows((out / "report.md").read_text(), skipped)
    # the replay's own bound, beside Table 3 and the yaw target
    assert set(summary["replay_pcrlb"]) == {"calibrated", "raw", "truth_velocity"}
    for case, target in summary["replay_targets"].items():
        bound = summary["replay_pcrlb"]["calibrated"][case]["phi"]
        assert target["yaw_bound_rad"] == bound > 0.0
        assert target["yaw_bound_ok"] == (bound <= 0.10)
    assert "φ √PCRLB" in (out / "report.md").read_text()
    windows = summary["table3"]["windows"]
    assert windows == summary["table4"]["windows"]
    assert windows["calibration"]["start_s"] >= windows["scored"]["end_s"]
    fits = summary["odometry_noise"]["replay_fit"]["calibrated"]
    assert all(f["calibration_window"] == windows["calibration"] for f in fits.values())
    assert set(summary["odometry_kinds"]) == {"calibrated", "raw", "truth_velocity"}
    assert "diagnostic" in summary["odometry_kinds"]["truth_velocity"]
    truth_noise = summary["odometry_noise"]["replay_truth_velocity"]
    assert truth_noise["calibration_window"] == windows["calibration"]
    assert all(
        f["calibration_window"] == windows["calibration"]
        for f in summary["odometry_noise"]["replay_fit"]["truth_velocity"].values()
    )
    # each draw's steady-state yaw RMSE (one draw here): the pooled figure of the same draw
    for case, t3 in summary["table3"]["calibrated"].items():
        per_draw = t3["phi"]["rmse_per_draw"]
        pooled = summary["bias_comparison"][case]["PLKF"]["yaw_rmse_rad"]
        assert per_draw == [pytest.approx(pooled, rel=1e-9)]
    for kind in ("calibrated", "raw", "truth_velocity"):
        assert set(summary["table3"][kind]) == {"case1", "case2", "case3", "case4"}
        for case, t3 in summary["table3"][kind].items():
            for state in STATES:
                assert math.isfinite(t3[state]["rmse_mean"]) and t3[state]["paper_rmse"] > 0
            t4 = summary["table4"][kind][case]
            assert 0 <= t4["nees_percent_beyond"] <= 100
            # one draw still gets the share's interval: by batch means over time
            assert t4["nees_beyond_interval"]["percent"] == t4["nees_percent_beyond"]
            assert t4["nees_beyond_interval"]["clustering"] == "time blocks"
            # of 10 blocks, those the steady state reaches (a re-created track leaves gaps)
            assert 2 <= t4["nees_beyond_interval"]["clusters"] <= 10
            assert set(t4["max_conditioning"]) == {"P", "R", "S"}
            assert t4["run_averaged_nees"] is None  # one draw: no band across draws
        assert set(summary["table3_best"][kind]) == set(summary["table3"][kind])
        assert set(summary["table4"][kind]["case1"]["yaw_bank"]) >= {"nees_percent_beyond"}
    assert set(summary["bias_comparison"]["case2"]) == {"PLKF", "BC-PLKF", "TEKF", "yaw bank"}
    # the bias comparison's PLKF is Table 4's calibrated PLKF, on the same draws
    for case, filters in summary["bias_comparison"].items():
        plkf = filters["PLKF"]["nees_percent_beyond"]
        assert plkf == summary["table4"]["calibrated"][case]["nees_percent_beyond"]
        assert all(0 <= f["nees_percent_beyond"] <= 100 for f in filters.values())
    assert set(summary["replay_targets"]) == set(summary["table3"]["calibrated"])
    # the turn-rate residual of the calibrated commands, both robots and the relative yaw, on
    # the calibration and the scored window, calibrated response and best FIR
    residual = summary["turn_rate_residual"]
    assert residual["windows"] == windows
    assert set(residual["fir"]) == {"1", "3"}
    assert residual["yaw_random_walk_span_s"] == pytest.approx(10.0 - 3.0, abs=0.02)
    for who in ("1", "3", "relative"):
        for window in ("calibration", "scored"):
            for model in ("calibrated", "fir"):
                st = residual["residual"][who][window][model]
                assert st["std"] > 0 and st["blocks"] >= 2 and st["yaw_random_walk_rad"] > 0
    # the accuracy's NEES band is across the independent team draws at each instant
    for acc in summary["accuracy"].values():
        band = acc["run_averaged_nees"]
        assert band["runs"] == 2 and band["instants"] > 0
        assert 0 <= band["in_band_percent"] <= 100
    for ratios in summary["pcrlb_ratio"].values():
        assert all(math.isfinite(v) and v > 0 for v in ratios.values())
    # report and every figure it shows
    report = (out / "report.md").read_text()
    assert "Truth-velocity odometry (diagnostic" in report and "turn-rate residual" in report
    figures = [line.split("](")[1].rstrip(")") for line in report.splitlines() if "](" in line]
    assert len(figures) >= 8
    assert all((out / f).is_file() for f in figures)


def test_yaw_bank_meets_the_eq32_rule() -> None:
    """Table 1, case 4, by Eq. 32: the yaw bank's mean updates to converge in φ is ≤ 12 or ≤ ⅓
    of the plain PLKF's from the same guesses on the same draws.

    Size: a 20 s team (200 updates), 3 guesses, 2 draws. A shorter team censors the plain
    PLKF's count at the run length (a 6 s team failed the rule at 4 of 6 seeds) and the Eq.-32
    threshold from 2 draws is noisy; at 20 s the rule held at every development seed root
    (11, 1-7). The seed root 8101 below was not used while developing.
    """
    sim = SimSettings(scenario=dataclasses.replace(default_scenario(), duration_s=20.0), n_poses=3)
    team = [team_task(s, i, sim) for i, s in enumerate(np.random.SeedSequence(8101).spawn(2))]
    table1, _, thresholds, _ = table1_summary(team)
    best = table1_best_summary(team, table1, thresholds)
    plkf = table1["case4"]["PLKF"]["paper_rule"]["phi"]["mean"]
    bank = best["case4"]["paper_rule"]["phi"]["mean"]
    assert bank <= 12 or bank <= plkf / 3, f"yaw bank {bank:.1f} updates, plain PLKF {plkf:.1f}"


def test_config_from_cli_arguments(tmp_path: Path) -> None:
    args = ReproduceArgs(out_dir=tmp_path, runs=2, dataset=tmp_path / "elsewhere")
    cfg = Wanasinghe2014Config.from_args(args)
    assert (cfg.runs, cfg.replay_runs, cfg.sweep_runs) == (2, 2, 2)
    assert cfg.replay.dataset == tmp_path / "elsewhere"
    assert (cfg.replay.observer, cfg.replay.observed) == (1, 3)  # the default pair
    paired = Wanasinghe2014Config.from_args(ReproduceArgs(out_dir=tmp_path, pairs=((4, 2),)))
    assert (paired.replay.observer, paired.replay.observed) == (4, 2)
    assert paired.replay.dataset == Wanasinghe2014Config().replay.dataset
    with pytest.raises(ConfigError, match=r"replays one pair, got 2; .*wanasinghe2014-pairs"):
        Wanasinghe2014Config.from_args(ReproduceArgs(out_dir=tmp_path, pairs=((4, 2), (1, 3))))
    default = Wanasinghe2014Config.from_args(ReproduceArgs(out_dir=tmp_path))
    assert (default.runs, default.sim.n_poses) == (20, 13)  # the paper's counts
    with pytest.raises(ConfigError, match="steady_state_s"):
        Wanasinghe2014Config(steady_state_s=1000.0)


def test_replay_rejects_a_folder_too_short(small_dataset: Path) -> None:
    with pytest.raises(DataError, match="share only"):
        prepare_replay(ReplaySettings(dataset=small_dataset, min_duration_s=100.0))
    with pytest.raises(ConfigError, match=r"robot\(s\) \[5\] of the pair 1 → 5.*--pair"):
        prepare_replay(ReplaySettings(dataset=small_dataset, observed=5))


def test_another_pair_is_replayed(small_dataset: Path) -> None:
    """``--pair 2,1``: robot 2 observes robot 1; the truth is robot 1 in robot 2's frame."""
    data = prepare_replay(ReplaySettings(dataset=small_dataset, observer=2, observed=1))
    assert data.robots == ("2", "1") and data.source.endswith("robots 2 → 1")
    default = prepare_replay(ReplaySettings(dataset=small_dataset))
    assert default.robots == ("1", "3")
    ds = load_mrclam(small_dataset)
    t = data.t[len(data.t) // 2 : len(data.t) // 2 + 1]
    obs, tgt = (ds.robot(r).groundtruth.at(t) for r in (2, 1))
    c, s = math.cos(obs.theta[0]), math.sin(obs.theta[0])
    dx, dy = tgt.x[0] - obs.x[0], tgt.y[0] - obs.y[0]
    got = data.relative_truth(t)[0]
    assert got[:2] == pytest.approx([c * dx + s * dy, -s * dx + c * dy], abs=1e-9)
    assert got[2] == pytest.approx(2.0)  # the observed robot's plane raised


def test_a_replay_draw_is_four_sensors_of_the_observer(small_dataset: Path) -> None:
    """The experiment's transformation of the MRCLAM recording: the pair, the odometry held on
    the grid with the fitted noise, the observed plane raised, one sensor per Table-2 setting."""
    settings = ReplaySettings(
        dataset=small_dataset, duration_s=10.0, min_duration_s=8.0, start_after_odometry_s=1.0
    )
    data = prepare_replay(settings)
    rec = replay_recording(data, np.random.default_rng(0))
    assert rec.robots == ("1", "3")
    assert rec.truth is not None and np.all(rec.truth[1].pose[:, 2] == settings.height)
    for od, fit in zip(rec.odometry, (data.fits["observer"], data.fits["observed"]), strict=True):
        np.testing.assert_array_equal(od.t, data.t[:-1])
        np.testing.assert_array_equal(od.sigma, [fit.sigma_v, fit.sigma_lateral, 0.0, fit.sigma_w])
    m = rec.measurements
    assert np.all(m.observer == 0) and np.all(m.target == 1)
    for sensor, (case, (s_r, s_b, rate)) in enumerate(TABLE2.items()):
        rows = m.sensor == sensor
        assert rows.sum() + data.skipped_epochs[case] == round(settings.duration_s * rate)
        np.testing.assert_array_equal(m.sigma[rows], np.tile([s_r, s_b, s_b], (rows.sum(), 1)))
        # noise-free readings would be the raised truth's range, azimuth and elevation
        truth = rec.relative_truth(0, 1, m.t[rows])
        np.testing.assert_allclose(m.value[rows], range_bearing(truth), atol=6 * max(s_r, s_b))


def test_the_replay_bound_falls_with_information_and_rises_with_noise(small_dataset: Path) -> None:
    """:func:`replay_pcrlb`: more readings or smaller σ never raise the bound, more odometry
    noise never lowers it, and the position part is at most that of one reading alone."""
    settings = _short_replay(small_dataset)
    data = prepare_replay(settings)
    bound = replay_pcrlb(data, settings, steady_state_s=3.0)
    noisier = replay_pcrlb(_inflated_by(data, 2.0), settings, steady_state_s=3.0)
    for case in TABLE2:
        for state in STATES:
            assert 0.0 < bound[case][state] <= noisier[case][state], (case, state)
        assert noisier[case]["phi"] > bound[case]["phi"]
    for more, fewer in (("case1", "case3"), ("case2", "case4"), ("case1", "case2")):
        for state in STATES:
            assert bound[more][state] <= bound[fewer][state] * (1 + 1e-9), (more, fewer, state)
    # one reading (r, θ, α) alone bounds the position by σ_r² + (r cos α σ_θ)² + (r σ_α)²
    # (range, azimuth and elevation directions); the filter's information only adds to it
    for case, (s_r, s_b, rate) in TABLE2.items():
        steps = _epochs(data.t, rate)
        steps = steps[data.valid[steps] & (data.t[steps] >= data.t[0] + 3.0)]
        rel = data.relative_truth(data.t[steps])[:, :3]
        r = np.linalg.norm(rel, axis=1)
        cos_el = np.hypot(rel[:, 0], rel[:, 1]) / r
        one_reading = np.mean(s_r**2 + (r * cos_el * s_b) ** 2 + (r * s_b) ** 2)
        assert sum(bound[case][st] ** 2 for st in STATES[:3]) <= one_reading, case


def _short_replay(dataset: Path, **changes: object) -> ReplaySettings:
    return dataclasses.replace(
        ReplaySettings(
            dataset=dataset, duration_s=10.0, min_duration_s=8.0, start_after_odometry_s=1.0
        ),
        **changes,
    )


def test_noise_inflation_is_fitted_on_the_calibration_window_only(small_dataset: Path) -> None:
    """The factor on the calibrated σ comes from replays of stretches of the calibration window
    (after the scored window, never overlapping it); it is the first factor of the grid that
    meets the target, and the calibrated odometry carries exactly that factor. Seed root 8203
    was not used while developing."""
    settings = _short_replay(small_dataset)
    data = prepare_replays(settings, steady_state_s=3.0, seed=8203, executor="serial", quiet=True)
    cal = data["calibrated"]
    fit = cal.inflation
    assert fit is not None and cal.calibration is not None and data["raw"].inflation is None
    window, scored = cal.calibration.calibration_window, cal.scored_window
    assert fit.stretches[0].start_s >= scored.end_s
    for a, b in zip(fit.stretches, fit.stretches[1:], strict=False):
        assert a.end_s == b.start_s
    for w in fit.stretches:
        assert window.start_s <= w.start_s < w.end_s <= window.end_s
        assert settings.min_duration_s <= w.duration_s <= settings.duration_s + 1e-9
    tried = fit.yaw_percent_beyond
    assert 1 <= len(tried) <= len(settings.inflation_grid) and fit.samples > 0
    assert all(p > settings.inflation_target_percent for p in tried[:-1])
    assert fit.met == (tried[-1] <= settings.inflation_target_percent)
    assert fit.k == settings.inflation_grid[len(tried) - 1]
    for od, label in zip(cal.odometry, ("observer", "observed"), strict=True):
        f = cal.fits[label]
        np.testing.assert_allclose(
            od.sigma, fit.k * np.array([f.sigma_v, f.sigma_lateral, 0.0, f.sigma_w])
        )
    # every stretch of this short window is replayed (fewer than max_inflation_stretches)
    assert len(fit.stretches) == fit.stretches_in_window >= 2
    # a target every factor meets stops at the first one; capped at one stretch, the fit
    # replays the window's first
    lax = prepare_replays(
        _short_replay(small_dataset, inflation_target_percent=99.99, max_inflation_stretches=1),
        steady_state_s=3.0,
        seed=8203,
        executor="serial",
        quiet=True,
    )["calibrated"].inflation
    assert lax is not None and lax.k == 1.0 and lax.met and len(lax.yaw_percent_beyond) == 1
    assert lax.stretches == fit.stretches[:1] and lax.samples < fit.samples
    assert lax.stretches_in_window == fit.stretches_in_window
    assert lax.to_dict()["stretches_in_window"] == fit.stretches_in_window


def test_a_nees_miss_states_the_bias_compensated_plkf_beside() -> None:
    """Where the BC-PLKF runs (the noisy cases), a NEES miss is stated with its figure beside
    the PLKF's; a case without it adds nothing."""
    entry = {"radial_bias_m": 0.0, "position_rmse_m": 0.1, "yaw_rmse_rad": 0.3}
    bias = {
        "case2": {
            "PLKF": {**entry, "nees_percent_beyond": 45.0},
            "BC-PLKF": {**entry, "nees_percent_beyond": 7.5},
        },
        "case3": {"PLKF": {**entry, "nees_percent_beyond": 11.2}},
    }
    text = _bias_nees_text(bias, ["case2", "case3"])
    assert "case2 7.5 % (PLKF 45.0 %)" in text and "case3" not in text
    assert _bias_nees_text(bias, ["case3"]) == ""


def test_spread_stretches_keeps_the_first_the_last_and_evenly_between() -> None:
    """The inflation fit's cap on a long recording: of 26 stretches, 8 are replayed, numbered
    0, 4, 7, 11, 14, 18, 21, 25 (round(i·25/7)); a window with no more than the cap keeps all,
    a cap of one keeps the first."""
    windows = tuple(CalibrationWindow(10.0 * i, 10.0 * (i + 1), "w") for i in range(26))
    kept = spread_stretches(windows, 8)
    assert [round(w.start_s / 10.0) for w in kept] == [0, 4, 7, 11, 14, 18, 21, 25]
    assert spread_stretches(windows[:8], 8) == windows[:8]
    assert spread_stretches(windows, 1) == windows[:1]
    assert spread_stretches(windows[:2], 3) == windows[:2]


def test_noise_inflation_settings_are_checked(small_dataset: Path) -> None:
    for bad in (
        {"inflation_grid": (2.0, 1.0)},
        {"inflation_grid": (0.5,)},
        {"inflation_grid": ()},
        {"inflation_draws": 0},
        {"inflation_target_percent": 0.0},
        {"max_inflation_stretches": 0},
        {"max_inflation_stretches": 2.5},
        {"max_inflation_stretches": True},
    ):
        with pytest.raises(ConfigError, match="inflation"):
            _short_replay(small_dataset, **bad)


def test_truth_velocity_replay_is_the_odometry_floor(medium_dataset: Path) -> None:
    """The diagnostic replay driven by the ground truth's own velocities shares the scored
    window, grid and draws of the calibrated one, has the identity response and its noise
    fitted on the same calibration window; and with the precise sensor (cases 1 and 3) the yaw
    bank started from the same pose ends far below the calibrated replay's yaw error (by a
    factor of about 10 at the development seeds 0-2; the test asks for 2). Seed root 8311 was
    not used while developing."""
    settings = ReplaySettings(
        dataset=medium_dataset,
        duration_s=60.0,
        calibration_noise_windows_s=(1.0, 5.0, 20.0),
        inflation_grid=(1.0,),
    )
    settle = 20.0
    data = prepare_replays(
        settings, steady_state_s=settle, seed=8311, executor="serial", quiet=True
    )
    assert list(data) == ["calibrated", "raw", "truth_velocity"]
    truth, cal = data["truth_velocity"], data["calibrated"]
    assert cal.calibration is not None and truth.response is not None
    np.testing.assert_array_equal(truth.t, cal.t)
    assert truth.response.window == cal.calibration.calibration_window
    assert (truth.response.latency_s, truth.response.time_constant_s) == (0.0, 0.0)
    assert truth.response.scales == ((1.0, 1.0), (1.0, 1.0))
    assert all(f.calibration_window == truth.response.window for f in truth.fits.values())
    assert truth.calibration is None and truth.turn_rate is None and cal.turn_rate is not None
    # the observer's held turn rate is the ground truth's, not its commands'
    t = truth.t[:-1]
    _, w_true, ok = ground_truth_velocities(
        load_mrclam(medium_dataset).robot(settings.observer).groundtruth, t + 0.005
    )
    held = truth.odometry[0].held_at(t)[:, 3]
    assert np.median(np.abs(held - w_true)[ok]) < 0.01
    assert np.median(np.abs(cal.odometry[0].held_at(t)[:, 3] - w_true)[ok]) > 0.02

    def yaw_rmse(kind: str) -> float:
        tracks = replay_task(np.random.SeedSequence(8311), 0, data[kind], settings, ("yaw bank",))
        errors = []
        for case in ("case1", "case3"):
            ev = tracks[case]["yaw bank"].evaluation
            errors.append(ev.error[ev.age >= settle, 3])
        return float(np.sqrt(np.mean(np.concatenate(errors) ** 2)))

    floor, calibrated = yaw_rmse("truth_velocity"), yaw_rmse("calibrated")
    assert floor < 0.5 * calibrated, f"truth velocity {floor:.3f} rad, calibrated {calibrated:.3f}"
