"""Link emulator and fault settings: loss, delay, duplicates, reordering, partitions, stalls,
parsing (by hand and fuzzed)."""

from __future__ import annotations

import itertools
import re

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from relloc.cli import main
from relloc.errors import ConfigError
from relloc.runtime.faults import (
    FaultSettings,
    LinkEmulator,
    LinkStall,
    Partition,
    RobotEvent,
    Stall,
    parse_partition,
    parse_robot_event,
    parse_stall,
)


def _run(settings, n=2000, sender="a", seed=3):
    link = LinkEmulator("me", settings, np.random.default_rng(seed))
    out = []
    for i in range(n):
        link.admit(i.to_bytes(4, "big"), sender, now_s=i * 0.01)
        out += [int.from_bytes(p, "big") for p in link.release(i * 0.01)]
    out += [int.from_bytes(p, "big") for p in link.release(1e9)]
    return link, out


def test_perfect_network_is_transparent():
    link, out = _run(FaultSettings())
    assert out == list(range(2000))
    assert link.counters.dropped == link.counters.duplicated == 0


def test_loss_rate_is_within_its_binomial_band():
    link, out = _run(FaultSettings(drop=0.3))
    lost = 2000 - len(out)
    assert lost == link.counters.dropped
    # Binomial(2000, 0.3): std = sqrt(2000·0.3·0.7) ≈ 20.5; 4σ band
    assert abs(lost - 600) < 4 * 20.5
    assert out == sorted(out)


def test_delay_duplicates_and_reordering():
    link, out = _run(FaultSettings(delay_ms=50.0), n=100)
    assert out == list(range(100))
    link = LinkEmulator("me", FaultSettings(delay_ms=50.0), np.random.default_rng(0))
    link.admit(b"x", "a", now_s=1.0)
    assert link.release(1.049) == [] and link.release(1.05) == [b"x"]
    link, out = _run(FaultSettings(duplicate=0.5), n=400)
    assert len(out) == 400 + link.counters.duplicated and link.counters.duplicated > 100
    link, out = _run(FaultSettings(reorder=0.2), n=400)
    assert sorted(out) == list(range(400)) and out != list(range(400))
    swaps = sum(1 for a, b in itertools.pairwise(out) if a > b)
    assert swaps == link.counters.reordered


def test_partition_cuts_only_across_sides_and_only_in_its_window():
    part = parse_partition("a,b@10-20")
    settings = FaultSettings(partitions=(part,))
    link = LinkEmulator("me", settings, np.random.default_rng(0))
    link.admit(b"1", "a", now_s=15.0)  # across the cut: lost
    link.admit(b"2", "c", now_s=15.0)  # same side as "me": kept
    link.admit(b"3", "a", now_s=20.0)  # healed
    assert link.release(30.0) == [b"2", b"3"]
    assert link.counters.partitioned == 1


def test_parsing_and_validation_name_the_flag():
    assert parse_robot_event("air1@12.5", "--kill").at_s == 12.5
    with pytest.raises(ConfigError, match="--kill"):
        parse_robot_event("air1", "--kill")
    with pytest.raises(ConfigError, match="--partition"):
        parse_partition("a@20-10")
    with pytest.raises(ConfigError, match="drop"):
        FaultSettings(drop=1.5)
    with pytest.raises(ConfigError, match="no earlier"):
        FaultSettings(restarts=(parse_robot_event("a@5", "--restart"),))
    with pytest.raises(ConfigError, match="unknown robot"):
        FaultSettings(kills=(parse_robot_event("zz@5", "--kill"),)).check_robots(("a", "b"))


@pytest.mark.parametrize(
    ("kills", "restarts", "message"),
    [
        (["a@1", "a@2"], [], "--kill a@2.0: a is already down then (killed at 1 s)"),
        (["a@1"], ["a@1.5", "a@2"], "--restart a@2.0: a is not down then (restarted at 1.5 s)"),
        (["a@1"], ["a@1"], "--restart a@1.0: a is not down then (no earlier --kill)"),
    ],
)
def test_a_kill_or_restart_that_would_do_nothing_is_refused(kills, restarts, message):
    """These were accepted: the second restart reported as completed, the second kill as a
    fault of its own."""
    events = {
        "kills": tuple(parse_robot_event(k, "--kill") for k in kills),
        "restarts": tuple(parse_robot_event(r, "--restart") for r in restarts),
    }
    with pytest.raises(ConfigError, match=re.escape(message)):
        FaultSettings(**events)
    kill, restart = parse_robot_event("a@1", "--kill"), parse_robot_event("a@2", "--restart")
    again = parse_robot_event("a@3", "--kill")
    FaultSettings(kills=(kill, again), restarts=(restart,)).check_robots(("a", "b"))
    with pytest.raises(ConfigError, match="its side holds the whole team, so it separates"):
        FaultSettings(partitions=(parse_partition("b,a@1-2"),)).check_robots(("a", "b"))


def test_a_stall_holds_one_link_from_its_time_then_releases_it_in_order():
    stall = parse_stall("a,me@10:0.5")
    assert stall == Stall(sender="a", receiver="me", at_s=10.0, wall_s=0.5)
    link = LinkStall("me", (stall, parse_stall("a,other@0:1")), max_records=9, max_bytes=99)
    assert not link.hold("a", 9.9, "early", wall_s=100.0, size=1)  # before its time: not held
    assert link.next_due is None
    assert link.hold("a", 10.0, "a1", wall_s=100.0, size=1)  # the stall starts: 0.5 wall s
    assert not link.hold("b", 10.0, "b1", wall_s=100.1, size=1)  # another sender: never held
    assert link.hold("a", 10.1, "a2", wall_s=100.2, size=1)
    assert link.next_due == 100.5 and link.due(100.49) == []
    assert link.due(100.5) == ["a1", "a2"] and link.held == 2
    assert not link.hold("a", 10.2, "a3", wall_s=100.6, size=1)  # over: the link is fine again
    assert link.next_due is None


def test_what_a_stall_holds_at_the_end_of_a_run_is_released():
    link = LinkStall("me", (parse_stall("a,me@0:60"),), max_records=9, max_bytes=99)
    assert link.hold("a", 0.0, "a1", wall_s=0.0, size=1)
    assert link.due(None) == ["a1"] and link.due(None) == []


def test_a_flood_on_a_stalled_link_is_bounded_and_counted():
    link = LinkStall("me", (parse_stall("a,me@0:60"),), max_records=3, max_bytes=25)
    for i in range(10):  # taken either way: held up to the bounds, the rest dropped
        assert link.hold("a", 0.0, f"a{i}", wall_s=0.0, size=10)
    assert link.held == 2 and link.dropped == 8  # 2 × 10 bytes fit in 25
    assert link.due(None) == ["a0", "a1"]
    link = LinkStall("me", (parse_stall("a,me@0:60"),), max_records=3, max_bytes=10**6)
    for i in range(5):
        link.hold("a", 0.0, f"a{i}", wall_s=0.0, size=10)
    assert link.held == 3 and link.dropped == 2


def test_every_fault_writes_the_argument_it_was_parsed_from():
    assert parse_partition("a,b@0.1-2.5").arg == "a,b@0.1-2.5"
    assert parse_stall("a,b@3.0:0.5").arg == "a,b@3.0:0.5"
    assert parse_robot_event("x@3.25", "--kill").arg == "x@3.25"
    stall = parse_stall("a,b@0.30000000000000004:1e-05")
    assert parse_stall(stall.arg) == stall  # exact, whatever the float


def test_stalls_lose_nothing_so_the_network_stays_perfect():
    settings = FaultSettings(stalls=(parse_stall("a,b@1:0.5"),))
    assert not settings.network_faulty
    assert settings.to_dict()["stalls"] == [
        {"sender": "a", "receiver": "b", "at_s": 1.0, "wall_s": 0.5}
    ]
    with pytest.raises(ConfigError, match="unknown robot 'zz'"):
        FaultSettings(stalls=(parse_stall("a,zz@1:0.5"),)).check_robots(("a", "b"))


@pytest.mark.parametrize(
    ("text", "why"),
    [
        ("a,b@1", "missing"),
        ("a@1:2", "missing"),
        ("a,a@1:2", "both"),
        ("a,b@-1:2", r"time \(s\): must be a finite number in \[0, inf\)"),
        ("a,b@1:0", r"wall time \(s\): must be a finite number in \(0, 60\]"),
        ("a,b@1:61", r"wall time \(s\): must be a finite number in \(0, 60\]"),
        ("a,b@nan:1", r"time \(s\): must be a finite number in \[0, inf\)"),
        ("a,b c@1:1", "valid id"),
    ],
)
def test_a_bad_stall_names_the_flag_and_why(text, why):
    with pytest.raises(ConfigError, match=f"--stall.*{why}"):
        parse_stall(text)


FLAG_TEXT = st.text(alphabet="ab,@:-.0123456789 einf", max_size=16)


@settings(max_examples=300, deadline=None, derandomize=True)
@given(text=FLAG_TEXT)
def test_fault_flags_parse_or_name_the_flag(text):
    """Whatever is typed after ``--stall``, ``--partition`` or ``--kill``: a valid fault, or a
    ConfigError naming the flag — never another exception."""
    for parse, flag, kind in (
        (parse_stall, "--stall", Stall),
        (parse_partition, "--partition", Partition),
        (lambda t: parse_robot_event(t, "--kill"), "--kill", RobotEvent),
    ):
        try:
            assert isinstance(parse(text), kind)
        except ConfigError as exc:
            assert flag in str(exc)


@pytest.mark.parametrize(
    ("scenario", "flags", "message"),
    [
        ("desilva2015", ["--kill", "ZZ@1"], "unknown robot 'ZZ'"),
        ("sharma2013", ["--stall", "1,ZZ@1:0.5"], "unknown robot 'ZZ'"),
        ("runtime-test-trio", ["--partition", "ZZ@1-2"], "unknown robot 'ZZ'"),
        ("guler2023", ["--stall", "a,b@1:0.5"], "do not emulate link stalls"),
        ("desilva2015", ["--kill", "L1@50"], "--kill L1@50.0: begins at or after the run's end"),
        ("runtime-test-trio", ["--partition", "observer@2-3"], "observer@2.0-3.0: begins at or"),
        ("default", ["--duration", "2"], "--duration: default does not read it; read by guler2023"),
        ("sharma2013", ["--stall", "1,2@2.5:1"], "--stall 1,2@2.5:1.0: begins at or after"),
    ],
)
def test_team_up_refuses_a_fault_it_cannot_apply_before_starting(
    tmp_path, capsys, trio_scenario, scenario, flags, message
):
    """Reproductions run 2 s here; the three-robot scenario file 2 s of its own."""
    if scenario == "runtime-test-trio":
        scenario = str(trio_scenario(2.0))
    else:
        flags = ["--duration", "2", *flags] if scenario != "default" else flags
    argv = ["team", "up", scenario, "--out", str(tmp_path / "out")]
    assert main([*argv, *flags, "--quiet"]) == 2
    assert message in capsys.readouterr().err
