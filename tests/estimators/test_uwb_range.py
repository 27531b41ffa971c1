"""Range-only estimators (relative pair bank, constant-velocity team) and the distance geometry
they start from, on small simulated teams. Seeds 11–14 were not used while developing."""

from __future__ import annotations

import numpy as np
import pytest

from relloc.core.recording import GroundTruth, Odometry, Recording, measurement_rows
from relloc.errors import DataError
from relloc.estimators.uwb_range import (
    RangePairBank,
    RangePairSettings,
    RangeTeamFilter,
    RangeTeamSettings,
    RelativeDeadReckoning,
)
from relloc.geometry.multilateration import (
    classical_mds,
    fill_by_shortest_paths,
    multilaterate,
    rigid_alignment,
)
from relloc.models.motion import VelocityNoise
from relloc.models.unicycle import unicycle_step
from relloc.pipeline.evaluation import evaluate
from relloc.pipeline.replay import replay

SIGMA_ODO = (0.01, 0.0, 0.0, 0.01)


def _unicycles(rng: np.random.Generator, duration: float = 60.0) -> Recording:
    """Two unicycles on different circles, odometry at 50 Hz, ranges (σ 5 cm) at 10 Hz."""
    dt = 0.02
    t = np.arange(0.0, duration, dt)
    u = [np.array([0.3, 0.25]), np.array([0.25, -0.15])]
    pose = [np.array([0.0, 0.0, 0.0]), np.array([3.0, 1.0, 2.0])]
    paths = [[], []]
    for _ in t:
        for k in range(2):
            paths[k].append(pose[k])
            pose[k] = unicycle_step(pose[k], u[k], dt)
    truth, odometry = [], []
    for k in range(2):
        p = np.array(paths[k])
        truth.append(GroundTruth(t=t, pose=np.column_stack([p[:, :2], np.zeros(t.size), p[:, 2]])))
        vel = np.tile([u[k][0], 0.0, 0.0, u[k][1]], (t.size, 1))
        vel += rng.normal(0, 1, vel.shape) * np.array(SIGMA_ODO)
        odometry.append(Odometry(t=t, velocity=vel, sigma=SIGMA_ODO))
    tr = t[::5]
    d = np.linalg.norm(truth[0].at(tr)[:, :3] - truth[1].at(tr)[:, :3], axis=1)
    rows = measurement_rows(
        "range", t=tr, observer=0, target=1, value=d + rng.normal(0, 0.05, d.size), sigma=[0.05]
    )
    return Recording(
        robots=("a", "b"),
        platforms=("ground", "ground"),
        odometry=tuple(odometry),
        measurements=rows,
        truth=tuple(truth),
    )


def test_range_pair_bank_converges_from_an_unknown_start_when_both_move():
    rec = _unicycles(np.random.default_rng(11))
    noise = VelocityNoise(observer=SIGMA_ODO, observed=SIGMA_ODO)
    bank = RangePairBank(0, 1, rec.robots, noise, RangePairSettings(sigma_range=0.05))
    ev = evaluate(replay(rec, [bank], record_rate_hz=2.0), rec)[0]
    err = np.linalg.norm(ev.error[:, :3], axis=1)
    assert err[0] > 0.5  # the start knows only the range
    assert np.all(err[ev.t > 40.0] < 0.25), err[ev.t > 40.0].max()
    beyond = np.mean(ev.nees[ev.t > 40.0] > 9.49)  # χ²₄(0.95)
    assert beyond < 0.5


def test_range_pair_bank_counts_the_ranges_its_gate_rejects():
    rec = _unicycles(np.random.default_rng(12), duration=20.0)
    m = rec.measurements
    outliers = measurement_rows(
        "range", t=m.t[[60, 120]] + 0.01, observer=0, target=1, value=[40.0, 55.0], sigma=[0.05]
    )
    spoilt = Recording(
        robots=rec.robots,
        platforms=rec.platforms,
        odometry=rec.odometry,
        measurements=type(m).concatenate([m, outliers]),
        truth=rec.truth,
    )
    noise = VelocityNoise(observer=SIGMA_ODO, observed=SIGMA_ODO)
    bank = RangePairBank(0, 1, rec.robots, noise, RangePairSettings(sigma_range=0.05))
    est = replay(spoilt, [bank], record_rate_hz=2.0)
    assert est.counts == {"ranges_gated": 2}
    assert bank.take_counts() == {}  # taken by the replay
    clean = RangePairBank(0, 1, rec.robots, noise, RangePairSettings(sigma_range=0.05))
    assert replay(rec, [clean], record_rate_hz=2.0).counts == {}


def test_dead_reckoning_from_the_true_start_drifts_slowly():
    rec = _unicycles(np.random.default_rng(12), duration=20.0)
    noise = VelocityNoise(observer=SIGMA_ODO, observed=SIGMA_ODO)
    start = (0.0, rec.relative_truth(0, 1, 0.0)[0], np.eye(4) * 1e-6)
    ev = evaluate(replay(rec, [RelativeDeadReckoning(0, 1, rec.robots, noise, start)]), rec)[0]
    err = np.linalg.norm(ev.error[:, :3], axis=1)
    assert err[0] < 1e-3 and err[-1] < 0.5


def _static_team(rng: np.random.Generator) -> tuple[Recording, np.ndarray]:
    xy = np.array([[0.0, 0.0], [5.0, 0.0], [0.0, 4.0], [4.0, 5.0], [2.0, 2.5]])
    n = xy.shape[0]
    t = np.linspace(0.0, 20.0, 201)
    parts = []
    for i in range(n):
        for j in range(i + 1, n):
            d = np.linalg.norm(xy[i] - xy[j])
            parts.append(
                measurement_rows(
                    "range",
                    t=t[:-1] + 1e-3 * (i * n + j),
                    observer=i,
                    target=j,
                    value=d + rng.normal(0, 0.05, t.size - 1),
                    sigma=[0.05],
                )
            )
    from relloc.core.recording import Measurements

    rows = Measurements.concatenate(parts)
    truth = tuple(GroundTruth(t=t, pose=np.tile([p[0], p[1], 0.0, 0.0], (t.size, 1))) for p in xy)
    still = Odometry(t=np.zeros(0), velocity=np.zeros((0, 4)), sigma=(0, 0, 0, 0))
    rec = Recording(
        robots=tuple("abcde"),
        platforms=("ground",) * n,
        odometry=(still,) * n,
        measurements=rows,
        truth=truth,
    )
    return rec, xy


def test_range_team_filter_with_anchors_localizes_the_free_robots():
    rng = np.random.default_rng(13)
    rec, xy = _static_team(rng)
    start = xy + np.r_[[[0, 0]] * 3, rng.normal(0, 0.4, (2, 2))]
    est = RangeTeamFilter(rec.robots, start, RangeTeamSettings(q=1e-4), anchors=(0, 1, 2))
    evs = evaluate(replay(rec, [est], record_rate_hz=1.0), rec)
    assert {e.subject for e in evs} == {"d", "e"}
    for e in evs:
        assert np.linalg.norm(e.error[-1]) < 0.05
    again = RangeTeamFilter(rec.robots, start, RangeTeamSettings(), anchors=(0, 1, 2))
    counts = replay(rec, [again]).counts
    assert counts["ranges_between_fixed_points"] == 3 * 200  # anchor–anchor links carry nothing
    assert counts["ranges_used"] + counts["ranges_gated"] == 7 * 200


def test_a_range_to_an_unknown_radio_is_counted_not_fused():
    """Such a row (no target robot, no landmark) was fused against the last landmark, or
    raised an IndexError without landmarks."""
    still = Odometry(t=np.zeros(0), velocity=np.zeros((0, 4)), sigma=(0, 0, 0, 0))
    rows = measurement_rows("range", t=[1.0], observer=1, value=[5.0], sigma=[0.05])
    for landmarks in ([[100.0, 100.0, 0.0]], np.zeros((0, 3))):
        rec = Recording(
            robots=("a", "b"),
            platforms=("ground",) * 2,
            odometry=(still, still),
            measurements=rows,
            landmarks=landmarks,
        )
        settings = RangeTeamSettings(gate=None)
        f = RangeTeamFilter(
            rec.robots, [[0.0, 0.0], [1.0, 0.0]], settings, anchors=(0,), landmarks=rec.landmarks
        )
        est = replay(rec, [f])
        assert est.counts["rows_of_unknown_target"] == 1 and est.counts["ranges_used"] == 0
        np.testing.assert_allclose(est.series("team", "b").mean[-1], [1.0, 0.0])


def test_mds_alignment_and_multilateration_recover_a_configuration():
    rng = np.random.default_rng(14)
    X = rng.uniform(0, 6, (6, 2))
    D = np.linalg.norm(X[:, None] - X[None], axis=2)
    Y = classical_mds(D)
    R, t = rigid_alignment(Y, X, reflection=True)
    np.testing.assert_allclose(Y @ R.T + t, X, atol=1e-8)
    angle = 0.7
    Rz = np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])
    R2, t2 = rigid_alignment(X, X @ Rz.T + [1.0, -2.0])
    np.testing.assert_allclose(R2, Rz, atol=1e-10)
    np.testing.assert_allclose(t2, [1.0, -2.0], atol=1e-10)
    # one free point from three fixed ones
    pairs = [(0, 1), (0, 2), (0, 3)]
    got = multilaterate(X[:1] + 0.3, X[1:4], pairs, D[0, 1:4])
    np.testing.assert_allclose(got, X[:1], atol=1e-6)
    D[0, 1:] = D[1:, 0] = np.nan
    with pytest.raises(DataError, match="point 0"):
        fill_by_shortest_paths(D)
