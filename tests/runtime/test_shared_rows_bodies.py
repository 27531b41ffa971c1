"""Shared readings (``rows``) between a table and its wire body: per-row lengths, landmark
bounds, unstated σ and who observed what."""

from __future__ import annotations

import numpy as np
import pytest

from relloc.runtime.messages import MessageRejected
from relloc.runtime.shared_rows import rows_body, rows_from_body

ROSTER = ("1", "2", "3")


def _body(**overrides: object) -> dict:
    body = {
        "stamps": np.array([0.1, 0.2]),
        "kinds": ["range_bearing", "bearing"],
        "subjects": ["1", ""],
        "landmarks": np.array([-1.0, 4.0]),
        "sensors": np.array([0.0, 2.0]),
        "values": np.array([3.0, 0.25, -0.5]),
        "sigmas": np.array([0.1, -1.0, 0.02]),
    }
    return body | {
        k: (np.asarray(v) if k not in ("kinds", "subjects") else v) for k, v in overrides.items()
    }


def _reason(body: dict, landmarks: int | None = None) -> str:
    with pytest.raises(MessageRejected) as info:
        rows_from_body(body, ROSTER, "2", landmarks)
    return info.value.reason


def test_a_body_becomes_the_senders_readings_with_unstated_sigma_as_nan():
    rows = rows_from_body(_body(), ROSTER, "2", landmarks=5)
    assert rows.observer.tolist() == [1, 1]
    assert rows.target.tolist() == [0, -1]
    assert rows.landmark.tolist() == [-1, 4] and rows.sensor.tolist() == [0, 2]
    np.testing.assert_array_equal(rows.value[0], [3.0, 0.25, np.nan])
    np.testing.assert_array_equal(rows.value[1], [-0.5, np.nan, np.nan])
    np.testing.assert_array_equal(rows.sigma[0], [0.1, np.nan, np.nan])
    np.testing.assert_array_equal(rows.sigma[1], [0.02, np.nan, np.nan])


@pytest.mark.parametrize(
    "change",
    [
        {"subjects": ["1"]},
        {"kinds": ["bearing"], "values": [0.25], "sigmas": [0.02]},
        {"sensors": [0.0]},
        {"landmarks": [-1.0]},
        {"sigmas": [0.1, -1.0]},
        {"values": [3.0, 0.25]},
    ],
    ids=["subjects", "kinds", "sensors", "landmarks", "sigmas", "values"],
)
def test_a_field_of_the_wrong_length_is_a_shape_error(change):
    assert _reason(_body(**change)) == "shape"


def test_an_unknown_kind_is_malformed():
    assert _reason(_body(kinds=["range_bearing", "smell"])) == "malformed"


def test_a_landmark_index_must_lie_within_the_receivers_map():
    assert _reason(_body(), landmarks=4) == "unknown_landmark"  # indices 0…3
    assert rows_from_body(_body(), ROSTER, "2", landmarks=5).size == 2


def test_the_body_of_a_table_carries_unstated_sigma_as_minus_one_and_subjects_by_id():
    rows = rows_from_body(_body(), ROSTER, "2")
    body = rows_body(rows, ROSTER)
    assert body["subjects"] == ["1", ""]
    assert body["kinds"] == ["range_bearing", "bearing"]
    assert np.asarray(body["sigmas"]).tolist() == [0.1, -1.0, 0.02]
    assert np.asarray(body["values"]).tolist() == [3.0, 0.25, -0.5]
