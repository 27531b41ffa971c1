"""TUM text of hand-made poses: ``timestamp tx ty tz qx qy qz qw``, stamps to the nanosecond."""

from __future__ import annotations

import math

import numpy as np

from relloc.pipeline.export.tum_files import tum_lines


def _rows(text: str) -> list[list[str]]:
    return [line.split() for line in text.splitlines() if not line.startswith("#")]


def test_a_stamp_keeps_every_nanosecond():
    text = tum_lines(np.array([1.123456789]), np.array([[1.0, 2.0, 3.0]]), np.array([0.0]))
    (row,) = _rows(text)
    assert row[0] == "1.123456789"
    assert [float(v) for v in row[1:]] == [1.0, 2.0, 3.0, 0.0, 0.0, 0.0, 1.0]


def test_a_quarter_turn_is_the_quaternion_0_0_sqrt_half_sqrt_half():
    text = tum_lines(np.array([2.0]), np.array([[0.5, -0.25, 0.0]]), np.array([math.pi / 2]))
    assert text.splitlines()[0] == "# timestamp tx ty tz qx qy qz qw"
    (row,) = _rows(text)
    values = [float(v) for v in row]
    assert values[:4] == [2.0, 0.5, -0.25, 0.0]
    np.testing.assert_allclose(values[4:], [0.0, 0.0, math.sqrt(0.5), math.sqrt(0.5)], atol=1e-15)


def test_a_negative_quarter_turn_has_a_negative_z():
    (row,) = _rows(tum_lines(np.array([0.0]), np.zeros((1, 3)), np.array([-math.pi / 2])))
    np.testing.assert_allclose(
        [float(v) for v in row[4:]], [0.0, 0.0, -math.sqrt(0.5), math.sqrt(0.5)], atol=1e-15
    )
