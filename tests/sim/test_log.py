"""The Log type: validation errors name the field and row; truth interpolation; relative poses."""

import numpy as np
import pytest

from relloc.core.poses import relative
from relloc.errors import DataError
from relloc.sim.log import (
    GroundTruth,
    Log,
    Measurements,
    Odometry,
    empty_measurements,
    relative_pose,
)


def _truth(n=5):
    t = np.arange(n) * 0.1
    pose = np.column_stack([t, 2 * t, np.zeros(n), 0.1 * t])
    return GroundTruth(t=t, pose=pose)


def _odometry(n=5):
    return Odometry(t=np.arange(n) * 0.1, velocity=np.ones((n, 4)), sigma=np.zeros(4))


def _measurements(**overrides):
    fields = dict(
        t=np.array([0.1, 0.1, 0.2]),
        observer=np.array([0, 1, 0]),
        observed=np.array([1, 0, 1]),
        z=np.array([[1.0, 0.1, 0.0], [1.0, -0.1, 0.0], [1.1, 0.1, 0.0]]),
        sigma=np.full((3, 3), 0.01),
    )
    fields.update(overrides)
    return Measurements(**fields)


def _log(measurements=None):
    return Log(
        robots=("a", "b"),
        kinds=("ground", "aerial"),
        truth=(_truth(), _truth()),
        odometry=(_odometry(), _odometry()),
        measurements=measurements if measurements is not None else _measurements(),
    )


def test_valid_log_and_arrays_are_read_only():
    log = _log()
    assert log.n_robots == 2 and log.index("b") == 1 and log.index(0) == 0
    assert log.measurements.size == 3
    with pytest.raises(ValueError):
        log.measurements.z[0, 0] = 5.0


@pytest.mark.parametrize(
    ("overrides", "message"),
    [
        ({"t": np.array([0.2, 0.1, 0.3])}, "measurements.t: timestamps must be sorted"),
        (
            {"z": np.array([[1.0, 0.1, 0.0], [np.nan, 0, 0], [1, 0, 0]])},
            "non-finite value in row 1",
        ),
        ({"z": np.ones((3, 2))}, "measurements.z: expected shape (N, 3)"),
        ({"observer": np.array([0, 1, 1])}, "row 2 has observer == observed"),
        ({"sigma": np.zeros((3, 3))}, "measurements.sigma: row 0"),
        (
            {
                "t": np.array([0.1, 0.2, 0.2]),
                "observer": np.array([0, 0, 0]),
                "observed": np.array([1, 1, 1]),
            },
            "duplicates (t, observer, observed)",
        ),
        ({"observer": np.array([0.0, 1.0, 0.0])}, "measurements.observer: expected a 1-D integer"),
    ],
)
def test_bad_measurements_name_the_field(overrides, message):
    with pytest.raises(DataError) as err:
        _measurements(**overrides)
    assert message in str(err.value)


def test_unknown_robot_id_is_named():
    with pytest.raises(DataError, match=r"measurements.observed: row 2 names unknown robot id 7"):
        _log(_measurements(observed=np.array([1, 0, 7])))


def test_truth_and_odometry_validation():
    with pytest.raises(DataError, match=r"truth.t: timestamps must be strictly increasing; row 2"):
        GroundTruth(t=np.array([0.0, 0.1, 0.1]), pose=np.zeros((3, 4)))
    with pytest.raises(DataError, match=r"truth.pose: expected shape \(N, 4\)"):
        GroundTruth(t=np.array([0.0, 0.1]), pose=np.zeros((2, 3)))
    with pytest.raises(DataError, match=r"odometry.sigma: standard deviations must be ≥ 0"):
        Odometry(t=np.array([0.0]), velocity=np.zeros((1, 4)), sigma=-np.ones(4))
    with pytest.raises(DataError, match=r"log\.kinds"):
        Log(
            robots=("a",),
            kinds=("boat",),
            truth=(_truth(),),
            odometry=(_odometry(),),
            measurements=empty_measurements(),
        )
    with pytest.raises(DataError, match="names must be unique"):
        Log(
            robots=("a", "a"),
            kinds=("ground", "ground"),
            truth=(_truth(), _truth()),
            odometry=(_odometry(), _odometry()),
            measurements=empty_measurements(),
        )


def test_truth_interpolation_is_circular_in_yaw_and_refuses_extrapolation():
    t = np.array([0.0, 1.0])
    gt = GroundTruth(t=t, pose=np.array([[0, 0, 0, np.pi - 0.1], [1, 2, 3, -np.pi + 0.1]]))
    mid = gt.at(0.5)[0]
    np.testing.assert_allclose(mid[:3], [0.5, 1.0, 1.5])
    assert abs(abs(mid[3]) - np.pi) < 1e-12
    with pytest.raises(DataError, match="outside the recorded span"):
        gt.at(1.5)


def test_zero_order_hold_odometry():
    od = Odometry(
        t=np.array([0.0, 1.0]),
        velocity=np.array([[1.0, 0, 0, 0], [2.0, 0, 0, 0]]),
        sigma=np.ones(4),
    )
    np.testing.assert_allclose(od.held_at([-0.5, 0.0, 0.99, 1.0, 5.0])[:, 0], [0, 1, 1, 2, 2])


def test_relative_pose_matches_core_pose_algebra():
    rng = np.random.default_rng(3)
    a = rng.normal(size=(20, 4))
    b = rng.normal(size=(20, 4))
    ours = relative_pose(a, b)
    for k in range(20):
        ref, _, _ = relative(a[k], b[k])
        np.testing.assert_allclose(ours[k, :3], ref[:3], atol=1e-12)
        assert abs(np.angle(np.exp(1j * (ours[k, 3] - ref[3])))) < 1e-12
