"""``relloc bench NAME [--json FILE]`` — run a benchmark and print/write its numbers."""

from __future__ import annotations

import argparse
import importlib
import importlib.util
from pathlib import Path

from relloc.bench import BENCHMARKS
from relloc.errors import ConfigError


def add_parser(subparsers: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    p = subparsers.add_parser(
        "bench",
        help="benchmarks (speed, scale, interval coverage) against a baseline run beside",
        description="Benchmarks: " + ", ".join(BENCHMARKS),
    )
    p.add_argument("name", help="benchmark: " + ", ".join(BENCHMARKS))
    p.add_argument("--json", type=Path, default=None, help="also write the numbers to this file")
    p.add_argument("--quiet", action="store_true", help="print nothing, only write --json")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from relloc.pipeline.output import check_writable_file, write_json_file

    module_name = BENCHMARKS.get(args.name)
    if module_name is None or importlib.util.find_spec(module_name) is None:
        have = [n for n, m in BENCHMARKS.items() if importlib.util.find_spec(m) is not None]
        raise ConfigError(f"unknown benchmark {args.name!r}; available: {', '.join(have)}")
    if args.json is not None:  # checked before the benchmark, not after it
        check_writable_file(args.json, "--json")
    result = importlib.import_module(module_name).run(quiet=args.quiet)
    if args.json is not None:
        write_json_file(args.json, result, "--json")
    return 0
