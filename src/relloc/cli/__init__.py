"""The ``relloc`` command: parse -> library call -> write outputs.

Each subcommand lives in its own module ``relloc.cli.<name>`` exposing ``add_parser(subparsers)``,
which registers the subparser and sets ``func=run(args) -> int``. Heavy imports happen inside
``run`` so ``relloc --help`` stays fast. Before a command runs,
:func:`relloc.cli.extras.check_command` checks the optional extras it needs (exit 5 with the
install line). After a command that writes an output folder (``--out``), the files there that an
earlier run left and this one did not replace are named on stderr. Known errors
(:class:`relloc.errors.RellocError`) become a one-line message and the class's exit code:
configuration 2, data 3, model 4, missing extra 5. A misspelt option is reported with the usage of
the subcommand it was given to.

Stopping: Ctrl-C (SIGINT) exits 130 and SIGTERM or SIGHUP exits 128 + the signal's number
(143, 129), each after the command's ``finally`` blocks have run — so a command that started
processes (Monte-Carlo workers, a team) stops them before it exits instead of leaving them
behind. A Monte-Carlo pool's workers keep the default SIGTERM and SIGHUP
(:mod:`relloc.pipeline.montecarlo`), so a signal to the whole process group stops them at
once, without a traceback. The team's own processes (``relloc node``, ``team clock``,
``airground world|robot``, which set ``team_process``) keep the default SIGTERM: their launcher
stops them that way and escalates to SIGKILL.
"""

from __future__ import annotations

import argparse
import importlib
import importlib.util
import os
import signal
import sys
import threading
import time
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path

from relloc import __version__
from relloc.datasets.paths import DATA_ENV
from relloc.errors import RellocError

SUBCOMMAND_MODULES = (
    "relloc.cli.run",
    "relloc.cli.reproduce",
    "relloc.cli.observability",
    "relloc.cli.bench",
    "relloc.cli.node",
    "relloc.cli.team",
    "relloc.cli.airground",
    "relloc.cli.certs",
    "relloc.cli.bag",
    "relloc.cli.mrclam",
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
    for leaf in _leaf_parsers(parser):
        leaf.add_argument(
            "--data-dir",
            type=Path,
            default=None,
            metavar="DIR",
            help="the data folder holding mrclam/, uwb/ and tiers/ (sets RELLOC_SHARED_DATA)",
        )
    return parser


def _leaf_parsers(parser: argparse.ArgumentParser) -> list[argparse.ArgumentParser]:
    """The parsers that run a command (no subcommands of their own)."""
    subs = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    if not subs:
        return [parser]
    return [leaf for a in subs for p in a.choices.values() for leaf in _leaf_parsers(p)]


def _subparser(
    parser: argparse.ArgumentParser, args: argparse.Namespace
) -> argparse.ArgumentParser:
    """The innermost (sub)parser the parsed command went through, for its usage line."""
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            chosen = getattr(args, action.dest or "", None)
            if chosen in action.choices:
                return _subparser(action.choices[chosen], args)
    return parser


def _note_earlier_files(out: Path, started: float) -> None:
    """Say which files of ``--out`` an earlier run left there (this run did not write them)."""
    from relloc.pipeline.output import earlier_files

    old = earlier_files(out, started)
    if old:
        names = ", ".join(str(p.relative_to(out)) for p in old[:5])
        more = f" and {len(old) - 5} more" if len(old) > 5 else ""
        print(
            f"relloc: note: {len(old)} file{'s' * (len(old) > 1)} under {out} from an earlier "
            "run, not this one: "
            f"{names}{more} (remove them, or use a new --out)",
            file=sys.stderr,
        )


def error_text(exc: BaseException) -> str:
    """``relloc: error: …`` and, one per line, the notes the error gathered on its way (e.g.
    which Monte-Carlo run raised it, and with which seed: :mod:`relloc.pipeline.montecarlo`)."""
    notes = "".join(f"\n  ({note})" for note in getattr(exc, "__notes__", ()))
    return f"relloc: error: {exc}{notes}"


def main(argv: Sequence[str] | None = None) -> int:
    from relloc.cli.extras import check_command

    parser = build_parser()
    args, unknown = parser.parse_known_args(argv)
    if unknown:  # exits 2 with the subcommand's usage, not the top-level one
        _subparser(parser, args).error(f"unrecognized arguments: {' '.join(unknown)}")
    if not getattr(args, "func", None):
        parser.print_help()
        return 2
    if getattr(args, "data_dir", None) is not None:  # children (workers, nodes) inherit it
        os.environ[DATA_ENV] = str(args.data_dir)
    try:
        check_command(args)
        started = time.time()
        with _terminate_as_exception(not getattr(args, "team_process", False)):
            code = int(args.func(args) or 0)
        if code == 0 and isinstance(getattr(args, "out", None), Path):
            _note_earlier_files(args.out, started)
        return code
    except RellocError as exc:
        print(error_text(exc), file=sys.stderr)
        return exc.exit_code
    except KeyboardInterrupt:
        print("relloc: interrupted", file=sys.stderr)
        return 130
    except Terminated as exc:
        print(f"relloc: stopped by {exc.signal.name}", file=sys.stderr)
        return 128 + exc.signal.value


class Terminated(BaseException):
    """SIGTERM or SIGHUP, raised in the main thread (a ``BaseException``, like
    ``KeyboardInterrupt``, so that no ``except Exception`` swallows it)."""

    def __init__(self, signum: int) -> None:
        self.signal = signal.Signals(signum)
        super().__init__(self.signal.name)


def _raise_terminated(signum: int, _frame: object) -> None:
    raise Terminated(signum)


@contextmanager
def _terminate_as_exception(wanted: bool) -> Iterator[None]:
    """While the block runs, SIGTERM and SIGHUP raise :class:`Terminated` (module docstring);
    the earlier handlers come back afterwards. Only the main thread can set handlers, so
    elsewhere (``main`` called from a thread) the block runs as it is."""
    if not wanted or threading.current_thread() is not threading.main_thread():
        yield
        return
    stops = (signal.SIGTERM, signal.SIGHUP)
    earlier = {s: signal.signal(s, _raise_terminated) for s in stops}
    try:
        yield
    finally:
        for s, handler in earlier.items():
            signal.signal(s, handler)
