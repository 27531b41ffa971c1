"""Bad and degenerate input to the plane geometry helpers (triangle bearing, MDS, rigid
alignment, multilateration): a ConfigError, a DataError or a refusal with its reason, never a
raw exception."""

import numpy as np
import pytest

from relloc.errors import ConfigError, DataError
from relloc.geometry.multilateration import classical_mds, multilaterate, rigid_alignment
from relloc.geometry.triangle import triangle_bearing


def test_sides_too_small_to_resolve_are_refused():
    tri = triangle_bearing(0.0, 1e-200, 1e-200, 1e-200, 1)
    assert not tri.ok
    assert "too small" in tri.reason


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"side": True}, "side"),
        ({"inequality_tol": float("nan")}, "inequality_tol"),
        ({"inequality_tol": -1.0}, "inequality_tol"),
        ({"inequality_tol": "0.05"}, "inequality_tol"),
        ({"min_sin": None}, "min_sin"),
        ({"min_sin": 1.0}, "min_sin"),
    ],
)
def test_triangle_arguments_are_checked(kwargs, match):
    with pytest.raises(ConfigError, match=match):
        triangle_bearing(0.0, 1.0, 1.0, 1.0, **{"side": 1, **kwargs})


@pytest.mark.parametrize("position", range(4))
@pytest.mark.parametrize("value", ["1.0", None, True])
def test_triangle_values_that_are_not_numbers_are_named(position, value):
    names = ("phi_j", "d_0j", "d_0i", "d_ij")
    values = [0.0, 1.0, 1.0, 1.0]
    values[position] = value
    with pytest.raises(DataError, match=f"triangle_bearing.{names[position]}: expected a number"):
        triangle_bearing(*values, 1)


def test_mds_needs_a_square_matrix():
    with pytest.raises(DataError, match="square"):
        classical_mds(np.zeros((2, 3)))


@pytest.mark.parametrize(
    ("a", "b"),
    [
        (np.zeros((0, 2)), np.zeros((0, 2))),
        (np.zeros((3, 2)), np.zeros((2, 2))),
        (np.array([[np.nan, 0.0], [1.0, 0.0]]), np.zeros((2, 2))),
    ],
)
def test_rigid_alignment_refuses_empty_mismatched_or_nan_points(a, b):
    with pytest.raises(DataError, match="rigid_alignment"):
        rigid_alignment(a, b)


ANCHORS = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
X0 = np.array([[0.5, 0.5]])


@pytest.mark.parametrize(
    ("initial", "fixed", "pairs", "distances", "match"),
    [
        (X0, ANCHORS, [(0, 1), (0, 2), (0, 3)], [1.0, np.nan, 1.0], "distances"),
        (X0, ANCHORS, [(0, 1), (0, 2), (0, 3)], [1.0, 1.0], "2 distances for 3 pairs"),
        (X0, ANCHORS, [(0, 7)], [1.0], "pairs"),
        (X0, ANCHORS, [(0, -1)], [1.0], "pairs"),
        (X0, ANCHORS, [(0, 0)], [1.0], "pairs"),
        (np.array([[np.nan, 0.5]]), ANCHORS, [(0, 1)], [1.0], "initial"),
        (X0, np.array([[0.0, np.inf]]), [(0, 1)], [1.0], "fixed"),
    ],
)
def test_multilaterate_refuses_bad_input(initial, fixed, pairs, distances, match):
    with pytest.raises(DataError, match=match):
        multilaterate(initial, fixed, pairs, np.array(distances))
