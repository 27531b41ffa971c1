"""The Recording: validation errors name the field and row; every measurement kind, the sensor
column, origin, NaN padding, duplicates and unknown-correspondence rows; skip reports; truth
interpolation; relative poses."""

import numpy as np
import pytest
from recording_samples import RBE, three_rows

from relloc.core.poses import relative
from relloc.core.recording import (
    CLUTTER,
    KIND_NAMES,
    KINDS,
    NO_TARGET,
    ORIGIN_UNKNOWN,
    VALUE_WIDTH,
    FileSkips,
    GroundTruth,
    Measurements,
    Odometry,
    Recording,
    SkippedRow,
    SkipReport,
    empty_measurements,
    kind_code,
    measurement_rows,
    relative_pose,
)
from relloc.errors import DataError


def _truth(n=5):
    t = np.arange(n) * 0.1
    pose = np.column_stack([t, 2 * t, np.zeros(n), 0.1 * t])
    return GroundTruth(t=t, pose=pose)


def _odometry(n=5):
    return Odometry(t=np.arange(n) * 0.1, velocity=np.ones((n, 4)), sigma=np.zeros(4))


def _recording(measurements=None, **overrides):
    fields = dict(
        robots=("a", "b"),
        platforms=("ground", "aerial"),
        truth=(_truth(), _truth()),
        odometry=(_odometry(), _odometry()),
        measurements=measurements if measurements is not None else three_rows(),
    )
    fields.update(overrides)
    return Recording(**fields)


def test_valid_recording_and_arrays_are_read_only():
    rec = _recording()
    assert rec.n_robots == 2 and rec.index("b") == 1 and rec.index(0) == 0
    assert rec.measurements.size == 3 and len(rec.measurements) == 3
    assert rec.measurements.kind_names() == ("range_bearing_elevation",) * 3
    with pytest.raises(ValueError):
        rec.measurements.value[0, 0] = 5.0
    with pytest.raises(DataError, match="unknown robot 'c'"):
        rec.index("c")


@pytest.mark.parametrize(
    ("overrides", "message"),
    [
        ({"t": np.array([0.2, 0.1, 0.3])}, "measurements.t: timestamps must be sorted"),
        (
            {"value": np.array([[1.0, 0.1, 0.0], [np.nan, 0, 0], [1, 0, 0]])},
            "row 1 has a non-finite ('range', 'azimuth', 'elevation') value",
        ),
        (
            {"value": np.array([[1.0, 0.1, 0.0], [np.inf, 0, 0], [1, 0, 0]])},
            "measurements.value: non-finite value in row 1",
        ),
        ({"value": np.ones((3, 2))}, "measurements.value: expected shape (N, 3)"),
        ({"observer": np.array([0, 1, 1])}, "row 2 has observer == target"),
        ({"sigma": np.zeros((3, 3))}, "row 0 has a standard deviation ≤ 0"),
        ({"value": np.array([[1.0, 0.1, 0.0], [-1.0, 0, 0], [1, 0, 0]])}, "row 1 has range ≤ 0"),
        ({"kind": np.array([RBE, 99, RBE])}, "row 1 has unknown kind code 99"),
        (
            {
                "t": np.array([0.1, 0.2, 0.2]),
                "observer": np.array([0, 0, 0]),
                "target": np.array([1, 1, 1]),
            },
            "row 2 repeats (t, kind, observer, sensor, target, landmark)",
        ),
        ({"observer": np.array([0.0, 1.0, 0.0])}, "measurements.observer: expected a 1-D integer"),
        ({"observer": np.array([0, -1, 0])}, "measurements.observer: row 1 is < 0"),
        ({"sensor": np.array([0, -2, 0])}, "measurements.sensor: row 1 is < 0"),
        ({"target": np.array([1, 0])}, "measurements.target: 2 rows but 3 timestamps"),
    ],
)
def test_bad_measurements_name_the_field(overrides, message):
    with pytest.raises(DataError) as err:
        three_rows(**overrides)
    assert message in str(err.value)


def test_unknown_indices_are_named():
    with pytest.raises(DataError, match=r"measurements.target: row 2 names unknown index 7"):
        _recording(three_rows(target=np.array([1, 0, 7])))
    with pytest.raises(DataError, match=r"measurements.landmark: row 0 names unknown index 0"):
        _recording(measurement_rows("range", t=[0.1], observer=0, value=[2.0], landmark=0))
    with pytest.raises(DataError, match=r"measurements.origin: row 0 names unknown index 5"):
        _recording(
            measurement_rows("range", t=[0.1], observer=0, value=[2.0], origin=np.array([5]))
        )


@pytest.mark.parametrize("name", KIND_NAMES)
def test_every_kind_round_trips_nan_padded(name):
    spec = KINDS[name]
    target = NO_TARGET if spec.needs_target == "none" else 1
    value = np.arange(1.0, spec.dim + 1.0).reshape(1, -1) * 0.5
    m = measurement_rows(name, t=[0.1], observer=0, value=value, sigma=0.1, target=target)
    assert m.kind_names() == (name,) and KIND_NAMES[int(m.kind[0])] == name
    assert m.value.shape == (1, VALUE_WIDTH) and m.sigma.shape == (1, VALUE_WIDTH)
    np.testing.assert_array_equal(m.values(name), value)
    assert np.isnan(m.value[0, spec.dim :]).all() and np.isnan(m.sigma[0, spec.dim :]).all()
    np.testing.assert_array_equal(m.sigma[0, : spec.dim], 0.1)
    rec = _recording(m)
    assert rec.measurements.of_kind(name).size == 1


def test_values_beyond_a_kind_must_be_nan_and_sigma_may_be_unstated():
    with pytest.raises(DataError, match=r"\(range\): row 0 has values beyond the kind's 1"):
        Measurements(
            t=np.array([0.1]),
            kind=np.array([kind_code("range")]),
            observer=np.array([0]),
            target=np.array([1]),
            value=np.array([[2.0, 0.0, np.nan]]),
            sigma=np.full((1, 3), np.nan),
        )
    with pytest.raises(DataError, match=r"σ given beyond the kind's 2 columns"):
        Measurements(
            t=np.array([0.1]),
            kind=np.array([kind_code("range_bearing")]),
            observer=np.array([0]),
            target=np.array([1]),
            value=np.array([[2.0, 0.1, np.nan]]),
            sigma=np.array([[0.1, 0.1, 0.1]]),
        )
    unstated = measurement_rows("bearing", t=[0.1], observer=0, value=[0.3], target=1)
    assert np.isnan(unstated.sigma).all()


def test_targets_a_kind_needs():
    with pytest.raises(DataError, match=r"\(height\): row 0 needs a target robot"):
        measurement_rows("height", t=[0.1], observer=0, value=[1.0])
    with pytest.raises(DataError, match=r"\(pose\): row 0 is absolute and must name no target"):
        measurement_rows("pose", t=[0.1], observer=0, value=[[1.0, 2.0, 0.1]], target=1)
    with pytest.raises(DataError, match="row 0 names both a robot and a landmark"):
        measurement_rows("range", t=[0.1], observer=0, value=[1.0], target=1, landmark=0)
    with pytest.raises(DataError, match="unknown measurement kind 'lidar'"):
        measurement_rows("lidar", t=[0.1], observer=0, value=[1.0])


def test_sensor_column_tells_apart_two_sensors_of_one_robot():
    two = measurement_rows(
        "range",
        t=[0.1, 0.1],
        observer=0,
        target=1,
        value=[2.0, 2.1],
        sensor=np.array([0, 1]),
    )
    np.testing.assert_array_equal(two.sensor, [0, 1])
    with pytest.raises(DataError, match="row 1 repeats"):
        measurement_rows("range", t=[0.1, 0.1], observer=0, target=1, value=[2.0, 2.1])
    # another kind at the same instant is not a duplicate
    both = Measurements.concatenate(
        [
            measurement_rows("range", t=[0.1], observer=0, target=1, value=[2.0]),
            measurement_rows("bearing", t=[0.1], observer=0, target=1, value=[0.3]),
        ]
    )
    assert both.kind_names() == ("range", "bearing")


def test_unknown_correspondence_rows_may_repeat_and_origin_is_for_scoring():
    # three readings of unknown correspondence at one instant (two robots and a clutter point)
    m = measurement_rows(
        "range_bearing",
        t=[0.1, 0.1, 0.1],
        observer=0,
        value=[[2.0, 0.1], [2.0, 0.1], [3.0, -0.2]],
        origin=np.array([1, ORIGIN_UNKNOWN, CLUTTER]),
    )
    np.testing.assert_array_equal(m.target, NO_TARGET)
    np.testing.assert_array_equal(m.origin, [1, ORIGIN_UNKNOWN, CLUTTER])
    assert _recording(m).measurements.size == 3
    # by default origin is the target where it is a robot, unknown elsewhere
    known = measurement_rows("range", t=[0.1, 0.2], observer=0, value=[1.0, 1.0], target=[1, -1])
    np.testing.assert_array_equal(known.origin, [1, ORIGIN_UNKNOWN])


def test_select_of_kind_and_concatenate_keep_every_column():
    a = measurement_rows(
        "range_bearing_elevation", t=[0.1, 0.3], observer=0, target=1, value=np.ones((2, 3))
    )
    b = measurement_rows("range", t=[0.2], observer=1, value=[4.0], sensor=2, landmark=-1)
    both = Measurements.concatenate([a, b])
    np.testing.assert_array_equal(both.t, [0.1, 0.2, 0.3])
    np.testing.assert_array_equal(both.sensor, [0, 2, 0])
    np.testing.assert_array_equal(both.observer, [0, 1, 0])
    assert both.of_kind("range").size == 1 and both.select(np.array([0, 2])).size == 2
    assert Measurements.concatenate([]).size == 0 and empty_measurements().size == 0


def test_truth_and_odometry_validation():
    with pytest.raises(DataError, match=r"truth.t: timestamps must be strictly increasing; row 2"):
        GroundTruth(t=np.array([0.0, 0.1, 0.1]), pose=np.zeros((3, 4)))
    with pytest.raises(DataError, match=r"truth.pose: expected shape \(N, 4\)"):
        GroundTruth(t=np.array([0.0, 0.1]), pose=np.zeros((2, 3)))
    with pytest.raises(DataError, match=r"odometry.sigma: standard deviations must be ≥ 0"):
        Odometry(t=np.array([0.0]), velocity=np.zeros((1, 4)), sigma=-np.ones(4))
    with pytest.raises(DataError, match=r"recording\.platforms\[0\]"):
        _recording(
            robots=("a",),
            platforms=("boat",),
            truth=(_truth(),),
            odometry=(_odometry(),),
            measurements=empty_measurements(),
        )
    with pytest.raises(DataError, match="names must be unique"):
        _recording(robots=("a", "a"), measurements=empty_measurements())
    with pytest.raises(DataError, match=r"recording\.truth: 1 entries for 2 robots"):
        _recording(truth=(_truth(),))


def test_a_recording_without_truth_spans_its_data_and_refuses_truth_queries():
    rec = _recording(truth=None)
    assert rec.span == pytest.approx((0.0, 0.4))
    with pytest.raises(DataError, match="relative_truth needs ground truth"):
        rec.relative_truth(0, 1, 0.1)


def test_truth_interpolation_is_circular_in_yaw_and_refuses_extrapolation():
    t = np.array([0.0, 1.0])
    gt = GroundTruth(t=t, pose=np.array([[0, 0, 0, np.pi - 0.1], [1, 2, 3, -np.pi + 0.1]]))
    mid = gt.at(0.5)[0]
    np.testing.assert_allclose(mid[:3], [0.5, 1.0, 1.5])
    assert abs(abs(mid[3]) - np.pi) < 1e-12
    with pytest.raises(DataError, match="outside the recorded span"):
        gt.at(1.5)


def test_zero_order_hold_odometry_and_its_stamps():
    od = Odometry(
        t=np.array([0.0, 1.0]),
        velocity=np.array([[1.0, 0, 0, 0], [2.0, 0, 0, 0]]),
        sigma=np.ones(4),
    )
    np.testing.assert_allclose(od.held_at([-0.5, 0.0, 0.99, 1.0, 5.0])[:, 0], [0, 1, 1, 2, 2])
    np.testing.assert_array_equal(od.stamp_at([-0.5, 0.5, 5.0]), [np.nan, 0.0, 1.0])


def test_skip_report_adds_up_per_file_and_reason():
    report = SkipReport(
        files=(
            FileSkips(
                file="a.dat",
                rows_read=10,
                rows_kept=7,
                skipped={"nan": 2, "duplicate time": 1},
                examples=(SkippedRow(line=4, reason="nan", text="1.0 nan"),),
            ),
            FileSkips(file="b.dat", rows_read=3, rows_kept=2, skipped={"nan": 1}),
        )
    )
    assert report.n_skipped == 4
    assert report.skipped_by_reason() == {"nan": 3, "duplicate time": 1}
    d = report.to_dict()
    assert d["rows_skipped"] == 4 and d["files"]["a.dat"]["rows_kept"] == 7
    assert d["files"]["a.dat"]["examples"] == [{"line": 4, "reason": "nan", "text": "1.0 nan"}]
    assert _recording(skips=report).skips.n_skipped == 4


def test_relative_pose_matches_core_pose_algebra():
    rng = np.random.default_rng(3)
    a = rng.normal(size=(20, 4))
    b = rng.normal(size=(20, 4))
    ours = relative_pose(a, b)
    for k in range(20):
        ref, _, _ = relative(a[k], b[k])
        np.testing.assert_allclose(ours[k, :3], ref[:3], atol=1e-12)
        assert abs(np.angle(np.exp(1j * (ours[k, 3] - ref[3])))) < 1e-12


def test_ground_truth_marks_its_gaps():
    pose = np.zeros((4, 4))
    truth = GroundTruth(t=np.array([0.0, 0.1, 1.1, 1.2]), pose=pose, gap_s=0.5)
    # inside the 1 s dropout the pose is bridged, not measured; outside the span it is unknown
    np.testing.assert_array_equal(
        truth.valid_at([0.0, 0.05, 0.1, 0.6, 1.1, 1.15, 1.2, 1.3]),
        [True, True, True, False, True, True, True, False],
    )
    assert GroundTruth(t=np.array([0.0, 5.0]), pose=np.zeros((2, 4))).valid_at(2.5).all()
    with pytest.raises(DataError, match="gap_s"):
        GroundTruth(t=np.array([0.0, 1.0]), pose=np.zeros((2, 4)), gap_s=0.0)
