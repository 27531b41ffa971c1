"""``relloc team up guler2023``: seed 003's air-ground team as processes over real Zenoh, in
closed loop, against the in-process reproduction on the same seeds."""

from __future__ import annotations

import json
import re

import pytest

from relloc.cli import main
from relloc.experiments.guler2023_team import largest_difference

pytest.importorskip("zenoh", reason="extra 'runtime' (eclipse-zenoh) not installed")

TEAM = ("R_0", "R_1", "R_2", "R_3", "R_4", "D_1", "D_2")


def _summary(out):
    return json.loads((out / "summary.json").read_text())


@pytest.mark.slow
def test_air_ground_processes_in_closed_loop_equal_the_in_process_run(tmp_path, capsys, printed_as):
    out = tmp_path / "out"
    argv = ["team", "up", "guler2023", "--out", str(out), "--duration", "1.5", "--seed", "3"]
    assert main(argv) == 0  # not --quiet (the other runs here are): the terminal summary
    s = _summary(out)
    # the line the terminal shows: this run's figures, the same as its summary.json's
    printed = capsys.readouterr().out
    line = re.search(
        r"^guler2023 (\S+): RMSE mean (\S+) m \(in-process (\S+) m\), worst (\S+) m "
        r"\(in-process (\S+) m\); largest \|Δ\| of a belief entry (\S+) "
        r"\(tolerance \S+; within tolerance\)$",
        printed,
        flags=re.M,
    )
    assert line is not None, printed
    d, r = s["distributed"], s["in_process"]
    assert line[1] == s["case"] == "two_drones"
    figures = [d["rmse_m_mean"], r["rmse_m_mean"], d["rmse_m_worst"], r["rmse_m_worst"]]
    shown = zip(line.groups()[1:], [*figures, s["agreement"]["max_abs_diff"]], strict=True)
    assert all(printed_as(text, value) for text, value in shown), (printed, d, r)
    assert d["rmse_m_mean"] > 0.0 and line[6] == "0"
    assert s["case"] == "two_drones" and s["agreement"]["perfect_network"]
    # the same functions on the same float64 numbers, no command delay: exactly equal
    assert s["agreement"]["max_abs_diff"] == 0.0, s["agreement"]
    assert s["agreement"]["within_tolerance"]
    assert all(d in (None, 0.0) for d in s["difference"].values()), s["difference"]
    assert s["distributed"] == s["in_process"]
    run = s["per_run"][0]
    ticks = run["ticks"]
    assert ticks == 30
    assert set(run["exit_codes"]) == {"clock", *TEAM}
    assert all(codes == [0] for codes in run["exit_codes"].values())
    world = run["messages"]["world"]
    # every robot's command reached the world at every tick; nothing was rejected anywhere
    assert world["cmd_received"] == dict.fromkeys(TEAM, ticks)
    assert world["rejected"] == 0 and not world["cmd_missing"] and not world["cmd_absent"]
    assert world["sent"]["sense"] == len(TEAM) * (ticks + 1)
    for robot, m in run["messages"]["robots"].items():
        assert m["rejected_by_reason"] == {} and m["rejected"] == 0, (robot, m)
        assert m["input_timeouts"] == m["inputs_missing_at_end"] == m["late_rows"] == 0, (robot, m)
        assert m["sent"]["cmd"] == ticks and m["sent"]["rows"] == ticks + 1
        assert (m["sent"].get("odom", 0) > 0) == (robot == "R_0")
        assert m["estimates"] == (ticks if robot in ("R_1", "R_2", "R_3", "R_4") else 0)
    follower = run["messages"]["robots"]["R_1"]
    # every teammate's readings of every tick and the leader's every command
    assert follower["received_delivered"] == {"rows": 6 * (ticks + 1), "odom": ticks}
    assert (out / "report.md").read_text().startswith("# relloc team up guler2023")


@pytest.mark.slow
def test_air_ground_team_survives_loss_a_partition_and_a_follower_killed_and_restarted(tmp_path):
    out = tmp_path / "out"
    argv = ["team", "up", "guler2023", "--out", str(out), "--duration", "2", "--seed", "1"]
    faults = ["--drop", "0.2", "--partition", "D_1@0.5-1.0", "--kill", "R_2@0.5"]
    assert main([*argv, *faults, "--restart", "R_2@1.0", "--quiet"]) == 0
    s = _summary(out)
    assert not s["agreement"]["perfect_network"]
    run = s["per_run"][0]
    assert run["exit_codes"]["R_2"] == [-9, 0]
    world = run["messages"]["world"]
    assert world["cmd_absent"] == {"R_2": 10}  # its motors stopped for 0.5 s
    assert world["cmd_received"]["R_2"] == 30  # 10 ticks before the kill, 20 after the restart
    # every teammate knew the restarted follower's subscriptions before its first tick: no
    # input of it went astray, so no robot waited for one and no command came too late
    assert not world["cmd_missing"] and world["rejected"] == 0
    assert all(m["input_timeouts"] == 0 for m in run["messages"]["robots"].values())
    r2 = run["messages"]["robots"]["R_2"]
    # (a killed process' counters are those of its last report, a quarter second before)
    assert r2["processes"] == 2 and 20 < r2["sent"]["cmd"] <= 30
    r1 = run["messages"]["robots"]["R_1"]
    assert r1["faults"]["dropped"] > 0 and r1["faults"]["partitioned"] > 0
    assert r1["received_delivered"]["rows"] < r1["received_wire"]["rows"]
    names = [f["fault"] for f in run["fault_accuracy"]]
    assert names == ["partition D_1@0.5-1", "kill R_2@0.5, back @1", names[2]]
    assert names[2].startswith("network drop=0.2")
    for f in run["fault_accuracy"][:2]:
        for side in ("before", "during", "after"):
            assert f[side]["distributed"]["estimate_rmse_m"] is not None
            assert f[side]["in_process"]["formation_rmse_m"] is not None
    # the restarted follower estimates again (from a broad prior) until the end
    assert r2["estimates"] >= 15


@pytest.mark.slow
def test_secure_air_ground_team_equals_the_in_process_run(tmp_path):
    """``--secure``: every process on mutual TLS with its own certificate (the world as the
    launcher identity, the only one allowed under ``clock/``); the arithmetic is unchanged."""
    out = tmp_path / "out"
    argv = ["team", "up", "guler2023", "--out", str(out), "--duration", "1", "--seed", "4"]
    assert main([*argv, "--secure", "--quiet"]) == 0
    s = _summary(out)
    assert s["secure"] is True
    assert s["agreement"]["max_abs_diff"] == 0.0 and s["distributed"] == s["in_process"]
    run = s["per_run"][0]
    assert run["messages"]["world"]["cmd_received"] == dict.fromkeys(TEAM, run["ticks"])
    assert all(m["rejected"] == 0 for m in run["messages"]["robots"].values())
    certs = {p.name for p in (out / "run0" / "certs").iterdir()}
    assert {f"{r}.pem" for r in TEAM} | {"launcher.pem"} <= certs


def test_largest_difference_compares_nested_figures():
    a = {"x": {"R1": 0.5, "R2": 1.0}, "v": "consistent", "n": None, "l": [1, 2]}
    assert largest_difference(a, a) == 0.0
    b = {"x": {"R1": 0.25, "R2": 1.0}, "v": "consistent", "n": None, "l": [1, 3]}
    assert largest_difference(a, b) == 1.0
    assert largest_difference({"v": "consistent"}, {"v": "conservative"}) == float("inf")
    assert largest_difference({"a": 1}, {"b": 1}) == float("inf")
    assert largest_difference(float("nan"), float("nan")) is None
