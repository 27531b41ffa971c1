"""CalibrationWindow: validation, membership, how windows are chosen and stated."""

import json

import numpy as np
import pytest

from relloc.calibration.window import (
    CalibrationWindow,
    following,
    leading_fraction,
    odometry_and_truth,
    spanning,
    split_span,
)
from relloc.datasets.mrclam import GroundTruth, Odometry
from relloc.errors import ConfigError, DataError


@pytest.mark.parametrize(
    ("start", "end", "match"),
    [
        (5.0, 5.0, "empty window"),
        (5.0, 4.0, "empty window"),
        (float("nan"), 4.0, "finite"),
        (0.0, float("inf"), "finite"),
    ],
)
def test_an_empty_or_non_finite_window_is_refused(start, end, match):
    with pytest.raises(ConfigError, match=match):
        CalibrationWindow(start, end, "run6")


def test_a_window_must_name_its_source():
    with pytest.raises(ConfigError, match="source"):
        CalibrationWindow(0.0, 1.0, "")


def test_the_window_is_closed_and_states_itself():
    w = CalibrationWindow(1.0, 3.0, "run6")
    assert w.contains([0.5, 1.0, 2.0, 3.0, 3.5]).tolist() == [False, True, True, True, False]
    assert w.duration_s == 2.0
    assert json.loads(json.dumps(w.to_dict())) == {"start_s": 1.0, "end_s": 3.0, "source": "run6"}
    err = w.too_little("no rows")
    assert isinstance(err, DataError) and "[1.00, 3.00] s of run6: no rows" in str(err)


def test_window_choices():
    assert leading_fraction(10.0, 30.0, 0.5, "r") == CalibrationWindow(10.0, 20.0, "r")
    assert following(10.0, 60.0, "r") == CalibrationWindow(10.0, 70.0, "r")
    assert spanning(np.array([3.0, 1.0, 7.0]), "r") == CalibrationWindow(1.0, 7.0, "r")
    with pytest.raises(ConfigError, match="fraction"):
        leading_fraction(0.0, 1.0, 0.0, "r")
    with pytest.raises(DataError, match="no time stamps"):
        spanning(np.zeros(0), "r")
    with pytest.raises(DataError, match="r: every time stamp is 2 s, so no calibration window"):
        spanning(np.array([2.0, 2.0]), "r")  # one instant is no window
    with pytest.raises(DataError, match="r: a time stamp is not finite"):
        spanning(np.array([2.0, np.nan]), "r")


def test_odometry_and_truth_is_where_a_robot_has_both(synthetic):
    t = np.arange(0.0, 10.0, 0.1)
    gt = GroundTruth(t=t, x=t, y=t, theta=0 * t, gap_threshold=0.5)
    odo = Odometry(t=np.array([2.0, 12.0]), v=np.zeros(2), omega=np.zeros(2))
    w = odometry_and_truth(synthetic.robot(1, gt, odo), "run6: robot 1")
    assert (w.start_s, w.end_s, w.source) == (2.0, float(t[-1]), "run6: robot 1")
    empty = Odometry(t=np.zeros(0), v=np.zeros(0), omega=np.zeros(0))
    with pytest.raises(DataError, match="robot 1 lacks odometry"):
        odometry_and_truth(synthetic.robot(1, gt, empty), "run6")


@pytest.mark.parametrize(
    ("spec", "calibration", "scored"),
    [
        ("first-half", (10.0, 20.0), (20.0, 30.0)),
        ("second-half", (20.0, 30.0), (10.0, 20.0)),
        (":12.5", (10.0, 12.5), (12.5, 30.0)),
        ("25:", (25.0, 30.0), (10.0, 25.0)),
    ],
)
def test_split_span_fits_on_one_side_and_scores_on_the_other(spec, calibration, scored):
    assert split_span(spec, 10.0, 30.0, "r") == (
        CalibrationWindow(*calibration, "r"),
        CalibrationWindow(*scored, "r"),
    )


def test_split_span_default_is_leading_fraction_half():
    # the default is the first half, the same window leading_fraction gives
    assert split_span("first-half", 0.015, 899.5, "r")[0] == leading_fraction(
        0.015, 899.5, 0.5, "r"
    )


@pytest.mark.parametrize(
    ("spec", "match"),
    [
        ("middle", "expected one of first-half, second-half"),
        ("5:20", "expected one of"),
        (":", "expected one of"),
        ("12", "expected one of"),
        (":abc", "'abc' is not a time"),
        ("nan:", "strictly inside"),
        (":10", "strictly inside"),
        ("30:", "strictly inside"),
        (":45", r"strictly inside the run's span \[10.00, 30.00\] s of r"),
    ],
)
def test_split_span_refuses_bad_values_naming_the_flag(spec, match):
    with pytest.raises(ConfigError, match=match) as err:
        split_span(spec, 10.0, 30.0, "r", flag="--calibration-window")
    assert str(err.value).startswith(f"--calibration-window {spec!r}")
