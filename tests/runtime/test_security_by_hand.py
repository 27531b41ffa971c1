"""The README's secure team by hand: ``relloc certs``, then ``relloc team clock`` as the TLS hub and
one ``relloc node`` per robot, each a fresh ``python -m relloc.cli`` process with its member's
Zenoh configuration (TLS only, access control). Every process exits 0 and every robot ran every
tick (intruders against the same configuration: test_security_team.py).
"""

from __future__ import annotations

import json
import stat

import pytest
from cli_process import relloc_process

from relloc.runtime.transport import free_loopback_port

pytestmark = pytest.mark.slow

ROBOTS = ("observer", "flyer", "rover")


def test_readme_secure_team_by_hand(trio_scenario, tmp_path):
    scenario = str(trio_scenario(2.0))
    certs = tmp_path / "certs"
    made = relloc_process("certs", str(certs), "--team", "demo", "--robots", ",".join(ROBOTS))
    assert made.wait(timeout=120) == 0, made.stdout.read() if made.stdout else ""
    for member in (*ROBOTS, "launcher", "ca"):
        assert stat.S_IMODE((certs / f"{member}.key").stat().st_mode) == 0o600
    hub = f"tls/127.0.0.1:{free_loopback_port()}"
    clock = relloc_process(
        "team",
        "clock",
        "--team",
        "demo",
        "--roster",
        ",".join(ROBOTS),
        "--duration",
        "2.0",
        "--zenoh-config",
        str(certs / "zenoh" / "launcher.json5"),
        "--listen",
        hub,
        "--report",
        str(tmp_path / "clock.json"),
    )
    nodes = {
        r: relloc_process(
            "node",
            "--robot",
            r,
            "--scenario",
            scenario,
            "--team",
            "demo",
            "--zenoh-config",
            str(certs / "zenoh" / f"{r}.json5"),
            "--connect",
            hub,
        )
        for r in ROBOTS
    }
    try:
        outputs = {r: p.communicate(timeout=240)[0] for r, p in nodes.items()}
        clock_out = clock.communicate(timeout=60)[0]
    finally:
        for p in (clock, *nodes.values()):
            if p.poll() is None:
                p.kill()
    assert clock.returncode == 0, clock_out
    for robot, out in outputs.items():
        assert nodes[robot].returncode == 0, out
        counters = json.loads(out.strip().splitlines()[-1])["counters"]
        assert counters["ticks"] == 20 and counters["teammate.joins"] == 2, counters
        assert counters.get("rejected", 0) == 0, counters
    report = json.loads((tmp_path / "clock.json").read_text())
    assert report["ticks"] == 20 and not report["ack_timeouts"]
