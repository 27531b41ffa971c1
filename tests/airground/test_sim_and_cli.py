"""Seeded closed-loop runs meet the paper's RMSE bound; the simulator's recording holds what the
filters consumed (replaying it through fresh filters gives the same estimates); mode switching
follows the drones' broadcasts; the drones fly their schedule; the reproduction runs end to end
through the CLI."""

import json
import pickle
from dataclasses import replace

import numpy as np
import pytest

from relloc.cli import main
from relloc.core.angles import wrap_angle
from relloc.core.recording import kind_code
from relloc.datasets.paths import default_uwb_csv
from relloc.errors import ConfigError
from relloc.experiments import guler2023
from relloc.experiments.guler2023 import (
    FilterFactory,
    build_cases,
    run_scenario_once,
    simulate_case,
)
from relloc.models.uwb_noise import TIERS_ROUNDED
from relloc.pipeline.frames import frame
from relloc.pipeline.replay import replay
from relloc.sim.airground import robot_names, simulate_airground


def test_seeded_two_drone_runs_meet_the_paper_bound():
    case = build_cases(TIERS_ROUNDED)["two_drones"].with_scenario(duration=30.0)
    for ss in np.random.SeedSequence(20260).spawn(2):
        res = run_scenario_once(ss, 1, case, False)
        assert res.rmse.shape == (4, 2)
        assert res.rmse.max() < 0.1  # paper: e_i^j < 0.1 m for all i, j (Section 4.1)


def test_recording_holds_the_team_its_commands_and_readings():
    case = build_cases(TIERS_ROUNDED)["two_drones"].with_scenario(duration=3.0)
    run, _ = simulate_case(case, np.random.default_rng(1))
    rec, sc = run.recording, case.scenario
    assert rec.robots == robot_names(sc) == ("R_0", "R_1", "R_2", "R_3", "R_4", "D_1", "D_2")
    assert rec.platforms == ("ground",) * 5 + ("aerial",) * 2
    m = rec.measurements
    ranges = m.of_kind("range")
    # every UWB epoch (every 2nd tick) ranges all 10 UGV pairs, observer < target
    assert ranges.size == 10 * (sc.n_steps // 2)
    assert np.all(ranges.observer < ranges.target) and np.all(ranges.target <= 4)
    sightings = m.of_kind("pair_sighting")
    assert sightings.size > 0 and set(sightings.observer) <= {5, 6}
    assert set(sightings.target) <= {1, 2, 3, 4}
    assert set(np.unique(m.kind)) == {kind_code("range"), kind_code("pair_sighting")}
    # the leader's odometry is its commanded arc (v, 0, 0, ω)
    np.testing.assert_array_equal(rec.odometry[0].velocity[0], [0.1, 0.0, 0.0, 0.04])
    assert run.formation_error.shape == (sc.n_steps, 4, 2)
    assert run.estimates.labels == tuple(f"R_{i}->R_0" for i in range(1, 5))
    # a run ships back from a Monte-Carlo worker
    shipped = pickle.loads(pickle.dumps(run))
    assert shipped.recording.meta == rec.meta and shipped.recording.robots == rec.robots


@pytest.mark.parametrize("yaw", [0.0, 0.3])
def test_frame_truth_is_the_relative_state_of_the_model(yaw):
    # airground_follower of (owner R_2, subject R_0) is x = [r, θ_2, θ_0] with r = p_0 − p_2,
    # all in the common frame F_G whose x axis is at ``common_frame_yaw``.
    case = build_cases(TIERS_ROUNDED)["formation"].with_scenario(duration=2.0)
    run, _ = simulate_case(case, np.random.default_rng(2))
    rec = replace(run.recording, meta={"common_frame_yaw": yaw})
    t = rec.truth[0].t
    x = frame("airground_follower").truth(rec, "R_2", "R_0", t)
    leader, follower = rec.truth[0].pose, rec.truth[2].pose
    c, s = np.cos(yaw), np.sin(yaw)
    r = leader[:, :2] - follower[:, :2]
    np.testing.assert_allclose(x[:, 0], c * r[:, 0] + s * r[:, 1], atol=1e-12)
    np.testing.assert_allclose(x[:, 1], -s * r[:, 0] + c * r[:, 1], atol=1e-12)
    np.testing.assert_allclose(wrap_angle(x[:, 2] - (follower[:, 3] - yaw)), 0.0, atol=1e-12)
    np.testing.assert_allclose(wrap_angle(x[:, 3] - (leader[:, 3] - yaw)), 0.0, atol=1e-12)


def _replayed(case, run):
    """The run's recording replayed through fresh filters started from the run's priors."""
    factory = FilterFactory(case)
    fresh = [factory(run.recording.robots, owner, prior) for owner, prior in run.priors.items()]
    t = run.estimates.beliefs[0].t
    return replay(run.recording, fresh, record_times=t)


@pytest.mark.parametrize("name", ["one_drone", "two_drones"])
def test_replaying_the_recording_gives_the_same_estimates(name):
    # one_drone: commands do not depend on the estimates (open loop); two_drones: the formation
    # controller closes the loop, and its commands are in the recording as odometry.
    case = build_cases(TIERS_ROUNDED)[name].with_scenario(duration=12.0)
    run, _ = simulate_case(case, np.random.default_rng(7))
    again = _replayed(case, run)
    assert again.labels == run.estimates.labels
    for a, b in zip(run.estimates.beliefs, again.beliefs, strict=True):
        np.testing.assert_array_equal(a.t, b.t)
        np.testing.assert_allclose(a.mean, b.mean, rtol=0, atol=1e-12)
        np.testing.assert_allclose(a.cov, b.cov, rtol=0, atol=1e-12)
        np.testing.assert_array_equal(a.info["sw"], b.info["sw"])
    for a, b in zip(run.estimates.updates, again.updates, strict=True):
        np.testing.assert_allclose(a.nis, b.nis, rtol=1e-10, atol=1e-12)
        np.testing.assert_array_equal(a.dof, b.dof)
    assert again.counts == run.estimates.counts


def test_simulated_modes_follow_the_broadcast_detections():
    case = build_cases(TIERS_ROUNDED)["one_drone"].with_scenario(duration=20.0)
    run, _ = simulate_case(case, np.random.default_rng(4))
    sightings = run.recording.measurements.of_kind("pair_sighting")
    sc = case.scenario
    frames = np.arange(1, sc.n_steps + 1, sc.camera_every) * sc.dt  # a camera frame every 2 ticks
    modes = []
    for owner in run.priors:
        series = run.estimates.series(owner, "R_0")
        i = run.recording.index(owner)
        expected = []
        for t in series.t:
            last = frames[frames <= t + 1e-9].max()
            seen = set(sightings.target[np.abs(sightings.t - last) < 1e-9])
            expected.append(1 if i in seen else 2 if seen else 3)
        np.testing.assert_array_equal(series.info["sw"], expected)
        modes.extend(expected)
    assert set(modes) >= {1, 2}


def test_the_drone_flies_its_schedule():
    # one drone, midpoints m_4, m_1, m_2 for 8 s each (offset 3): near the end of each window it
    # hovers closest to the scheduled midpoint (p_0 + p_i) / 2.
    case = build_cases(TIERS_ROUNDED)["one_drone"].with_scenario(duration=20.0)
    run, _ = simulate_case(case, np.random.default_rng(4))
    truth = run.recording.truth
    assert truth is not None
    nearest = []
    for t in (7.5, 15.5, 19.5):
        drone = truth[5].at(t)[0, :2]
        leader = truth[0].at(t)[0, :2]
        mids = [0.5 * (leader + truth[i].at(t)[0, :2]) for i in range(1, 5)]
        nearest.append(1 + int(np.argmin([np.hypot(*(drone - mid)) for mid in mids])))
    assert nearest == [4, 1, 2]


def test_the_controller_must_match_the_control_mode():
    case = build_cases(TIERS_ROUNDED)["two_drones"].with_scenario(duration=1.0)
    with pytest.raises(ConfigError, match="needs a follower controller"):
        simulate_airground(case.scenario, FilterFactory(case), None, np.random.default_rng(0))


def test_cli_reproduce_smoke(tmp_path, monkeypatch, guler2023_short_plan):
    # The real CLI path with a short plan (5 % durations, one run per block).
    monkeypatch.setattr(guler2023, "default_plan", lambda runs: guler2023_short_plan)
    out = tmp_path / "g"
    code = main(
        [
            "reproduce",
            "guler2023",
            "--out",
            str(out),
            "--executor",
            "serial",
            "--quiet",
            "--seed",
            "7",
        ]
    )
    assert code == 0
    s = json.loads((out / "summary.json").read_text())
    assert s["experiment"] == "guler2023" and s["seed"] == 7
    for key in ("one_drone", "two_drones", "formation"):
        assert set(s[key]["mode_fraction"]) == {"sw1", "sw2", "sw3"}
        assert abs(sum(s[key]["mode_fraction"].values()) - 1.0) < 1e-9
        for axes in s[key]["rmse_m"].values():
            assert set(axes) == {"x", "y"}
    assert set(s["formation"]["rmse_m"]) == {"R1", "R2"}
    assert "formation_rmse_m" in s["formation"]
    assert {"bias_m", "spread_m", "outlier_rate"} <= set(s["uwb_noise_fit"])
    assert s["sweep_dwell_time"]["points"] and s["sweep_drones"]["points"]
    assert [p["side_m"] for p in s["formation_size"]["points"]] == [0.7, 0.9]
    assert [p["scale"] for p in s["sweep_camera_noise"]["points"]] == [0.5, 1.0, 2.0, 4.0]
    assert "chosen" in s["camera_noise"]["source"] and len(s["departures"]) >= 5
    assert s["two_drones"]["nees_run_average"]["verdict"] is None  # one run: no valid band
    report = (out / "report.md").read_text()
    assert "paper [m]" in report and "estimates_two_drones.png" in report
    for png in ("traces_one_drone.png", "estimates_two_drones.png", "sweeps.png", "uwb_noise.png"):
        assert (out / png).is_file()


def test_a_uwb_file_of_rows_out_of_order_says_what_was_skipped(tmp_path):
    """A reversed CSV once ended in "empty window" alone (now "every time stamp is … s"), not
    saying that 8,706 rows were skipped as out of order."""
    from relloc.datasets.uwb import load_uwb_csv
    from relloc.errors import DataError
    from relloc.experiments.guler2023 import whole_recording

    lines = default_uwb_csv().read_text().splitlines()
    path = tmp_path / "reversed.csv"
    path.write_text("\n".join([lines[0], *lines[:0:-1]]) + "\n")
    with pytest.raises(
        DataError,
        match=r"every time stamp is \S+ s, so no calibration window; \d+ rows of the file were "
        r"skipped \(\d+ time",
    ):
        whole_recording(load_uwb_csv(path))
