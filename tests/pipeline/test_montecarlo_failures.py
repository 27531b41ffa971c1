"""A Monte-Carlo run that fails is named: its error carries the run and the seed that
reproduce it, and a process pool leaves no worker behind."""

from __future__ import annotations

import multiprocessing

import numpy as np
import pytest

from relloc.cli import error_text
from relloc.errors import DataError
from relloc.pipeline.montecarlo import run_monte_carlo


def _second_run_fails(seed: np.random.SeedSequence, run: int) -> int:
    if run == 1:
        raise ValueError("the filter diverged")
    return run


@pytest.mark.parametrize("executor", ["serial", "process"])
def test_the_error_of_a_failing_run_names_the_run_and_the_seed(executor):
    with pytest.raises(ValueError, match="the filter diverged") as info:
        run_monte_carlo(_second_run_fails, 3, 7, executor=executor, description="sweep")
    assert info.value.__notes__ == ["sweep: run 1 of 3 (seed 7)"]
    assert multiprocessing.active_children() == []


def _second_run_is_refused(seed: np.random.SeedSequence, run: int) -> int:
    if run == 1:
        raise DataError("a->b: the belief is not finite")
    return run


def test_the_command_line_prints_the_run_beside_a_relloc_error():
    """Before: the CLI printed only ``str(exc)``, so the run and its seed were lost."""
    with pytest.raises(DataError) as info:
        run_monte_carlo(_second_run_is_refused, 3, 7, executor="serial", description="sweep")
    assert error_text(info.value) == (
        "relloc: error: a->b: the belief is not finite\n  (sweep: run 1 of 3 (seed 7))"
    )
