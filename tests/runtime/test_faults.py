"""Link emulator and fault settings: loss, delay, duplicates, reordering, partitions, parsing."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from relloc.errors import ConfigError
from relloc.runtime.faults import (
    FaultSettings,
    LinkEmulator,
    parse_partition,
    parse_robot_event,
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
