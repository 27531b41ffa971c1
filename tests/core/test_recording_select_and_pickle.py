"""Measurements.select keeps a valid table without checking it again; recordings pickle."""

import pickle
import re

import numpy as np
import pytest

from relloc.core.recording import (
    GroundTruth,
    Measurements,
    Odometry,
    Recording,
    measurement_rows,
)
from relloc.errors import DataError


def _table() -> Measurements:
    return Measurements.concatenate(
        [
            measurement_rows("bearing", t=np.arange(4.0), observer=0, target=1, value=np.zeros(4)),
            measurement_rows("range", t=np.arange(4.0), observer=1, value=np.ones(4)),
        ]
    )


def test_select_by_mask_slice_and_increasing_indices_agree():
    m = _table()
    mask = m.t >= 2.0
    by_mask, by_slice = m.select(mask), m.select(slice(4, 8))
    by_index = m.select(np.flatnonzero(mask))
    for a, b in ((by_mask, by_slice), (by_mask, by_index)):
        for name in ("t", "kind", "observer", "target", "value", "sigma", "landmark", "origin"):
            assert np.array_equal(getattr(a, name), getattr(b, name), equal_nan=True)
    assert not by_slice.t.flags.writeable and not by_mask.value.flags.writeable


def test_select_out_of_order_is_checked():
    m = _table()
    with pytest.raises(DataError, match="sorted"):
        m.select(np.array([3, 0]))
    with pytest.raises(DataError, match="sorted"):
        m.select(slice(None, None, -1))
    with pytest.raises(DataError, match="mask"):
        m.select(np.ones(3, dtype=bool))


def test_recording_survives_pickling():
    t = np.arange(3.0)
    rec = Recording(
        robots=("a", "b"),
        platforms=("ground", "ground"),
        odometry=tuple(Odometry(t=t, velocity=np.zeros((3, 4)), sigma=np.zeros(4)) for _ in "ab"),
        measurements=_table(),
        truth=tuple(GroundTruth(t=t, pose=np.zeros((3, 4))) for _ in "ab"),
        meta={"source": "test"},
    )
    back = pickle.loads(pickle.dumps(rec))
    assert back.meta == {"source": "test"} and back.robots == rec.robots
    assert np.array_equal(back.measurements.value, rec.measurements.value, equal_nan=True)
    with pytest.raises(TypeError):
        back.meta["x"] = 1  # type: ignore[index]


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"observer": 1.7, "target": 0.9}, "observer must hold integer indices"),  # was 1, 0
        ({"value": [[1.0, 0.0]], "kind": "range_bearing_elevation"}, "value is not (1, 3)"),
        ({"sigma": [1.0, 1.0]}, "sigma is not (1, 1) numbers"),
        ({"target": [1, 2]}, "target is not (1,) numbers"),
        ({"t": ["x"]}, "t: expected real numbers"),
        ({"kind": ["range"]}, "kind ['range'] is not a kind's name"),
    ],
)
def test_rows_of_the_wrong_shape_or_type_are_refused_naming_the_argument(kwargs, message):
    """These were truncated silently (non-integer indices) or raised raw numpy errors."""
    args = {"kind": "range", "t": [0.0], "observer": 1, "target": 0, "value": [2.0]} | kwargs
    with pytest.raises(DataError, match=re.escape(f"measurement_rows: {message}")):
        measurement_rows(args.pop("kind"), **args)


def test_a_range_beyond_any_sensor_is_refused_naming_the_row():
    """One range of 10¹² m left a pseudo-linear track with a negative-variance covariance, and
    the EKFs stuck near 10¹¹ m, without a word."""
    with pytest.raises(DataError, match=r"\(range\): row 1 has range 1e\+12 beyond 10000 m"):
        measurement_rows("range", t=[0.0, 1.0], observer=1, target=0, value=[2.0, 1e12])
    rbe = measurement_rows(
        "range_bearing_elevation", t=[0.0], observer=1, target=0, value=[[1e4, 0.1, 0.0]]
    )
    assert rbe.value[0, 0] == 1e4


def test_a_nan_query_time_is_refused():
    """``GroundTruth.at(nan)`` returned a NaN pose and ``Odometry.held_at(nan)`` the last
    velocity (NaN passes every span check)."""
    gt = GroundTruth(t=[0.0, 1.0], pose=[[0.0, 0.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0]], where="gt")
    od = Odometry(t=[0.0, 1.0], velocity=[[0.1, 0, 0, 0]] * 2, sigma=(0, 0, 0, 0), where="od")
    for call in (
        lambda: gt.at([0.5, np.nan]),
        lambda: od.held_at(np.nan),
        lambda: od.stamp_at(np.nan),
    ):
        with pytest.raises(DataError, match=r"^(gt|od): a query time is NaN"):
            call()
    assert od.held_at(0.5)[0, 0] == 0.1
