"""Which robots sense in the seed-002 scenario (``DeSilvaScenario.sensing``, ``--sensing``).

The paper's leaders L1, L2 sense; ``--sensing all`` makes the pods scan too. These tests check
the simulator's scans, the flag's parsing and that the figures are of the sensing robots.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from relloc.core.recording import kind_code
from relloc.errors import ConfigError
from relloc.experiments.desilva2015 import (
    DURATION_S,
    FINAL_WINDOW_S,
    TRACKED_FRACTION,
    RunConfig,
    _task,
    kidnap_metrics,
    metrics,
    sensing_robots,
)
from relloc.experiments.desilva2015_team import tracked_at_end
from relloc.pipeline.montecarlo import spawn_seeds
from relloc.sim.multihypothesis import ROBOT_NAMES, DeSilvaScenario, simulate


@pytest.mark.parametrize("sensing", [(), (1, 0), (0, 0), (0, 5), (-1, 0)])
def test_bad_sensing_sets_are_refused(sensing: tuple[int, ...]) -> None:
    with pytest.raises(ConfigError, match=r"DeSilvaScenario\.sensing"):
        DeSilvaScenario(sensing=sensing)


def test_sensing_robots_read_the_flag() -> None:
    assert sensing_robots(None) == (0, 1) == DeSilvaScenario().sensing
    assert sensing_robots("all") == (0, 1, 2, 3, 4)
    assert sensing_robots("P1, L1") == (0, 2)
    with pytest.raises(ConfigError, match="--sensing"):
        sensing_robots("L3")


@pytest.mark.parametrize("sensing", [(0, 1), (1, 3), (0, 1, 2, 3, 4)])
def test_only_the_sensing_robots_scan_and_platforms_stay(sensing: tuple[int, ...]) -> None:
    scenario = DeSilvaScenario(duration=2.0, sensing=sensing)
    rec = simulate(scenario, np.random.default_rng(3))
    m = rec.measurements
    for kind in ("height", "range", "bearing_elevation"):
        rows = m.kind == kind_code(kind)
        assert set(np.unique(m.observer[rows]).tolist()) == set(sensing), kind
    # every scan: one height per teammate (always available) at every direct-fusion tick
    heights = m.kind == kind_code("height")
    scans = round(scenario.duration * scenario.direct_rate)
    assert heights.sum() == scans * len(sensing) * (len(ROBOT_NAMES) - 1)
    assert rec.platforms == ("ground", "ground", "aerial", "aerial", "aerial")


def test_figures_are_those_of_the_sensing_robots() -> None:
    scenario = DeSilvaScenario(duration=3.0, sensing=(1, 3))
    result = _task(spawn_seeds(5, 1)[0], 0, RunConfig(scenario=scenario))
    assert result.observers == (1, 3)
    assert result.pos_err.shape[0] == 2
    # an observer's own column is empty
    assert np.isnan(result.pos_err[0, :, 1]).all() and np.isnan(result.pos_err[1, :, 3]).all()
    pairs = set(metrics([result])["per_pair"])
    assert pairs == {f"L2->{n}" for n in ("L1", "P1", "P2", "P3")} | {
        f"P2->{n}" for n in ("L1", "L2", "P1", "P3")
    }
    # a kidnapped sensing robot is scored by the others only: P2 (robot 3) is the observer of
    # row 1, whose own column is never tracked; with L2 tracking everyone P2 is re-found in all
    tracked = np.ones_like(result.tracked)
    tracked[0, :, 1] = tracked[1, :, 3] = False
    everyone = dataclasses.replace(result, tracked=tracked)
    kidnap = (3, 1.0, 3.0, -2.0, 2.0)
    assert kidnap_metrics([everyone], kidnap)["refound_rate"] == 1.0
    assert tracked_at_end([everyone], 3) == 1.0


#: Root seed of this test, not used while developing ``--sensing`` (development used the
#: children of 99 and of 73019); its first two children, not hand-picked. A first version of the
#: test ran 15 s with a 4 s final window on the children of 73019 and failed on its run 1: L1's
#: and P3's filters of L2 were tracked in 0.63 and 0.51 of the last scans. Traced in L1's filter:
#: each 1 s fusion pulled the dominant track to the true yaw with a small covariance (σ_ψ about
#: 0.02 rad), and within the next scans L1's own readings gave the weight back to a broader
#: component about 0.9 rad off in yaw, both within 0.2 m in position (with only confirmed filters
#: shared, or no indirect fusion, all 20 filters were tracked). The test now runs
#: the experiment's own duration and criterion, under which the reproduction (seed 2026,
#: 25 runs, ``--sensing all``) found every teammate in every run.
EVERY_ROBOT_SEEDS = spawn_seeds(60611, 2)


@pytest.mark.slow
@pytest.mark.parametrize("run", range(len(EVERY_ROBOT_SEEDS)))
def test_with_every_robot_sensing_every_filter_finds_its_teammate(run: int) -> None:
    """The experiment's criterion (tracked in ≥ 90 % of the scans of the last 10 s of 30 s)
    for all 20 filters, with seed 002's sharing."""
    scenario = DeSilvaScenario(duration=DURATION_S, sensing=(0, 1, 2, 3, 4))
    result = _task(EVERY_ROBOT_SEEDS[run], run, RunConfig(scenario=scenario))
    final = result.times >= result.times[-1] - FINAL_WINDOW_S
    frac = result.tracked[:, final, :].mean(axis=1)
    for li, observer in enumerate(result.observers):
        others = [j for j in range(len(ROBOT_NAMES)) if j != observer]
        assert np.all(frac[li, others] >= TRACKED_FRACTION), frac
