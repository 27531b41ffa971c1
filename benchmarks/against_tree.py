"""A relloc benchmark of this checkout against another checkout of relloc, in the same run.

Usage::

    git worktree add ../relloc-base edd70d1      # the tree to compare with
    .venv/bin/python benchmarks/against_tree.py filters ../relloc-base/src [--rounds 6]

Each round runs ``relloc.bench.<BENCH>.run(quiet=True)`` (``measure()`` where the module has
one, as ``cooperative`` does: its ``run`` measures in a child of its own) once per tree, each
in its own process with the tree's ``src`` first on ``PYTHONPATH``. The order of the trees
alternates between rounds so that a drift in machine load falls on both. Every run is pinned to
one core with single-threaded BLAS, and ``time.perf_counter`` is replaced by
``time.process_time`` (CPU time), so other work on a shared machine counts less. For every
numeric leaf of the benchmark's result the best over rounds is printed per tree: the minimum of
a time, the maximum of a rate or any figure where larger is better (a name ending ``_per_s``,
or with ``ratio``, ``speedup``, ``realtime``, ``largest`` or ``fraction``). The ratio is
oriented so that > 1 means this checkout is faster: baseline time ÷ this time, or this rate ÷
baseline rate. ``setup``, ``machine``, ``targets`` and ``seed`` blocks are left out, and so are
the leaves that describe the machine (``load_average…``, ``cpu_count``). Identical runs vary by
up to ±25 % on a loaded 2-core machine: compare on a quiet one, with several rounds.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

CHILD = r"""
import json, os, sys, time, importlib
if hasattr(os, "sched_setaffinity"):
    os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})
time.perf_counter = time.process_time
bench = importlib.import_module("relloc.bench." + sys.argv[1])
# a benchmark whose run() measures in a child of its own (cooperative) is measured here, where
# perf_counter is CPU time (this process already has single-threaded BLAS, one core)
result = bench.measure() if hasattr(bench, "measure") else bench.run(quiet=True)
print(json.dumps(result, default=lambda o: o.tolist() if hasattr(o, "tolist") else str(o)))
"""
RATE_WORDS = ("ratio", "speedup", "realtime", "largest", "fraction")
SKIPPED = ("setup", "machine", "targets", "seed")
MACHINE_LEAVES = ("load_average", "cpu_count")


def leaves(node: Any, prefix: str = "") -> Iterator[tuple[str, float]]:
    """``(dotted path, value)`` of every numeric leaf (lists indexed, booleans skipped)."""
    if isinstance(node, dict):
        for k, v in node.items():
            yield from leaves(v, f"{prefix}.{k}" if prefix else str(k))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            yield from leaves(v, f"{prefix}[{i}]")
    elif isinstance(node, int | float) and not isinstance(node, bool):
        yield prefix, float(node)


def run_tree(bench: str, src: Path) -> dict[str, float]:
    """One run of ``bench`` with ``src`` first on the path; its numeric leaves."""
    env = dict(os.environ, PYTHONPATH=str(src))
    env.update(OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1", MKL_NUM_THREADS="1")
    done = subprocess.run(
        [sys.executable, "-c", CHILD, bench], env=env, capture_output=True, text=True, check=False
    )
    if done.returncode:
        raise SystemExit(f"{bench} in {src}: exit {done.returncode}\n{done.stderr[-2000:]}")
    return dict(leaves(json.loads(done.stdout.strip().splitlines()[-1])))


def round_order(rounds: int) -> list[tuple[str, str]]:
    """Which tree runs first in each round: they alternate, so a drift in load falls on both."""
    return [("baseline", "this") if r % 2 == 0 else ("this", "baseline") for r in range(rounds)]


def table(bench: str, base: Path, this: Path, runs: dict[str, list[dict[str, float]]]) -> list[str]:
    """The table lines from every run's leaves (``runs[tree]``, one per round): per leaf, the
    best of each tree and their ratio."""
    rounds = len(runs["baseline"])
    lines = [f"{bench}: {rounds} rounds; baseline {base}; this {this}; ratio > 1: this is faster"]
    for key in runs["baseline"][0]:
        leaf = key.rsplit(".", 1)[-1]
        if (
            key.split(".")[0] in SKIPPED
            or leaf.startswith(MACHINE_LEAVES)
            or not all(key in r for rs in runs.values() for r in rs)
        ):
            continue
        rate = leaf.endswith("_per_s") or any(word in leaf for word in RATE_WORDS)
        best = max if rate else min
        b, t = best(r[key] for r in runs["baseline"]), best(r[key] for r in runs["this"])
        ratio = (t / b if rate else b / t) if b and t else float("nan")
        lines.append(f"{key:58s} baseline {b:11.4g}  this {t:11.4g}  ratio {ratio:5.2f}")
    return lines


def compare(bench: str, base: Path, this: Path, rounds: int) -> list[str]:
    """Run ``bench`` ``rounds`` times per tree (:func:`round_order`) and give :func:`table`."""
    src = {"baseline": base, "this": this}
    runs: dict[str, list[dict[str, float]]] = {"baseline": [], "this": []}
    for order in round_order(rounds):
        for name in order:
            runs[name].append(run_tree(bench, src[name]))
    return table(bench, base, this, runs)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("bench", help="a relloc.bench module: filters, cooperative, multihypothesis")
    p.add_argument("baseline_src", type=Path, help="the other checkout's src folder")
    p.add_argument("--rounds", type=int, default=3, help="runs per tree (default 3)")
    args = p.parse_args(argv)
    if args.rounds < 1 or not (args.baseline_src / "relloc").is_dir():
        p.error("--rounds must be ≥ 1 and BASELINE_SRC must hold the relloc package")
    this = Path(__file__).resolve().parent.parent / "src"
    print("\n".join(compare(args.bench, args.baseline_src.resolve(), this, args.rounds)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
