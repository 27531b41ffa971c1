"""``relloc reproduce guler2023``'s reduction of one run (``reduce_run``) on a hand-made run:
a leader standing 2 m ahead of its one follower, the follower's beliefs of the leader in the
``airground_follower`` frame with known errors, its modes and block counters, the true
formation error; the RMSE per axis, the 2-DOF position NEES, the mode ticks and counts."""

from __future__ import annotations

import numpy as np

from relloc.core.estimates import BeliefSeries, Estimates
from relloc.core.gaussian import Gaussian
from relloc.core.recording import GroundTruth, Odometry, Recording, empty_measurements
from relloc.estimators.switching_ekf import BLOCKS
from relloc.experiments.guler2023 import reduce_run
from relloc.sim.airground import AirGroundRun

T = np.array([0.25, 0.5, 0.75, 1.0])


def _run() -> AirGroundRun:
    still = Odometry(t=np.zeros(0), velocity=np.zeros((0, 4)), sigma=np.zeros(4))
    truth = (
        GroundTruth(t=np.array([0.0, 1.0]), pose=np.array([[2.0, 0.0, 0.0, 0.0]] * 2)),
        GroundTruth(t=np.array([0.0, 1.0]), pose=np.zeros((2, 4))),
    )
    rec = Recording(
        robots=("R_0", "R_1"),
        platforms=("ground", "ground"),
        odometry=(still, still),
        measurements=empty_measurements(),
        truth=truth,
        meta={"common_frame_yaw": 0.0},
    )
    # truth x = (r_x, r_y, θ_1, θ_0) = (2, 0, 0, 0); errors (±0.3, 0.4, 0.1, 0)
    errors = np.array(
        [[0.3, 0.4, 0.1, 0.0], [0.3, 0.4, 0.1, 0.0], [-0.3, 0.4, 0.1, 0.0], [-0.3, 0.4, 0.1, 0.0]]
    )
    belief = BeliefSeries(
        owner="R_1",
        subject="R_0",
        frame="airground_follower",
        t=T,
        mean=np.array([2.0, 0.0, 0.0, 0.0]) + errors,
        cov=np.stack([np.eye(4)] * 4),
        age=np.zeros(4),
        info={"sw": np.array([1.0, 2.0, 2.0, 3.0])},
    )
    counts = {"range_applied": 5, "range_rejected": 1, "camera_applied": 2, "triangle_refusals": 2}
    estimates = Estimates(estimator="switching_ekf", beliefs=(belief,), counts=counts)
    return AirGroundRun(
        recording=rec,
        estimates=estimates,
        priors={"R_1": Gaussian(mean=np.zeros(4), cov=np.eye(4))},
        formation_error=np.array([[[0.3, -0.4]], [[-0.3, 0.4]]]),
    )


def test_one_run_reduced_by_hand() -> None:
    nis = dict.fromkeys(BLOCKS, 1.5)
    r = reduce_run(_run(), nis_sums=nis, refusal_examples=("x",), keep_traces=False)
    np.testing.assert_allclose(r.rmse, [[0.3, 0.4]])
    np.testing.assert_allclose(r.heading_rmse, [0.1])
    # the true r − r_des of the follower over the two ticks, per axis
    np.testing.assert_allclose(r.formation_rmse, [[0.3, 0.4]])
    # NEES of (r_x, r_y) only, identity covariance: 0.09 + 0.16 at every tick
    np.testing.assert_allclose(r.nees_position, [[0.25]] * 4)
    np.testing.assert_array_equal(r.mode_ticks, [1.0, 2.0, 1.0])
    assert r.accepted == {"range": 5, "camera": 2, "triangle": 0, "leader_heading": 0}
    assert r.rejected == {"range": 1, "camera": 0, "triangle": 0, "leader_heading": 0}
    assert r.triangle_refusals == 2 and r.refusal_examples == ("x",)
    assert r.nis_sums == nis and r.traces is None
    assert (
        reduce_run(_run(), nis_sums=nis, refusal_examples=(), keep_traces=True).traces is not None
    )
