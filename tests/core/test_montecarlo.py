"""Monte-Carlo runner: results depend only on (seed, run index), not on the executor."""

import numpy as np
import pytest

from relloc.errors import ConfigError
from relloc.pipeline.montecarlo import run_monte_carlo


def draw(seed_sequence, index, scale):
    rng = np.random.default_rng(seed_sequence)
    return index, float(scale * rng.normal())


def test_serial_and_process_pool_agree():
    serial = run_monte_carlo(draw, 6, 11, executor="serial", task_args=(2.0,), quiet=True)
    pooled = run_monte_carlo(draw, 6, 11, executor="process", task_args=(2.0,), quiet=True)
    assert serial == pooled
    assert [i for i, _ in serial] == list(range(6))
    assert len({v for _, v in serial}) == 6


def test_bad_executor_and_runs():
    with pytest.raises(ConfigError, match="unknown executor"):
        run_monte_carlo(draw, 2, 0, executor="gpu", task_args=(1.0,))
    with pytest.raises(ConfigError, match="runs"):
        run_monte_carlo(draw, 0, 0, executor="serial", task_args=(1.0,))


@pytest.mark.parametrize(
    ("runs", "seed", "message"),
    [
        (2.5, 0, "runs: expected an integer"),
        ("2", 0, "runs: expected an integer"),
        (True, 0, "runs: expected an integer"),  # ran once
        (2, -1, "seed: must be ≥ 0"),
        (2, 1.5, "seed: expected an integer"),
    ],
)
def test_runs_and_seed_of_the_wrong_type_name_themselves(runs, seed, message):
    """These raised raw numpy errors, or (``True``) ran once."""
    with pytest.raises(ConfigError, match=message):
        run_monte_carlo(draw, runs, seed, executor="serial", task_args=(1.0,))
