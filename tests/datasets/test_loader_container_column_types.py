"""The dataset containers refuse boolean columns: a mask passed where times, positions or ids
belong is neither a number column nor an id column (``relloc.datasets.columns.check_columns``)."""

from __future__ import annotations

import numpy as np
import pytest

from relloc.datasets.mrclam import GroundTruth, Measurements
from relloc.errors import DataError

T = np.array([0.0, 1.0, 2.0])
MASK = np.array([True, False, True])


def test_a_boolean_position_column_is_not_finite_numbers():
    with pytest.raises(DataError, match=r"mrclam GroundTruth\.x: values must be finite numbers"):
        GroundTruth(t=T, x=MASK, y=0 * T, theta=0 * T, gap_threshold=0.5)


def test_a_boolean_id_column_is_not_integers():
    with pytest.raises(DataError, match=r"mrclam Measurements\.subject: values must be integers"):
        Measurements(
            t=T,
            subject=MASK,
            barcode=np.array([5, 14, 5]),
            range=np.array([1.0, 2.0, 1.5]),
            bearing=np.array([0.1, -0.2, 0.0]),
        )
