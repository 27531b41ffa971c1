"""Robustness of the team pipeline: stopped odometry, isolated robots, malformed input."""

import numpy as np
import pytest

from relloc.errors import ConfigError, DataError
from relloc.estimators.cooperative import (
    Detections,
    OdometryModel,
    OdometryStream,
    PipelineSettings,
    SensorModel,
    TeamRecording,
    run_team,
)
from relloc.metrics import nees, state_errors
from relloc.sim.cooperative import sharma2013_scenario, simulate


@pytest.fixture(scope="module")
def sim():
    scenario = sharma2013_scenario(duration=25.0)
    return scenario, simulate(scenario, np.random.default_rng(21))


def _settings(scenario, **kw):
    odo = OdometryModel(
        q_v0=scenario.sigma_v**2 * scenario.dt,
        q_w0=scenario.sigma_w**2 * scenario.dt,
        max_hold_s=0.5,
        stale_q_v=4.0,
        stale_q_w=0.05,
    )
    return PipelineSettings(
        odometry=odo, sensor=SensorModel(sigma_bearing=scenario.sigma_bearing), **kw
    )


def test_odometry_that_stops_and_a_robot_that_sees_nobody(sim):
    scenario, s = sim
    rec = s.recording
    odo = list(rec.odometry)
    o = odo[1]
    keep = o.t < 8.0
    odo[1] = OdometryStream(o.t[keep], o.v[keep], o.w[keep])
    d = rec.detections
    blind = ((d.observer == 2) | (d.target_robot == 2)) & (d.t > 12.0) & (d.t < 20.0)
    recording = TeamRecording(
        odometry=tuple(odo), detections=d.select(~blind), landmarks_xy=rec.landmarks_xy
    )
    run = run_team(recording, s.prior, 0.0, s.t[::10], _settings(scenario, anchors=(0, 1)))
    stale = run.counts.stale_odometry_s
    # last command at 7.9 s, held 0.5 s, then stale until the end (25 s)
    assert stale[1] == pytest.approx(25.0 - 7.9 - 0.5, abs=1e-6)
    assert all(x == 0.0 for i, x in enumerate(stale) if i != 1)
    assert np.isfinite(run.mean).all() and np.isfinite(run.cov).all()
    # after the outage every robot, the blind one and the one without odometry included, is
    # back within its consistent bound: final 3-DOF NEES below χ²₃(0.999) = 16.27
    err = state_errors(run.mean[-1], s.truth[::10][-1], angle_indices=(2,))
    assert np.all(nees(err, run.cov[-1]) < 16.27)


def test_malformed_inputs_raise_named_errors(sim):
    scenario, s = sim
    with pytest.raises(DataError, match=r"odometry\.t"):
        OdometryStream(np.array([0.0, 0.2, 0.1]), np.zeros(3), np.zeros(3))
    with pytest.raises(DataError, match="itself"):
        Detections(
            np.zeros(1), np.array([1]), np.array([1]), np.array([-1]), np.ones(1), np.zeros(1)
        )
    with pytest.raises(DataError, match="non-finite"):
        OdometryStream(np.array([0.0, 1.0]), np.array([np.nan, 0.0]), np.zeros(2))
    with pytest.raises(ConfigError, match="q_v0"):
        OdometryModel(q_v0=-1.0, q_w0=0.1)
    with pytest.raises(ConfigError, match="filter"):
        PipelineSettings(
            odometry=OdometryModel(q_v0=0.1, q_w0=0.1),
            sensor=SensorModel(sigma_bearing=0.1),
            filter="ukf",  # type: ignore[arg-type]
        )
    two_robots = TeamRecording(
        odometry=s.recording.odometry[:2],
        detections=s.recording.detections.select(np.zeros(len(s.recording.detections), bool)),
        landmarks_xy=s.recording.landmarks_xy,
    )
    with pytest.raises(ConfigError, match="dimension"):
        run_team(two_robots, s.prior, 0.0, s.t, _settings(scenario))
