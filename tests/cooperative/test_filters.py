"""Joint EIF ≡ joint EKF; exact multi-step block prediction; χ² gating of outliers; the
estimator contract (beliefs, update records, counts)."""

from dataclasses import replace

import numpy as np

from relloc.core.contract import Estimator
from relloc.core.gaussian import Gaussian
from relloc.core.recording import Measurements, measurement_rows
from relloc.estimators.cooperative import (
    CooperativeEstimator,
    CooperativeSettings,
    HeldCommands,
    OdometryModel,
    SensorModel,
    TeamPending,
    accumulate_prediction,
    command_timeline,
)
from relloc.estimators.eif import ExtendedInformationFilter
from relloc.estimators.joint_ekf import JointEkf
from relloc.models.planar_measurement import RowKind, ScalarRows, linearise_rows
from relloc.models.unicycle import unicycle_jacobians, unicycle_step
from relloc.sim.cooperative import sharma2013_scenario, simulate


def test_eif_and_ekf_single_epoch_identical():
    rng = np.random.default_rng(0)
    n = 4
    A = rng.normal(size=(3 * n, 3 * n))
    prior = Gaussian(mean=rng.normal(size=3 * n) * 20, cov=A @ A.T + np.eye(3 * n))
    eif, ekf = ExtendedInformationFilter.from_prior(prior), JointEkf(prior)
    F = np.tile(np.eye(3), (n, 1, 1))
    F[:, :2, 2] = rng.normal(size=(n, 2))
    Q = np.stack([np.diag(rng.uniform(0.1, 1.0, 3)) for _ in range(n)])
    mean_pred = prior.mean + rng.normal(size=3 * n)
    for f in (eif, ekf):
        f.predict(mean_pred, F, Q)
    rows = ScalarRows(
        kind=np.array([RowKind.BEARING, RowKind.BEARING, RowKind.RANGE, RowKind.POSE_X]),
        observer=np.array([0, 1, 3, 2]),
        target=np.array([1, -1, 0, -1]),
        landmark_xy=np.array([[0.0, 0.0], [50.0, 50.0], [0.0, 0.0], [0.0, 0.0]]),
        z=np.array([0.2, -0.4, 25.0, 3.0]),
        sigma=np.array([0.1, 0.1, 1.0, 2.0]),
        group=np.arange(4),
    )
    lin = linearise_rows(ekf.mean(), rows)
    eif.update(lin)
    ekf.update(lin)
    assert np.allclose(eif.mean(), ekf.mean(), atol=1e-8)
    assert np.allclose(eif.covariance(), ekf.covariance(), atol=1e-8)


def _settings(scenario, **kw) -> CooperativeSettings:
    odo = OdometryModel.from_discrete(scenario.sigma_v, scenario.sigma_w, scenario.dt)
    return CooperativeSettings(
        odometry=odo, sensor=SensorModel(sigma_bearing=scenario.sigma_bearing), **kw
    )


def test_eif_equals_ekf_on_a_seeded_team_run(team_run):
    scenario = sharma2013_scenario(duration=15.0, gps_robots=(0,))
    sim = simulate(scenario, np.random.default_rng(11))
    out_t = sim.recording.truth[0].t[::5]
    runs = [
        team_run(
            sim.recording,
            sim.prior,
            _settings(scenario, anchors=(0, 1), use_fixes=True, filter=kind),
            out_t,
        )
        for kind in ("eif", "ekf")
    ]
    assert np.allclose(runs[0].mean, runs[1].mean, atol=1e-6)
    assert np.allclose(runs[0].cov, runs[1].cov, atol=1e-6)
    assert runs[0].counts.to_dict() == runs[1].counts.to_dict()
    assert runs[0].counts.fixes_used > 0 and runs[0].counts.ignored_unused == 0


def test_block_prediction_equals_step_by_step():
    """One accumulated (Φ, Q) over many held odometry steps = K single EKF predictions."""
    rng = np.random.default_rng(2)
    t = np.cumsum(rng.uniform(0.01, 0.05, size=40))
    v, w = rng.uniform(0.2, 1.0, 40), rng.normal(size=40) * 0.5
    model = OdometryModel(q_v0=0.01, q_w0=0.02, k_v=0.003, max_hold_s=10.0, max_step_s=10.0)
    # the loop holds command k over (t[k], t[k+1]]
    held = HeldCommands(
        begin=t[:-1],
        end=t[1:],
        stamp=t[:-1, None],
        v=v[:-1, None],
        w=w[:-1, None],
        in_force=np.full(1, np.nan),
    )
    timeline, stale = command_timeline(held, model)
    assert stale.robot.size == 0
    pose0 = np.array([[1.0, -2.0, 0.3]])
    pending = TeamPending.at(pose0)
    accumulate_prediction(pending, timeline, float(t[0]), float(t[-1]), 10.0)
    P0 = np.diag([0.5, 0.4, 0.1])
    pose, P = pose0[0].copy(), P0.copy()
    for k in range(39):
        dt = t[k + 1] - t[k]
        u = np.array([v[k], w[k]])
        F, G = unicycle_jacobians(pose, u, dt)
        Qu = np.diag([0.01 + 0.003 * abs(v[k]), 0.02]) / dt
        P = F @ P @ F.T + G @ Qu @ G.T
        pose = unicycle_step(pose, u, dt)
    assert np.allclose(pending.pose[0], pose, atol=1e-12)
    assert np.allclose(pending.F[0] @ P0 @ pending.F[0].T + pending.Q[0], P, atol=1e-12)


def test_timeline_holds_each_command_at_most_max_hold():
    """A command older than max_hold_s leaves the robot still at the stale rates; a robot that
    has not reported is still at (q_v0, q_ω0); the stale interval closes at the next command."""
    model = OdometryModel(q_v0=0.1, q_w0=0.2, k_v=1.0, max_hold_s=0.5, stale_q_v=7.0, stale_q_w=8.0)
    nan = np.nan
    held = HeldCommands(
        begin=np.array([0.0, 1.0]),
        end=np.array([1.0, 2.0]),
        stamp=np.array([[0.0, nan], [1.0, nan]]),  # robot 0: commands at 0 and 1; robot 1: none
        v=np.array([[2.0, 0.0], [3.0, 0.0]]),
        w=np.zeros((2, 2)),
        in_force=np.array([nan, nan]),
    )
    timeline, stale = command_timeline(held, model)
    assert np.array_equal(timeline.start, [0.0, 0.5, 1.0, 1.5])
    assert np.array_equal(timeline.v[:, 0], [2.0, 0.0, 3.0, 0.0])
    assert np.array_equal(timeline.q_v[:, 0], [2.1, 7.0, 3.1, 7.0])
    assert np.array_equal(timeline.q_v[:, 1], [0.1] * 4) and not timeline.v[:, 1].any()
    assert (stale.robot.tolist(), stale.start.tolist(), stale.end.tolist()) == ([0], [0.5], [1.0])


def test_outliers_are_gated_and_counted(team_run):
    scenario = sharma2013_scenario(duration=10.0)
    sim = simulate(scenario, np.random.default_rng(5))
    m = sim.recording.measurements
    bad = np.zeros(m.size, dtype=bool)
    bad[np.arange(200, m.size, 97)] = True
    value = np.array(m.value)
    value[bad, 0] += 2.0
    recording = replace(sim.recording, measurements=replace(m, value=value))
    run = team_run(
        recording,
        sim.prior,
        _settings(scenario, anchors=(0, 1), p_gate=0.999),
        recording.truth[0].t[::10],
    )
    assert run.counts.rejected_gate >= 0.9 * bad.sum()
    assert run.counts.rejected_gate <= bad.sum() + 0.01 * m.size
    assert np.isfinite(run.mean).all()


def test_contract_beliefs_and_update_records(team_run):
    """Beliefs per robot in world_pose2; one update record (NIS, dof, conditioning) per
    detection or fix used; counted rows add up."""
    scenario = sharma2013_scenario(duration=6.0, gps_robots=(0,), sigma_range=1.0)
    sim = simulate(scenario, np.random.default_rng(3))
    rec = sim.recording
    settings = replace(
        _settings(scenario, anchors=(0,), use_range=True, use_fixes=True),
        sensor=SensorModel(sigma_bearing=scenario.sigma_bearing, sigma_range0=1.0),
    )
    assert isinstance(CooperativeEstimator(rec.robots, sim.prior, settings), Estimator)
    run = team_run(rec, sim.prior, settings, rec.truth[0].t[::5])
    series = run.estimates.series("team", "2")
    assert series.frame == "world_pose2" and series.mean.shape == (run.t.size, 3)
    assert series.age[0] == 0.0 and series.age[-1] == rec.truth[0].t[-1]
    updates = [run.estimates.updates_of("team", r) for r in rec.robots]
    c = run.counts
    assert sum(u.t.size for u in updates) == c.used
    dof = np.concatenate([u.dof for u in updates])
    assert set(dof.tolist()) == {2, 3}  # range + bearing per detection, x-y-ψ per fix
    assert np.sum(dof == 3) == c.fixes_used == updates[0].dof.tolist().count(3)
    cond_s = np.concatenate([u.cond_s for u in updates])
    cond_r = np.concatenate([u.cond_r for u in updates])
    assert np.all(np.isfinite(cond_s)) and np.all(cond_s > 0)
    assert np.allclose(cond_r[dof == 2], np.log10(1.0**2 / scenario.sigma_bearing**2))
    nis = np.concatenate([u.nis for u in updates])
    assert np.all(nis >= 0) and 0.2 < np.mean(nis / dof) < 5.0
    detections = rec.measurements.of_kind("range_bearing")
    landmark_1 = int(np.sum(detections.landmark == 1))
    assert c.ignored_not_anchor == landmark_1
    assert c.used + c.rejected + c.ignored_not_anchor == rec.measurements.size


def test_rows_it_cannot_or_may_not_use_are_counted(team_run):
    scenario = sharma2013_scenario(duration=3.0, gps_robots=(0,))
    sim = simulate(scenario, np.random.default_rng(4))
    rec = sim.recording
    t = rec.truth[0].t
    extra = [
        measurement_rows("range", t=t[5:8], observer=0, target=1, value=np.full(3, 20.0)),
        measurement_rows("bearing", t=t[5:7], observer=2, value=np.zeros(2)),  # of whom?
    ]
    recording = replace(rec, measurements=Measurements.concatenate([rec.measurements, *extra]))
    n_fixes = rec.measurements.of_kind("pose").size
    run = team_run(recording, sim.prior, _settings(scenario, anchors=(0, 1)), t[::5])
    assert run.counts.ignored_unmodelled == 5
    assert run.counts.ignored_unused == n_fixes > 0
    off = CooperativeSettings(
        odometry=_settings(scenario).odometry,
        sensor=SensorModel(sigma_bearing=0.1),
        use_bearing=False,
    )
    dead = team_run(rec, sim.prior, off, t[::5])
    assert dead.counts.used == 0 and dead.counts.epochs == 0
    assert dead.counts.ignored_unused == rec.measurements.size
