"""Fuzzing of :func:`relloc.datasets.bag_mapping.parse_mapping` with TOML text (the layer
above :func:`~relloc.datasets.bag_mapping.mapping_from_dict`, which test_rosbag.py fuzzes with
Python values): the sample mapping with a value replaced by a TOML literal of any kind
(dates, times, huge integers, inf/nan, arrays, inline tables), lines dropped, repeated or
cut, and text of TOML's characters. Each reads as a mapping or is a ConfigError prefixed with
the origin."""

from __future__ import annotations

from bag_samples import SAMPLE_MAPPING
from hypothesis import example, given, settings
from hypothesis import strategies as st

from relloc.datasets.bag_mapping import BagMapping, parse_mapping
from relloc.errors import ConfigError

LINES = SAMPLE_MAPPING.strip().splitlines()
VALUE_LINES = [i for i, line in enumerate(LINES) if " = " in line]

_literals = st.one_of(
    st.sampled_from(
        [
            "1979-05-27",
            "1979-05-27T07:32:00Z",
            "1979-05-27T07:32:00-08:00",
            "07:32:00",
            "1979-05-27T07:32:00",
            "inf",
            "-inf",
            "nan",
            "true",
            "0x_ff",
            "0o777",
            "1e999",
            "-0.0",
            "1" * 5000,
            "0x" + "f" * 5000,
            "'literal'",
            '"""multi\nline"""',
            '"\\u0000"',
            '"/u/{a}/{b}/{c}"',
            '"{a}"',
            "[]",
            "[[]]",
            "[1, 'a', 2.5]",
            "[0.0, 5.0, 0.0, 1.0]",
            "[1e308, 1e308, 1e308]",
            "{}",
            "{ name = 'x' }",
            "{ a = { b = [1] } }",
            "",
        ]
    ),
    st.integers().map(str),
    st.floats(allow_nan=False, allow_infinity=False).map(repr),
    st.text(max_size=8).map(lambda s: '"' + s.replace("\\", "\\\\").replace('"', '\\"') + '"'),
)


@st.composite
def _texts(draw: st.DrawFn) -> str:
    """The sample mapping with 1–3 edits: a value replaced by a literal, a line dropped or
    repeated, a key renamed; then possibly cut short."""
    lines = list(LINES)
    for _ in range(draw(st.integers(1, 3))):
        how = draw(st.sampled_from(["value", "value", "drop", "repeat", "key"]))
        i = draw(st.sampled_from(VALUE_LINES if how in ("value", "key") else range(len(lines))))
        if i >= len(lines):
            continue
        key, sep, _ = lines[i].partition(" = ")
        if how == "value" and sep:
            lines[i] = f"{key} = {draw(_literals)}"
        elif how == "key" and sep:
            new_key = draw(st.sampled_from(["nme", "robots", "uwb", "x", '"a.b"']))
            lines[i] = f"{new_key} = {lines[i].partition(' = ')[2]}"
        elif how == "drop":
            del lines[i]
        elif how == "repeat":
            lines.insert(i, lines[i])
    text = "\n".join(lines) + "\n"
    if draw(st.integers(0, 4)) == 0:
        text = text[: draw(st.integers(0, len(text)))]
    return text


def _parse(text: str) -> None:
    try:
        mapping = parse_mapping(text, "fuzzed.toml")
    except ConfigError as exc:
        assert str(exc).startswith("fuzzed.toml: "), str(exc)
        return
    assert isinstance(mapping, BagMapping)


@settings(derandomize=True, max_examples=200, deadline=None)
@given(text=_texts())
@example(SAMPLE_MAPPING.replace("sigma = 0.1", "sigma = " + "1" * 5000))  # was ValueError
@example(SAMPLE_MAPPING.replace('name = "n_4"', "name = 0x" + "f" * 5000))  # was ValueError
@example(SAMPLE_MAPPING.replace("sigma = 0.1", "sigma = 0x" + "f" * 5000))  # was ValueError
@example(SAMPLE_MAPPING.replace("sigma = 0.1", "sigma = 1" + "0" * 4300))
def test_fuzzed_mapping_text_parses_or_names_the_file(text):
    _parse(text)


@settings(derandomize=True, max_examples=100, deadline=None)
@given(text=st.text(alphabet="[]{}=\"'.,#\n \\abnrotsmeu_0123456789-+:TZ", max_size=60))
def test_toml_like_text_parses_or_names_the_file(text):
    _parse(text)


def test_the_sample_mapping_parses():
    assert [r.name for r in parse_mapping(SAMPLE_MAPPING, "m.toml").robots] == ["alpha", "beta"]
