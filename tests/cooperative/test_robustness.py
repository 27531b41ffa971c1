"""Robustness of the team filter: stopped odometry, isolated robots, input it cannot use."""

from dataclasses import replace

import numpy as np
import pytest

from relloc.core.recording import measurement_rows
from relloc.errors import ConfigError, DataError
from relloc.estimators.cooperative import (
    CooperativeEstimator,
    CooperativeSettings,
    OdometryModel,
    SensorModel,
)
from relloc.metrics import nees, state_errors
from relloc.pipeline.replay import replay
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
    return CooperativeSettings(
        odometry=odo, sensor=SensorModel(sigma_bearing=scenario.sigma_bearing), **kw
    )


def test_odometry_that_stops_and_a_robot_that_sees_nobody(sim, team_run):
    scenario, s = sim
    rec = s.recording
    odo = list(rec.odometry)
    keep = odo[1].t < 8.0
    odo[1] = replace(odo[1], t=odo[1].t[keep], velocity=odo[1].velocity[keep])
    m = rec.measurements
    blind = ((m.observer == 2) | (m.target == 2)) & (m.t > 12.0) & (m.t < 20.0)
    recording = replace(rec, odometry=tuple(odo), measurements=m.select(~blind))
    run = team_run(recording, s.prior, _settings(scenario, anchors=(0, 1)), rec.truth[0].t[::10])
    stale = run.counts.stale_odometry_s
    # last command at 7.9 s, held 0.5 s, then stale until the end (25 s)
    assert stale[1] == pytest.approx(25.0 - 7.9 - 0.5, abs=1e-6)
    assert all(x == 0.0 for i, x in enumerate(stale) if i != 1)
    assert np.isfinite(run.mean).all() and np.isfinite(run.cov).all()
    # after the outage every robot, the blind one and the one without odometry included, is
    # back within its consistent bound: final 3-DOF NEES below χ²₃(0.999) = 16.27
    truth = np.stack([g.pose[-1, [0, 1, 3]] for g in rec.truth])
    err = state_errors(run.mean[-1], truth, angle_indices=(2,))
    assert np.all(nees(err, run.cov[-1]) < 16.27)


def test_bad_settings_raise_config_errors(sim):
    scenario, s = sim
    with pytest.raises(ConfigError, match="q_v0"):
        OdometryModel(q_v0=-1.0, q_w0=0.1)
    with pytest.raises(ConfigError, match="filter"):
        CooperativeSettings(
            odometry=OdometryModel(q_v0=0.1, q_w0=0.1),
            sensor=SensorModel(sigma_bearing=0.1),
            filter="ukf",  # type: ignore[arg-type]
        )
    with pytest.raises(ConfigError, match="dimension"):
        CooperativeEstimator(s.recording.robots[:2], s.prior, _settings(scenario))
    with pytest.raises(ConfigError, match="landmarks"):
        CooperativeEstimator(
            s.recording.robots, s.prior, _settings(scenario), np.array([1.0, np.nan])
        )


def _replay(recording, prior, settings):
    est = CooperativeEstimator(recording.robots, prior, settings, recording.landmarks)
    return replay(recording, [est], record_rate_hz=1.0)


def test_input_the_filter_cannot_use_raises_data_errors(sim):
    scenario, s = sim
    rec = s.recording
    # a team of three robots cannot use readings of robots 4 and 5
    three = CooperativeEstimator(
        rec.robots[:3],
        type(s.prior)(mean=s.prior.mean[:9], cov=s.prior.cov[:9, :9]),
        _settings(scenario),
        rec.landmarks,
    )
    with pytest.raises(DataError, match="not among the filter's 3"):
        replay(rec, [three], record_rate_hz=1.0)
    # a unicycle does not move sideways
    odo = list(rec.odometry)
    velocity = np.array(odo[3].velocity)
    velocity[40, 1] = 0.5
    odo[3] = replace(odo[3], velocity=velocity)
    with pytest.raises(DataError, match="lateral or vertical velocity"):
        _replay(replace(rec, odometry=tuple(odo)), s.prior, _settings(scenario))
    # an absolute fix is useless without its noise
    fix = measurement_rows("pose", t=np.array([5.0]), observer=0, value=np.zeros((1, 3)))
    no_sigma = replace(
        rec, measurements=type(rec.measurements).concatenate([rec.measurements, fix])
    )
    with pytest.raises(DataError, match="states no σ"):
        _replay(no_sigma, s.prior, _settings(scenario, use_fixes=True))


def test_a_long_still_gap_is_one_exact_step():
    """A 10⁷ s gap once cost 10⁸ prediction steps (the process was killed for memory); a team
    standing still steps exactly in one (F = I), the same as in many small steps."""
    from relloc.estimators.cooperative import TeamPending, TeamTimeline, accumulate_prediction

    pose = np.array([[0.0, 0.0, 0.3], [1.0, 2.0, -1.2]])

    def predicted(w: float, t1: float) -> TeamPending:
        still = np.zeros((1, 2))
        timeline = TeamTimeline(
            start=np.zeros(1), v=still, w=still + w, q_v=still + 0.01, q_w=still + 0.002
        )
        pending = TeamPending.at(pose)
        accumulate_prediction(pending, timeline, 0.0, t1, 0.1)
        return pending

    one, many = predicted(0.0, 50.0), predicted(1e-300, 50.0)  # 1e-300: stepped 500 times
    np.testing.assert_allclose(one.pose, many.pose, atol=1e-12)
    np.testing.assert_allclose(one.F, many.F, atol=1e-12)
    np.testing.assert_allclose(one.Q, many.Q, rtol=1e-10)
    huge = predicted(0.0, 1e7)
    np.testing.assert_allclose(huge.Q[:, 2, 2], 0.002 * 1e7)
