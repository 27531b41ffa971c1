"""Builders of small synthetic MRCLAM-type datasets with known error models."""

from pathlib import Path

import numpy as np
import pytest

from relloc.calibration.odometry import command_response
from relloc.core.angles import wrap_angle
from relloc.datasets.mrclam import (
    GroundTruth,
    Landmarks,
    LoadReport,
    Measurements,
    MrclamDataset,
    Odometry,
    RobotData,
)

GAP_THRESHOLD_S = 0.5


def no_measurements() -> Measurements:
    return Measurements(
        np.zeros(0), np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(0), np.zeros(0)
    )


def measurements(t, subject, rng_m, bearing) -> Measurements:
    order = np.argsort(t, kind="stable")
    subject = np.asarray(subject, dtype=np.int64)[order]
    return Measurements(
        np.asarray(t, dtype=float)[order],
        subject,
        subject + 100,
        np.asarray(rng_m, dtype=float)[order],
        np.asarray(bearing, dtype=float)[order],
    )


def robot(subject, gt, odo, meas=None) -> RobotData:
    return RobotData(
        subject=subject,
        barcode=subject + 100,
        groundtruth=gt,
        odometry=odo,
        measurements=meas if meas is not None else no_measurements(),
    )


def still_robot(subject, x, y, theta, duration, meas=None) -> RobotData:
    """A robot standing at ``(x, y, θ)`` for ``duration`` s (10 Hz ground truth, no command)."""
    t = np.arange(0.0, duration, 0.1)
    gt = GroundTruth(
        t=t,
        x=np.full(t.size, x),
        y=np.full(t.size, y),
        theta=np.full(t.size, theta),
        gap_threshold=GAP_THRESHOLD_S,
    )
    odo = Odometry(t=np.array([0.0]), v=np.zeros(1), omega=np.zeros(1))
    return robot(subject, gt, odo, meas)


def dataset(robots, landmarks_xy=None, first_landmark=10) -> MrclamDataset:
    xy = np.zeros((0, 2)) if landmarks_xy is None else np.asarray(landmarks_xy, dtype=float)
    subjects = np.arange(first_landmark, first_landmark + len(xy), dtype=np.int64)
    return MrclamDataset(
        path=Path("synthetic"),
        t0_unix=0.0,
        barcodes={},
        robots={r.subject: r for r in robots},
        landmarks=Landmarks(subject=subjects, xy=xy, std=np.zeros_like(xy)),
        report=LoadReport(folder="synthetic"),
    )


def commanded_robot(
    subject: int,
    rng: np.random.Generator,
    *,
    duration: float,
    latency: float = 0.0,
    scale_v: float = 1.0,
    scale_w: float = 1.0,
    sigma_v: float = 0.0,
    sigma_w: float = 0.0,
    dt: float = 0.01,
    command_period: float = 1.0,
    time_constant: float = 0.0,
) -> RobotData:
    """A unicycle driven by piecewise-constant commands: the true input is
    ``(s_v c_v + n_v, s_ω c_ω + n_ω)`` with ``c`` the commands delayed by τ and (for
    ``time_constant`` T > 0) passed through a first-order lag, white per-step noise ``n`` of σ
    ``sigma_v``, ``sigma_w`` on a ``dt`` grid; ground truth on that grid (midpoint heading)."""
    t_cmd = np.arange(0.0, duration, command_period)
    odo = Odometry(
        t=t_cmd, v=rng.uniform(0.1, 0.4, t_cmd.size), omega=rng.uniform(-0.5, 0.5, t_cmd.size)
    )
    t = np.arange(0.0, duration, dt)
    v_cmd, w_cmd = command_response(odo.at, t, latency, time_constant)
    v = scale_v * v_cmd + sigma_v * rng.standard_normal(t.size)
    w = scale_w * w_cmd + sigma_w * rng.standard_normal(t.size)
    theta = np.concatenate([[0.0], np.cumsum(w * dt)])[:-1]
    mid = theta + 0.5 * w * dt
    x = np.concatenate([[0.0], np.cumsum(v * dt * np.cos(mid))])[:-1]
    y = np.concatenate([[0.0], np.cumsum(v * dt * np.sin(mid))])[:-1]
    gt = GroundTruth(
        t=t, x=x, y=y, theta=np.asarray(wrap_angle(theta)), gap_threshold=GAP_THRESHOLD_S
    )
    return robot(subject, gt, odo)


class Synthetic:
    """The builders above, handed to the tests by the ``synthetic`` fixture."""

    measurements = staticmethod(measurements)
    robot = staticmethod(robot)
    still_robot = staticmethod(still_robot)
    dataset = staticmethod(dataset)
    commanded_robot = staticmethod(commanded_robot)


@pytest.fixture
def synthetic() -> type[Synthetic]:
    return Synthetic
