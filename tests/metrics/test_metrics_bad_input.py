"""Hostile input to every public metric: arrays that are not real numbers, infinite entries,
degenerate shapes and settings of the wrong type or range give a DataError or ConfigError naming
the function and the argument, never a raw numpy error, a silent NaN or a wrong answer."""

from __future__ import annotations

import numpy as np
import pytest

from relloc.errors import ConfigError, DataError
from relloc.metrics import (
    anees,
    chi2_upper,
    clopper_pearson,
    condition_log10_batch,
    integrated_time,
    mean_chi2_band,
    nees,
    paper_thresholds,
    percent_beyond,
    percent_beyond_interval,
    projected_nees,
    radial_errors,
    rmse,
    run_average_band,
    state_errors,
    updates_to_converge,
    updates_to_converge_per_state,
)

NAN, INF = float("nan"), float("inf")
E2 = np.eye(2)
T3 = [0.0, 1.0, 2.0]


@pytest.mark.parametrize(
    ("call", "message"),
    [
        # each was a raw ValueError or TypeError, or read None as NaN, True as 1, 1+1j as 1
        (lambda: nees(["a", "b"], E2), "NEES/NIS: vector"),
        (lambda: nees([1.0, 0.0], "ab"), "NEES/NIS: covariance"),
        (lambda: nees([True, False], E2), "NEES/NIS: vector"),
        (lambda: projected_nees(["a", "b"], E2, [[1.0], [0.0]]), "projected_nees: error"),
        (lambda: anees(["a"], 2), "anees: nees_values"),
        (lambda: anees(None, 2), "anees: nees_values"),  # was NaN
        (lambda: anees([[1.0, 2.0], [1.0]], 2), "anees: nees_values"),
        (lambda: anees(np.array([1 + 1j]), 2), "anees: nees_values"),
        (lambda: run_average_band([["a", "b"], ["c", "d"]], 2), "run_average_band: nees_runs"),
        (lambda: percent_beyond(["a"], 1.0), "percent_beyond: values"),
        (lambda: percent_beyond(None, 1.0), "percent_beyond: values"),  # was NaN
        (lambda: integrated_time("abc"), "integrated_time: series"),
        (lambda: percent_beyond_interval(["a"] * 3, T3, 1.0), "percent_beyond_interval: values"),
        (lambda: percent_beyond_interval([1.0] * 3, "abc", 1.0), "percent_beyond_interval: times"),
        (lambda: condition_log10_batch("abc"), "condition_log10_batch: M"),
        (lambda: paper_thresholds("ab"), "paper_thresholds: known_init_rmse"),
        (lambda: updates_to_converge(["a"], 0.05), "updates_to_converge: series"),
        (lambda: updates_to_converge(None, 0.05), "updates_to_converge: series"),  # was None
        (lambda: state_errors(["a"] * 4, ["b"] * 4), "state_errors: estimate"),
        (lambda: rmse(["a"]), "rmse: errors"),
        (lambda: rmse(None), "rmse: errors"),
        (lambda: radial_errors(["a"] * 3, ["b"] * 3), "radial_errors: estimate"),
    ],
)
def test_arrays_that_are_not_real_numbers_are_a_data_error(call, message) -> None:
    with pytest.raises(DataError, match=f"{message}: expected"):
        call()


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda: chi2_upper(2, None), r"chi2_upper: p"),  # raw TypeError
        (lambda: chi2_upper(2, "0.9"), r"chi2_upper: p"),  # was read as 0.9
        (lambda: mean_chi2_band(2, 3, [0.9]), r"mean_chi2_band: p"),
        (
            lambda: chi2_upper(10**400),
            r"chi2_upper: dof: must be in 1…9007199254740992",
        ),  # Overflow
        (lambda: mean_chi2_band(10**10, 10**10), r"mean_chi2_band: dof · n_samples: must be in 1…"),
        (lambda: run_average_band(np.ones((3, 5)), 2, "0.9"), r"run_average_band: p"),
        (lambda: run_average_band(np.ones((1, 5)), 2, NAN), r"run_average_band: p"),  # unchecked
        (lambda: run_average_band(np.ones((1, 5)), 0), r"run_average_band: dof"),
        (lambda: clopper_pearson(1, 5, None), r"clopper_pearson: confidence"),
        (lambda: clopper_pearson(None, 5, 0.9), r"clopper_pearson: successes"),
        (lambda: clopper_pearson(1, "5", 0.9), r"clopper_pearson: size"),
        (lambda: clopper_pearson(1, 1e300, 0.9), r"clopper_pearson: size"),  # was (·, nan)
        (
            lambda: percent_beyond_interval([1.0] * 3, T3, 1.0, confidence=None),
            r"percent_beyond_interval: confidence",
        ),
        (
            lambda: percent_beyond_interval(np.arange(9.0), np.arange(9.0), 4.0, confidence=1e-300),
            r"percent_beyond_interval: confidence 1e-300 is too close",  # was about clopper_pearson
        ),
        (
            lambda: percent_beyond_interval([1.0] * 3, T3, 1.0, expected_percent=None),
            r"percent_beyond_interval: expected_percent",
        ),
        (
            lambda: percent_beyond_interval([1.0] * 3, T3, 1.0, expected_percent=True),
            r"percent_beyond_interval: expected_percent",  # was read as 1 %
        ),
        (
            lambda: percent_beyond_interval([1.0] * 3, T3, 1.0, shared_recording="no"),
            r"percent_beyond_interval: shared_recording",  # "no" was true
        ),
        (lambda: percent_beyond_interval([1.0] * 3, T3, "1"), r"percent_beyond_interval: bound"),
        (lambda: percent_beyond([1.0, 2.0], True), r"percent_beyond: bound"),
        (lambda: percent_beyond([1.0, 2.0], [1.0, 3.0, 4.0]), r"percent_beyond: bound \(3,\)"),
        (lambda: percent_beyond([1.0, 2.0, 3.0], [[1.0], [3.0]]), r"percent_beyond: bound"),
        (lambda: paper_thresholds([[1.0, 2.0]], margin=NAN), r"paper_thresholds: margin"),
        (lambda: paper_thresholds([[1.0, 2.0]], margin=-1.0), r"paper_thresholds: margin"),
        (lambda: paper_thresholds([[1.0, 2.0]], margin=None), r"paper_thresholds: margin"),
        (lambda: updates_to_converge([0.1, 0.01], NAN), r"updates_to_converge: threshold"),
        (lambda: updates_to_converge([0.1, 0.01], 0.0), r"updates_to_converge: threshold"),
        (lambda: updates_to_converge([0.1, 0.01], None), r"updates_to_converge: threshold"),
        (lambda: updates_to_converge([0.1, 0.01], [0.05, 0.05]), r"updates_to_converge: threshold"),
        (
            lambda: updates_to_converge_per_state([[0.1, 0.01]], [NAN, 0.05]),
            r"updates_to_converge_per_state: thresholds\[0\]",
        ),
        (
            lambda: updates_to_converge_per_state([[0.1, 0.01]], ["a", "b"]),
            r"updates_to_converge_per_state: thresholds",
        ),
        (lambda: nees([], np.zeros((0, 0))), r"NEES/NIS: vector \(0,\)"),  # was 0.0
        (
            lambda: projected_nees([], np.zeros((0, 0)), np.zeros((0, 1))),
            r"projected_nees: error \(0,\)",  # was a raw IndexError
        ),
    ],
)
def test_bad_settings_and_shapes_are_a_config_error(call, message) -> None:
    with pytest.raises(ConfigError, match=message):
        call()


@pytest.mark.parametrize(
    ("call", "message"),
    [
        # each gave NaN, counted as a missing record, or inf, a spurious verdict
        (lambda: nees([INF, 0.0], E2), "NEES/NIS: 1 infinite vector"),
        (lambda: projected_nees([INF, 0.0], E2, [[1.0], [0.0]]), "projected_nees: 1 infinite"),
        (lambda: state_errors([0.0, 0.0, 0.0, INF], np.zeros(4)), "state_errors: 1 infinite"),
        (lambda: state_errors(np.zeros(4), [INF, 0.0, 0.0, 0.0]), "state_errors: 1 infinite"),
        (lambda: paper_thresholds([[NAN, 2.0], [NAN, 1.0]]), r"paper_thresholds: .* columns \[0\]"),
        (lambda: paper_thresholds([[-1.0, 2.0]]), "paper_thresholds: .* negative"),
        (lambda: paper_thresholds([[INF, 2.0]]), "paper_thresholds: .* infinite"),
        (lambda: rmse([1e200, 1e200]), "rmse: errors beyond"),  # was NaN
        (lambda: integrated_time([1e-300, 0, 0, 0, 0, 0]), "integrated_time: the series' spread"),
        (lambda: integrated_time([1e300, -1e300] * 3), "integrated_time: the series' spread"),
        (lambda: run_average_band(np.full((3, 5), -1.0), 2), "run_average_band: 15 negative"),
        (
            lambda: percent_beyond_interval([1.0, 2.0, 3.0], [0.0, 1e308, -1e308], 1.0),
            "percent_beyond_interval: times from",  # batch_s was inf
        ),
        (
            lambda: updates_to_converge([[0.1, 0.01], [0.2, 0.3]], 0.05),
            r"updates_to_converge: series \(2, 2\)",  # was flattened into one series
        ),
        (lambda: radial_errors(1.0, 1.0), r"radial_errors: shapes \(\)"),  # raw IndexError
    ],
)
def test_impossible_or_overflowing_data_is_a_data_error(call, message) -> None:
    with np.errstate(over="ignore", invalid="ignore"), pytest.raises(DataError, match=message):
        call()


def test_a_per_value_bound_skips_gaps_with_its_values_and_valid_input_is_unchanged() -> None:
    assert percent_beyond([1.0, 2.0], [1.0, 3.0]) == 0.0
    # a per-value bound with a gap among the values was a raw ValueError
    assert percent_beyond([1.0, NAN, 5.0], [0.5, 0.5, 6.0]) == 50.0
    assert percent_beyond(np.array([[1.0, 4.0]]), np.float64(2.0)) == 50.0
    assert chi2_upper(np.int64(2), np.float64(0.95)) == pytest.approx(5.991464547107979)
    assert updates_to_converge(np.array([0.1, 0.01]), np.float64(0.05)) == 2
    assert paper_thresholds([[NAN, 1.0], [2.0, 3.0]]).tolist() == pytest.approx([2.1, 3.15])
    assert nees([NAN, 0.0], E2) != nees([NAN, 0.0], E2)  # a missing record stays NaN
    assert state_errors([NAN, 0.0, 0.0, 0.0], np.zeros(4))[1:].tolist() == [0.0, 0.0, 0.0]
