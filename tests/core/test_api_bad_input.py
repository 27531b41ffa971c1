"""Bad input to the core Python API — the Recording constructor, Measurements.select and
concatenate, the vectorised pose algebra, circular interpolation, conditioning — is an error of
relloc's own naming the argument, never a raw numpy/Python exception or a silently wrong
result."""

from __future__ import annotations

import numpy as np
import pytest
from recording_samples import three_rows

from relloc.core.angles import circular_interp
from relloc.core.linalg import condition_log10
from relloc.core.recording import (
    CLUTTER,
    NO_TARGET,
    ORIGIN_UNKNOWN,
    GroundTruth,
    Measurements,
    Odometry,
    Recording,
    compose_pose,
    empty_measurements,
    relative_pose,
)
from relloc.errors import DataError, ModelError


def _truth(t0: float = 0.0, n: int = 5) -> GroundTruth:
    t = t0 + np.arange(n) * 0.1
    return GroundTruth(t=t, pose=np.column_stack([t, 2 * t, np.zeros(n), 0.1 * t]))


def _odometry() -> Odometry:
    return Odometry(t=np.arange(5) * 0.1, velocity=np.ones((5, 4)), sigma=np.zeros(4))


def _recording(**overrides) -> Recording:  # type: ignore[no-untyped-def]
    fields = dict(
        robots=("a", "b"),
        platforms=("ground", "aerial"),
        truth=(_truth(), _truth()),
        odometry=(_odometry(), _odometry()),
        measurements=three_rows(),
    )
    fields.update(overrides)
    return Recording(**fields)


# --- 1. the Recording constructor ----------------------------------------------------------


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("platforms", None),  # was TypeError: object of type 'NoneType' has no len()
        ("odometry", None),
        ("robots", None),  # was TypeError: 'NoneType' object is not iterable
        ("robots", "ab"),  # was silently the robots 'a' and 'b'
        ("platforms", {"ground": 1, "aerial": 2}),  # would iterate the keys
        ("truth", 5),
    ],
)
def test_recording_refuses_a_field_that_is_not_a_sequence_naming_it(field, value) -> None:
    with pytest.raises(DataError, match=f"recording.{field}: expected a sequence"):
        _recording(**{field: value})


def test_recording_materialises_generators_as_tuples() -> None:
    # was TypeError: object of type 'generator' has no len()
    rec = _recording(
        robots=(r for r in ("a", "b")),
        platforms=(p for p in ("ground", "aerial")),
        odometry=(od for od in (_odometry(), _odometry())),
        truth=(gt for gt in (_truth(), _truth())),
    )
    assert rec.robots == ("a", "b") and rec.platforms == ("ground", "aerial")
    assert isinstance(rec.odometry, tuple) and len(rec.odometry) == 2
    assert isinstance(rec.truth, tuple) and len(rec.truth) == 2


@pytest.mark.parametrize(
    "landmarks",
    [
        np.zeros((2, 2)),  # was a raw ValueError from reshape
        np.zeros(6),  # was silently reshaped to two landmarks
        np.zeros((1, 2, 3)),
        None,
        [["a", "b", "c"]],
    ],
)
def test_recording_refuses_landmarks_not_of_shape_l_by_3(landmarks) -> None:
    with pytest.raises(DataError, match=r"recording\.landmarks"):
        _recording(landmarks=landmarks)


def test_recording_takes_landmarks_l_by_3_and_an_empty_list_as_none() -> None:
    assert _recording(landmarks=np.ones((4, 3))).landmarks.shape == (4, 3)
    assert _recording(landmarks=[]).landmarks.shape == (0, 3)


@pytest.mark.parametrize(
    ("field", "value"), [("meta", None), ("meta", [1, 2]), ("skips", {"files": ()})]
)
def test_recording_refuses_meta_and_skips_of_the_wrong_type(field, value) -> None:
    with pytest.raises(DataError, match=f"recording.{field}: expected"):
        _recording(**{field: value})


def test_recording_refuses_a_platform_that_is_not_a_string() -> None:
    with pytest.raises(DataError, match=r"recording.platforms\[1\]"):
        _recording(platforms=("ground", ["aerial"]))


# --- 2. Measurements.select and concatenate -----------------------------------------------


@pytest.mark.parametrize("index", [[0, 10], np.array([3]), [-4]])
def test_select_refuses_an_index_out_of_range(index) -> None:
    # was a raw IndexError
    with pytest.raises(DataError, match=r"measurements\.select: an index is out of range for 3"):
        three_rows().select(index)


@pytest.mark.parametrize("index", [np.array([1.0]), 1.5, 1, np.array([[0, 1]]), ["a"]])
def test_select_refuses_a_float_a_scalar_or_a_2d_index(index) -> None:
    # a float array was a raw IndexError; a scalar int gave a table of 0-d columns
    with pytest.raises(DataError, match=r"measurements\.select: expected a slice"):
        three_rows().select(index)


def test_select_keeps_numpy_indexing_for_valid_picks() -> None:
    m = three_rows()
    assert m.select([-1]).t.tolist() == [0.2]
    assert m.select([]).size == 0
    assert m.select([0, 2]).t.tolist() == [0.1, 0.2]
    assert m.select(slice(1, None)).size == 2


@pytest.mark.parametrize(
    ("parts", "message"),
    [
        ("m5", "part 1 is a int, not a Measurements table"),  # was AttributeError
        ("m", "expected a sequence of Measurements tables, got Measurements"),
        (None, "expected a sequence of Measurements tables, got NoneType"),
    ],
)
def test_concatenate_refuses_parts_that_are_not_tables(parts, message) -> None:
    m = three_rows()
    given = {"m5": [m, 5], "m": m, None: None}[parts]
    with pytest.raises(DataError, match=f"measurements.concatenate: {message}"):
        Measurements.concatenate(given)


def test_concatenate_reads_a_generator_once() -> None:
    # was a raw ValueError: the generator was consumed by the time column
    a = three_rows()
    b = three_rows(t=np.array([0.3, 0.3, 0.4]))
    out = Measurements.concatenate(p for p in (b, a))
    assert out.t.tolist() == [0.1, 0.1, 0.2, 0.3, 0.3, 0.4]
    assert Measurements.concatenate(p for p in ()).size == empty_measurements().size == 0


# --- 3. relative_pose / compose_pose -------------------------------------------------------


@pytest.mark.parametrize("f", [relative_pose, compose_pose])
@pytest.mark.parametrize(
    ("a", "b"),
    [
        (np.zeros((2, 3)), np.zeros((2, 3))),  # was a raw IndexError
        (np.zeros((2, 5)), np.zeros((2, 5))),  # was silently a 5th column of garbage
        (np.zeros((2, 4)), np.zeros((2, 5))),
        (np.zeros((2, 2, 4)), np.zeros((2, 2, 4))),
    ],
)
def test_pose_algebra_refuses_poses_that_are_not_4_wide(f, a, b) -> None:
    with pytest.raises(DataError, match=f"{f.__name__}: poses are \\(x, y, z, ψ\\)"):
        f(a, b)


@pytest.mark.parametrize("f", [relative_pose, compose_pose])
def test_pose_algebra_refuses_row_counts_that_differ(f) -> None:
    # was a raw broadcast ValueError
    with pytest.raises(DataError, match=f"{f.__name__}: 2 poses against 3"):
        f(np.zeros((2, 4)), np.zeros((3, 4)))


def test_pose_algebra_still_broadcasts_one_pose_over_many() -> None:
    a = np.array([1.0, 2.0, 0.5, 0.3])
    B = np.random.default_rng(0).normal(size=(6, 4))
    rel = relative_pose(a, B)
    assert rel.shape == (6, 4)
    np.testing.assert_allclose(compose_pose(a, rel)[:, :3], B[:, :3], atol=1e-12)


# --- 4. circular_interp --------------------------------------------------------------------


@pytest.mark.parametrize(
    "t_known",
    [
        [1.0, 0.0, 2.0],  # unsorted: np.interp gave 0.0 at t = 0.5
        [0.0, 0.0, 1.0],  # repeated: np.interp gave 1.5 at t = 0.5
        [0.0, np.nan, 1.0],
    ],
)
def test_circular_interp_refuses_times_not_strictly_increasing(t_known) -> None:
    with pytest.raises(DataError, match="circular_interp: the sample times must be strictly"):
        circular_interp([0.5], t_known, [0.0, 1.0, 2.0])


@pytest.mark.parametrize(
    ("t_known", "angles"), [([0.0, 1.0], [0.0, 1.0, 2.0]), ([], []), ([[0.0, 1.0]], [[0.0, 1.0]])]
)
def test_circular_interp_refuses_shapes_that_do_not_fit(t_known, angles) -> None:
    with pytest.raises(DataError, match="circular_interp: expected 1-D sample times"):
        circular_interp([0.5], t_known, angles)


def test_circular_interp_still_interpolates_across_the_wrap() -> None:
    out = circular_interp([0.5], [0.0, 1.0], [np.pi - 0.1, -np.pi + 0.1])
    np.testing.assert_allclose(np.abs(out), [np.pi], atol=1e-12)


# --- 5. condition_log10 --------------------------------------------------------------------


@pytest.mark.parametrize(
    "M",
    [
        np.zeros((0, 0)),  # was a raw IndexError
        np.ones((1, 3)),  # was silently inf: (1, 3) + (3, 1) broadcast to (3, 3)
        2.0,  # was an AxisError
        np.ones((2, 2, 2)),
    ],
)
def test_condition_log10_refuses_a_matrix_that_is_empty_or_not_square(M) -> None:
    with pytest.raises(ModelError, match="condition_log10: expected a square matrix"):
        condition_log10(M)


def test_condition_log10_of_a_valid_matrix_is_unchanged() -> None:
    assert condition_log10(np.diag([1.0, 100.0])) == pytest.approx(2.0)
    assert condition_log10(np.diag([1.0, 0.0])) == float("inf")


# --- 7. truth spans that do not overlap ----------------------------------------------------


def test_span_of_truth_spans_that_do_not_overlap_is_an_error_naming_the_robots() -> None:
    # was the inverted span (10.0, 0.4), reported downstream as an empty replay window
    rec = _recording(robots=("a", "b"), truth=(_truth(), _truth(t0=10.0)))
    with pytest.raises(DataError, match="truth of 'b' starts at 10 s, after that of 'a' ends"):
        _ = rec.span
    assert _recording(truth=(_truth(), _truth(t0=0.2))).span == pytest.approx((0.2, 0.4))


# --- 8. negative indices other than the sentinels -----------------------------------------


@pytest.mark.parametrize(
    ("overrides", "field"),
    [
        ({"target": np.array([1, -3, 1])}, "target"),  # was read as "no target"
        ({"target": np.array([1, -1, 1]), "landmark": np.array([-1, -2, -1])}, "landmark"),
        ({"origin": np.array([1, -3, 1])}, "origin"),
    ],
)
def test_measurements_refuse_negative_indices_other_than_the_sentinels(overrides, field) -> None:
    with pytest.raises(DataError, match=f"measurements.{field}: row 1 is -[23]; the only negative"):
        three_rows(**overrides)


def test_measurements_keep_the_sentinels() -> None:
    m = three_rows(
        target=np.array([1, NO_TARGET, 1]), origin=np.array([1, ORIGIN_UNKNOWN, CLUTTER])
    )
    assert m.target.tolist() == [1, -1, 1] and m.origin.tolist() == [1, -2, -1]
