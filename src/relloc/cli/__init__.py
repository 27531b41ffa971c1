"""The ``relloc`` command: parse -> library call -> write outputs.

Each subcommand lives in its own module ``relloc.cli.<name>`` exposing
``add_parser(subparsers)``, which registers the subparser and sets ``func=run(args) -> int``.
Heavy imports happen inside ``run`` so ``relloc --help`` stays fast. Known errors
(:class:`relloc.errors.RellocError`) become a one-line message and the class's exit code.
"""

from __future__ import annotations

import argparse
import importlib
import importlib.util
import sys
from collections.abc import Sequence

from relloc import __version__
from relloc.errors import RellocError

SUBCOMMAND_MODULES = (
    "relloc.cli.run",
    "relloc.cli.reproduce",
    "relloc.cli.observability",
    "relloc.cli.bench",
    "relloc.cli.node",
    "relloc.cli.team",
    "relloc.cli.certs",
    "relloc.cli.bag",
)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="relloc",
        description="Relative and cooperative localization of heterogeneous multi-robot teams.",
    )
    parser.add_argument("--version", action="version", version=f"relloc {__version__}")
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in SUBCOMMAND_MODULES:
        if importlib.util.find_spec(name) is not None:
            importlib.import_module(name).add_parser(subparsers)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help()
        return 2
    try:
        return int(args.func(args) or 0)
    except RellocError as exc:
        print(f"relloc: error: {exc}", file=sys.stderr)
        return exc.exit_code
    except KeyboardInterrupt:
        print("relloc: interrupted", file=sys.stderr)
        return 130
