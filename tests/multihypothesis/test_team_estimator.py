"""The Gaussian-sum fuser under the estimator contract, replayed on recordings (seed 002)."""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from relloc.core.contract import Estimator, HeldOdometry, Silent
from relloc.core.estimates import Recorder
from relloc.core.recording import (
    CLUTTER,
    KIND_NAMES,
    KINDS,
    NO_TARGET,
    GroundTruth,
    Measurements,
    Odometry,
    Recording,
    empty_measurements,
    measurement_rows,
)
from relloc.errors import ConfigError, DataError
from relloc.estimators.gaussian_sum import GaussianSumFuser
from relloc.experiments.desilva2015 import filter_settings
from relloc.experiments.multihypothesis_scores import NO_READING, leader_scores
from relloc.fusion.gaussian_sum_estimator import (
    GaussianSumEstimator,
    bearing_kind,
    bearing_rows,
    scan_times,
    team,
)
from relloc.fusion.messages import EquivalentMeasurement
from relloc.pipeline.montecarlo import spawn_seeds
from relloc.pipeline.replay import feed_ticks, replay
from relloc.sim.multihypothesis import ROBOT_NAMES, DeSilvaScenario, simulate

SCENARIO = DeSilvaScenario(duration=3.0)
SETTINGS = filter_settings(SCENARIO)


def _scan_arrays(rec: Recording, i: int, t: float) -> tuple[Any, Any, Any]:
    """Heights, ranges (per teammate) and bearings of leader ``i``'s scan at ``t``."""
    m = rec.measurements
    others = [j for j in range(rec.n_robots) if j != i]
    heights, ranges = np.full(len(others), np.nan), np.full(len(others), np.nan)
    for kind, out in (("height", heights), ("range", ranges)):
        sel = np.flatnonzero((m.t == t) & (m.observer == i) & (m.kind == KIND_NAMES.index(kind)))
        out[[others.index(int(j)) for j in m.target[sel]]] = m.value[sel, 0]
    rows = bearing_rows(m, i, "bearing_elevation")
    return heights, ranges, m.value[rows[m.t[rows] == t], :2]


def _reference(rec: Recording, sharing: bool) -> dict[tuple[int, float], dict[int, Any]]:
    """The seed-002 loop written out with bare fusers: predict on the filter grid, direct
    scans, then every second all broadcasts fused by the others (after the scan's record)."""
    grid = rec.odometry[0].t
    u = np.stack([od.velocity for od in rec.odometry], axis=1)
    fusers = {i: GaussianSumFuser(i, [j for j in range(5) if j != i], SETTINGS) for i in (0, 1)}
    out: dict[tuple[int, float], dict[int, Any]] = {}
    next_fusion = 1.0
    for k, t in enumerate(grid):
        for i, fus in fusers.items():
            if k:
                fus.predict(u[k - 1, i], np.delete(u[k - 1], i, axis=0), grid[k] - grid[k - 1])
        for i, fus in fusers.items():
            if np.any((rec.measurements.t == t) & (rec.measurements.observer == i)):
                fus.direct_scan(*_scan_arrays(rec, i, float(t)))
                out[(i, float(t))] = {j: fus.summary(j) for j in fus.teammates}
        if sharing and t - grid[0] >= next_fusion - 1e-9:
            next_fusion += 1.0
            messages = [msg for fus in fusers.values() for msg in fus.broadcast()]
            for i, fus in fusers.items():
                for msg in messages:
                    if msg.sender != i:
                        fus.fuse(msg)
    return out


@pytest.mark.parametrize("sharing", [True, False])
def test_replayed_estimators_equal_the_fuser_loop(sharing: bool) -> None:
    rec = simulate(SCENARIO, np.random.default_rng(spawn_seeds(5, 1)[0]))
    estimators = team(rec.robots, (0, 1), SETTINGS, sharing=sharing)
    assert all(isinstance(e, Estimator) for e in estimators)
    times = scan_times(rec.measurements, rec.robots, (0, 1), SETTINGS)
    estimates = replay(rec, estimators, record_times=times)
    reference = _reference(rec, sharing)
    compared = 0
    for s in estimates.beliefs:
        i, j = rec.index(s.owner), rec.index(s.subject)
        for k, t in enumerate(s.t):
            ref = reference[(i, float(t))][j]
            np.testing.assert_array_equal(s.mean[k], ref.belief.mean)
            np.testing.assert_array_equal(s.cov[k], ref.belief.cov)
            assert s.info["weight"][k] == ref.weight
            assert s.info["components"][k] == ref.components
            assert s.info["bearing_row"][k] == ref.assoc
            assert s.info["scan_t"][k] == t
            compared += 1
    # a belief of every teammate whose filter had tracks, at every scan of every leader
    assert compared == sum(s is not None for v in reference.values() for s in v.values())
    assert compared > 0.9 * 4 * len(reference)
    created = [e for e in estimates.events if e.kind == "created"]
    assert {(e.owner, e.subject) for e in created} == {
        (ROBOT_NAMES[i], ROBOT_NAMES[j]) for i in (0, 1) for j in range(5) if j != i
    }


def _three_robots(rows: Measurements) -> Recording:
    t = np.array([0.0, 1.0])
    return Recording(
        robots=("A", "B", "C"),
        platforms=("ground", "aerial", "aerial"),
        odometry=tuple(Odometry(t=t, velocity=np.zeros((2, 4)), sigma=np.zeros(4)) for _ in "ABC"),
        measurements=rows,
        truth=tuple(
            GroundTruth(t=t, pose=np.tile([x, y, z, psi], (2, 1)))
            for x, y, z, psi in ((0, 0, 0, 0), (3, 1, 0.5, 3.0), (-2, 2, 1.0, -3.0))
        ),
        landmarks=np.zeros((1, 3)),
    )


def test_measure_uses_its_rows_and_counts_the_rest() -> None:
    t = np.array([0.5])
    rows = Measurements.concatenate(
        [
            measurement_rows("height", t=t, observer=0, target=1, value=[0.5]),
            measurement_rows("height", t=t, observer=0, target=1, value=[0.6], sensor=1),
            measurement_rows("range", t=t, observer=0, target=1, value=[3.2]),
            measurement_rows("range", t=t, observer=0, value=[2.0]),  # unknown target
            measurement_rows("bearing_elevation", t=t, observer=0, value=[[0.32, 0.15]]),
            measurement_rows("bearing_elevation", t=t, observer=0, target=2, value=[[1, 0]]),
            measurement_rows("bearing_elevation", t=t, observer=0, landmark=0, value=[[1, 0]]),
            measurement_rows("bearing", t=t, observer=0, value=[0.3]),
            measurement_rows("pose", t=t, observer=0, value=[[0, 0, 0]]),
            measurement_rows("height", t=t, observer=1, target=0, value=[-0.5]),  # B's row
        ]
    )
    est = GaussianSumEstimator(("A", "B", "C"), 0, SETTINGS)
    est.advance(0.0, HeldOdometry.still(3))
    est.advance(0.5, HeldOdometry.still(3))
    est.measure(rows)
    assert est.take_counts() == {
        "rows_used:height": 1,
        "rows_used:range": 1,
        "rows_used:bearing_elevation": 1,
        "rows_repeated_in_a_scan:height": 1,
        "rows_not_modelled:range": 1,
        "rows_not_modelled:bearing_elevation": 2,
        "rows_not_modelled:bearing": 1,
        "rows_not_modelled:pose": 1,
    }
    (belief,) = est.beliefs()  # B, born from the one bearing with its range and height
    assert belief.subject == "B" and belief.frame == "relative_pose4"
    assert belief.info["scan_t"] == 0.5 and belief.info["bearing_row"] == 0.0
    assert est.take_counts() == {}
    with pytest.raises(DataError, match="names robot 5"):
        est.measure(measurement_rows("range", t=t, observer=0, target=5, value=[1.0]))
    with pytest.raises(DataError, match="odometry of 2 robots"):
        est.advance(1.0, HeldOdometry.still(2))


_KIND = st.sampled_from(KIND_NAMES)


@st.composite
def _rows(draw: st.DrawFn) -> Measurements:
    """Up to 12 rows of any kind at two time stamps, for observers 0 and 1, with any target
    the kind allows (distinct sensors, so no two rows repeat a key)."""
    n = draw(st.integers(0, 12))
    parts = [empty_measurements()]
    for k in range(n):
        kind = draw(_KIND)
        spec = KINDS[kind]
        observer = draw(st.integers(0, 1))
        if spec.needs_target == "none":
            target = NO_TARGET
        elif spec.needs_target == "robot":
            target = draw(st.sampled_from([j for j in range(3) if j != observer]))
        else:
            target = draw(st.sampled_from([NO_TARGET] + [j for j in range(3) if j != observer]))
        value = [draw(st.floats(0.1, 3.0)) for _ in range(spec.dim)]
        t = draw(st.sampled_from([0.25, 0.5]))
        parts.append(
            measurement_rows(kind, t=[t], observer=observer, target=target, value=[value], sensor=k)
        )
    return Measurements.concatenate(parts)


@settings(derandomize=True, max_examples=40, deadline=None)
@given(rows=_rows(), elevation=st.booleans())
def test_every_row_of_the_observer_is_used_or_counted(rows: Measurements, elevation: bool) -> None:
    st_ = replace(SETTINGS, use_elevation=elevation)
    est = GaussianSumEstimator(("A", "B", "C"), 0, st_)
    est.advance(0.0, HeldOdometry.still(3))
    est.advance(0.5, HeldOdometry.still(3))
    est.measure(rows)
    counts = est.take_counts()
    assert sum(counts.values()) == int(np.sum(rows.observer == 0))
    for b in est.beliefs():
        assert np.isfinite(b.mean).all() and b.info["scan_t"] in (0.25, 0.5)


def test_messages_are_fused_at_the_next_step_and_sharing_is_a_setting() -> None:
    rec = simulate(SCENARIO, np.random.default_rng(3))
    m = rec.measurements
    ests = team(rec.robots, (0, 1), SETTINGS)
    grid = rec.odometry[0].t
    for k, t in enumerate(grid[grid <= 1.0 + 1e-9]):
        batch = m.select(m.t == t)
        odometry = HeldOdometry(
            velocity=np.stack([od.velocity[max(k - 1, 0)] for od in rec.odometry]),
            stamp=np.full(5, t),
        )
        for e in ests:
            e.advance(float(t), odometry)
            e.measure(batch)
        out = [e.outbox() for e in ests]
    assert all(out) and all(isinstance(msg, EquivalentMeasurement) for msg in out[0])
    before = [b.mean for b in ests[0].beliefs()]
    ests[0].receive(out[1] + ["not a message"])
    after = [b.mean for b in ests[0].beliefs()]
    assert all(np.array_equal(a, b) for a, b in zip(before, after, strict=True))
    ests[0].advance(1.0, odometry)  # zero time step: only the queued messages change it
    assert ests[0].take_counts()["messages_not_modelled"] == 1
    fused = [b.mean for b in ests[0].beliefs()]
    assert not all(np.array_equal(a, b) for a, b in zip(before, fused, strict=True))
    quiet = GaussianSumEstimator(rec.robots, 0, SETTINGS, sharing=False)
    quiet.advance(0.0, HeldOdometry.still(5))
    quiet.advance(1.0, HeldOdometry.still(5))
    assert quiet.outbox() == []
    with pytest.raises(ConfigError, match="fusion_period"):
        GaussianSumEstimator(rec.robots, 0, SETTINGS, fusion_period=0.0)
    with pytest.raises(ConfigError, match="distinct"):
        team(rec.robots, (0, 0), SETTINGS)


class _Log(Silent):
    """Records the event times and the stamps of the readings it is given."""

    name = "log"

    def __init__(self) -> None:
        self.owner = "A"
        self.events: list[float] = []
        self.fed: list[tuple[float, tuple[float, ...]]] = []

    def advance(self, t: float, odometry: HeldOdometry) -> None:
        self.events.append(t)

    def measure(self, batch: Measurements) -> None:
        self.fed.append((self.events[-1], tuple(batch.t.tolist())))

    def beliefs(self) -> list[Any]:
        return []


def test_replay_on_a_clock_feeds_readings_at_the_next_tick() -> None:
    clock = np.arange(0.0, 1.0, 0.25)
    stamps = np.array([0.1, 0.2, 0.25 + 1e-12, 0.3, 0.74])
    rows = measurement_rows("range", t=stamps, observer=0, target=1, value=np.ones(5))
    rec = replace(_three_robots(empty_measurements()), measurements=rows)
    log = _Log()
    replay(rec, [log], clock=clock, record_times=clock[[1, 3]])
    np.testing.assert_array_equal(log.events, clock)
    assert log.fed == [(0.25, (0.1, 0.2, 0.25 + 1e-12)), (0.5, (0.3,)), (0.75, (0.74,))]
    np.testing.assert_array_equal(feed_ticks(stamps, clock), [0.25, 0.25, 0.25, 0.5, 0.75])
    with pytest.raises(ConfigError, match="after the last tick"):
        feed_ticks([0.8], clock)
    with pytest.raises(ConfigError, match="record time"):
        replay(rec, [_Log()], clock=clock, record_times=[0.3])
    with pytest.raises(ConfigError, match="strictly increasing"):
        replay(rec, [_Log()], clock=np.array([0.0, 0.5, 0.5]))
    with pytest.raises(ConfigError, match="no clock tick"):
        replay(rec, [_Log()], clock=clock, start=0.3, end=0.4)


def test_leader_scores_look_up_origins_and_wrap_the_yaw() -> None:
    t = np.array([0.5, 0.5, 0.5])
    rows = measurement_rows(
        "bearing_elevation",
        t=t,
        observer=0,
        value=np.zeros((3, 2)),
        origin=np.array([2, CLUTTER, 1]),
    )
    rec = _three_robots(rows)
    assert bearing_kind(SETTINGS) == "bearing_elevation"
    recorder = Recorder("gaussian_sum")
    truth_b = rec.relative_truth(0, 1, 0.5)[0]
    mean = truth_b + np.array([0.0, 0.0, 0.0, 2 * np.pi - 0.2])  # yaw error −0.2 once wrapped
    info = {"components": 3.0, "confirmed": 1.0, "scan_t": 0.5}
    recorder.record(
        0.5,
        "A",
        [
            _belief("B", mean, info | {"bearing_row": 2.0, "decision_row": 0.0}),
            _belief(
                "C",
                rec.relative_truth(0, 2, 0.5)[0],
                info | {"bearing_row": -1.0, "decision_row": 1.0},
            ),
        ],
    )
    sc = leader_scores(recorder.results(), rec, 0, np.array([0.5]), "bearing_elevation")
    np.testing.assert_allclose(sc.error[0, 1], [0, 0, 0, -0.2], atol=1e-12)
    np.testing.assert_allclose(sc.nees[0, 1], 0.04 / 0.01)  # cov diag 0.01
    np.testing.assert_array_equal(sc.assoc_origin[0], [NO_READING, 1, NO_READING])
    np.testing.assert_array_equal(sc.joint_origin[0], [NO_READING, 2, CLUTTER])
    assert np.isnan(sc.error[0, 0]).all() and sc.components[0].tolist() == [0, 3, 3]
    bad = Recorder("gaussian_sum")
    bad.record(0.5, "A", [_belief("B", mean, info | {"bearing_row": 3.0, "decision_row": -1.0})])
    with pytest.raises(DataError, match="bearing row 3"):
        leader_scores(bad.results(), rec, 0, np.array([0.5]), "bearing_elevation")


def _belief(subject: str, mean: Any, info: dict[str, float]) -> Any:
    from relloc.core.contract import Belief

    return Belief(
        subject=subject, frame="relative_pose4", mean=mean, cov=np.eye(4) * 0.01, info=info
    )


def test_simulator_gives_a_recording_of_scans_with_hidden_bearings() -> None:
    rec = simulate(replace(SCENARIO, clutter_density=1e-5), np.random.default_rng(1))
    m = rec.measurements
    assert rec.robots == ROBOT_NAMES and rec.platforms[:2] == ("ground", "ground")
    bearings = m.of_kind("bearing_elevation")
    assert np.all(bearings.target == NO_TARGET)
    assert set(np.unique(bearings.origin)) <= {CLUTTER, 0, 1, 2, 3, 4}
    assert np.any(bearings.origin == CLUTTER)
    heights = m.of_kind("height")
    # every leader's scan has a height of each of its 4 teammates, scans at 10 Hz
    assert heights.size == 2 * 4 * round(SCENARIO.duration * SCENARIO.direct_rate)
    assert set(np.unique(m.observer)) == {0, 1}
