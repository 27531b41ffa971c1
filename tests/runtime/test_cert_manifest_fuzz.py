"""Fuzzing of the manifest (``team.json``) that :func:`relloc.runtime.certs.load_team_certs`
reads: a manifest of another JSON type, keys dropped or added, a team or robot ids of any type
or hostile text (path separators, ``..``, the launcher's id, duplicates) is refused with a
DataError naming ``team.json``; only a manifest of valid, distinct ids leads to the certificate
files it names, all inside the folder. The certificates are made once, outside the loop."""

from __future__ import annotations

import json
import re
import tempfile
from pathlib import Path
from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from relloc.errors import DataError
from relloc.runtime.certs import LAUNCHER_ID, TeamCerts, load_team_certs, make_team_certs
from relloc.runtime.keys import CLOCK_ID

pytest.importorskip("cryptography")

TEAM = "demo"
ROBOTS = ("a", "b")
VALID = {"team": TEAM, "robots": list(ROBOTS), "launcher": LAUNCHER_ID}
_ID = re.compile(r"[A-Za-z0-9_-]{1,64}")


def _cert_files() -> dict[str, bytes]:
    with tempfile.TemporaryDirectory() as folder:
        certs = make_team_certs(Path(folder) / "certs", TEAM, ROBOTS)
        return {p.name: p.read_bytes() for p in certs.folder.iterdir() if p.name != "team.json"}


FILES = _cert_files()

_hostile_ids = st.sampled_from(
    [
        "a",
        "b",
        "",
        "../certs/a",
        "a/b",
        "/tmp/a",
        ".",
        "..",
        "*",
        "a b",
        "a\x00",
        "a\n",
        "é",
        "ca",
        "x" * 65,
        "A",
        LAUNCHER_ID,
        CLOCK_ID,
    ]
)
_json = st.recursive(
    st.one_of(
        st.none(),
        st.booleans(),
        st.integers(),
        st.floats(allow_nan=True, allow_infinity=True),
        st.text(max_size=6),
        _hostile_ids,
    ),
    lambda inner: (
        st.lists(inner, max_size=4)
        | st.dictionaries(st.sampled_from(["team", "robots", "launcher", "x"]), inner, max_size=3)
    ),
    max_leaves=10,
)


@st.composite
def _manifests(draw: st.DrawFn) -> Any:
    """The valid manifest with its team, robots or launcher replaced or dropped, a key added,
    or a document of another shape altogether."""
    doc: Any = dict(VALID)
    for key in draw(st.lists(st.sampled_from(["team", "robots", "launcher", "x"]), max_size=3)):
        action = draw(st.sampled_from(["ids", "json", "drop"]))
        if action == "drop":
            doc.pop(key, None)
        elif action == "ids" and key == "robots":
            doc[key] = draw(st.lists(_hostile_ids, max_size=4))
        elif action == "ids":
            doc[key] = draw(_hostile_ids)
        else:
            doc[key] = draw(_json)
    if draw(st.integers(0, 9)) == 0:
        doc = draw(_json)
    return doc


def _well_formed(doc: Any) -> bool:
    """A manifest of a valid team id and distinct, valid robot ids other than the launcher's
    and the clock's."""
    if not isinstance(doc, dict) or not isinstance(doc.get("team"), str):
        return False
    robots = doc.get("robots")
    return (
        bool(_ID.fullmatch(doc["team"]))
        and isinstance(robots, list)
        and bool(robots)
        and all(isinstance(r, str) and _ID.fullmatch(r) for r in robots)
        and len(set(robots)) == len(robots)
        and LAUNCHER_ID not in robots
        and CLOCK_ID not in robots
    )


def _load(text: str) -> None:
    with tempfile.TemporaryDirectory() as root:
        folder = Path(root) / "certs"
        folder.mkdir()
        for name, data in FILES.items():
            (folder / name).write_bytes(data)
        manifest = folder / "team.json"
        manifest.write_bytes(text.encode("utf-8", "surrogatepass"))
        try:
            certs = load_team_certs(folder)
        except DataError as exc:
            message = str(exc)
            assert message.startswith(str(folder)), message
            if not message.startswith(f"{manifest}:"):  # past the manifest: its ids were valid
                doc = json.loads(text)
                assert _well_formed(doc), (doc, message)
            return
        doc = json.loads(text)
        assert _well_formed(doc), doc
        assert certs == TeamCerts(folder, doc["team"], tuple(doc["robots"]))


@settings(derandomize=True, max_examples=150, deadline=None)
@given(doc=_manifests())
def test_a_fuzzed_manifest_is_read_or_refused_naming_team_json(doc):
    _load(json.dumps(doc))


@settings(derandomize=True, max_examples=60, deadline=None)
@given(
    text=st.one_of(
        st.text(alphabet='{}[]":,0123456789 teamrobotsab.-/NaInfinity', max_size=40),
        st.integers(0, 60).map(lambda n: json.dumps(VALID)[:n]),
        st.binary(max_size=20).map(lambda b: b.decode("latin-1")),
    )
)
def test_manifest_text_that_is_not_json_is_refused_naming_team_json(text):
    _load(text)


def test_the_valid_manifest_reads_back():
    _load(json.dumps(VALID))
