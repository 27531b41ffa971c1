"""The report texts of the rarer outcomes, from small summary parts shaped like the real ones:
a run-averaged NEES band with a verdict, a pair never confirmed, the conditioning bound
reached, a yaw error from the initial guess, a bound the model allows, a table with no value,
no minimal moving set, an estimator that output nothing."""

from __future__ import annotations

import numpy as np

from relloc.core.estimates import Estimates
from relloc.experiments.desilva2015 import _band_verdict
from relloc.experiments.guler2023 import _band_text
from relloc.experiments.mrclam_association import _verdict
from relloc.experiments.sharma2013_team import accuracy
from relloc.experiments.sharma_observability import _named_sets
from relloc.experiments.wanasinghe2014_pairs import _median_range
from relloc.experiments.wanasinghe2014_report import (
    _replay_yaw_cause,
    _yaw_bound_text,
    conditioning_text,
)
from relloc.metrics import run_average_band


def test_a_judged_run_average_band_is_stated_with_its_shares() -> None:
    rng = np.random.default_rng(0)
    band = run_average_band(1.3 * rng.chisquare(2, size=(20, 200)), 2)
    assert band["verdict"] == "over-confident"
    assert _band_verdict(band) == (
        "over-confident by the NEES averaged over the 20 runs at each scan: 72 % of the scans "
        "inside its 95 % band [1.22, 2.97], 0 % below, 28 % above"
    )
    assert _band_text(band) == "72 / 0 / 28: over-confident"
    single = run_average_band(rng.chisquare(2, size=(1, 200)), 2)
    assert _band_verdict(single) == f"not judged ({single['reason']})"
    assert _band_text(single) == f"— ({single['reason']})"


def test_a_pair_never_confirmed_is_not_measured() -> None:
    assert _verdict(None, 0.9) == "not measured (no confirmed track)"
    assert _verdict(0.95, 0.9) == "0.950, met"
    assert _verdict(0.5, 0.9) == "0.500, missed"


def test_conditioning_reaching_the_bound_names_the_cases() -> None:
    def summary(worst: dict[str, float]) -> dict[str, object]:
        return {
            "table4": {
                "calibrated": {
                    c: {"max_conditioning": {"P": v, "R": 1.0, "S": 2.0}} for c, v in worst.items()
                }
            }
        }

    text = conditioning_text(summary({"case1": 6.4, "case2": 3.0, "case3": 7.0}))
    assert "case1 6.40, case2 3.00, case3 7.00. " in text
    assert "In case1, case3 P reaches 6: the observed robot's height is constant" in text
    assert text.endswith("the yaw variance stays large; R and S stay well conditioned.")
    assert "All stay below 6" not in text
    assert conditioning_text(summary({"case1": 5.9})).endswith("All stay below 6, as in the paper.")


def test_a_yaw_bank_well_below_the_plkf_blames_the_initial_guess() -> None:
    def summary(plkf: float, bank: float) -> dict[str, object]:
        case1 = {"case1": {"phi": {"rmse_mean": plkf}}}
        return {
            "table3": {"calibrated": case1},
            "table3_best": {"calibrated": {"case1": {"phi": {"rmse_mean": bank}}}},
        }

    assert _replay_yaw_cause(summary(0.2, 0.1)) == (
        "Part of it is the initial guess: the yaw bank from the same pose reaches 0.100 rad in "
        "case 1; the rest is odometry drift the slow motion cannot correct."
    )
    assert _replay_yaw_cause(summary(0.2, 0.15)).startswith(
        "The yaw bank from the same pose gives 0.150 rad in case 1, so the initial guess is not"
    )


def test_a_yaw_bound_the_model_allows_says_the_filter_misses_it() -> None:
    targets = {
        c: {"yaw_bound_ok": ok, "yaw_bound_rad": b, "yaw_rmse_rad": r}
        for c, ok, b, r in (("case1", True, 0.05, 0.15), ("case2", True, 0.04, 0.16))
    }
    text = _yaw_bound_text(targets, ["case1", "case2"])
    assert "is case1 0.050, case2 0.040 rad there" in text
    assert text.endswith("RMSE is 3.000–4.000 times it: the model allows the target and the "
                         "filter misses it. ")  # fmt: skip
    targets["case2"]["yaw_bound_ok"] = False
    assert ": in case2 the model itself does not allow 0.10 rad" in _yaw_bound_text(
        targets, ["case1", "case2"]
    )


def test_a_table_cell_without_values_is_a_dash() -> None:
    assert _median_range([], 3) == "—"
    assert _median_range([0.2, 0.1, 0.4], 2) == "0.20 (0.10–0.40)"


def test_no_minimal_moving_set_stays_none() -> None:
    assert _named_sets(None) is None
    assert _named_sets([[0, 2]]) == [["robot 1 moving", "robot 3 moving"]]


def test_an_estimator_that_output_nothing_scores_no_records() -> None:
    assert accuracy(Estimates(estimator="sharma2013"), None) == {  # type: ignore[arg-type]
        "pos_rmse_m": None,
        "heading_rmse_rad": None,
        "records": 0,
    }
