"""Dataset files that exist but cannot be read, and the MRCLAM containers' queries on empty
streams, non-finite times and unknown landmarks."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

from relloc.datasets.mrclam import GroundTruth, Landmarks, Odometry, load_mrclam
from relloc.datasets.uwb import load_uwb_csv
from relloc.errors import DataError

sys.path.insert(0, str(Path(__file__).parent))
from test_mrclam import _small_dataset

# a regular file on Linux whose read fails with an I/O error, whoever runs the test
UNREADABLE = Path("/proc/self/mem")
needs_unreadable = pytest.mark.skipif(not UNREADABLE.is_file(), reason="needs /proc/self/mem")


@needs_unreadable
def test_an_mrclam_file_that_cannot_be_read_is_named(tmp_path: Path) -> None:
    folder = _small_dataset(tmp_path / "ds")
    target = folder / "Robot2_Odometry.dat"
    target.unlink()
    target.symlink_to(UNREADABLE)
    with pytest.raises(DataError, match=r"Robot2_Odometry\.dat: cannot read: .*Input/output"):
        load_mrclam(folder)


@needs_unreadable
def test_a_uwb_csv_that_cannot_be_read_is_named(tmp_path: Path) -> None:
    csv = tmp_path / "uwb.csv"
    csv.symlink_to(UNREADABLE)
    with pytest.raises(DataError, match=r"uwb\.csv: cannot read UWB csv: .*Input/output"):
        load_uwb_csv(csv)


def test_queries_of_empty_streams_are_invalid_or_zero() -> None:
    """A robot without ground truth or odometry (hand-built containers): every truth query is
    NaN and invalid, every command 0."""
    empty = np.zeros(0)
    truth = GroundTruth(t=empty, x=empty, y=empty, theta=empty, gap_threshold=0.5)
    q = truth.at([0.0, 1.0])
    assert np.isnan(q.x).all() and np.isnan(q.y).all() and np.isnan(q.theta).all()
    assert not q.valid.any() and not q.inside.any() and not q.in_gap.any()
    v, w = Odometry(t=empty, v=empty, omega=empty).at([0.0, 1.0])
    np.testing.assert_array_equal(v, [0.0, 0.0])
    np.testing.assert_array_equal(w, [0.0, 0.0])


def test_a_non_finite_truth_query_is_refused() -> None:
    t = np.array([0.0, 1.0])
    truth = GroundTruth(t=t, x=t, y=t, theta=0 * t, gap_threshold=0.5)
    with pytest.raises(DataError, match=r"GroundTruth\.at: query times must be finite"):
        truth.at([0.5, np.nan])


def test_an_unknown_landmark_is_named() -> None:
    lm = Landmarks(subject=np.array([6, 7]), xy=np.zeros((2, 2)), std=np.zeros((2, 2)))
    np.testing.assert_array_equal(lm.position(7), [0.0, 0.0])
    with pytest.raises(DataError, match=r"landmark 9 is not in Landmark_Groundtruth\.dat"):
        lm.position(9)
