"""Which optional extras a command needs, checked before it computes anything.

A core install (``pip install relloc``) has numpy, scipy, sympy, networkx and rich; everything
else is an extra (``pyproject.toml``). :func:`check_command` runs before a subcommand starts
and raises :class:`relloc.errors.DependencyError` (exit code 5) with the install line, so a
missing extra never surfaces as a raw ``ModuleNotFoundError`` after minutes of computing.
``relloc run`` alone treats ``plot`` as optional: without it, it writes no figures
(:func:`available`).
"""

from __future__ import annotations

import argparse
import importlib.util

from relloc.errors import DependencyError

#: Extra name → the top-level modules it provides (as imported).
EXTRA_MODULES: dict[str, tuple[str, ...]] = {
    "plot": ("matplotlib",),
    "runtime": ("zenoh", "msgpack", "cryptography"),
    "ros": ("rosbags", "mcap", "mcap_ros2"),
    "cluster": ("distributed",),
    "bench": ("filterpy", "evo"),
}

#: ``relloc bench NAME`` → the extras that benchmark needs.
BENCH_EXTRAS: dict[str, tuple[str, ...]] = {
    "filters": ("bench",),
    "runtime": ("runtime",),
    "secure": ("runtime",),
}


def missing_modules(extra: str) -> list[str]:
    """The modules of ``extra`` that cannot be imported here."""
    out = []
    for module in EXTRA_MODULES[extra]:
        try:
            found = importlib.util.find_spec(module) is not None
        except (ImportError, ValueError):  # a blocked or broken package counts as absent
            found = False
        if not found:
            out.append(module)
    return out


def available(extra: str) -> bool:
    """Whether every module of ``extra`` can be imported."""
    return not missing_modules(extra)


def require_extras(extras: tuple[str, ...], what: str) -> None:
    """Raise :class:`DependencyError` naming the first missing extra and its install line."""
    for extra in extras:
        absent = missing_modules(extra)
        if absent:
            raise DependencyError(
                f"{what} needs the '{extra}' extra ({', '.join(absent)} not installed); "
                f"install it with: pip install 'relloc[{extra}]'"
            )


def needed_extras(args: argparse.Namespace) -> tuple[str, ...]:
    """The extras the parsed command needs before it starts (``relloc run``: none — it drops
    its figures without ``plot``)."""
    command = getattr(args, "command", None)
    extras: list[str] = []
    if command == "reproduce":
        extras.append("plot")  # every reproduction writes figures
    elif command == "team":
        extras.append("runtime")
        if getattr(args, "team_command", None) == "up":
            extras.append("plot")  # the team report has figures
    elif command == "node":
        extras.append("runtime")
    elif command == "bench":
        extras.extend(BENCH_EXTRAS.get(getattr(args, "name", ""), ()))
    if getattr(args, "mcap", None):  # an MCAP export (--mcap FILE) is written with mcap
        extras.append("ros")
    executor = getattr(args, "executor", None)
    if isinstance(executor, str) and executor.startswith("dask://"):
        extras.append("cluster")
    return tuple(extras)


def check_command(args: argparse.Namespace) -> None:
    """Fail fast (exit 5) if the parsed command needs an extra that is not installed."""
    command = getattr(args, "command", None) or "relloc"
    sub = getattr(args, "team_command", None)
    name = getattr(args, "name", None) if command in ("reproduce", "bench") else None
    what = " ".join(str(w) for w in ("relloc", command, sub or name) if w)
    require_extras(needed_extras(args), what)
