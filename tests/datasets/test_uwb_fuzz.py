"""Property-based fuzzing of the UWB csv loader (hypothesis, derandomised, bounded).

Random mutations of realistic TIERS text — random bytes and unicode, quotes, BOMs, huge / NaN /
out-of-range numbers, shuffled, duplicated and dropped lines, dropped and extra columns, CRLF,
truncation — may make the loader raise :class:`DataError` (naming the file) and nothing else; when
it loads, ``n_rows + skipped.n_skipped == data_rows`` and the arrays keep their guarantees.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from uwb_samples import check_recording, tiers_lines

from relloc.datasets.uwb import UwbRecording, load_uwb_csv
from relloc.errors import DataError

FUZZ = settings(derandomize=True, max_examples=120, deadline=None)

BASE = tiers_lines(10)  # header + 60 data rows
N_ROWS = len(BASE) - 1
TOKENS = (
    "nan", "NaN", "inf", "-inf", "-1", "0", "-0.0", "1e19", "18446744073709551617",
    "9223372036854775807", "1e308", "1e-320", "1e999", "", '"', '""', '"1.0"', "abc", "١٢",
    "\ufeff1", "1_0", " 3 ", "0x10", "1.0\x00",
)  # fmt: skip
token = st.one_of(
    st.sampled_from(TOKENS),
    st.floats().map(repr),
    st.integers(min_value=-(2**70), max_value=2**70).map(str),
    st.text(max_size=6),
)
position = st.integers(min_value=0, max_value=10**6)
Mutation = tuple[str, int, object]
mutation: st.SearchStrategy[Mutation] = st.one_of(
    st.tuples(st.just("insert_bytes"), position, st.binary(min_size=1, max_size=6)),
    st.tuples(st.just("insert_text"), position, st.text(min_size=1, max_size=6)),
    st.tuples(st.just("insert_quote"), position, st.sampled_from(['"', '""', "'"])),
    st.tuples(st.just("bom"), position, st.none()),
    st.tuples(st.just("set_field"), position, st.tuples(st.integers(0, 9), token)),
    st.tuples(st.just("drop_field"), position, st.integers(0, 9)),
    st.tuples(st.just("add_field"), position, token),
    st.tuples(st.just("swap_lines"), position, position),
    st.tuples(st.just("duplicate_line"), position, position),
    st.tuples(st.just("drop_line"), position, st.none()),
    st.tuples(st.just("truncate"), position, st.none()),
    st.tuples(st.just("crlf"), position, st.none()),
)


def _at_line(lines: list[bytes], pos: int, edit: Callable[[bytes], bytes]) -> list[bytes]:
    """``lines`` with line ``pos mod len`` passed through ``edit`` (the header included)."""
    out = list(lines)
    if out:
        k = pos % len(out)
        out[k] = edit(out[k])
    return out


def _set_field(line: bytes, k: int, value: bytes) -> bytes:
    fields = line.split(b",")
    fields[k % len(fields)] = value
    return b",".join(fields)


def _drop_field(line: bytes, k: int) -> bytes:
    fields = line.split(b",")
    del fields[k % len(fields)]
    return b",".join(fields)


def _mutate_bytes(data: bytes, kind: str, pos: int, arg: object) -> bytes:
    """Mutations of the whole file's bytes (may create or remove line breaks)."""
    at = pos % (len(data) + 1)
    if kind == "insert_bytes":
        assert isinstance(arg, bytes)
        return data[:at] + arg + data[at:]
    if kind in ("insert_text", "insert_quote"):
        assert isinstance(arg, str)
        return data[:at] + arg.encode("utf-8", "surrogatepass") + data[at:]
    if kind == "truncate":
        return data[:at]
    assert kind == "crlf"
    return data.replace(b"\n", b"\r\n")


def _mutate_lines(lines: list[bytes], kind: str, pos: int, arg: object) -> list[bytes]:
    """Mutations of one line or of the order of lines."""
    if kind == "bom":
        return _at_line(lines, pos, lambda line: b"\xef\xbb\xbf" + line)
    if kind == "set_field":
        assert isinstance(arg, tuple)
        k, value = arg
        return _at_line(
            lines, pos, lambda line: _set_field(line, k, value.encode("utf-8", "surrogatepass"))
        )
    if kind == "drop_field":
        assert isinstance(arg, int)
        return _at_line(lines, pos, lambda line: _drop_field(line, arg))
    if kind == "add_field":
        assert isinstance(arg, str)
        return _at_line(lines, pos, lambda line: line + b"," + arg.encode("utf-8", "surrogatepass"))
    if not lines:
        return lines
    i = pos % len(lines)
    out = list(lines)
    if kind == "swap_lines":
        assert isinstance(arg, int)
        j = arg % len(out)
        out[i], out[j] = out[j], out[i]
    elif kind == "duplicate_line":
        assert isinstance(arg, int)
        out.insert(arg % (len(out) + 1), out[i])
    else:
        assert kind == "drop_line"
        del out[i]
    return out


def _apply(mutations: list[Mutation]) -> bytes:
    data = b"\n".join(BASE) + b"\n"
    for kind, pos, arg in mutations:
        if kind in ("insert_bytes", "insert_text", "insert_quote", "truncate", "crlf"):
            data = _mutate_bytes(data, kind, pos, arg)
        else:
            lines = _mutate_lines(data.split(b"\n"), kind, pos, arg)
            data = b"\n".join(lines)
    return data


@pytest.fixture(scope="module")
def csv_path(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("uwb_fuzz") / "fuzzed.csv"


@pytest.fixture(scope="module")
def clean(tmp_path_factory: pytest.TempPathFactory) -> UwbRecording:
    """The unmutated text, loaded."""
    path = tmp_path_factory.mktemp("uwb_clean") / "clean.csv"
    path.write_bytes(b"\n".join(BASE) + b"\n")
    return load_uwb_csv(path)


def _load_or_data_error(path: Path, data: bytes) -> UwbRecording | None:
    """Load ``data``; a DataError (naming the file) gives None, any other exception fails."""
    path.write_bytes(data)
    try:
        rec = load_uwb_csv(path)
    except DataError as exc:
        assert str(path) in str(exc)
        return None
    check_recording(rec, data)
    return rec


@FUZZ
@given(mutations=st.lists(mutation, min_size=1, max_size=6))
def test_no_mutation_breaks_the_loader_or_the_row_count(csv_path, mutations):
    _load_or_data_error(csv_path, _apply(mutations))


# line-local corruptions that make a row unusable whatever the rest of the file holds
SPOIL: dict[str, Callable[[bytes, int], bytes]] = {
    "invalid byte": lambda line, p: line[: p % len(line)] + b"\xff" + line[p % len(line) :],
    "open quote": lambda line, p: _set_field(line, p, b'"' + line.split(b",")[p % 8]),
    "NaN field": lambda line, p: _set_field(line, (0, 3, 4, 7)[p % 4], b"nan"),
    "wrapping id": lambda line, p: _set_field(line, 1 + p % 2, b"18446744073709551617"),
    "self pair": lambda line, p: _set_field(line, 2, line.split(b",")[1]),
    "negative range": lambda line, p: _set_field(line, 3 + p % 2, b"-1.0"),
    "dropped field": lambda line, p: _drop_field(line, p),
    "extra field": lambda line, p: line + b"," + str(p).encode(),
    "inner BOM": lambda line, p: b"\xef\xbb\xbf" + line,
}


@FUZZ
@given(
    spoiled=st.dictionaries(
        st.integers(min_value=2, max_value=N_ROWS + 1),
        st.tuples(st.sampled_from(sorted(SPOIL)), st.integers(min_value=0, max_value=200)),
        min_size=1,
        max_size=12,
    )
)
def test_each_spoiled_line_costs_exactly_itself(csv_path, clean, spoiled):
    lines = list(BASE)
    for k, (kind, p) in spoiled.items():
        lines[k - 1] = SPOIL[kind](lines[k - 1], p)
    rec = _load_or_data_error(csv_path, b"\n".join(lines) + b"\n")
    assert rec is not None
    kept = [k - 2 for k in range(2, N_ROWS + 2) if k not in spoiled]
    assert rec.t.tolist() == clean.t[kept].tolist()
    assert rec.uwb_range.tolist() == clean.uwb_range[kept].tolist()
    assert rec.node1.tolist() == clean.node1[kept].tolist()
    assert rec.skipped.n_skipped == len(spoiled)
    first = sorted(spoiled)[:5]
    assert [e.line for e in rec.skipped.examples] == first


@FUZZ
@given(
    k=st.integers(min_value=2, max_value=N_ROWS + 1),
    t=st.one_of(st.floats(), st.floats(min_value=1.6714629e9, max_value=1.6714630e9)),
)
def test_one_mistyped_timestamp_costs_at_most_its_row(csv_path, k, t):
    lines = list(BASE)
    lines[k - 1] = _set_field(lines[k - 1], 0, repr(t).encode())
    rec = _load_or_data_error(csv_path, b"\n".join(lines) + b"\n")
    assert rec is not None and rec.n_rows >= N_ROWS - 1


@FUZZ
@given(order=st.permutations(range(1, N_ROWS + 1)), copies=st.lists(position, max_size=5))
def test_shuffled_and_repeated_rows_keep_time_in_order(csv_path, order, copies):
    body = [BASE[i] for i in order]
    for c in copies:
        body.insert(c % (len(body) + 1), body[c % len(body)])
    rec = _load_or_data_error(csv_path, b"\n".join([BASE[0], *body]) + b"\n")
    assert rec is not None  # every row is valid on its own: some order always survives
