"""Executor equivalence: serial, local process pool and a local Dask cluster give identical runs.

The Monte-Carlo task is a real (small) estimation run: a unicycle driven by noisy odometry is
dead-reckoned with the midpoint model, and the run returns its final pose error. Results depend
only on ``SeedSequence(seed).spawn(n)[i]``, so every executor must return bit-identical lists.
The Dask cluster is started by the test on loopback (threads inside this process, TCP scheduler),
and reached through the same ``dask://HOST:PORT`` spec the CLI accepts.
"""

from __future__ import annotations

import numpy as np
import pytest

from relloc.models.unicycle import unicycle_step
from relloc.pipeline.montecarlo import run_monte_carlo


def dead_reckoning_error(seed_sequence, index, n_steps, dt):
    """Drive a unicycle on a circle; integrate noisy odometry; return the final pose error."""
    rng = np.random.default_rng(seed_sequence)
    u_true = np.array([0.5, 0.2])
    truth = np.zeros(3)
    estimate = np.zeros(3)
    for _ in range(n_steps):
        truth = unicycle_step(truth, u_true, dt)
        estimate = unicycle_step(estimate, u_true + rng.normal(0.0, [0.05, 0.02]), dt)
    return index, tuple(float(e) for e in estimate - truth)


def test_serial_process_and_dask_give_identical_results():
    distributed = pytest.importorskip("distributed", reason="extra 'cluster' not installed")
    args = (200, 0.05)
    serial = run_monte_carlo(dead_reckoning_error, 8, 2024, executor="serial", task_args=args)
    pooled = run_monte_carlo(dead_reckoning_error, 8, 2024, executor="process", task_args=args)
    with distributed.LocalCluster(
        n_workers=2,
        threads_per_worker=1,
        processes=False,
        protocol="tcp",
        host="127.0.0.1",
        dashboard_address=":0",
    ) as cluster:
        address = cluster.scheduler_address.removeprefix("tcp://")
        on_dask = run_monte_carlo(
            dead_reckoning_error, 8, 2024, executor=f"dask://{address}", task_args=args
        )
    assert serial == pooled == on_dask
    assert [i for i, _ in serial] == list(range(8))
    assert len({err for _, err in serial}) == 8  # independent streams per run
    other_seed = run_monte_carlo(dead_reckoning_error, 8, 2025, executor="serial", task_args=args)
    assert other_seed != serial
