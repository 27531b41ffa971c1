"""Property-based fuzzing of the scenario parser (hypothesis, derandomised and bounded).

Documents are mutated copies of the built-in ``default.toml``: random values of random types at
random keys, deletions, unknown keys, huge/tiny/non-finite numbers, random and over-long
strings, deep nesting, many robots, and raw byte edits of the file. Whatever the mutation,
:func:`load_scenario` either returns a scenario or raises :class:`ConfigError` naming the file;
a scenario that loads simulates a short run (≤ 2 s, ≤ 2000 steps) or raises ConfigError.
"""

import copy
import dataclasses
import json
import math
import tomllib
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from relloc.errors import ConfigError
from relloc.sim.scenario import load_scenario
from relloc.sim.simulate import simulate

DEFAULT_TEXT = resources.files("relloc.sim").joinpath("scenarios/default.toml").read_text("utf-8")
DEFAULT_DOC = tomllib.loads(DEFAULT_TEXT)
FUZZ = settings(
    derandomize=True,
    max_examples=150,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)


@dataclasses.dataclass(frozen=True)
class Nested:
    """An empty array nested ``depth`` deep, written directly (no recursion while emitting)."""

    depth: int


# --------------------------------------------------------------------------- a TOML writer


def _string(s: str) -> str:
    """A TOML basic string: JSON's escapes are TOML's, plus DEL, which TOML must escape."""
    return json.dumps(s, ensure_ascii=False).replace("\x7f", "\\u007f")


def _value(v: Any) -> str:
    if isinstance(v, Nested):
        return "[" * v.depth + "]" * v.depth
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float) and math.isnan(v):
        return "nan"
    if isinstance(v, float) and math.isinf(v):
        return "inf" if v > 0 else "-inf"
    if isinstance(v, float):
        return repr(v)
    if isinstance(v, str):
        return _string(v)
    if isinstance(v, list):
        return "[" + ", ".join(_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{_string(k)} = {_value(x)}" for k, x in v.items()) + "}"
    raise TypeError(f"cannot write {type(v).__name__} as TOML")


def to_toml(doc: dict[str, Any]) -> str:
    """The document as top-level ``key = value`` lines with inline tables."""
    return "".join(f"{_string(k)} = {_value(v)}\n" for k, v in doc.items())


def test_the_writer_round_trips_the_default_scenario():
    assert tomllib.loads(to_toml(DEFAULT_DOC)) == DEFAULT_DOC


# --------------------------------------------------------------------------- mutations

SPECIAL_NUMBERS = [0, -1, 1e-308, 5e-324, -1e-308, 1e308, -1e308, 9.2e18, 1e9, 2**63, 10**40]
SPECIAL_NUMBERS += [math.nan, math.inf, -math.inf, 0.0, -0.0, 1e-3, 360.0, 400.0]
SPECIAL_TEXT = ["", " ", "a/b", "a*", "x" * 10_000, "waypoints", "velocity", "ground", "aerial"]
SPECIAL_TEXT += ["tangent", "fixed", "observer", "aerial1", "ground2", "é\n\t\x00\x7f"]
texts = st.text(st.characters(exclude_categories=("Cs",)), max_size=12) | st.sampled_from(
    SPECIAL_TEXT
)
numbers = (
    st.sampled_from(SPECIAL_NUMBERS)
    | st.floats(allow_nan=True, allow_infinity=True)
    | st.integers(-(10**20), 10**20)
)
scalars = numbers | st.booleans() | texts
values = st.recursive(
    scalars,
    lambda inner: st.lists(inner, max_size=5) | st.dictionaries(texts, inner, max_size=3),
    max_leaves=10,
)

KeyPath = tuple[str | int, ...]


def _paths(node: Any, prefix: KeyPath = ()) -> list[KeyPath]:
    """Every key/index path below ``node`` (depth-first, in document order)."""
    if isinstance(node, dict):
        items: list[tuple[str | int, Any]] = list(node.items())
    elif isinstance(node, list):
        items = list(enumerate(node))
    else:
        return []
    out: list[KeyPath] = []
    for k, child in items:
        out.append((*prefix, k))
        out += _paths(child, (*prefix, k))
    return out


def _node(doc: dict[str, Any], path: KeyPath) -> Any:
    node: Any = doc
    for k in path:
        node = node[k]
    return node


def _parent(doc: dict[str, Any], path: KeyPath) -> Any:
    return _node(doc, path[:-1])


def _mutate(doc: dict[str, Any], data: st.DataObject) -> None:
    """Apply one random mutation to ``doc`` in place."""
    kind = data.draw(
        st.sampled_from(["set", "number", "delete", "unknown", "nest", "clone", "name"])
    )
    paths = _paths(doc)
    if kind == "clone" and isinstance(doc.get("robots"), list) and doc["robots"]:
        n = data.draw(st.integers(1, 70))
        robot = doc["robots"][-1]
        doc["robots"] += [
            {**copy.deepcopy(robot), "name": f"r{i}"} if isinstance(robot, dict) else robot
            for i in range(n)
        ]
        return
    if kind == "unknown":
        tables = [()] + [p for p in paths if isinstance(_node(doc, p), dict)]
        _node(doc, data.draw(st.sampled_from(tables)))[data.draw(texts)] = data.draw(scalars)
        return
    if not paths:
        return
    if kind == "number":
        leaves = [p for p in paths if isinstance(_node(doc, p), (int, float))]
        paths = leaves or paths
    if kind == "name":
        paths = [p for p in paths if p[-1] == "name"] or paths
    path = data.draw(st.sampled_from(paths))
    parent = _parent(doc, path)
    if kind == "delete":
        del parent[path[-1]]
    elif kind == "nest":
        parent[path[-1]] = Nested(data.draw(st.integers(1, 6000)))
    elif kind == "number":
        parent[path[-1]] = data.draw(numbers)
    elif kind == "name":
        parent[path[-1]] = data.draw(texts)
    else:
        parent[path[-1]] = data.draw(values)


def _load_and_simulate(path: Path) -> None:
    """``load_scenario`` then a short ``simulate``; only ConfigError may come out of either,
    and a load error names the file."""
    try:
        scenario = load_scenario(path)
    except ConfigError as exc:
        assert str(exc).startswith(f"{path}: ")
        return
    duration = min(scenario.duration_s, 2.0, 2000.0 / scenario.propagation_rate_hz)
    try:
        short = dataclasses.replace(scenario, duration_s=duration)
        simulate(short, np.random.default_rng(0))
    except ConfigError:
        pass


@FUZZ
@given(data=st.data())
def test_mutated_default_scenario_loads_or_raises_config_error(tmp_path, data):
    doc = copy.deepcopy(DEFAULT_DOC)
    for _ in range(data.draw(st.integers(1, 4))):
        _mutate(doc, data)
    path = tmp_path / "fuzz.toml"
    path.write_text(to_toml(doc), encoding="utf-8")
    _load_and_simulate(path)


@FUZZ
@given(data=st.data())
def test_default_scenario_with_other_numbers_loads_or_raises_config_error(tmp_path, data):
    """Only numbers change (to plausible, extreme or non-finite values), so the structure stays
    valid and most documents load and reach the simulator."""
    doc = copy.deepcopy(DEFAULT_DOC)
    leaves = [p for p in _paths(doc) if isinstance(_node(doc, p), (int, float))]
    plausible = st.floats(-30.0, 30.0) | st.sampled_from(SPECIAL_NUMBERS)
    for path in data.draw(st.lists(st.sampled_from(leaves), min_size=1, max_size=3)):
        _parent(doc, path)[path[-1]] = data.draw(plausible)
    path = tmp_path / "numbers.toml"
    path.write_text(to_toml(doc), encoding="utf-8")
    _load_and_simulate(path)


@FUZZ
@given(
    edits=st.lists(
        st.tuples(st.floats(0.0, 1.0), st.integers(0, 40), st.binary(max_size=8)),
        min_size=1,
        max_size=4,
    )
)
def test_byte_edited_default_file_loads_or_raises_config_error(tmp_path, edits):
    """Raw edits of the file: replace ``n`` bytes at a relative position with random bytes
    (which may break the TOML syntax or the UTF-8 encoding)."""
    raw = bytearray(DEFAULT_TEXT.encode("utf-8"))
    for where, n, new in edits:
        i = int(where * len(raw))
        raw[i : i + n] = new
    path = tmp_path / "bytes.toml"
    path.write_bytes(bytes(raw))
    _load_and_simulate(path)
