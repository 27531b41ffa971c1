"""Fuzz of :func:`relloc.core.checks.floats`, the one rule for an array argument of real
numbers: any rectangular nesting of integers and floats comes back as numpy's float array of it;
anything holding text, None, a bool or a complex number, or nested raggedly, is the caller's
error class naming where, never a raw exception or a silent conversion."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from relloc.core.checks import floats
from relloc.errors import DataError, ModelError

REAL = st.one_of(st.integers(-(2**53), 2**53), st.floats(allow_nan=True, allow_infinity=True))
FOREIGN = st.one_of(st.text(max_size=3), st.none(), st.booleans(), st.complex_numbers())


@st.composite
def rectangular(draw: st.DrawFn, leaf: st.SearchStrategy[object]) -> object:
    """A scalar, or a list of one, two or three dimensions filled with ``leaf``."""
    shape = draw(st.lists(st.integers(1, 3), max_size=3))
    if not shape:
        return draw(leaf)
    size = int(np.prod(shape))
    flat = draw(st.lists(leaf, min_size=size, max_size=size))
    return np.array(flat, dtype=object).reshape(shape).tolist()


@settings(max_examples=300, deadline=None, derandomize=True)
@given(value=rectangular(REAL))
def test_rectangular_real_numbers_come_back_as_numpys_floats(value: object) -> None:
    out = floats(value, "w")
    expected = np.asarray(value, dtype=float)
    assert out.dtype == np.float64 and out.shape == expected.shape
    np.testing.assert_array_equal(out, expected)


@settings(max_examples=300, deadline=None, derandomize=True)
@given(value=rectangular(REAL), foreign=FOREIGN, data=st.data())
def test_anything_but_real_numbers_is_the_callers_error_naming_where(
    value: object, foreign: object, data: st.DataObject
) -> None:
    flat = np.array(value, dtype=object).reshape(-1)
    flat[data.draw(st.integers(0, flat.size - 1))] = foreign
    bad = flat.reshape(np.shape(value)).tolist() if np.ndim(value) else foreign
    with pytest.raises(ModelError, match=r"^where: expected (real numbers|an array of numbers)"):
        floats(bad, "where", ModelError)


@pytest.mark.parametrize("ragged", [[[1.0], [1.0, 2.0]], [1.0, [2.0]], [[[1.0]], [2.0]]])
def test_ragged_nesting_is_a_data_error(ragged: object) -> None:
    with pytest.raises(DataError, match=r"^w: expected (an array of numbers|real numbers)"):
        floats(ragged, "w")


def test_a_float64_array_comes_back_as_it_is() -> None:
    a = np.arange(3.0)
    assert floats(a, "w") is a
