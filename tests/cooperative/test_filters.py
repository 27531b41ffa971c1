"""Joint EIF ≡ joint EKF; exact multi-step block prediction; χ² gating of outliers."""

import numpy as np

from relloc.core.gaussian import Gaussian
from relloc.estimators.cooperative import (
    InputTimeline,
    OdometryModel,
    OdometryStream,
    PipelineSettings,
    SensorModel,
    TeamPending,
    TeamTimeline,
    advance,
    run_team,
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


def test_eif_equals_ekf_on_a_seeded_team_run():
    scenario = sharma2013_scenario(duration=15.0, gps_robots=(0,))
    sim = simulate(scenario, np.random.default_rng(11))
    odo = OdometryModel.from_discrete(scenario.sigma_v, scenario.sigma_w, scenario.dt)
    runs = []
    for kind in ("eif", "ekf"):
        settings = PipelineSettings(
            odometry=odo,
            sensor=SensorModel(sigma_bearing=scenario.sigma_bearing),
            anchors=(0, 1),
            use_fixes=True,
            filter=kind,
        )
        runs.append(run_team(sim.recording, sim.prior, 0.0, sim.t[::5], settings))
    assert np.allclose(runs[0].mean, runs[1].mean, atol=1e-6)
    assert np.allclose(runs[0].cov, runs[1].cov, atol=1e-6)
    assert runs[0].counts.to_dict() == runs[1].counts.to_dict()


def test_block_prediction_equals_step_by_step():
    """One accumulated (Φ, Q) over many held odometry steps = K single EKF predictions."""
    rng = np.random.default_rng(2)
    t = np.cumsum(rng.uniform(0.01, 0.05, size=40))
    v, w = rng.uniform(0.2, 1.0, 40), rng.normal(size=40) * 0.5
    model = OdometryModel(q_v0=0.01, q_w0=0.02, k_v=0.003, max_hold_s=10.0, max_step_s=10.0)
    timeline = TeamTimeline.merge([InputTimeline.build(OdometryStream(t, v, w), model)])
    pose0 = np.array([[1.0, -2.0, 0.3]])
    pending = TeamPending.at(pose0)
    advance(pending, timeline, float(t[0]), float(t[-1]), 10.0)
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


def test_outliers_are_gated_and_counted():
    scenario = sharma2013_scenario(duration=10.0)
    sim = simulate(scenario, np.random.default_rng(5))
    det = sim.recording.detections
    bad = np.zeros(len(det), dtype=bool)
    bad[np.arange(200, len(det), 97)] = True
    bearing = np.where(bad, det.bearing + 2.0, det.bearing)
    corrupted = type(det)(det.t, det.observer, det.target_robot, det.landmark, det.range, bearing)
    recording = type(sim.recording)(
        odometry=sim.recording.odometry, detections=corrupted, landmarks_xy=scenario.landmarks_xy
    )
    odo = OdometryModel.from_discrete(scenario.sigma_v, scenario.sigma_w, scenario.dt)
    settings = PipelineSettings(
        odometry=odo, sensor=SensorModel(sigma_bearing=0.1), anchors=(0, 1), p_gate=0.999
    )
    run = run_team(recording, sim.prior, 0.0, sim.t[::10], settings)
    assert run.counts.rejected_gate >= 0.9 * bad.sum()
    assert run.counts.rejected_gate <= bad.sum() + 0.01 * len(det)
    assert np.isfinite(run.mean).all()
