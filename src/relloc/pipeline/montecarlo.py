"""Executor-agnostic Monte-Carlo runner.

Every run gets its own independent stream from ``np.random.SeedSequence(seed).spawn(n_runs)``,
so results depend only on ``(seed, run index)`` — never on the executor, the worker count or the
order in which runs finish. Executors:

- ``"serial"``: in this process (debugging, tests);
- ``None`` / ``"process"``: a local :class:`concurrent.futures.ProcessPoolExecutor` on all cores;
- ``"dask://HOST:PORT"``: a Dask ``distributed`` cluster (extra ``cluster``).
"""

from __future__ import annotations

import os
import signal
import sys
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import Executor, Future, ProcessPoolExecutor
from contextlib import contextmanager
from typing import Any, TypeVar

import numpy as np

from relloc.core.checks import count
from relloc.errors import ConfigError, require

R = TypeVar("R")


class SerialExecutor(Executor):
    """A :class:`concurrent.futures.Executor` that runs each task at submission, in this process."""

    def submit(self, fn: Callable[..., R], /, *args: Any, **kwargs: Any) -> Future[R]:
        future: Future[R] = Future()
        try:
            future.set_result(fn(*args, **kwargs))
        except BaseException as exc:
            future.set_exception(exc)
        return future


@contextmanager
def executor_from_spec(
    spec: str | Executor | None, *, max_workers: int | None = None
) -> Iterator[Executor]:
    """Open the executor a spec names (see module docstring) and close it afterwards.

    An :class:`Executor` instance passes through untouched (and is not shut down here). When
    the block raises — an error, Ctrl-C, or SIGTERM (:mod:`relloc.cli`) — a process pool
    cancels the runs it has not started, waits for the ones running, and its workers exit:
    none is left behind, and none goes on to run the rest of the set.
    """
    if isinstance(spec, Executor):
        yield spec
        return
    if spec in (None, "", "process"):
        pool = ProcessPoolExecutor(
            max_workers=max_workers or os.cpu_count() or 1, initializer=_stop_at_once
        )
        try:
            yield pool
        except BaseException:  # interrupted or failed: drop the runs not started yet
            pool.shutdown(wait=True, cancel_futures=True)
            raise
        pool.shutdown(wait=True)
        return
    if spec == "serial":
        yield SerialExecutor()
        return
    if isinstance(spec, str) and spec.startswith("dask://"):
        host, _, port = spec[len("dask://") :].rpartition(":")
        if not host or not port.isdigit() or not 0 < int(port) < 65536:
            raise ConfigError(f"--executor: {spec!r} is not dask://HOST:PORT (a port 1…65535)")
        distributed = require("distributed", "cluster")
        address = f"tcp://{host}:{port}"
        try:
            client = distributed.Client(address, timeout=20)
        except OSError as exc:
            raise ConfigError(
                f"--executor: cannot reach a Dask scheduler at {address}: {exc}"
            ) from exc
        try:
            yield client.get_executor()
        finally:
            client.close()
        return
    raise ConfigError(
        f"--executor: unknown executor {spec!r}; use 'process', 'serial' or 'dask://HOST:PORT'"
    )


def _stop_at_once() -> None:
    """A pool worker's start: SIGTERM and SIGHUP stop it at once (the default action).

    A forked worker inherits the handler :mod:`relloc.cli` sets, which raises an exception: a
    signal sent to the whole process group (``timeout``, a closed terminal, a job scheduler)
    then raised it inside every worker, which printed a traceback and could die holding the
    lock of the result queue, so that the command hung. The command itself still stops on the
    signal as the CLI says (its pool's runs are cancelled, the workers left are gone)."""
    for stop in (signal.SIGTERM, signal.SIGHUP):
        signal.signal(stop, signal.SIG_DFL)


MAX_RUNS = 1_000_000
"""Most Monte-Carlo runs of one experiment (more would hang in seeding before any output)."""


def spawn_seeds(seed: int, n_runs: int) -> list[np.random.SeedSequence]:
    """Independent child seed sequences, one per run (``SeedSequence(seed).spawn(n_runs)``)."""
    if count(n_runs, "runs") > MAX_RUNS:
        raise ConfigError(f"runs: must be in 1…{MAX_RUNS}, got {n_runs}")
    return np.random.SeedSequence(count(seed, "seed", low=0)).spawn(n_runs)


def run_monte_carlo(
    task: Callable[..., R],
    n_runs: int,
    seed: int,
    *,
    executor: str | Executor | None = None,
    task_args: Sequence[Any] = (),
    description: str = "Monte Carlo",
    quiet: bool = False,
) -> list[R]:
    """Run ``task(seed_sequence, run_index, *task_args)`` per run; results come in run order.

    ``task`` must be a picklable top-level function (or ``functools.partial`` of one); it builds its
    own ``np.random.default_rng(seed_sequence)``. An error a run raises propagates as it is,
    with a note naming the run and the seed that reproduce it (:func:`_result`); a process pool
    is shut down first (:func:`executor_from_spec`).
    """
    seeds = spawn_seeds(seed, n_runs)
    with executor_from_spec(executor) as pool:
        futures = [pool.submit(task, ss, i, *task_args) for i, ss in enumerate(seeds)]
        show = not quiet and sys.stderr.isatty()
        if show:
            from rich.progress import Progress

            with Progress(transient=True) as progress:
                bar = progress.add_task(description, total=n_runs)
                results = []
                for i, f in enumerate(futures):
                    results.append(_result(f, i, n_runs, seed, description))
                    progress.advance(bar)
                return results
        return [_result(f, i, n_runs, seed, description) for i, f in enumerate(futures)]


def _result(future: Future[R], run: int, n_runs: int, seed: int, description: str) -> R:
    """The result of run ``run``; an error it raised gets the note ``description: run i of n
    (seed s)``, which tells the run apart from the others and reproduces it alone."""
    try:
        return future.result()
    except Exception as exc:
        exc.add_note(f"{description}: run {run} of {n_runs} (seed {seed})")
        raise
