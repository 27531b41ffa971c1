"""A command stopped by SIGTERM (a supervisor, ``timeout``, ``kill``) or Ctrl-C stops the
processes it started before it exits: Monte-Carlo workers, a team's robots, clock and
in-process reference. Without it they were left running: the pool's workers hold both ends of
their task pipe, so they never see their parent go (found with ``kill -TERM`` on
``relloc team up``: the reference worker and the fork server stayed for good)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from cli_process import relloc_process

from relloc.runtime.transport import free_loopback_port

pytestmark = pytest.mark.skipif(
    not sys.platform.startswith("linux"), reason="reads the process tree from /proc"
)


def _children() -> dict[int, list[int]]:
    """Every live process's children, from /proc (parent pid → child pids)."""
    tree: dict[int, list[int]] = {}
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            stat = (entry / "stat").read_text()
        except OSError:  # gone meanwhile
            continue
        fields = stat.rsplit(")", 1)[1].split()
        if fields[0] == "Z":  # a zombie has exited; only its parent's wait is missing
            continue
        tree.setdefault(int(fields[1]), []).append(int(entry.name))
    return tree


def _descendants(pid: int) -> set[int]:
    tree, out, todo = _children(), set(), [pid]
    while todo:
        for child in tree.get(todo.pop(), []):
            if child not in out:
                out.add(child)
                todo.append(child)
    return out


def _alive(pids: set[int]) -> set[int]:
    live = {p for kids in _children().values() for p in kids}
    return pids & live


def _wait_for(predicate, timeout: float) -> bool:
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if predicate():
            return True
        time.sleep(0.2)
    return False


def _stop_and_check(
    argv: list[str], at_least: int, signum: int, code: int, to_group: bool = False
) -> str:
    """Start ``relloc ARGV``, wait until it has ``at_least`` processes below it, send
    ``signum`` (``to_group``: to its whole process group, as ``timeout`` or a closed terminal
    do); it must exit with ``code`` and leave none of them alive."""
    proc = subprocess.Popen(
        [sys.executable, "-m", "relloc.cli", *argv],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        # a shell's default SIGINT: a test runner's worker may ignore it, and an ignored SIGINT
        # is inherited (Python then installs no KeyboardInterrupt handler)
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
        start_new_session=to_group,
    )
    try:
        assert _wait_for(lambda: len(_descendants(proc.pid)) >= at_least, 120), (
            f"fewer than {at_least} processes started"
        )
        time.sleep(1.0)  # let them get busy
        started = _descendants(proc.pid)
        if to_group:
            os.killpg(proc.pid, signum)
        else:
            proc.send_signal(signum)
        out, _ = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == code, out
    assert _wait_for(lambda: not _alive(started), 15), (
        f"left running after {signal.Signals(signum).name}: {sorted(_alive(started))}\n{out}"
    )
    return out


def test_sigterm_stops_a_monte_carlo_run_and_its_workers(tmp_path):
    out = _stop_and_check(
        ["run", "--out", str(tmp_path / "o"), "--runs", "400", "--quiet", "--no-plots"],
        at_least=2,
        signum=signal.SIGTERM,
        code=128 + signal.SIGTERM,
    )
    assert "relloc: stopped by SIGTERM" in out
    assert not (tmp_path / "o" / "summary.json").exists()


@pytest.mark.parametrize("signum", [signal.SIGTERM, signal.SIGHUP])
def test_a_signal_to_the_process_group_stops_the_run_and_its_workers_quietly(tmp_path, signum):
    # the workers get the signal too: they stop at once, with no traceback, and the command
    # does not hang on a result queue a dying worker held (it did with the CLI's handler)
    out = _stop_and_check(
        ["run", "--out", str(tmp_path / "o"), "--runs", "400", "--quiet", "--no-plots"],
        at_least=2,
        signum=signum,
        code=128 + signum,
        to_group=True,
    )
    assert out.strip() == f"relloc: stopped by {signal.Signals(signum).name}"


def test_sigterm_stops_a_team_and_its_reference(tmp_path):
    # the default team: a clock, five robots and the in-process reference, beside the fork
    # server and the resource tracker (paced at real time, so it is mid-run when stopped)
    out = _stop_and_check(
        ["team", "up", "default", "--out", str(tmp_path / "t"), "--realtime", "1", "--quiet"],
        at_least=9,
        signum=signal.SIGTERM,
        code=128 + signal.SIGTERM,
    )
    assert "relloc: stopped by SIGTERM" in out


def test_ctrl_c_stops_a_monte_carlo_run_without_running_the_rest(tmp_path):
    # SIGINT to the command alone (not to its process group, as a terminal would): the
    # workers finish the runs they hold, drop the rest and exit
    out = _stop_and_check(
        ["run", "--out", str(tmp_path / "o"), "--runs", "400", "--quiet", "--no-plots"],
        at_least=2,
        signum=signal.SIGINT,
        code=130,
    )
    assert "relloc: interrupted" in out


def test_a_team_process_keeps_the_default_sigterm():
    # its launcher stops a straggling robot with SIGTERM and escalates to SIGKILL: the node
    # dies at once, as before (no handler that would first unwind a blocked Zenoh call)
    endpoint = f"tcp/127.0.0.1:{free_loopback_port()}"
    node = relloc_process(
        "node", "--robot", "observer", "--scenario", "default", "--team", "straggler",
        "--listen", endpoint, "--clock-timeout", "60",
    )  # fmt: skip
    try:
        time.sleep(4.0)  # up, and waiting for a clock that never comes
        assert node.poll() is None
        node.send_signal(signal.SIGTERM)
        node.communicate(timeout=30)
    finally:
        if node.poll() is None:
            node.kill()
    assert node.returncode == -signal.SIGTERM
