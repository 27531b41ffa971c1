"""Any contract estimator in a robot node: the window driver's message rule, the ``mail``
codec, re-filtering late readings from a checkpoint, seed 002's leaders as processes (``relloc team
up desilva2015-kidnapped``, ``--sharing-policy``, ``--sensing``) and seed 001's agents as
processes (``relloc team up sharma2013``).

The driver tests run two seed-002 leaders' drivers in one process, window by window, handing
each other only what the node protocol hands over (stamped messages and progress): they must
reproduce the in-process replay exactly. The end-to-end test launches the whole team over
loopback Zenoh.
"""

from __future__ import annotations

import dataclasses
import json
import re

import numpy as np
import pytest

from relloc.cli import main
from relloc.core.recording import Measurements, empty_measurements
from relloc.errors import DataError
from relloc.experiments.desilva2015 import RunConfig, leader_estimates
from relloc.experiments.sharma2013_team import in_process
from relloc.experiments.team_sources import (
    desilva_recording,
    desilva_scenario,
    named_node_parts,
    sharma_node_parts,
    sharma_sim,
)
from relloc.fusion.messages import EquivalentMeasurement
from relloc.runtime.mail import mail_body, mail_items
from relloc.runtime.messages import decode, encode, est_bodies, estimates_from_bodies
from relloc.runtime.node import window_overdue
from relloc.runtime.summary import latest_of_each_time
from relloc.runtime.teammates import ReceivedOdometry

ROSTER = ("L1", "L2", "P1", "P2", "P3")


def _agent_lines(printed, prefix):
    """``{robot: (position RMSE, in-process RMSE, max |Δ| of a mean entry)}`` as ``team up``
    prints them for a team EIF's agents (lines starting ``{prefix}agent ROBOT:``)."""
    found = re.findall(
        rf"^{re.escape(prefix)}agent (\S+): position RMSE (\S+) m \(in-process (\S+) m\), "
        r"max \|Δ\| of a mean entry (\S+)$",
        printed,
        flags=re.M,
    )
    assert len({robot for robot, *_ in found}) == len(found), printed
    return {robot: tuple(figures) for robot, *figures in found}


def _leader_drivers(duration_s: float, policy: str = "all"):
    recording = desilva_recording("desilva2015", 4, 0, duration_s)
    parts = [
        named_node_parts("desilva2015", r, 4, 0, duration_s, sharing_policy=policy)
        for r in ("L1", "L2")
    ]
    streams = []
    for robot in recording.robots:
        s = ReceivedOdometry()
        od = recording.odometry[recording.index(robot)]
        s.add(od.t, od.velocity)
        streams.append(s)
    return recording, parts, streams


def _exchange(pairs):
    """Hand each driver's sent messages to the other, stamped (what ``mail`` carries)."""
    for d, other in pairs:
        for stamp, m in d.take_sent():
            other.deliver(stamp, d.robot, [m])


@pytest.mark.parametrize("policy", ["all", "mutual-confirmed"])
def test_two_leader_drivers_exchanging_mail_reproduce_the_in_process_replay(policy):
    recording, parts, streams = _leader_drivers(4.0, policy)
    drivers = [p.driver for p in parts]
    pairs = list(zip(drivers, drivers[::-1], strict=True))
    edges = np.round(np.arange(0, 41) * 0.1, 12)
    for k in range(40):
        last = k == 39
        for p in parts:
            rows = p.source.rows(edges[k], edges[k + 1], inclusive=last)
            p.driver.start_window(
                edges[k],
                edges[k + 1],
                streams=streams,
                rows=rows,
                present=set(ROSTER),
                inclusive=last,
            )
        stalls = 0
        # a driver learns a teammate's progress with the messages sent before it (one mail)
        shipped = [other.progress for _, other in pairs]
        while not all([d.run(until=p) for (d, _), p in zip(pairs, shipped, strict=True)]):
            shipped = [other.progress for _, other in pairs]
            _exchange(pairs)
            stalls += 1
            assert stalls < 100, "the drivers wait for each other forever"
        _exchange(pairs)
    reference = leader_estimates(
        recording, RunConfig(scenario=desilva_scenario("desilva2015", 4.0), sharing_policy=policy)
    )
    got = {s.key: s for d in drivers for s in d.take_new().beliefs}
    assert set(got) == {s.key for s in reference.beliefs}
    for ref in reference.beliefs:
        g = got[ref.key]
        np.testing.assert_array_equal(g.t, ref.t)
        np.testing.assert_allclose(g.mean, ref.mean, rtol=0, atol=1e-12)
        np.testing.assert_allclose(g.cov, ref.cov, rtol=0, atol=1e-12)
    fused = {k: v for d in drivers for k, v in d.counters().items() if "messages" in k}
    assert fused.get("messages_late", 0) == 0
    assert fused.get("messages_fused:mutual", 0) > 0
    # seed 002's policy fuses the other leader's beliefs of the pods (indirect messages); the
    # restricted one skips them (and sends only confirmed filters)
    indirect = fused.get("messages_fused:indirect", 0)
    skipped = fused.get("messages_fused:skipped", 0)
    if policy == "all":
        assert indirect > 0 and skipped == 0
    else:
        assert indirect == 0 and skipped > 0


def _eqm(subject: int, k: int, t: float) -> EquivalentMeasurement:
    rng = np.random.default_rng(subject * 10 + k)
    means = rng.normal(size=(k, 4))
    covs = np.stack([np.eye(4) * (1 + i) for i in range(k)])
    return EquivalentMeasurement(
        sender=0,
        subject=subject,
        time=t,
        means=means,
        covs=covs,
        prior_means=means + 0.1,
        prior_covs=covs * 2,
        weights=np.arange(1, k + 1, dtype=float),
    )


def test_mail_round_trip_and_split_keeps_the_progress_of_the_earliest_message():
    sent = [(1.0, _eqm(1, 3, 1.0)), (1.0, _eqm(2, 2, 1.0)), (2.0, _eqm(3, 4, 2.0))]
    whole = mail_body(2.5, sent, ROSTER, 65_536)
    assert len(whole) == 1 and whole[0]["progress"] == 2.5
    parts = mail_body(2.5, sent, ROSTER, 1024 + 5 * 400)  # at most 5 tracks a part
    assert [p["progress"] for p in parts] == [1.0, 2.5]
    got = []
    for body in parts:
        msg = decode(encode("mail", "L1", 0, 2.5, body), roster=ROSTER, key_sender="L1")
        got += [(stamp, m) for stamp, ms in mail_items(msg.body, ROSTER, "L1") for m in ms]
    assert [s for s, _ in got] == [1.0, 1.0, 2.0]
    for (_, a), (_, b) in zip(sent, got, strict=True):
        assert (a.sender, a.subject, a.time) == (b.sender, b.subject, b.time)
        for name in ("means", "covs", "prior_means", "prior_covs", "weights"):
            np.testing.assert_allclose(getattr(a, name), getattr(b, name), rtol=0, atol=1e-15)


def test_mail_of_its_sender_itself_is_rejected_and_only_equivalent_measurements_are_mailed():
    """A ``mail`` whose message is of its own sender decodes (the wire check knows no
    subjects' meaning) and is then refused as ``malformed``, naming why."""
    from relloc.runtime.messages import MessageRejected

    body = mail_body(1.0, [(1.0, _eqm(1, 2, 1.0))], ROSTER, 65_536)[0]
    msg = decode(encode("mail", "L2", 0, 1.0, body), roster=ROSTER, key_sender="L2")
    with pytest.raises(MessageRejected) as info:
        mail_items(msg.body, ROSTER, "L2")
    assert info.value.reason == "malformed"
    assert "mail:" in str(info.value) and "sender and subject must differ" in str(info.value)
    with pytest.raises(DataError, match="mail: cannot send a Measurements"):
        mail_body(1.0, [(1.0, empty_measurements())], ROSTER, 65_536)


def test_a_window_is_overdue_max_lag_ticks_after_its_end():
    assert window_overdue(0.3, 0.8, 0.1, 5) and window_overdue(0.3, 0.9, 0.1, 5)
    assert not window_overdue(0.3, 0.7, 0.1, 5)
    assert window_overdue(0.1 + 0.2, 0.1 * 8, 0.1, 5)  # on the grid, up to round-off


@pytest.mark.slow
def test_desilva_leaders_as_processes_match_in_process_and_refind_the_kidnapped_pod(tmp_path):
    out = tmp_path / "out"
    argv = ["team", "up", "desilva2015-kidnapped", "--out", str(out), "--duration", "10"]
    assert main([*argv, "--seed", "0", "--quiet"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    agree = summary["agreement"]
    run = summary["per_run"][0]
    # what would explain a disagreement on a perfect network, shown if it fails
    protocol = {
        "clock_ack_timeouts": run["clock_ack_timeouts"],
        **{
            robot: {
                "overdue_windows": m["overdue_windows"],
                "waiting_for_mail": m["overdue_windows_waiting_for_mail"],
                "acks_held": (m["acks_held"], m["acks_held_expired"]),
                "messages_late": m["tracks"].get("messages_late"),
                "departures_seen": m["teammate_departures_seen"],
                "held_until_appearance": m["held_until_appearance"],
                "rejected": m["rejected_by_reason"],
            }
            for robot, m in run["messages"].items()
        },
    }
    assert agree["perfect_network"] and agree["within_tolerance"], (agree, protocol)
    assert agree["max_abs_diff"] < 1e-9
    assert not run["clock_ack_timeouts"], protocol
    # on a perfect network neither leader waits so long for the other that a window is overdue
    for leader in ("L1", "L2"):
        assert run["messages"][leader]["overdue_windows"] == 0, protocol
        assert run["messages"][leader]["overdue_windows_waiting_for_mail"] == 0, protocol
    for figure, diff in summary["difference"].items():
        assert diff is None or abs(diff) <= summary["tolerance"]["figure"], figure
    kidnapped = summary["kidnapped"]
    assert kidnapped["distributed"] == kidnapped["in_process"]
    # P2 (moved by 3 m, −2 m, 2 rad at 5 s) is re-found by both leaders, across processes
    assert kidnapped["distributed"]["time_to_refind_s"] is not None
    assert kidnapped["distributed"]["tracked_last_second"] == 1.0
    assert set(run["exit_codes"]) == {"clock", *ROSTER}
    assert all(codes == [0] for codes in run["exit_codes"].values())
    for robot, m in run["messages"].items():
        assert m["rejected"] == 0 and m["final_report"]
        assert (m["sent"]["mail"] > 0) == (robot in ("L1", "L2"))
    for me, mate in (("L1", "L2"), ("L2", "L1")):
        # every mail the teammate sent, but perhaps its last (sent as this leader finished)
        got, sent = (
            run["messages"][me]["received_delivered"]["mail"],
            run["messages"][mate]["sent"]["mail"],
        )
        assert sent - 1 <= got <= sent
    assert (out / "report.md").read_text().startswith("# relloc team up — desilva2015-kidnapped")


def test_a_stalled_link_holds_the_team_and_the_leaders_still_match_in_process(tmp_path):
    """``--stall P1,L2@3:0.5``: from 3 s on, L2 hears nothing from P1 for half a second of wall
    time, then everything in order. L2's windows wait for P1's odometry, L1's for L2's
    progress; both hold their acks until it comes (:meth:`RobotNode._send_due_acks`), so the
    clock never runs far enough ahead to force a window through, and the run still matches
    the in-process one exactly. With the hold switched off this run differs by 5.57 (26 of
    L2's windows forced through)."""
    out = tmp_path / "out"
    argv = ["team", "up", "desilva2015-kidnapped", "--out", str(out), "--duration", "6"]
    assert main([*argv, "--seed", "0", "--stall", "P1,L2@3:0.5", "--quiet"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["faults"]["stalls"] == [
        {"sender": "P1", "receiver": "L2", "at_s": 3.0, "wall_s": 0.5}
    ]
    run = summary["per_run"][0]
    m = run["messages"]
    assert m["L2"]["faults"]["stalled"] > 0 and m["L1"]["faults"]["stalled"] == 0
    held = {robot: (m[robot]["acks_held"], m[robot]["acks_held_expired"]) for robot in m}
    assert held["L2"][0] >= 1 and all(expired == 0 for _, expired in held.values()), held
    assert all(m[robot]["overdue_windows"] == 0 for robot in m), held
    assert not run["clock_ack_timeouts"]
    agree = summary["agreement"]
    assert agree["perfect_network"] and agree["within_tolerance"], (agree, held)
    assert agree["max_abs_diff"] < 1e-9
    assert all(codes == [0] for codes in run["exit_codes"].values())


@pytest.mark.slow
def test_a_sharing_policy_reaches_the_leader_processes(tmp_path):
    """``--sharing-policy mutual-confirmed``: both leader processes skip the other's beliefs of
    the pods (indirect messages) and agree with the in-process run of the same policy. The run
    is shorter than the 5 s steady-state start, so its RMSE is undefined in both and agrees."""
    out = tmp_path / "out"
    argv = ["team", "up", "desilva2015", "--out", str(out), "--duration", "4", "--seed", "3"]
    assert main([*argv, "--sharing-policy", "mutual-confirmed", "--quiet"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["sharing_policy"] == "mutual-confirmed"
    agree = summary["agreement"]
    assert agree["perfect_network"] and agree["within_tolerance"], agree
    for leader in ("L1", "L2"):
        tracks = summary["per_run"][0]["messages"][leader]["tracks"]
        assert tracks.get("messages_fused:indirect", 0) == 0, tracks
        assert tracks["messages_fused:skipped"] > 0 and tracks["messages_fused:mutual"] > 0
    assert "sharing policy `mutual-confirmed`" in (out / "report.md").read_text()


@pytest.mark.slow
def test_the_sensing_robots_reach_every_robot_process(tmp_path, capsys, printed_as):
    """``--sensing L1,P2``: every process simulates those robots sensing, so P2 runs a fuser
    (beliefs of its teammates, mail to L1) and L2 only shares its odometry; the distributed
    beliefs and figures of both fusers agree with the in-process run of the same sensing robots,
    and the summary and report name them."""
    out = tmp_path / "out"
    argv = ["team", "up", "desilva2015", "--out", str(out), "--duration", "6", "--seed", "3"]
    assert main([*argv, "--sensing", "L1,P2"]) == 0  # not --quiet: the terminal summary too
    summary = json.loads((out / "summary.json").read_text())
    printed = capsys.readouterr().out
    line = re.search(
        r"^(\S+): success rate (\S+) \(in-process (\S+)\), position RMSE (\S+) m "
        r"\(in-process (\S+) m\); largest \|Δ\| of a belief entry (\S+) "
        r"\(tolerance 1e-06; within tolerance\)$",
        printed,
        flags=re.M,
    )
    assert line is not None, printed
    d, r = summary["distributed"], summary["in_process"]
    assert line[1] == summary["experiment"] == "desilva2015"
    assert d["pos_rmse_m"] is not None and d["success_rate"] is not None, d
    figures = [d["success_rate"], r["success_rate"], d["pos_rmse_m"], r["pos_rmse_m"]]
    shown = zip(line.groups()[1:], [*figures, summary["agreement"]["max_abs_diff"]], strict=True)
    assert all(printed_as(text, value) for text, value in shown), (printed, d, r)
    assert summary["sensing"] == ["L1", "P2"] and summary["paper_sensing"] == ["L1", "L2"]
    assert summary["processes_per_run"]["fusers"] == 2
    agree = summary["agreement"]
    assert agree["perfect_network"] and agree["within_tolerance"], agree
    assert agree["max_abs_diff"] < 1e-9
    for figure, diff in summary["difference"].items():
        assert diff is None or abs(diff) <= summary["tolerance"]["figure"], figure
    pairs = {f"{me}->{mate}" for me in ("L1", "P2") for mate in ROSTER if mate != me}
    for side in ("distributed", "in_process"):
        assert set(summary[side]["success_rate_per_pair"]) == pairs, side
    run = summary["per_run"][0]
    assert all(codes == [0] for codes in run["exit_codes"].values())
    for robot, m in run["messages"].items():
        assert m["rejected"] == 0 and m["final_report"]
        fuser = robot in ("L1", "P2")
        assert (m["estimates"] > 0) == fuser and (m["sent"]["mail"] > 0) == fuser, robot
    assert run["messages"]["P2"]["tracks"]["messages_fused:mutual"] > 0
    assert "Sensing robots L1, P2 (`--sensing`" in (out / "report.md").read_text()


def test_an_agent_refilters_late_readings_from_a_checkpoint_and_matches_the_in_process_eif():
    """Seed 001's team EIF in one agent's driver, window by window; a third of its teammates'
    readings arrive two windows late and are re-filtered from the checkpoints: the beliefs
    equal the in-process EIF's (the readings are fused at their own time stamps)."""
    scenario, sim = sharma_sim(2, 0, 3.0)
    recording = sim.recording
    parts = sharma_node_parts("1", 2, 0, 3.0, "two_landmarks")
    driver = parts.driver
    streams = []
    for od in recording.odometry:
        s = ReceivedOdometry()
        s.add(od.t, od.velocity)
        streams.append(s)
    m = recording.measurements
    rng = np.random.default_rng(11)  # which readings are late (seed not used elsewhere)
    late = (m.observer != 0) & (rng.random(m.size) < 0.33)
    edges = np.round(np.arange(0, 31) * 0.1, 12)
    held_back: list[tuple[int, Measurements]] = []
    for k in range(30):
        last = k == 29
        inside = (m.t >= edges[k]) & ((m.t <= edges[k + 1]) if last else (m.t < edges[k + 1]))
        driver.start_window(
            edges[k],
            edges[k + 1],
            streams=streams,
            rows=m.select(inside & ~late),
            present=set(recording.robots[1:]),
            inclusive=last,
        )
        assert driver.run()
        held_back.append((k + 2, m.select(inside & late)))
        due = [h for h in held_back if h[0] == k or last]
        held_back = [h for h in held_back if not (h[0] == k or last)]
        for _, rows in due:
            assert driver.refilter(rows) == 0
    counters = driver.counters()
    assert counters["rows_refiltered"] == int(late.sum()) > 0
    assert counters["rows_late_lost"] == 0
    reference = in_process(recording, sim, scenario, "two_landmarks")
    got = latest_of_each_time(
        estimates_from_bodies(
            "eif", [("1", b) for b in est_bodies(driver.take_new(), frame="world_pose2")]
        )
    )
    for ref in reference.beliefs:
        g = got.series("1", ref.subject)
        np.testing.assert_array_equal(np.round(g.t, 9), np.round(ref.t, 9))
        np.testing.assert_allclose(g.mean, ref.mean, rtol=0, atol=1e-9)
        np.testing.assert_allclose(g.cov, ref.cov, rtol=0, atol=1e-9)


@pytest.mark.slow
@pytest.mark.parametrize("stall", [None, "2,1@1:0.5"])
def test_sharma_agents_as_processes_each_equal_the_in_process_eif(
    tmp_path, capsys, stall, printed_as
):
    """Also when agent 1 hears nothing from agent 2 for half a second of wall time from 1 s on
    (``--stall``): agent 1 holds its ack until agent 2's odometry and readings come, so the
    clock never forces its window through without them. Not ``--quiet`` (the runs of
    ``test_sharma_team_faults`` are): every agent's row of the terminal summary."""
    out = tmp_path / "out"
    argv = ["team", "up", "sharma2013", "--out", str(out), "--duration", "3"]
    assert main(argv + (["--stall", stall] if stall else [])) == 0
    summary = json.loads((out / "summary.json").read_text())
    printed = _agent_lines(capsys.readouterr().out, "run 0 ")
    assert set(printed) == set(summary["per_run"][0]["agents"]) == {"1", "2", "3", "4", "5"}
    ref = summary["per_run"][0]["in_process"]["pos_rmse_m"]
    for robot, a in summary["per_run"][0]["agents"].items():
        figures = (a["pos_rmse_m"], ref, a["max_abs_mean_diff"])
        assert all(map(printed_as, printed[robot], figures)), (robot, printed[robot], figures)
    agree = summary["agreement"]
    assert agree["perfect_network"] and agree["within_tolerance"], agree
    run = summary["per_run"][0]
    if stall:
        first = run["messages"]["1"]
        assert first["faults"]["stalled"] > 0 and first["acks_held"] >= 1
        assert first["acks_held_expired"] == 0 and first["overdue_windows"] == 0
    assert set(run["agents"]) == {"1", "2", "3", "4", "5"}
    for robot, a in run["agents"].items():
        assert a["pos_rmse_m"] == pytest.approx(run["in_process"]["pos_rmse_m"], abs=1e-9), robot
        assert a["readings_late"] == 0 and a["records_missing"] == 0
        m = run["messages"][robot]
        assert m["sent"]["rows"] == m["sent"]["odom"] == 30 and m["rejected"] == 0
        assert m["received_delivered"]["rows"] == 4 * 30  # every teammate's, every tick


def _handmade_fit(folder: str):
    """Error models for the runtime test (round values, not fitted: the test is of the runtime,
    the fit has its own tests and takes half a minute)."""
    from relloc.calibration.camera import CameraFit
    from relloc.calibration.odometry import OdometryModelFit
    from relloc.calibration.window import CalibrationWindow
    from relloc.experiments.mrclam_cl import FittedModels

    window = CalibrationWindow(start_s=1.0, end_s=400.0, source=folder)  # inside run 6
    return FittedModels(
        odometry=OdometryModelFit(
            calibration_window=window,
            latency_s=0.1,
            time_constant_s=0.0,
            scale_v=(0.9,) * 5,
            scale_w=(0.8,) * 5,
            q_v0=1e-6,
            k_v=0.01,
            q_w0=1e-6,
            k_w=0.04,
            k_wv=0.0,
            odometry_window_s=5.0,
        ),
        camera=CameraFit(
            calibration_window=window,
            bearing_offset=(0.0,) * 5,
            sigma_bearing_raw=0.007,
            bearing_inflation=25.0,
            sigma_bearing=0.035,
            range_bias_coeffs=(0.06, 0.0, 0.0, 0.0, 0.0),
            sigma_range_raw=0.04,
            range_inflation=15.0,
            sigma_range=0.17,
            range_interval_s=1.0,
            correlation={"range": {"1s": 0.8}},
            n_residuals=100,
        ),
    )


def test_fitted_models_round_trip_through_fit_json(tmp_path):
    from relloc.calibration.window import CalibrationWindow
    from relloc.experiments.fit_file import load_fit, save_fit
    from relloc.experiments.mrclam_cl import OdometryInflation

    halves = CalibrationWindow(0.0, 200.0, "x"), CalibrationWindow(200.0, 400.0, "x")
    inflation = OdometryInflation(1.5, True, 5.0, ((1.0, 9.5), (1.5, 4.25)), *halves)
    fit = dataclasses.replace(_handmade_fit("somewhere"), odometry_inflation=inflation)
    save_fit(fit, tmp_path / "fit.json")
    assert load_fit(tmp_path / "fit.json") == fit
    (tmp_path / "bad.json").write_text('{"odometry": {}}')
    with pytest.raises(DataError, match=r"bad\.json: odometry\.calibration_window: missing"):
        load_fit(tmp_path / "bad.json")
    (tmp_path / "bad.json").write_text("[" * 100_000 + "]" * 100_000)  # RecursionError once
    with pytest.raises(DataError, match=r"bad\.json: not the fitted models"):
        load_fit(tmp_path / "bad.json")


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (("camera", "sigma_range", "nan"), "camera.sigma_range: expected float, got a string"),
        (("odometry", "k_v", None), "odometry.k_v: expected float, got null"),
        (("camera", "sigma_range", -0.36), "camera.sigma_range: must be > 0, got -0.36"),
        (("camera", "sigma_range", 10**400), "camera.sigma_range: must be a finite number"),
        (("odometry", "scale_v", [[1, 2]] * 5), r"odometry.scale_v\[0\]: expected float"),
        (("odometry", "latency_s", -100), "odometry.latency_s: -100.0 s is outside"),
        (("odometry", "time_constant_s", 1e12), "time_constant_s: 1000000000000.0 s is"),
        (("odometry_inflation", "k", -1.5), "odometry_inflation.k: must be > 0"),
        (("odometry_inflation", "met", "false"), "odometry_inflation.met: expected bool"),
        (("camera", "range_bias_coeffs", []), "camera.range_bias_coeffs: 0 values"),
        (("camera", "sigma_rnage", 0.1), "camera.sigma_rnage: unknown key"),
        (("odometry", "calibration_window", {"start_s": 5, "end_s": 1, "source": "x"}), "empty"),
        (("odometry_inflation", "tried", [[1.0]]), r"tried\[0\]: expected 2 values, got 1"),
    ],
)
def test_a_fit_file_edited_by_hand_is_refused_naming_the_key(tmp_path, edit, message):
    """Each of these once crashed a robot process (TypeError, ValueError) or was used as is."""
    from relloc.experiments.fit_file import load_fit, save_fit

    save_fit(_handmade_fit("x"), tmp_path / "fit.json")
    raw = json.loads((tmp_path / "fit.json").read_text())
    section, key, value = edit
    raw[section][key] = value
    (tmp_path / "fit.json").write_text(json.dumps(raw))
    with pytest.raises(DataError, match=rf"fit\.json: .*{message}"):
        load_fit(tmp_path / "fit.json")


def test_a_fit_of_another_team_or_span_is_refused():
    from relloc.experiments.fit_file import check_fit_for

    fit = _handmade_fit("x")  # five robots, windows in [1, 400] s
    check_fit_for(fit, 5, (0.0, 400.0), "f: ")
    with pytest.raises(DataError, match=r"f: odometry\.scale_v: 5 values, for a team of 4"):
        check_fit_for(fit, 4, (0.0, 400.0), "f: ")
    with pytest.raises(DataError, match=r"odometry\.calibration_window: \[1\.00, 400\.00\]"):
        check_fit_for(fit, 5, (10.0, 400.0), "f: ")


@pytest.mark.slow
def test_mrclam_agents_as_processes_each_equal_the_in_process_eif(tmp_path, capsys, printed_as):
    from relloc.datasets.paths import default_mrclam_dataset
    from relloc.experiments.fit_file import save_fit

    folder = default_mrclam_dataset()
    if not folder.is_dir():
        pytest.skip(f"{folder} is not here")
    save_fit(_handmade_fit(str(folder)), tmp_path / "fit.json")
    out = tmp_path / "out"
    argv = ["team", "up", str(folder), "--estimator", "cooperative", "--out", str(out)]
    assert main([*argv, "--fit", str(tmp_path / "fit.json"), "--duration", "2"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    # the terminal summary (not --quiet): every agent's row, the figures of summary.json
    printed = _agent_lines(capsys.readouterr().out, "")
    run = summary["per_run"][0]
    assert set(printed) == set(run["agents"]) == {"1", "2", "3", "4", "5"}
    for robot, a in run["agents"].items():
        figures = (a["pos_rmse_m"], run["in_process"]["pos_rmse_m"], a["max_abs_mean_diff"])
        assert a["pos_rmse_m"] is not None, robot
        assert all(map(printed_as, printed[robot], figures)), (robot, printed[robot], figures)
    assert summary["agreement"]["within_tolerance"], summary["agreement"]
    run = summary["per_run"][0]
    assert set(run["agents"]) == {"1", "2", "3", "4", "5"}
    for robot, a in run["agents"].items():
        assert a["records_missing"] == 0 and a["readings_late"] == 0, robot
        assert run["messages"][robot]["sent"]["rows"] > 0
