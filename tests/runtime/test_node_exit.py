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


def test_a_node_whose_clock_leaves_mid_run_filters_up_to_its_last_instant(session):
    """The clock's token goes after tick 5 of 20: the node counts ``exit.clock_left``, does not
    claim the run's end, and its last window ends the run there, holding the readings taken at
    its last instant (every reading of ``[0, t_5]`` is used)."""
    from node_harness import DT, TEAM, hand_node, tick

    from relloc.experiments.team_sources import named_node_parts
    from relloc.runtime import keys
    from relloc.runtime.node import TIME_TOL
    from relloc.runtime.transport import Incoming

    parts = named_node_parts("desilva2015", "L1", 5, 0, 20 * DT)
    node = hand_node(parts, "L1", session, talkers=parts.talkers)
    for k in range(1, 6):
        tick(node, k)
    assert node._pending  # the teammates sent nothing: every window waits for them
    node._on_incoming(Incoming(keys.alive_key(TEAM, "clock"), b"", presence="left"))
    assert node.counters["exit.clock_left"] == 1 and node.counters["final"] == 1
    assert node._done and not node.reached_end and not node._pending
    readings = parts.source.rows(0.0, 5 * DT, inclusive=True)
    assert readings.t.max() >= 5 * DT - TIME_TOL  # some are taken at the last instant
    node.estimator.take_new()  # the estimator's counts are brought up to date with it
    used = sum(v for k, v in node.estimator.counters().items() if k.startswith("rows_used:"))
    assert used == readings.size
