"""Fuzzing of :func:`relloc.experiments.fit_file.load_fit` (the ``--fit`` JSON file): keys
dropped or added, values of any JSON type (NaN, inf, huge numbers, nesting), sections replaced
and text that is not JSON read as the fitted models or are refused with a DataError naming the
file (and, for a value, its key)."""

from __future__ import annotations

import dataclasses
import json
import tempfile
from pathlib import Path
from typing import Any

from hypothesis import given, settings
from hypothesis import strategies as st
from test_estimator_nodes import _handmade_fit

from relloc.calibration.window import CalibrationWindow
from relloc.errors import DataError
from relloc.experiments.fit_file import load_fit, save_fit
from relloc.experiments.mrclam_cl import FittedModels, OdometryInflation

HALVES = CalibrationWindow(1.0, 200.0, "run"), CalibrationWindow(200.0, 400.0, "run")
_BASE = _handmade_fit("run")  # five robots; here with every optional field filled in
FIT = dataclasses.replace(
    _BASE,
    odometry=dataclasses.replace(_BASE.odometry, unfitted_robots=(2,)),
    camera=dataclasses.replace(
        _BASE.camera, bearing_bias_coeffs=(0.0,) * 15, bearing_bias_limits=(-0.5, 0.5) * 5
    ),
    odometry_inflation=OdometryInflation(1.5, True, 5.0, ((1.0, 9.5), (1.5, 4.25)), *HALVES),
)


def _valid_document() -> dict[str, Any]:
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "fit.json"
        save_fit(FIT, path)
        return json.loads(path.read_text())


VALID = _valid_document()

_leaf = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(),
    st.sampled_from([0, -1, 1, 2, 10**30, -(10**30), 10**400, 2**63]),
    st.floats(allow_nan=True, allow_infinity=True),
    st.text(max_size=6),
)
_json = st.recursive(
    _leaf,
    lambda inner: (
        st.lists(inner, max_size=4)
        | st.dictionaries(
            st.sampled_from(["start_s", "end_s", "source", "range", "1s", "k", "x", ""]),
            inner,
            max_size=4,
        )
    ),
    max_leaves=12,
)


def _paths(doc: Any, prefix: tuple[Any, ...] = ()) -> list[tuple[Any, ...]]:
    """Every key path into ``doc`` (object keys and list indices)."""
    out = [prefix] if prefix else []
    if isinstance(doc, dict):
        for k, v in doc.items():
            out += _paths(v, (*prefix, k))
    elif isinstance(doc, list):
        for i, v in enumerate(doc):
            out += _paths(v, (*prefix, i))
    return out


PATHS = _paths(VALID)


@st.composite
def _documents(draw: st.DrawFn) -> Any:
    """The valid document with 1–3 edits: a value replaced, a key dropped, a key added."""
    doc = json.loads(json.dumps(VALID))
    for _ in range(draw(st.integers(1, 3))):
        path = draw(st.sampled_from(PATHS))
        parent = doc
        try:
            for step in path[:-1]:
                parent = parent[step]
            last = path[-1]
            parent[last]  # an earlier edit may have removed the path
        except (KeyError, IndexError, TypeError):
            continue
        action = draw(st.sampled_from(["replace", "replace", "drop", "add"]))
        if action == "replace":
            parent[last] = draw(_json)
        elif action == "drop":
            del parent[last]
        elif isinstance(parent, dict):
            parent[draw(st.sampled_from(["extra", "Scale_v", ""]))] = draw(_json)
        else:
            parent.append(draw(_json))
    if draw(st.integers(0, 9)) == 0:
        doc = draw(_json)  # a document of another shape altogether
    return doc


def _named(path: Path, exc: DataError) -> None:
    assert str(exc).startswith(str(path)), str(exc)


@settings(derandomize=True, max_examples=200, deadline=None)
@given(doc=_documents())
def test_a_fuzzed_fit_file_is_read_or_refused_naming_the_file(doc):
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "fuzzed_fit.json"
        path.write_text(json.dumps(doc))
        try:
            fit = load_fit(path)
        except DataError as exc:
            _named(path, exc)
            return
        assert isinstance(fit, FittedModels)


@settings(derandomize=True, max_examples=100, deadline=None)
@given(
    text=st.one_of(
        st.text(alphabet='{}[]":,0123456789.eE-+ NaInfitynul"odmecra', max_size=40),
        st.integers(0, 4000).map(lambda n: json.dumps(VALID)[:n]),
        st.binary(max_size=20).map(lambda b: b.decode("latin-1")),
    )
)
def test_fit_file_text_that_is_not_json_is_refused_naming_the_file(text):
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "fuzzed_fit.json"
        path.write_bytes(text.encode("utf-8", "surrogatepass"))
        try:
            fit = load_fit(path)
        except DataError as exc:
            _named(path, exc)
            return
        assert fit == FIT


def test_the_valid_fit_file_reads_back():
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "fit.json"
        path.write_text(json.dumps(VALID))
        assert load_fit(path) == FIT
