"""Fuzzing of :func:`relloc.experiments.mrclam_team.parse_case` (``--case MODE/ANCHORS`` of
``relloc team up MRCLAM_DIR --estimator cooperative``): any text, cases with a part changed,
and values that are not text are a ``(mode, anchors)`` of the case or a ConfigError naming
``--case``."""

from __future__ import annotations

from hypothesis import given, settings
from hypothesis import strategies as st

from relloc.errors import ConfigError
from relloc.experiments.mrclam_cl import ANCHORS, MODES
from relloc.experiments.mrclam_team import parse_case

_parts = st.one_of(st.sampled_from([*MODES, *ANCHORS, "", "/", " "]), st.text(max_size=6))
CASES = st.one_of(
    st.text(max_size=30),
    st.lists(_parts, max_size=4).map("/".join),
    st.tuples(st.sampled_from(MODES), st.sampled_from(ANCHORS)).map("/".join),
    st.tuples(_parts, _parts).map("".join),
    st.none(),
    st.integers(),
    st.binary(max_size=8),
    st.lists(st.sampled_from([*MODES, *ANCHORS]), max_size=2),
)


@settings(derandomize=True, max_examples=200, deadline=None)
@given(case=CASES)
def test_a_fuzzed_case_is_its_parts_or_names_the_flag(case):
    try:
        mode, anchors = parse_case(case)
    except ConfigError as exc:
        assert str(exc).startswith("--case: "), str(exc)
        return
    assert mode in MODES and anchors in ANCHORS and case == f"{mode}/{anchors}"


def test_every_case_parses():
    for mode in MODES:
        for anchors in ANCHORS:
            assert parse_case(f"{mode}/{anchors}") == (mode, anchors)
