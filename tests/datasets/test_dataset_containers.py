"""The MRCLAM per-robot containers and the UWB recording check themselves: data built by
hand or by a transform (``dataclasses.replace``, a cut, a calibration, a bag's radios) is
refused with a DataError naming the container and the column, instead of an IndexError, a NaN
fit or a silently wrong answer from unsorted times later (before, every case below was
accepted)."""

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from relloc.core.recording import FileSkips
from relloc.datasets.mrclam import GroundTruth, Measurements, Odometry
from relloc.datasets.uwb import UwbRecording
from relloc.errors import DataError

T = np.array([0.0, 1.0, 2.0])


def _truth(**changes):
    base = dict(t=T, x=T.copy(), y=0 * T, theta=0 * T, gap_threshold=0.5)
    return GroundTruth(**{**base, **changes})


def _odometry(**changes):
    return Odometry(**{**dict(t=T, v=0.2 + 0 * T, omega=0 * T), **changes})


def _camera(**changes):
    base = dict(
        t=T,
        subject=np.array([2, 3, 2]),
        barcode=np.array([5, 14, 5]),
        range=np.array([1.0, 2.0, 1.5]),
        bearing=np.array([0.1, -0.2, 0.0]),
    )
    return Measurements(**{**base, **changes})


NAN_AT_1 = np.array([0.0, np.nan, 2.0])
INF_AT_2 = np.array([0.0, 1.0, np.inf])


@pytest.mark.parametrize(
    ("build", "match"),
    [
        (lambda: _truth(theta=NAN_AT_1), r"GroundTruth\.theta: values must be finite"),
        (lambda: _truth(x=INF_AT_2), r"GroundTruth\.x: values must be finite"),
        (lambda: _truth(t=NAN_AT_1), r"GroundTruth\.t: values must be finite"),
        (lambda: _truth(y=np.zeros(2)), r"GroundTruth\.y: expected a 1-D array .* \(2,\)"),
        (lambda: _truth(t=np.zeros((3, 1))), r"GroundTruth\.t: expected a 1-D array"),
        (lambda: _truth(t=np.array([0.0, 2.0, 1.0])), r"strictly increasing; t\[1\] = 2\.0"),
        (lambda: _truth(t=np.array([0.0, 1.0, 1.0])), r"GroundTruth\.t: .* strictly increasing"),
        (lambda: _truth(gap_threshold=0.0), r"gap_threshold: must be a positive number"),
        (lambda: _truth(gap_threshold=float("nan")), r"gap_threshold"),
        (lambda: _truth(gap_threshold=True), r"gap_threshold"),
        (lambda: _odometry(v=INF_AT_2), r"Odometry\.v: values must be finite"),
        (lambda: _odometry(omega=np.array(["a", "b", "c"])), r"Odometry\.omega: .* finite"),
        (lambda: _odometry(t=np.array([0.0, 2.0, 1.0])), r"Odometry\.t: .* non-decreasing"),
        (lambda: _camera(range=np.array([1.0, 2.0])), r"Measurements\.range: expected a 1-D"),
        (lambda: _camera(bearing=NAN_AT_1), r"Measurements\.bearing: values must be finite"),
        (lambda: _camera(subject=np.array([2.0, 3.0, 2.0])), r"Measurements\.subject: .*integer"),
        (lambda: _camera(t=np.array([1.0, 0.0, 2.0])), r"Measurements\.t: .* non-decreasing"),
    ],
)
def test_bad_contents_are_refused_naming_the_column(build, match):
    with pytest.raises(DataError, match=match):
        build()


def test_what_the_containers_allow():
    """Shared stamps where the data has them (a camera frame, a repeated command), empty
    tables, and integer columns."""
    shared = np.array([0.0, 1.0, 1.0])
    assert len(_camera(t=shared)) == 3
    assert _odometry(t=shared).at(1.5)[0][0] == pytest.approx(0.2)
    empty = np.zeros(0)
    GroundTruth(t=empty, x=empty, y=empty, theta=empty, gap_threshold=0.5)
    assert _truth(x=np.array([0, 1, 2])).at(0.5).x[0] == pytest.approx(0.5)


def test_a_transform_is_checked_too():
    """``replace`` re-runs the checks, so a NaN cannot be put into a loaded robot's data."""
    with pytest.raises(DataError, match=r"GroundTruth\.theta"):
        replace(_truth(), theta=NAN_AT_1)
    assert len(_camera().of_subject(2)) == 2


def _uwb(**changes):
    base = dict(
        path=Path("ranges.csv"),
        t=np.array([0.0, 0.0, 0.1]),
        node1=np.array([1, 1, 1]),
        node2=np.array([2, 3, 2]),
        uwb_range=np.array([2.0, 3.0, 2.1]),
        mocap_range=np.array([2.0, 3.0, 2.0]),
        data_rows=3,
        skipped=FileSkips(file="ranges.csv", rows_read=3, rows_kept=3),
    )
    return UwbRecording(**{**base, **changes})


@pytest.mark.parametrize(
    ("changes", "match"),
    [
        ({"uwb_range": NAN_AT_1}, r"ranges\.csv: UwbRecording\.uwb_range: .* finite numbers"),
        ({"mocap_range": INF_AT_2}, r"UwbRecording\.mocap_range: .* finite numbers"),
        ({"node2": np.array([2.0, 3.0, 2.0])}, r"UwbRecording\.node2: values must be integers"),
        ({"node1": np.array([1, 1])}, r"UwbRecording\.node1: expected a 1-D array"),
        ({"node2": np.array([2, 1, 2])}, r"pairs a node with itself"),
        ({"t": np.array([0.0, 0.2, 0.1])}, r"UwbRecording\.t: times must be non-decreasing"),
    ],
)
def test_a_uwb_recording_refuses_bad_rows(changes, match):
    assert _uwb().links() == [(1, 2), (1, 3)]
    with pytest.raises(DataError, match=match):
        _uwb(**changes)
