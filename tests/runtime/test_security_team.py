"""Intruders against a real team: every robot, the clock and the launcher are OS processes over
loopback Zenoh, and an outside session attacks while the team runs.

- plain network: the intruder can reach every key, so it tries every message that crashed or
  confused a process before (sender ``clock`` on robot streams, a tick at t = 10¹², control about
  robot "nobody", ``stats`` from ``clock``, spoofed kills/restarts, a premature end,
  future-stamped odometry, oversized payloads, a flood); the team keeps running, every attack is
  rejected and counted by reason, and the observer's estimates still equal the in-process run's
  on the same seed (max |Δ| < 1e-9, the clean run's criterion in test_team.py) — nothing the
  intruder sent reached its filters;
- ``--secure`` (mutual TLS + access control): an intruder without a certificate, one with a
  certificate of another CA, and one with a valid certificate of another robot (``rover``) try
  the attacks: the first two never see the team (no link), the third is confined by Zenoh's
  access control to rover's own key prefix — only what it sends there reaches relloc: a
  malformed message and rover's odometry with a huge sequence number (which would make the
  genuine stream look old), both counted by the teammates, and by rover itself as messages on
  its own key from another process (``own_key``) — and the estimates again equal the
  in-process ones.

Each run: 3 robots, 5 s simulated, paced at 2.5x real time so the attack lands mid-run.
"""

from __future__ import annotations

import json
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from relloc.estimators.track_manager import default_tracker
from relloc.pipeline.team_report import track_team
from relloc.runtime import keys
from relloc.runtime.access import member_config
from relloc.runtime.certs import make_team_certs
from relloc.runtime.launcher import Collected, TeamLauncher, TeamSettings
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

TEAM = "team"
SEED = 3
ODOM = {"stamps": np.array([0.0, 0.05]), "u": np.zeros((2, 4))}
AGREEMENT_TOL = 1e-9


class Intruder:
    """An outside Zenoh session: watches the team's liveliness and clock, then attacks."""

    def __init__(self, settings: TransportSettings) -> None:
        self.settings = settings
        self.members_seen: set[str] = set()
        self.ticks_seen = 0
        self.failure: BaseException | None = None

    def run(self, attack: Callable[[Any], None] | None, watch_s: float) -> None:
        try:
            session = open_session(self.settings)
        except BaseException as exc:  # a refused TLS setup may fail at open: nothing got in
            self.failure = exc
            return
        inbox = Inbox()
        try:
            inbox.watch_presence(session, keys.alive_wildcard(TEAM))
            inbox.subscribe(session, keys.clock_key(TEAM, "tick"))
            deadline = time.monotonic() + watch_s
            while time.monotonic() < deadline and not (attack and self.ticks_seen):
                item = inbox.get(timeout=0.1)
                if item is None:
                    continue
                if item.presence == "joined":
                    self.members_seen.add(keys.parse_presence_key(item.key)[1])
                elif item.presence == "data":
                    self.ticks_seen += 1
            if attack is not None and self.ticks_seen:
                attack(session)
                time.sleep(0.5)
        finally:
            inbox.close()
            session.close()


def _put(session: Any, key: str, *payloads: bytes) -> None:
    publisher = declare_publisher(session, key)
    for payload in payloads:
        publisher.put(payload)
    publisher.undeclare()


def _ctl(action: str, robot: str, t: float = 1.0) -> bytes:
    return encode("ctl", "clock", 10_000, t, {"action": action, "robot": robot})


def _every_attack(session: Any) -> None:
    robot = lambda r, kind: keys.robot_key(TEAM, r, kind)  # noqa: E731
    eqm = {"target": "flyer", "mean": np.zeros(4), "cov": np.eye(4)}
    _put(session, robot("clock", "odom"), encode("odom", "clock", 0, 0.1, ODOM))
    _put(session, robot("clock", "eqm"), encode("eqm", "clock", 0, 0.1, eqm))
    tick = {"k": 2, "n": 10**13, "dt": 0.1}
    _put(session, keys.clock_key(TEAM, "tick"), encode("tick", "clock", 9_999, 1e12, tick))
    ctl = keys.clock_key(TEAM, "ctl")
    _put(session, ctl, _ctl("restart", "nobody"), _ctl("kill", "flyer"))
    _put(session, ctl, *[_ctl("restart", "observer") for _ in range(5)], _ctl("end", ""))
    _put(session, robot("clock", "stats"), encode("stats", "clock", 0, 1.0, {"counters": {}}))
    _put(session, robot("clock", "ack"), encode("ack", "clock", 0, 1.0, {"k": 1}))
    future = {"stamps": np.array([0.1, 1e6]), "u": np.zeros((2, 4))}
    _put(session, robot("flyer", "odom"), encode("odom", "flyer", 10**6, 0.1, future))
    _put(session, robot("rover", "odom"), *[b"\x00" * 1_000_000] * 5)
    _put(session, robot("observer", "odom"), *[encode("odom", "observer", 0, 0.1, ODOM)] * 300)


def _run_team(settings: TeamSettings, intruders: list[tuple[Intruder, Any, float]]) -> Collected:
    rec = load_team(settings.scenario, settings.seed).recording
    launcher = TeamLauncher(settings, rec.robots, rec.span[1] - rec.span[0])
    threads = [threading.Thread(target=i.run, args=(a, w)) for i, a, w in intruders]
    for thread in threads:
        thread.start()
    try:
        collected = launcher.run()  # raises if any process failed
    finally:
        for thread in threads:
            thread.join(timeout=60)
    return collected


def _assert_estimates_match_in_process(collected: Collected, scenario: str) -> None:
    rec = load_team(scenario, SEED).recording
    distributed = assemble_estimates(collected, rec.robots, "plkf")
    reference = track_team(rec, default_tracker(), rng=np.random.default_rng(run_seeds(SEED)[1]))
    agree = agreement(distributed, reference)
    assert agree["max_abs_mean_diff"] < AGREEMENT_TOL, agree
    assert agree["max_abs_cov_diff"] < AGREEMENT_TOL, agree
    assert all(p["only_in_process"] == p["only_distributed"] == 0 for p in agree["pairs"].values())


def _settings(scenario: Path, out: Path, port: int, **extra: Any) -> TeamSettings:
    return TeamSettings(
        scenario=str(scenario), out_dir=out, seed=SEED, port=port, realtime_factor=2.5, **extra
    )


def test_plain_team_survives_every_attack_and_counts_it(trio_scenario, tmp_path):
    scenario = trio_scenario(5.0)
    port = free_loopback_port()
    intruder = Intruder(TransportSettings(connect=(loopback_endpoint(port),)))
    collected = _run_team(
        _settings(scenario, tmp_path / "out", port), [(intruder, _every_attack, 60.0)]
    )
    assert intruder.ticks_seen and intruder.failure is None
    per_robot = robot_messages(collected, ("observer", "flyer", "rover"))
    for robot, m in per_robot.items():
        assert m["processes"] == 1 and m["final_report"] and m["ticks"] == 50, (robot, m)
        reasons = m["rejected_by_reason"]
        common = {"unknown_sender": 2, "bad_tick": 1, "unknown_target": 1, "premature_end": 1}
        assert {k: reasons.get(k) for k in common} == common, (robot, reasons)
        assert reasons.get("oversized") == 5, (robot, reasons)
        assert reasons.get("future") == (None if robot == "flyer" else 1), (robot, reasons)
        flooded = robot != "observer"  # the flood used the observer's name
        assert (reasons.get("rate_limited", 0) > 0) == flooded, (robot, reasons)
        # a robot hears what was sent in its name on its own key from another process: the
        # observer the flood, flyer the future-stamped odometry (rover's key got only payloads
        # too large to read)
        own = reasons.get("own_key", 0)
        assert {"observer": own > 0, "flyer": own == 1, "rover": own == 0}[robot], reasons
    assert collected.kills == [] and collected.restarts == []
    assert dict(collected.rejected_by_reason) == {
        "unknown_target": 1,
        "unscheduled": 6,
        "unknown_sender": 1,
    }
    clock = (tmp_path / "out" / "clock.json").read_text()
    assert '"unknown_sender": 1' in clock
    _assert_estimates_match_in_process(collected, str(scenario))


def _confined_attacks(session: Any) -> None:
    """What a holder of rover's certificate tries outside rover's prefix, plus one bad message
    inside it (allowed by the access control, refused by relloc)."""
    flyer_odom = encode("odom", "flyer", 10**6, 0.1, ODOM)
    _put(session, keys.robot_key(TEAM, "flyer", "odom"), flyer_odom)
    est = {
        "target": "flyer",
        "track": "",
        "frame": "relative_pose4",
        "stamps": [0.5],
        "means": np.full((1, 4), 96.4),
        "covs": np.eye(4)[None],
        "ages": [0.0],
        "update_stamps": [],
        "update_ages": [],
        "nis": [],
        "update_dofs": [],
        "cond_r": [],
        "cond_s": [],
        "info_names": [],
        "info": [],
    }
    _put(session, keys.robot_key(TEAM, "observer", "est"), encode("est", "observer", 99, 0.5, est))
    ctl = keys.clock_key(TEAM, "ctl")
    _put(session, ctl, _ctl("kill", "flyer"), _ctl("end", ""))
    tick = {"k": 2, "n": 10**13, "dt": 0.1}
    _put(session, keys.clock_key(TEAM, "tick"), encode("tick", "clock", 9_999, 1e12, tick))
    token = session.liveliness().declare_token(keys.alive_key(TEAM, "flyer"))
    time.sleep(0.2)
    token.undeclare()
    rover_odom = keys.robot_key(TEAM, "rover", "odom")
    _put(session, rover_odom, b"\xc1")
    # rover's own stream with a huge sequence number: before the jump bound, every genuine
    # odometry message of rover after it was dropped as an old duplicate
    _put(session, rover_odom, encode("odom", "rover", 10**9, 0.1, ODOM))


def test_secure_team_keeps_out_intruders_and_confines_a_stolen_certificate(trio_scenario, tmp_path):
    scenario = trio_scenario(5.0)
    roster = ("observer", "flyer", "rover")
    certs = make_team_certs(tmp_path / "certs", TEAM, roster)
    other = make_team_certs(tmp_path / "other-ca", TEAM, roster)
    port = free_loopback_port()
    tls = loopback_endpoint(port, "tls")

    def config_file(name: str, config: dict[str, Any]) -> Path:
        path = tmp_path / f"{name}.json5"
        path.write_text(json.dumps(config))
        return path

    no_cert = member_config(certs, "flyer")
    link = no_cert["transport"]["link"]["tls"]
    for field in ("connect_private_key", "connect_certificate"):
        del link[field]
    link["enable_mtls"] = False
    intruders = {
        "tcp": TransportSettings(connect=(loopback_endpoint(port),)),
        "no_certificate": TransportSettings(
            connect=(tls,), config_file=config_file("nocert", no_cert)
        ),
        "other_ca": TransportSettings(
            connect=(tls,), config_file=config_file("other", member_config(other, "flyer"))
        ),
        "stolen_rover": TransportSettings(
            connect=(tls,), config_file=config_file("rover", member_config(certs, "rover"))
        ),
    }
    spies = {name: Intruder(s) for name, s in intruders.items()}
    plan = [
        (
            spy,
            _confined_attacks if name == "stolen_rover" else _every_attack,
            60.0 if name == "stolen_rover" else 3.0,
        )
        for name, spy in spies.items()
    ]
    settings = _settings(scenario, tmp_path / "out", port, secure=True, certs_dir=certs.folder)
    collected = _run_team(settings, plan)

    for name in ("tcp", "no_certificate", "other_ca"):
        assert spies[name].members_seen == set() and spies[name].ticks_seen == 0, name
    assert spies["stolen_rover"].members_seen == {*roster, "clock"}
    per_robot = robot_messages(collected, roster)
    for robot, m in per_robot.items():
        assert m["processes"] == 1 and m["final_report"] and m["ticks"] == 50, (robot, m)
        # rover hears both on its own key, from a process that is not rover's: own_key
        expected = {"own_key": 2} if robot == "rover" else {"malformed": 1, "seq_jump": 1}
        assert m["rejected_by_reason"] == expected, (robot, m["rejected_by_reason"])
        assert m["teammate_joins_seen"] == 2 and m["teammate_departures_seen"] == 0
    assert collected.kills == [] and dict(collected.rejected_by_reason) == {}
    _assert_estimates_match_in_process(collected, str(scenario))
