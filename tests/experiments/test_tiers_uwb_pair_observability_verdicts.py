"""The observability verdict of ``relloc reproduce tiers-uwb``'s pairs
(:func:`relloc.experiments.tiers_uwb_pairs.observability`, the range-only seed-000 model's rank
along the recorded relative states and odometry) on hand-built two-robot recordings: full rank
along the whole stretch (the real bag never reaches it), at half of it, and nowhere.

Robot a circles at v = 0.5 m/s, ω = 0.3 rad/s (from 5 s on in the half case, standing before);
robot b drives along +x at 0.5 m/s from (1, 2). The rank needs both robots moving (the model's
generic condition ``v_l ≠ 0 and v_c ≠ 0``) and b off a's sensor plane: at equal heights the
range cannot tell z from −z and the rank is 3 of 4 at every instant."""

from __future__ import annotations

import numpy as np

from relloc.core.recording import GroundTruth, Odometry, Recording, empty_measurements
from relloc.experiments.tiers_uwb_pairs import OBSERVABILITY_SAMPLES, observability

T = np.linspace(0.0, 10.0, 1001)
SIGMA = np.array([0.05, 0.0, 0.0, 0.05])
V, W = 0.5, 0.3
GENERIC = "generic rank 4 of 4; needs v_l ≠ 0 and v_c ≠ 0"


def _recording(b_height: float, a_starts_s: float = 0.0) -> Recording:
    moving = T >= a_starts_s
    heading = W * np.where(moving, T - a_starts_s, 0.0)
    a_pose = np.column_stack(
        [V / W * np.sin(heading), V / W * (1 - np.cos(heading)), np.zeros(T.size), heading]
    )
    a_velocity = np.where(moving[:, None], [V, 0.0, 0.0, W], 0.0)
    b_pose = np.column_stack(
        [1.0 + 0.5 * T, np.full(T.size, 2.0), np.full(T.size, b_height), np.zeros(T.size)]
    )
    b_velocity = np.tile([0.5, 0.0, 0.0, 0.0], (T.size, 1))
    return Recording(
        robots=("a", "b"),
        platforms=("ground", "ground"),
        odometry=(
            Odometry(t=T, velocity=a_velocity, sigma=SIGMA),
            Odometry(t=T, velocity=b_velocity, sigma=SIGMA),
        ),
        measurements=empty_measurements(),
        truth=(GroundTruth(t=T, pose=a_pose), GroundTruth(t=T, pose=b_pose)),
    )


def test_both_moving_off_the_plane_is_observable_along_the_whole_stretch() -> None:
    assert observability(_recording(b_height=1.0), 0, 1, 2.0, 8.0) == {
        "verdict": "observable along the whole stretch",
        "full_rank_share": 1.0,
        "max_rank": 4,
        "state_dim": 4,
        "samples": OBSERVABILITY_SAMPLES,
        "generic_conditions": GENERIC,
    }


def test_an_observer_standing_for_the_first_half_gives_the_share_of_instants() -> None:
    """40 instants over [2, 8] s, t_k = 2 + 6k/39: the 20 before 5 s (a standing) are short
    of full rank, the 20 after are not — 50 %."""
    assert OBSERVABILITY_SAMPLES == 40
    verdict = observability(_recording(b_height=1.0, a_starts_s=5.0), 0, 1, 2.0, 8.0)
    assert verdict["verdict"] == "observable at 50 % of the sampled instants"
    assert verdict["full_rank_share"] == 0.5 and verdict["max_rank"] == 4


def test_robots_at_one_height_are_unobservable_with_the_highest_rank_seen() -> None:
    verdict = observability(_recording(b_height=0.0), 0, 1, 2.0, 8.0)
    assert verdict["verdict"] == "unobservable along this stretch (rank ≤ 3 of 4)"
    assert verdict["full_rank_share"] == 0.0 and verdict["max_rank"] == 3
