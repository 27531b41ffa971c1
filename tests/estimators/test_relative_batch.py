"""The batch of relative filters: every filter equals the same filter run alone, the contract
(beliefs, updates, counts) and bad configuration."""

from __future__ import annotations

import numpy as np
import pytest

from relloc.core.contract import Estimator, HeldOdometry
from relloc.core.gaussian import Gaussian
from relloc.core.recording import (
    GroundTruth,
    Measurements,
    Odometry,
    Recording,
    kind_code,
    measurement_rows,
    relative_pose,
)
from relloc.errors import ConfigError, DataError
from relloc.estimators.initialisation import fully_unknown, known_pose
from relloc.estimators.relative import FilterSettings, RelativeTracker
from relloc.estimators.relative_batch import RelativeFilterBatch, TrackSpec
from relloc.estimators.yaw_bank import YawBankSettings, YawBankTracker
from relloc.models.measurement import RangeBearingNoise, range_bearing
from relloc.models.motion import VelocityNoise
from relloc.pipeline.evaluation import at_times, evaluate
from relloc.pipeline.replay import replay

ROBOTS = ("l", "a", "b")
STEPS = 300
#: Body velocities (v_x, v_y, v_z, ω) and their noise σ per robot.
VELOCITY = np.array([[0.4, 0.0, 0.0, 0.15], [0.3, 0.05, 0.02, -0.2], [0.25, 0.0, 0.0, 0.1]])
SIGMA = np.array([[0.02, 0.0, 0.0, 0.01], [0.03, 0.03, 0.01, 0.02], [0.02, 0.0, 0.0, 0.02]])
START = np.array([[0.0, 0.0, 0.0, 0.3], [3.0, 1.0, 2.0, -1.0], [2.0, -2.5, 0.0, 2.0]])
#: Sensors of the observer: (σ_r, σ_θ, σ_α), rate (Hz), observed robot.
SENSORS = (
    ((0.0068, 0.0036, 0.0036), 10.0, "a"),
    ((0.1466, 0.1, 0.1), 5.0, "a"),
    ((0.0068, 0.0036, 0.0036), 10.0, "b"),
)


def _unicycle_truth(i: int, t: np.ndarray) -> np.ndarray:
    """Exact poses of robot ``i`` under its constant body velocity."""
    v, vy, vz, w = VELOCITY[i]
    x0, y0, z0, yaw0 = START[i]
    yaw = yaw0 + w * t
    # ∫ R(yaw) (v, vy) dt in closed form
    x = x0 + (v * (np.sin(yaw) - np.sin(yaw0)) + vy * (np.cos(yaw) - np.cos(yaw0))) / w
    y = y0 + (-v * (np.cos(yaw) - np.cos(yaw0)) + vy * (np.sin(yaw) - np.sin(yaw0))) / w
    return np.stack([x, y, z0 + vz * t, yaw], axis=-1)


def _recording(rng: np.random.Generator) -> Recording:
    t = np.arange(STEPS + 1) / 100.0
    truth = [_unicycle_truth(i, t) for i in range(3)]
    odometry = tuple(
        Odometry(
            t=t[:-1],
            velocity=VELOCITY[i] + SIGMA[i] * rng.standard_normal((STEPS, 4)),
            sigma=SIGMA[i],
        )
        for i in range(3)
    )
    parts = []
    for s, (sigma, rate, target) in enumerate(SENSORS):
        steps = np.arange(round(100 / rate), STEPS + 1, round(100 / rate))
        j = ROBOTS.index(target)
        z = range_bearing(relative_pose(truth[0][steps], truth[j][steps]))
        z = z + np.asarray(sigma) * rng.standard_normal(z.shape)
        parts.append(
            measurement_rows(
                "range_bearing_elevation",
                t=t[steps],
                observer=0,
                target=j,
                value=z,
                sigma=sigma,
                sensor=s,
            )
        )
    # rows the batch must leave alone: other kinds, an unknown target, a sensor nobody tracks,
    # no stated σ, another observer's reading
    parts += [
        measurement_rows("range", t=[0.5], observer=0, target=1, value=[[3.0]]),
        measurement_rows("range_bearing_elevation", t=[0.6], observer=0, value=[[3.0, 0.1, 0.2]]),
        measurement_rows(
            "range_bearing_elevation",
            t=[0.7],
            observer=0,
            target=1,
            value=[[3.0, 0.1, 0.2]],
            sigma=[0.1, 0.1, 0.1],
            sensor=7,
        ),
        measurement_rows(
            "range_bearing_elevation",
            t=[0.75],
            observer=0,
            target=2,
            value=[[3.0, 0.1, 0.2]],
            sensor=2,
        ),
        measurement_rows(
            "range_bearing_elevation",
            t=[0.8],
            observer=1,
            target=2,
            value=[[3.0, 0.1, 0.2]],
            sigma=[0.1, 0.1, 0.1],
        ),
    ]
    return Recording(
        robots=ROBOTS,
        platforms=("ground", "aerial", "ground"),
        odometry=odometry,
        measurements=Measurements.concatenate(parts),
        truth=tuple(GroundTruth(t=t, pose=p) for p in truth),
    )


def _specs(recording: Recording) -> list[TrackSpec]:
    known_a = known_pose(recording.relative_truth("l", "a", 0.0)[0])
    known_b = known_pose(recording.relative_truth("l", "b", 0.0)[0])
    guess = fully_unknown(np.array([4.0, -1.0, 1.0, 2.5]), sigma_position=5.0)
    specs = []
    for sensor in (0, 1):
        for kind in ("plkf", "tekf", "bcplkf"):
            for name, prior in (("known", known_a), ("guess", guess)):
                specs.append(
                    TrackSpec(
                        label=f"s{sensor}/{kind}/{name}",
                        subject="a",
                        kind=kind,  # type: ignore[arg-type]
                        prior_mean=prior.mean,
                        prior_cov=prior.cov,
                        sensor=sensor,
                    )
                )
        specs.append(
            TrackSpec(
                label=f"s{sensor}/bank",
                subject="a",
                kind="plkf",
                prior_mean=guess.mean,
                prior_cov=guess.cov,
                sensor=sensor,
                bank=True,
            )
        )
    specs.append(
        TrackSpec(
            label="plkf",
            subject="b",
            kind="plkf",
            prior_mean=known_b.mean,
            prior_cov=known_b.cov,
            sensor=2,
        )
    )
    return specs


def _batch(
    recording: Recording, specs: list[TrackSpec], bank: YawBankSettings
) -> RelativeFilterBatch:
    return RelativeFilterBatch(
        specs,
        owner="l",
        robots=recording.robots,
        odometry_sigma=[od.sigma for od in recording.odometry],
        bank=bank,
    )


Step = tuple[float, np.ndarray, np.ndarray, float, float]


def _alone(recording: Recording, spec: TrackSpec, bank: YawBankSettings) -> list[Step]:
    """The filter of ``spec`` run on its own: ``(t, mean, cov, nis, n_alive)`` after each of
    its updates (``n_alive`` NaN for a single filter)."""
    j = recording.index(spec.subject)
    sigma = SENSORS[spec.sensor][0]
    settings = FilterSettings(
        kind=spec.kind,
        motion_noise=VelocityNoise(observer=tuple(SIGMA[0]), observed=tuple(SIGMA[j])),  # type: ignore[arg-type]
        sensor_noise=RangeBearingNoise(
            sigma_r=sigma[0], sigma_azimuth=sigma[1], sigma_elevation=sigma[2]
        ),
    )
    prior = Gaussian(mean=spec.prior_mean, cov=spec.prior_cov)
    tracker: RelativeTracker | YawBankTracker = (
        YawBankTracker(prior, settings, bank) if spec.bank else RelativeTracker(prior, settings)
    )
    m = recording.measurements
    mine = (
        (m.observer == 0)
        & (m.target == j)
        & (m.sensor == spec.sensor)
        & (m.kind == kind_code("range_bearing_elevation"))
        & np.isfinite(m.sigma[:, 0])
    )
    out: list[Step] = []
    for k in range(1, STEPS + 1):
        tracker.predict(
            recording.odometry[0].velocity[k - 1],
            recording.odometry[j].velocity[k - 1],
            k / 100.0 - (k - 1) / 100.0,  # the replay's step between events
        )
        for q in np.flatnonzero(mine & np.isclose(m.t, k / 100.0, rtol=0.0, atol=1e-9)):
            inn = tracker.update(m.value[q])
            alive = float(tracker.n_alive) if isinstance(tracker, YawBankTracker) else np.nan
            belief = tracker.belief
            out.append((float(m.t[q]), belief.mean, belief.cov, float(inn.nis), alive))
    return out


def test_every_filter_of_the_batch_equals_the_filter_run_alone() -> None:
    recording = _recording(np.random.default_rng(4))
    specs = _specs(recording)
    bank = YawBankSettings(n_components=8)
    batch = _batch(recording, specs, bank)
    assert isinstance(batch, Estimator)
    m = recording.measurements
    record = np.unique(m.t[m.observer == 0])
    estimates = replay(recording, [batch], record_times=record)
    scored = {(e.subject, e.track): e for e in evaluate(estimates, recording, at_updates=True)}
    assert len(scored) == len(specs)
    for spec in specs:
        alone = _alone(recording, spec, bank)
        ev = scored[(spec.subject, spec.label)]
        series = estimates.series("l", spec.subject, spec.label)
        updates = estimates.updates_of("l", spec.subject, spec.label)
        assert series.frame == "relative_pose4"
        np.testing.assert_array_equal(ev.t, [a[0] for a in alone])
        picked = at_times(series, ev.t)
        np.testing.assert_allclose(picked.mean, [a[1] for a in alone], rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(picked.cov, [a[2] for a in alone], rtol=1e-9, atol=1e-14)
        np.testing.assert_allclose(updates.nis, [a[3] for a in alone], rtol=1e-7, atol=1e-10)
        assert np.all(updates.dof == 3)
        assert np.all(np.isfinite(updates.cond_r)) and np.all(np.isfinite(updates.cond_s))
        np.testing.assert_array_equal(updates.age, updates.t)  # the batch started at t = 0
        if spec.bank:
            np.testing.assert_array_equal(picked.info["n_alive"], [a[4] for a in alone])
            assert picked.info["n_alive"][0] == 8 and picked.info["n_alive"][-1] >= 1
        else:
            assert "n_alive" not in series.info
        # evaluated at its updates: the error of the belief right after each one, with its NIS
        truth = recording.relative_truth("l", spec.subject, ev.t)
        err = picked.mean - truth
        err[:, 3] = np.arctan2(np.sin(err[:, 3]), np.cos(err[:, 3]))
        np.testing.assert_allclose(ev.error, err, atol=1e-12)
        np.testing.assert_array_equal(ev.nis, updates.nis)


def test_rows_the_batch_does_not_fuse_are_counted_by_reason() -> None:
    recording = _recording(np.random.default_rng(5))
    batch = _batch(recording, _specs(recording), YawBankSettings())
    estimates = replay(recording, [batch], record_times=np.zeros(0))
    # the loop takes the batch's counts into the estimates record
    assert estimates.counts == {
        "rows_of_kind_range": 1,
        "rows_of_unknown_target": 1,
        "rows_of_untracked_target_or_sensor": 1,
        "rows_without_sigma": 1,
    }
    assert batch.take_counts() == {}


def test_the_first_event_sets_the_clock_and_time_cannot_go_back() -> None:
    recording = _recording(np.random.default_rng(6))
    specs = _specs(recording)
    batch = _batch(recording, specs, YawBankSettings())
    with pytest.raises(ConfigError, match="before the first advance"):
        batch.beliefs()
    still = HeldOdometry(velocity=VELOCITY, stamp=np.zeros(3))
    batch.advance(2.0, still)
    beliefs = batch.beliefs()
    assert [b.track for b in beliefs] == [s.label for s in specs]
    for b, s in zip(beliefs, specs, strict=True):
        if not s.bank:
            np.testing.assert_array_equal(b.mean, s.prior_mean)
        assert b.age == 0.0
    with pytest.raises(DataError, match=r"RelativeFilterBatch\.advance: time went back from 2\.0"):
        batch.advance(1.0, still)
    with pytest.raises(DataError, match="odometry of shape"):
        batch.advance(3.0, HeldOdometry(velocity=np.zeros((2, 4)), stamp=np.zeros(2)))


def test_bad_specs_are_config_errors() -> None:
    recording = _recording(np.random.default_rng(7))
    prior = known_pose(np.array([3.0, 1.0, 2.0, 0.0]))
    good = {
        "label": "x",
        "subject": "a",
        "kind": "plkf",
        "prior_mean": prior.mean,
        "prior_cov": prior.cov,
    }
    with pytest.raises(ConfigError, match="pseudo-linear"):
        TrackSpec(**{**good, "kind": "tekf", "bank": True})
    with pytest.raises(ConfigError, match="kind"):
        TrackSpec(**{**good, "kind": "ukf"})
    with pytest.raises(ConfigError, match="prior"):
        TrackSpec(**{**good, "prior_mean": np.zeros(3)})
    with pytest.raises(ConfigError, match="NaN"):
        TrackSpec(**{**good, "prior_mean": np.array([np.nan, 0.0, 0.0, 0.0])})
    with pytest.raises(ConfigError, match="sensor"):
        TrackSpec(**{**good, "sensor": -1})
    sig = [od.sigma for od in recording.odometry]
    with pytest.raises(ConfigError, match="repeats"):
        RelativeFilterBatch([TrackSpec(**good)] * 2, owner="l", robots=ROBOTS, odometry_sigma=sig)
    with pytest.raises(ConfigError, match="not on the team"):
        RelativeFilterBatch(
            [TrackSpec(**{**good, "subject": "z"})], owner="l", robots=ROBOTS, odometry_sigma=sig
        )
    with pytest.raises(ConfigError, match="itself"):
        RelativeFilterBatch(
            [TrackSpec(**{**good, "subject": "l"})], owner="l", robots=ROBOTS, odometry_sigma=sig
        )
    with pytest.raises(ConfigError, match="owner"):
        RelativeFilterBatch([TrackSpec(**good)], owner="q", robots=ROBOTS, odometry_sigma=sig)
    with pytest.raises(ConfigError, match="odometry σ"):
        RelativeFilterBatch([TrackSpec(**good)], owner="l", robots=ROBOTS, odometry_sigma=sig[:2])
    with pytest.raises(ConfigError, match="no filters"):
        RelativeFilterBatch([], owner="l", robots=ROBOTS, odometry_sigma=sig)


def test_evaluation_at_times_that_were_not_recorded_is_refused() -> None:
    recording = _recording(np.random.default_rng(8))
    batch = _batch(recording, _specs(recording), YawBankSettings())
    estimates = replay(recording, [batch], record_times=np.array([1.0]))
    with pytest.raises(ConfigError, match="not recorded"):
        evaluate(estimates, recording, at_updates=True)
