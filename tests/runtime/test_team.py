"""A real team over loopback Zenoh: every robot its own OS process, a clock process, a hub.

- a 3-robot team finds itself (liveliness), produces estimates, and — on a perfect network —
  agrees with the in-process run on the same seed to floating-point round-off;
- malformed, oversized, spoofed and unknown-sender messages injected by an outside session are
  rejected and counted by the robots, which keep working;
- a killed robot is noticed by its teammates (its liveliness token vanishes) and its restart
  rejoins the team mid-run (the observer re-finds its track).

Every process is started by the launcher and killed in its ``finally`` block.
"""

from __future__ import annotations

import json
import re
import threading
import time

import msgpack
import numpy as np
import pytest

from relloc.cli import main
from relloc.estimators.track_manager import default_tracker
from relloc.pipeline.team_report import track_team
from relloc.runtime import keys
from relloc.runtime.faults import FaultSettings, parse_robot_event
from relloc.runtime.launcher import TeamLauncher, TeamSettings
from relloc.runtime.messages import encode
from relloc.runtime.scenario import load_team, run_seeds
from relloc.runtime.summary import agreement, assemble_estimates, robot_messages
from relloc.runtime.transport import (
    Inbox,
    TransportSettings,
    declare_publisher,
    free_loopback_port,
    loopback_endpoint,
    open_session,
)

pytestmark = pytest.mark.slow


def _inject_bad_messages(team: str, endpoint: str, roster: tuple[str, ...]) -> None:
    """Join the hub, wait until every robot is alive (so its subscriptions are known here),
    then declare liveliness tokens of no member's layout (a wildcard token reaches every
    presence subscriber whose wildcard it overlaps; ``*/observer`` once counted as a join of
    the observer) and publish one message of each bad kind on teammates' odometry keys."""
    deadline = time.monotonic() + 60
    # the hub listens only once the launcher runs; Zenoh retries the endpoint until then
    session = open_session(TransportSettings(connect=(endpoint,)))
    inbox = Inbox()
    try:
        inbox.watch_presence(session, keys.alive_wildcard(team))
        alive: set[str] = set()
        while not set(roster) <= alive and time.monotonic() < deadline:
            item = inbox.get(timeout=0.5)
            parsed = None if item is None else keys.parse_presence_key(item.key)
            if parsed is not None and item is not None and item.presence == "joined":
                alive.add(parsed[1])
        liveliness = session.liveliness()
        stray = [
            liveliness.declare_token(f"relloc/{team}/{suffix}")
            for suffix in ("**", "alive/**", "*/observer")
        ]
        good = encode("odom", "flyer", 10_000, 0.0, {"stamps": [0.0], "u": np.zeros((1, 4))})
        bad = {
            keys.robot_key(team, "flyer", "odom"): [
                b"\x92\x01",  # a msgpack array, not a message
                b"\xc1",  # not msgpack at all
                b"\x00" * 70_000,  # oversized
                good.replace(b"flyer", b"rover"),  # sender field differs from its key
            ],
            keys.robot_key(team, "mallory", "odom"): [
                msgpack.packb(msgpack.unpackb(good) | {"sender": "mallory"})
            ],
        }
        for key, payloads in bad.items():
            publisher = declare_publisher(session, key)
            for payload in payloads:
                publisher.put(payload)
            publisher.undeclare()
        time.sleep(0.5)
        for token in stray:
            token.undeclare()
        time.sleep(0.2)
    finally:
        inbox.close()
        session.close()


def test_three_robot_team_finds_itself_agrees_and_rejects_bad_messages(trio_scenario, tmp_path):
    path = trio_scenario(4.0)
    port = free_loopback_port()
    # paced at 2.5× real time, as a team runs: unpaced, the clock ticks as fast as the acks come,
    # and on a starved machine a teammate's odometry can then arrive after its window is due
    # (max_lag_ticks), which the node fills with held velocities by design (overdue_windows)
    settings = TeamSettings(
        scenario=str(path), out_dir=tmp_path / "out", seed=3, port=port, realtime_factor=2.5
    )
    rec = load_team(str(path), 3).recording
    launcher = TeamLauncher(settings, rec.robots, rec.span[1] - rec.span[0])
    failures: list[BaseException] = []

    def inject() -> None:
        try:
            _inject_bad_messages(settings.team, loopback_endpoint(port), rec.robots)
        except BaseException as exc:
            failures.append(exc)

    injector = threading.Thread(target=inject)
    injector.start()
    try:
        collected = launcher.run()
    finally:
        injector.join(timeout=60)
    assert not failures, failures

    clock = (tmp_path / "out" / "clock.json").read_text()
    assert all(f'"robot": "{r}"' in clock for r in rec.robots)  # every robot arrived
    per_robot = robot_messages(collected, rec.robots)
    for robot in rec.robots:
        m = per_robot[robot]
        assert m["processes"] == 1 and m["final_report"]
        assert m["ticks"] == 40
        assert m["teammate_joins_seen"] == 2
        assert m["received_wire"]["odom"] == 2 * 40  # both teammates, every tick
    observer = per_robot["observer"]
    assert observer["estimates"] > 40
    # the bad messages were rejected and counted by every robot subscribed to odometry
    for robot in ("observer", "rover"):
        reasons = per_robot[robot]["rejected_by_reason"]
        assert reasons == {
            "malformed": 2,
            "oversized": 1,
            "spoofed": 1,
            "unknown_sender": 1,
        }, reasons
    distributed = assemble_estimates(collected, rec.robots, "plkf")
    assert set(distributed.labels) == {"observer->flyer", "observer->rover"}
    reference = track_team(rec, default_tracker(), rng=np.random.default_rng(run_seeds(3)[1]))
    agree = agreement(distributed, reference)
    diagnostics = (agree, collected.stats["observer"], collected.presence)
    assert agree["max_abs_mean_diff"] < 1e-9 and agree["max_abs_cov_diff"] < 1e-9, diagnostics
    assert all(p["only_in_process"] == p["only_distributed"] == 0 for p in agree["pairs"].values())


def test_killed_robot_is_noticed_and_its_restart_rejoins(trio_scenario, tmp_path):
    path = trio_scenario(5.0)
    faults = FaultSettings(
        kills=(parse_robot_event("flyer@1.0", "--kill"),),
        restarts=(parse_robot_event("flyer@3.5", "--restart"),),
    )
    settings = TeamSettings(scenario=str(path), out_dir=tmp_path / "out", seed=5, faults=faults)
    rec = load_team(str(path), 5).recording
    collected = TeamLauncher(settings, rec.robots, rec.span[1] - rec.span[0]).run()

    assert [k["robot"] for k in collected.kills] == ["flyer"]
    assert [r["robot"] for r in collected.restarts] == ["flyer"]
    per_robot = robot_messages(collected, rec.robots)
    assert per_robot["flyer"]["processes"] == 2  # two incarnations reported
    for robot in ("observer", "rover"):
        seen = (per_robot[robot], collected.presence)
        assert per_robot[robot]["teammate_departures_seen"] == 1, seen
        assert per_robot[robot]["teammate_joins_seen"] == 3, seen  # two teammates + one rejoin
    flyer_events = [e for e in collected.events if e[2] == "flyer"]
    kinds = [e[3] for e in flyer_events]
    # the observer's track of the dead robot expires, and is re-found after the restart
    assert kinds[:3] == ["created", "deleted", "recreated"], flyer_events
    deleted_t = flyer_events[1][0]
    refound_t = flyer_events[2][0]
    assert 1.0 < deleted_t <= 1.0 + 2.0 + 0.3  # within the keep window after the kill
    assert refound_t >= 3.3  # back only once the robot is (one tick of filter lag)
    distributed = assemble_estimates(collected, rec.robots, "plkf")
    flyer = distributed.series("observer", "flyer")
    assert flyer.t.size and (flyer.t > 4.0).any()  # estimates after the restart


def test_team_up_with_a_gate_gates_as_the_in_process_run(trio_scenario, tmp_path, capsys):
    # --gate reaches every robot's track manager and the in-process reference alike: a tight
    # gate (P = 0.5: it rejects 49 of the 80 readings of this run) and still the same estimates
    out = tmp_path / "out"
    argv = ["team", "up", str(trio_scenario(4.0)), "--out", str(out), "--seed", "3",
            "--port", str(free_loopback_port()), "--gate", "0.5"]  # fmt: skip
    assert main(argv) == 0
    printed = capsys.readouterr().out  # the terminal summary (runtime.team.print_summary)
    assert "team up — " in printed and "position RMSE" in printed and "in-process" in printed
    assert all(robot in printed for robot in ("observer", "flyer", "rover"))
    summary = json.loads((out / "summary.json").read_text())
    assert summary["gate_probability"] == 0.5
    assert summary["yaw_bank_components"] == 12  # relloc run's track manager, yaw bank included
    assert summary["messages"]["per_robot"]["observer"]["tracks"]["rows_gated"] > 0
    agree = summary["agreement"]
    assert agree["within_tolerance"], agree
    # every top-level key is documented: the team report's, or the ones team up adds
    from relloc.pipeline import team_report
    from relloc.runtime import team

    docs = (team_report.__doc__ or "") + (team.__doc__ or "")
    named = {
        w for span in re.findall(r"``(.+?)``", docs, flags=re.S) for w in re.findall(r"\w+", span)
    }
    assert [key for key in summary if key not in named] == []
