"""``relloc reproduce sharma-observability``'s Fig. 2 scenario and PCRLB on hand-derived
facts: the first commands of the waypoint controller (``fig2_trajectories``: 5 m/s, turn rate
1.5 × the heading error within ±0.6 rad/s, 0.3 rad/s circling within 10 m of the waypoint),
bounds that any filter must respect (``team_bounds``), and the report's condition texts
(``_conditions_text``)."""

from __future__ import annotations

import math

import numpy as np

from relloc.experiments.sharma_observability import _conditions_text, fig2_trajectories, team_bounds


def test_first_commands_head_for_the_first_waypoints() -> None:
    """Robot 1 at (20, −20) facing 0 sees its waypoint (40, 20) at atan2(40, 20) = 1.107 rad:
    saturated at +0.6; robot 2 at (60, −30) facing 0.5 sees (150, −100) at −0.661 rad, an
    error of −1.161: −0.6; robot 3 at (90, 10) facing 0 sees (320, 40) at atan2(30, 230) =
    0.1297 rad: 1.5 × 0.1297; robots 4 and 5 start on their waypoints: circle at 0.3."""
    P, U, t = fig2_trajectories(0.1)
    np.testing.assert_allclose(t, [0.0, 0.1])
    np.testing.assert_allclose(U[0, :, 0], 5.0)
    np.testing.assert_allclose(U[0, :, 1], [0.6, -0.6, 1.5 * math.atan2(30.0, 230.0), 0.3, 0.3])
    # the first step turns each robot by ω·Ts
    np.testing.assert_allclose(P[1, :, 2] - P[0, :, 2], 0.1 * U[0, :, 1], atol=1e-12)


def test_bounds_respect_the_gps_fix_and_the_unobservable_translation() -> None:
    """With GPS on robot 1 (σ 1 m every step, with the 5 m prior) its position bound is below
    1 m from the first step on. With no landmark the team's common translation is known from
    the five 5 m priors only: the mean x has variance ≥ 25/5, and the largest robot variance
    is at least the mean's, so some robot's √B_x is ≥ √5 m."""
    gps = team_bounds(0.2, robot=0)["GPS on robot 1"]
    assert np.all(gps[:, :2] < 1.0)
    largest = max(float(team_bounds(0.2, robot=r)["no landmarks"][0, 0]) for r in range(5))
    assert largest >= math.sqrt(5.0)


def test_condition_texts() -> None:
    assert _conditions_text(None) == "not enumerated"
    assert _conditions_text([["robot 2 moving"], []]) == "no motion needed"
    assert (
        _conditions_text([["robot 1 moving", "robot 2 moving"], ["robot 3 moving"]])
        == "robot 1 moving and robot 2 moving or robot 3 moving"
    )


def test_report_states_the_fig2_shares_and_the_bound_table() -> None:
    from relloc.experiments.sharma_observability import _report

    edge = {
        "rank": 3,
        "state_dim": 6,
        "conditions": [["v_2"]],
        "unobservable_directions": ["translation"],
        "paper_claim": "Lemma 1",
        "agrees": True,
        "evidence": {"rank_at": {"generic": 3, "V_j = 0": 2}},
    }
    summary = {
        "seed": 2,
        "runs": 4,
        "cases": {"edge_robot_robot": edge, "edge_robot_landmark": edge | {"agrees": False}},
        # β = 1 at 3 of 4 instants; rank 3n and β = 1 agree at 2 of them
        "fig2": {"t": [0.0, 0.5, 1.0, 1.5], "beta": [1, 1, 0, 1], "agreement_fraction": 0.5},
        "pcrlb_robot2": {
            "two landmarks": {
                "sqrt_bound_final": [1.5, 2.5, 0.05],
                "sqrt_bound_mean_second_half": [1.25, 2.25, 0.04],
            }
        },
        "timing_s": {"fig2": 1.5},
    }
    md = _report(summary, [])
    assert (
        "β(G) = 1 during 75 % of the run; 'β = 1 ⇔ rank 3n' holds at 50.0 % of the 4 "
        "evaluated instants" in md
    )
    assert "| edge_robot_robot | 3/6 | v_2 | translation | Lemma 1 | agrees |" in md
    assert "| edge_robot_landmark | 3/6 | v_2 | translation | Lemma 1 | DISAGREES |" in md
    assert "| two landmarks | 1.5 | 2.5 | 0.05 | 1.25 | 2.25 | 0.04 |" in md
    assert "| V_j = 0 | 2 |" in md


def test_moving_sets_are_not_enumerated_beyond_the_first_ten_teams() -> None:
    from relloc.experiments.sharma_observability import CONDITION_RUNS, random_team_task

    assert CONDITION_RUNS == 10
    seed = np.random.SeedSequence(5).spawn(1)[0]
    # the eleventh team (run index 10) is not enumerated
    assert random_team_task(seed, 10, "theorem2_connected_no_landmarks")["moving_sets"] is None
