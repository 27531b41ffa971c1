"""``relloc reproduce sharma2013``'s ``observability_rank`` entries (``observability_ranks``)
for a two-robot team seen at one instant: the paper's predicted ranks (Theorems 2–4:
3(n − 1) with no landmark, 3n − 1 with one, 3n with two or with GPS) beside the ranks of the
nonlinear observability matrix, and the edges used."""

from __future__ import annotations

import numpy as np

from relloc.experiments.sharma2013 import observability_ranks


def test_two_robots_each_seeing_the_other_and_a_landmark() -> None:
    first = {
        # both robots see each other (one tree edge); robot 1 sees landmark 1, robot 2 landmark 2
        "mid_edges": {"robots": [(0, 1), (1, 0)], "landmarks": [(0, 0), (1, 1)]},
        "landmarks_xy": np.array([[10.0, 5.0], [-20.0, 30.0]]),
        "mid_state": np.array([[0.0, 0.0, 0.3], [15.0, -4.0, 1.2]]),
        "mid_inputs": np.array([[5.0, 0.1], [5.0, -0.2]]),
    }
    ranks = observability_ranks(first, 2)
    expected = {
        "no_landmark": (3, 3, 0),
        "one_landmark": (5, 5, 1),
        "two_landmarks": (6, 6, 2),
        "gps_robot1": (6, 6, 0),
    }
    for case, (paper, rank, landmark_edges) in expected.items():
        r = ranks[case]
        assert (r["paper_rank"], r["rank"], r["landmark_edges"]) == (paper, rank, landmark_edges)
        assert r["state_dim"] == 6 and r["robot_edges"] == 1
        assert r["full_rank"] is (rank == 6)
