"""Every ``relloc …`` command line the README or a module docstring shows names a real command.

The command lines are taken from code spans (````relloc …```` and ``` ``relloc …`` ```), from
lines of fenced code blocks and from the literal blocks of docstrings (the indented lines after
a paragraph ending in ``::``), a line ending in ``\\`` joined to the next. Each is walked
through the real argument parser (:func:`relloc.cli.build_parser`): its words must name
existing (sub)commands, its ``--flags`` must be options of the command they follow, a
lower-case name given to ``reproduce``, ``bench`` or ``observability`` must be a registered
experiment, benchmark or built-in model, and one given to ``team up`` a reproduction it runs as
processes or ``default``; a flag given to ``reproduce`` or ``team up`` must be one that target
reads (their ``READ_BY``). A ``relloc node --robot …`` line that is not a synopsis (no ``|``
or ``[…]``) is parsed whole and put through the node's own checks
(:func:`relloc.cli.node.check_arguments`: its ``READ_BY`` and ``MODE_READ_BY``).
Placeholders (``NAME``, ``DIR``, ``SCENARIO.toml``, ``...``) are not checked. A renamed flag or
experiment then fails here instead of leaving the documentation wrong.
"""

from __future__ import annotations

import argparse
import ast
import contextlib
import io
import re
from pathlib import Path

import pytest

from relloc.bench import BENCHMARKS
from relloc.cli import build_parser, node, team
from relloc.core.checks import refuse_unread
from relloc.errors import ConfigError
from relloc.experiments import registry
from relloc.experiments.registry import EXPERIMENTS
from relloc.observability.builtin import BUILTIN_MODELS
from relloc.runtime.scenario import REPRODUCTIONS

ROOT = Path(__file__).resolve().parents[2]
SPAN = re.compile(r"``?(relloc [^`]+?)``?")
NAMED = {
    "reproduce": set(EXPERIMENTS),
    "bench": set(BENCHMARKS),
    "observability": set(BUILTIN_MODELS),
    "up": {*REPRODUCTIONS, "guler2023", "default"},  # or a scenario file or a dataset folder
}
PARSER = build_parser()
#: Commands whose flags are read by only some targets: the target's kind and the map of which
#: kinds read each flag (a documented line must not show a flag its target refuses).
READ_BY = {
    "reproduce": lambda name, words: (registry.READ_BY, name),
    "up": lambda name, words: (
        team.READ_BY,
        team.up_target_kind(
            argparse.Namespace(
                scenario=name, estimator="cooperative" if "cooperative" in words else None
            )
        ),
    ),
}
#: A flag whose field has another name (``--pair`` sets ``pairs``).
FIELDS = {flag: field for field, flag in registry.FLAGS.items()}


def documented_commands() -> list[tuple[str, str]]:
    """``(where, command line)`` for every ``relloc …`` line of the README and the docstrings."""
    texts = [("README.md", (ROOT / "README.md").read_text())]
    for path in sorted((ROOT / "src" / "relloc").rglob("*.py")):
        tree = ast.parse(path.read_text())
        for item in ast.walk(tree):
            if isinstance(item, (ast.Module, ast.ClassDef, ast.FunctionDef)):
                doc = ast.get_docstring(item)
                if doc:
                    texts.append((str(path.relative_to(ROOT)), doc))
    found = []
    for where, text in texts:
        lines = [m.group(1) for m in SPAN.finditer(text)]
        blocks = re.findall(r"```[a-z]*\n(.*?)```", text, flags=re.S) + literal_blocks(text)
        joined = (re.sub(r"\\\n\s*", " ", block) for block in blocks)  # `\` continues a line
        lines += [ln.strip() for block in joined for ln in block.splitlines()]
        for line in lines:
            line = line.split("#")[0].strip()
            if line.startswith("relloc "):
                found.append((where, " ".join(line.split())))
    return sorted(set(found))


def literal_blocks(text: str) -> list[str]:
    """The reStructuredText literal blocks of ``text``: the indented (or blank) lines that
    follow a line ending in ``::``."""
    blocks, block, inside = [], [], False
    for line in [*text.splitlines(), "end"]:
        if inside and (not line.strip() or line[0] in " \t"):
            block.append(line)
            continue
        if block:
            blocks.append("\n".join(block))
        block, inside = [], line.rstrip().endswith("::")
    return blocks


def node_problems(words: list[str]) -> list[str]:
    """What the node's own checks refuse in a whole ``relloc node`` line (its words after
    ``relloc``): the parser's error, or :func:`relloc.cli.node.check_arguments`'."""
    stderr = io.StringIO()
    try:
        with contextlib.redirect_stderr(stderr):
            args = PARSER.parse_args(words)
        node.check_arguments(args)
    except SystemExit:
        return [stderr.getvalue().strip().splitlines()[-1]]
    except ConfigError as exc:
        return [str(exc)]
    return []


def subcommands(parser: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    """The subcommands of ``parser`` by name (empty for a command that runs)."""
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            return dict(action.choices)
    return {}


def problems(line: str) -> list[str]:
    """What in ``line`` does not exist in the parser (empty when everything does)."""
    words = line.split()[1:]
    parser, path = PARSER, []
    while words and words[0] in subcommands(parser):
        path.append(words[0])
        parser = subcommands(parser)[words.pop(0)]
    found = []
    if words and subcommands(parser) and re.fullmatch(r"[a-z][a-z0-9-]*", words[0]):
        found.append(f"'{' '.join(path)}' has no subcommand {words[0]!r}")
    if words and path and path[-1] in NAMED and re.fullmatch(r"[a-z][a-z0-9_-]*", words[0]):
        if words[0] not in NAMED[path[-1]]:
            found.append(f"'{path[-1]}' knows no {words[0]!r}")
    options = parser._option_string_actions
    flags = [m.group(1) for m in (re.match(r"\[?(--[a-z][a-z0-9-]*)", w) for w in words) if m]
    found += [f"'{' '.join(path)}' has no option {flag}" for flag in flags if flag not in options]
    if not found and words and path and path[-1] in READ_BY and words[0] in NAMED[path[-1]]:
        read_by, kind = READ_BY[path[-1]](words[0], words)
        given = [FIELDS.get(flag, options[flag].dest) for flag in flags]
        try:
            refuse_unread(kind, given, read_by, flags={v: k for k, v in FIELDS.items()})
        except ConfigError as exc:
            found.append(str(exc))
    synopsis = any("|" in w or w.startswith("[") for w in words)  # alternatives, optionals
    if not found and path == ["node"] and "--robot" in words and not synopsis:
        found += node_problems(line.split()[1:])
    return found


COMMANDS = documented_commands()


def test_the_documentation_shows_commands() -> None:
    where = {w for w, _ in COMMANDS}
    assert "README.md" in where and len(COMMANDS) >= 30, COMMANDS


@pytest.mark.parametrize(("where", "line"), COMMANDS, ids=[f"{w}:{c}" for w, c in COMMANDS])
def test_a_documented_command_exists(where: str, line: str) -> None:
    assert problems(line) == [], f"{where}: {line}"


@pytest.mark.parametrize(
    ("line", "expected"),
    [
        ("relloc reproduce sharma2013 --runz 3", "has no option --runz"),
        ("relloc reproduce sharma2031", "knows no 'sharma2031'"),
        ("relloc team upp default", "has no subcommand 'upp'"),
        ("relloc bench filterz", "knows no 'filterz'"),
        ("relloc team up sharma2031 --out d", "knows no 'sharma2031'"),
        ("relloc reproduce tiers-uwb --seed 3", "--seed: tiers-uwb does not read it"),
        ("relloc team up guler2023 --tick 0.2", "--tick: guler2023 does not read it"),
        ("relloc node --robot a --scenario sharma2013 --gate 0.9", "--gate: sharma2013 does not"),
        ("relloc node --robot a --tick 0.2", "--tick: a node on the clock's ticks does not"),
        ("relloc node --robot a --realtime --paced 2", "--paced: --realtime does not read it"),
        ("relloc node --robot a --run -1", "--run: must be ≥ 0"),
        ("relloc node --robot a --seed x", "invalid int value: 'x'"),
    ],
)
def test_a_wrong_command_is_caught(line: str, expected: str) -> None:
    assert any(expected in p for p in problems(line)), problems(line)
