"""Building blocks of the two observability reproductions (the full runs are CLI acceptance)."""

from __future__ import annotations

import numpy as np
import pytest

from relloc.experiments import sharma_observability as sharma
from relloc.experiments import wanasinghe_observability as wanasinghe


def test_printed_equation_checks() -> None:
    checks = wanasinghe._equation_checks()
    assert {k: v["agrees"] for k, v in checks.items()} == {
        "eq16_gradient_row1": False,
        "eq20_det_H_pmo": False,
        "eq21_gram_grad_phi_L_f2_h": False,
        "eq30_gram_bearing_rows": True,
        "eq31_gram_grad_phi_L_f2_h2": True,
    }
    assert checks["eq20_det_H_pmo"]["ours"] == "1"
    assert checks["eq21_gram_grad_phi_L_f2_h"]["ours"] == "2"


def test_vertical_velocity_counterexamples() -> None:
    cases = wanasinghe._vertical_counterexamples(samples=2, seed=0)
    for case in cases.values():
        assert case["rank"] == 3 and case["agrees"] is False
        assert case["evidence"]["rank_horizontal"] == 4
        assert case["unobservable_directions"] == ["(x, y, z, phi) ∝ (0, 0, 0, 1)"]


@pytest.mark.parametrize("case", list(sharma.TEAM_CASES))
def test_random_team_cases_have_the_theorem_rank(case: str) -> None:
    seed = np.random.SeedSequence(11).spawn(1)[0]
    out = sharma.random_team_task(seed, 0, case)
    assert out["rank"] == out["expected_rank"] == sharma.TEAM_CASES[case][1]
    assert len(out["directions"]) == 15 - out["rank"]


def test_fig2_connectivity_changes_and_beta_matches_full_rank() -> None:
    series = sharma.fig2_series(duration=30.0, every=20)
    beta = series["beta"]
    assert beta[0] == 1 and beta.min() == 0  # the team starts connected, then splits
    assert series["agreement_fraction"] == 1.0
    assert np.all(series["sigma_min"][beta == 0] == 0.0)
    assert np.all(series["sigma_min"][beta == 1] > 0.0)
