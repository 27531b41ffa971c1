"""``relloc reproduce NAME --out DIR [--runs N] [--seed S] [--dataset PATH] [--executor E]
[--calibration-window SPLIT] [--mcap FILE] [--tum DIR]`` (``--calibration-window``: mrclam-cl's
calibration and scoring windows; the last two: one representative run's estimates, where the
experiment states one — :func:`relloc.experiments.registry.exported_run`).

Prints the seed and run counts, the report's ours-vs-paper tables laid out for the terminal
(:mod:`relloc.cli.comparison`) and every file written.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from relloc.cli.export_args import add_export_arguments, export_request, print_export
from relloc.experiments import registry


def add_parser(subparsers: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    p = subparsers.add_parser(
        "reproduce",
        help="reproduce a seed paper's experiment (summary.json, report.md, figures)",
        description="Reproduce an experiment. Names: " + ", ".join(registry.EXPERIMENTS),
    )
    p.add_argument("name", help="experiment name: " + ", ".join(registry.EXPERIMENTS))
    p.add_argument("--out", type=Path, required=True, help="output folder")
    p.add_argument("--runs", type=int, default=None, help="Monte-Carlo runs (default: the paper's)")
    p.add_argument("--seed", type=int, default=2026, help="master seed (default 2026)")
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
    p.add_argument("--quiet", action="store_true", help="no progress display")
    add_export_arguments(p, "one representative run's estimates (where the experiment has any)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    reproduce = registry.get(args.name)
    export = export_request(args)
    if export is not None and registry.exported_run(args.name) is None:
        from relloc.errors import ConfigError

        exporting = [n for n in registry.available() if registry.exported_run(n) is not None]
        raise ConfigError(
            f"--mcap/--tum: {args.name} does not export estimates; experiments that do: "
            + ", ".join(exporting)
        )
    summary = reproduce(
        registry.ReproduceArgs(
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
        )
    )
    if not args.quiet:
        from relloc.cli.comparison import comparison_text
        from relloc.cli.console import terminal_width

        print(f"{args.name}: seed {summary.get('seed')}, runs {json.dumps(summary.get('runs'))}")
        print(comparison_text(args.name, args.out, width=terminal_width()))
        print_export(summary.get("export"))
    return 0
