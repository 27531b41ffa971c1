"""The team reproductions' sources (``relloc.experiments.team_sources``): which run's seed a
process simulates, when the kidnapped-robot scenario moves its pod in a shortened run, and the
scenario a team name and its options give."""

from __future__ import annotations

import numpy as np
import pytest

from relloc.experiments import team_sources
from relloc.experiments.desilva2015 import sensing_robots


def _state(seq: np.random.SeedSequence) -> list[int]:
    return [int(v) for v in seq.generate_state(4)]


@pytest.mark.parametrize("run", [0, 1, 3])
def test_run_i_of_seed_s_is_child_i_of_the_seed_sequence(run: int) -> None:
    """Documented: run ``i`` of seed ``S`` is ``SeedSequence(S).spawn(n)[i]``."""
    expected = np.random.SeedSequence(7).spawn(5)[run]
    assert _state(team_sources.run_seed(7, run)) == _state(expected)
    assert _state(team_sources.run_seed(7, 0)) != _state(team_sources.run_seed(7, 1))


@pytest.mark.parametrize(
    ("duration", "when"),
    [(30.0, 15.0), (60.0, 15.0), (100.0, 15.0), (20.0, 10.0), (8.0, 4.0)],
)
def test_the_kidnap_is_at_15_s_or_at_half_a_shorter_run(duration: float, when: float) -> None:
    """P2 (robot 3) moved by (3 m, −2 m, 2 rad) at 15 s, or at half the run when it is shorter
    than 30 s; never later in a longer run."""
    assert team_sources.kidnap_of(duration) == (3, when, 3.0, -2.0, 2.0)


def test_the_scenario_of_each_team_name() -> None:
    plain = team_sources.desilva_scenario("desilva2015", 12.0)
    assert plain.duration == 12.0 and plain.kidnap is None
    assert plain.sensing == sensing_robots(None)
    kidnapped = team_sources.desilva_scenario("desilva2015-kidnapped", 12.0)
    assert kidnapped.duration == 12.0 and kidnapped.kidnap == (3, 6.0, 3.0, -2.0, 2.0)
    paper = team_sources.desilva_scenario("desilva2015-kidnapped", None)
    assert paper.duration == 30.0 and paper.kidnap == (3, 15.0, 3.0, -2.0, 2.0)
    assert team_sources.desilva_scenario("desilva2015", None).duration == 30.0


def test_the_sensing_robots_given_replace_the_leaders() -> None:
    assert team_sources.desilva_scenario("desilva2015", 5.0, (0, 2)).sensing == (0, 2)
    assert team_sources.desilva_scenario("desilva2015", 5.0, (4,)).sensing == (4,)


def test_a_sharma_agent_records_every_half_second() -> None:
    """Seed 001's agents record every robot's pose every 0.5 s (the in-process rate)."""
    parts = team_sources.sharma_node_parts("2", 0, 0, 2.0, "two_landmarks")
    times = parts.driver.record_times(0.0, 2.0, True, None)
    np.testing.assert_array_equal(times, [0.0, 0.5, 1.0, 1.5, 2.0])
