"""A ``relloc node`` that stops before its run's end (its clock silent or gone) says so and exits
non-zero; one that reaches the end exits 0 (test_security_by_hand.py)."""

from __future__ import annotations

import json
import time

import pytest
from cli_process import relloc_process

from relloc.cli import main
from relloc.runtime.transport import free_loopback_port


def test_a_node_whose_clock_never_ticks_exits_non_zero_and_says_so(capsys):
    endpoint = f"tcp/127.0.0.1:{free_loopback_port()}"
    argv = ["node", "--robot", "observer", "--scenario", "default", "--team", "silent"]
    assert main([*argv, "--listen", endpoint, "--clock-timeout", "0.5"]) == 1
    out, err = capsys.readouterr()
    counters = json.loads(out.strip().splitlines()[-1])["counters"]
    assert counters["exit.clock_silent"] == 1 and "ticks" not in counters
    assert "robot 'observer' stopped before the run's end: the clock was silent" in err
    assert "after 0 ticks; --clock-timeout 0.5 s" in err


@pytest.mark.slow
def test_a_node_whose_clock_is_killed_exits_non_zero_and_says_so():
    hub = f"tcp/127.0.0.1:{free_loopback_port()}"
    team = ["--team", "orphan"]
    roster = "observer,flyer,rover"  # the default scenario's: the clock waits for all three
    clock = relloc_process(
        "team", "clock", *team, "--roster", roster, "--duration", "5", "--listen", hub
    )
    node = relloc_process(
        "node",
        "--robot",
        "observer",
        "--scenario",
        "default",
        *team,
        "--connect",
        hub,
        merge_stderr=False,
    )
    try:
        time.sleep(8.0)  # both up and the clock's presence heard; no tick (two robots missing)
        clock.kill()
        out, err = node.communicate(timeout=60)
    finally:
        for p in (clock, node):
            if p.poll() is None:
                p.kill()
            p.communicate()
    assert node.returncode == 1, err
    counters = json.loads(out.strip().splitlines()[-1])["counters"]
    assert counters["exit.clock_left"] == 1, counters
    assert "robot 'observer' stopped before the run's end: the clock left" in err
