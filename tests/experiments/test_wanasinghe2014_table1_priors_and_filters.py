"""Table 1's set-up in the seed-000 simulation (:mod:`relloc.experiments.wanasinghe2014_sim`):
which filters each case runs, the priors of cases 2–4 built from the same fixed guesses
(case 2: true position, the guess's yaw; case 3: the guess's position, true yaw; case 4: the
guess), and the error arrays gathered per case, filter and guess in guess order."""

from __future__ import annotations

import math

import numpy as np

from relloc.experiments.wanasinghe2014_sim import (
    ACCURACY,
    SimSettings,
    _table1_errors,
    _table1_filters,
    table1_label,
    table1_priors,
)
from relloc.pipeline.evaluation import SeriesEvaluation


def test_the_filters_of_each_case() -> None:
    assert _table1_filters("case1") == ("TEKF",)  # its PLKF is the accuracy filter
    assert _table1_filters("case2") == ("PLKF", "TEKF", "bank")
    assert _table1_filters("case3") == ("PLKF", "TEKF")  # known yaw: the bank is the PLKF
    assert _table1_filters("case4") == ("PLKF", "TEKF", "bank")
    assert table1_label("case4", "bank", 12) == "table1/case4/bank/guess12"


def test_cases_2_to_4_share_the_guesses() -> None:
    settings = SimSettings(n_poses=5)
    truth0 = np.array([4.0, -1.0, 2.0, 0.3])
    priors = table1_priors(truth0, settings, np.random.default_rng(46031))  # seed: case 1 only
    assert len(priors["case1"]) == 1
    assert all(len(priors[c]) == 5 for c in ("case2", "case3", "case4"))
    for (m2, c2), (m3, _), (m4, c4) in zip(
        priors["case2"], priors["case3"], priors["case4"], strict=True
    ):
        np.testing.assert_allclose(m2[:3], truth0[:3])
        assert m2[3] == m4[3]
        np.testing.assert_allclose(m3[:3], m4[:3])
        assert m3[3] == truth0[3]
        # an unknown yaw: σ = π/√3 in cases 2 and 4
        assert c2[3, 3] == c4[3, 3] == (math.pi / math.sqrt(3.0)) ** 2
    # the guesses differ in yaw
    assert len({float(m[3]) for m, _ in priors["case4"]}) == 5


def _scored(value: float) -> SeriesEvaluation:
    k = 3
    return SeriesEvaluation(
        owner="observer",
        subject="aerial1",
        track="t",
        platform="aerial",
        frame="relative_pose4",
        t=np.arange(k, dtype=float),
        error=np.full((k, 4), value),
        sigma=np.ones((k, 4)),
        nees=np.ones(k),
        age=np.arange(k, dtype=float),
        cond_p=np.ones(k),
        update_t=np.arange(k, dtype=float),
        update_age=np.arange(k, dtype=float),
        nis=np.ones(k),
        nis_dof=np.full(k, 3),
        cond_r=np.ones(k),
        cond_s=np.ones(k),
    )


def test_the_errors_are_gathered_per_case_filter_and_guess() -> None:
    """Two guesses; the filter of guess g has error g + 10·case + 100·(filter index)."""
    settings = SimSettings(n_poses=2)
    scored = {("aerial1", ACCURACY): _scored(-1.0)}
    for c, case in enumerate(("case1", "case2", "case3", "case4"), start=1):
        for f, filt in enumerate(_table1_filters(case)):
            for g in range(1 if case == "case1" else 2):
                scored[("aerial1", table1_label(case, filt, g))] = _scored(g + 10 * c + 100 * f)
    out = _table1_errors(scored, settings)
    assert set(out["case1"]) == {"PLKF", "TEKF"} and out["case1"]["PLKF"].shape == (1, 3, 4)
    assert out["case1"]["PLKF"][0, 0, 0] == -1.0 and out["case1"]["TEKF"][0, 0, 0] == 10.0
    assert out["case4"]["bank"].shape == (2, 3, 4)
    assert out["case4"]["bank"][:, 0, 0].tolist() == [240.0, 241.0]
    assert out["case3"]["TEKF"][:, 0, 0].tolist() == [130.0, 131.0]
    assert set(out["case3"]) == {"PLKF", "TEKF"}
