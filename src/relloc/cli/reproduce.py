"""``relloc reproduce NAME --out DIR [--runs N] [--seed S] [--dataset PATH] [--executor E]
[--calibration-window SPLIT] [--pair A,B ...] [--sensing ROBOTS] [--mcap FILE] [--tum DIR]``
(``--calibration-window``: mrclam-cl's calibration and scoring windows; ``--pair``: the
replayed robots of wanasinghe2014 (one pair) and wanasinghe2014-pairs (repeatable);
``--sensing``: desilva2015's sensing robots; the last two: one representative run's estimates,
where the experiment states one — :func:`relloc.experiments.registry.exported_run`). A flag
the experiment does not read is refused (:func:`relloc.experiments.registry.refuse_unread`, run by
the function :func:`relloc.experiments.registry.get` returns).

Prints the seed and run counts, the report's ours-vs-paper tables laid out for the terminal
(:mod:`relloc.cli.comparison`) and every file written.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from relloc.cli.export_args import add_export_arguments, export_request, print_export
from relloc.cli.flags import integer_list, nonempty_path
from relloc.errors import ConfigError
from relloc.experiments import registry


def add_parser(subparsers: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    p = subparsers.add_parser(
        "reproduce",
        help="reproduce a seed paper's experiment (summary.json, report.md, figures)",
        description="Reproduce an experiment. Names: " + ", ".join(registry.EXPERIMENTS),
    )
    p.add_argument("name", help="experiment name: " + ", ".join(registry.EXPERIMENTS))
    p.add_argument("--out", type=nonempty_path, required=True, help="output folder")
    p.add_argument("--runs", type=int, default=None, help="Monte-Carlo runs (default: the paper's)")
    p.add_argument(
        "--seed", type=int, default=None, help=f"master seed (default {registry.DEFAULT_SEED})"
    )
    p.add_argument("--dataset", type=Path, default=None, help="a folder in MRCLAM layout")
    p.add_argument(
        "--executor",
        default=None,
        help="'process' (default, all cores), 'serial', or 'dask://HOST:PORT'",
    )
    p.add_argument("--bag", type=Path, default=None, help="a ROS 2 bag (tiers-uwb)")
    p.add_argument("--map", type=Path, default=None, help="the bag's topic mapping TOML")
    p.add_argument(
        "--calibrate-on",
        type=Path,
        default=None,
        help="another bag of the same hardware to calibrate on",
    )
    p.add_argument(
        "--calibration-window",
        default=None,
        metavar="SPLIT",
        help="mrclam-cl: fit the error models on 'first-half' (default) or 'second-half' of the "
        "run, ':T' (up to T s) or 'T:' (from T s), and score on the rest",
    )
    p.add_argument(
        "--pair",
        action="append",
        default=None,
        metavar="A,B",
        help="wanasinghe2014: the dataset's observer and observed robot of the real-trajectory "
        "replay (default 1,3); wanasinghe2014-pairs: repeat it for each pair to replay "
        "(default: every robot observing the next two)",
    )
    p.add_argument(
        "--sensing",
        default=None,
        metavar="ROBOTS",
        help="desilva2015: the simulated robots that sense, 'all' or names such as L1,L2,P1 "
        "(default: the paper's leaders L1,L2)",
    )
    p.add_argument("--quiet", action="store_true", help="no progress display")
    add_export_arguments(p, "one representative run's estimates (where the experiment has any)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    reproduce = registry.get(args.name)
    export = export_request(args)
    if export is not None and registry.exported_run(args.name) is None:
        exporting = [n for n in registry.available() if registry.exported_run(n) is not None]
        raise ConfigError(
            f"--mcap/--tum: {args.name} does not export estimates; experiments that do: "
            + ", ".join(exporting)
        )
    request = registry.ReproduceArgs(
        out_dir=args.out,
        runs=args.runs,
        seed=args.seed,
        dataset=args.dataset,
        executor=args.executor,
        quiet=args.quiet,
        export=export,
        bag=args.bag,
        map=args.map,
        calibrate_on=args.calibrate_on,
        calibration_window=args.calibration_window,
        pairs=robot_pairs(args.pair),
        sensing=args.sensing,
    )
    summary = reproduce(request)
    if not args.quiet:
        from relloc.cli.comparison import comparison_text
        from relloc.cli.console import terminal_width

        seed = summary.get("seed")
        drawn = "no seed (nothing drawn at random)" if seed is None else f"seed {seed}"
        print(f"{args.name}: {drawn}, runs {_runs_text(summary.get('runs'))}")
        print(comparison_text(args.name, args.out, width=terminal_width()))
        print_export(summary.get("export"))
    return 0


def _runs_text(runs: object) -> str:
    """The runs of a summary for the console: a count, or each block's count (``one_drone 3,
    two_drones 11``) where an experiment runs its blocks a different number of times."""
    if isinstance(runs, dict):
        return ", ".join(f"{block} {n}" for block, n in runs.items())
    return json.dumps(runs)


def robot_pairs(texts: list[str] | None) -> tuple[tuple[int, int], ...] | None:
    """Each ``--pair A,B`` → ``(A, B)``; ``None`` (no flag) stays ``None``."""
    if texts is None:
        return None
    pairs = []
    for text in texts:
        robots = integer_list(text, "--pair")
        if robots is None or len(robots) != 2:
            raise ConfigError(f"--pair: two robots OBSERVER,OBSERVED, got {text!r}")
        pairs.append((robots[0], robots[1]))
    return tuple(pairs)
