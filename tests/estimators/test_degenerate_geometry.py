"""Degenerate but valid geometry: a drone straight above its observer, robots nearly co-located,
bearings at ±π, nearly singular or huge covariances, long spells at rest, a static range-only
pair, and a teammate 10 km away. Every filter stays finite, symmetric PSD and accurate."""

from __future__ import annotations

import math

import numpy as np
import pytest

from relloc.core.gaussian import Gaussian
from relloc.core.recording import GroundTruth, Odometry, Recording, measurement_rows
from relloc.estimators.cooperative import (
    CooperativeEstimator,
    CooperativeSettings,
    OdometryModel,
    SensorModel,
)
from relloc.estimators.initialisation import InitPolicy
from relloc.estimators.kernels import SCALAR_OPS, tekf_terms
from relloc.estimators.relative import UPDATE_KINDS, FilterSettings, RelativeTracker
from relloc.estimators.track_manager import TrackManagerSettings, managers_for
from relloc.estimators.uwb_range import RangePairBank, RangePairSettings
from relloc.estimators.yaw_bank import YawBankSettings, YawBankTracker
from relloc.metrics import nees, state_errors
from relloc.models.measurement import RangeBearingNoise, range_bearing, range_bearing_jacobian
from relloc.models.motion import VelocityNoise
from relloc.pipeline.replay import replay
from relloc.sim.cooperative import CooperativeScenario, simulate
from relloc.sim.sensors import add_noise, range_azimuth_elevation

SIGMA_Z = (0.0068, 0.0036, 0.0036)
NOISE = RangeBearingNoise(sigma_r=SIGMA_Z[0], sigma_azimuth=SIGMA_Z[1], sigma_elevation=SIGMA_Z[2])
MOTION = VelocityNoise(observer=(0.01,) * 4, observed=(0.01,) * 4)


def _settings(kind: str) -> FilterSettings:
    return FilterSettings(kind=kind, motion_noise=MOTION, sensor_noise=NOISE)  # type: ignore[arg-type]


def _assert_sane(mean: np.ndarray, cov: np.ndarray, *, exactly_symmetric: bool = True) -> None:
    """Finite, symmetric (exactly, or to 1e-15 ‖P‖), PSD to rounding (eigenvalues ≥ −1e-12 ‖P‖)."""
    assert np.isfinite(mean).all() and np.isfinite(cov).all()
    if exactly_symmetric:
        np.testing.assert_array_equal(cov, np.swapaxes(cov, -1, -2))
    else:
        np.testing.assert_allclose(
            cov, np.swapaxes(cov, -1, -2), rtol=0, atol=1e-15 * np.abs(cov).max()
        )
    eig = np.linalg.eigvalsh(cov)
    scale = np.max(np.abs(cov), axis=(-2, -1), keepdims=True)[..., 0]
    assert np.all(eig >= -1e-12 * scale), eig.min()


def _recording(rel, *, duration=10.0, yaw=0.3, seed=1) -> Recording:
    """Static observer at the origin (yaw 0); the target at world position ``rel(t)`` with a
    fixed yaw; odometry at 100 Hz, noisy range/bearing/elevation at 10 Hz."""
    dt = 0.01
    t = np.arange(round(duration / dt) + 1) * dt
    p = rel(t)
    v = (p[1:] - p[:-1]) / dt  # exact over each held interval
    c, s = math.cos(yaw), math.sin(yaw)
    v_body = np.column_stack(
        [c * v[:, 0] + s * v[:, 1], -s * v[:, 0] + c * v[:, 1], v[:, 2], np.zeros(t.size - 1)]
    )
    tm = np.arange(1, round(duration * 10) + 1) / 10.0
    z = add_noise(range_azimuth_elevation(rel(tm)), np.array(SIGMA_Z), np.random.default_rng(seed))
    sig = np.array([1e-3, 1e-2, 1e-2, 1e-2])
    return Recording(
        robots=("l", "c"),
        platforms=("ground", "aerial"),
        truth=(
            GroundTruth(t=t, pose=np.zeros((t.size, 4))),
            GroundTruth(t=t, pose=np.column_stack([p, np.full(t.size, yaw)])),
        ),
        odometry=(
            Odometry(t=t[:-1], velocity=np.zeros((t.size - 1, 4)), sigma=sig),
            Odometry(t=t[:-1], velocity=v_body, sigma=sig),
        ),
        measurements=measurement_rows(
            "range_bearing_elevation", t=tm, observer=0, target=1, value=z, sigma=SIGMA_Z
        ),
    )


_RUNS = [(k, "known", False) for k in UPDATE_KINDS] + [
    (k, "measurement", bank) for k in UPDATE_KINDS for bank in (False, True)
]


def _run(rec: Recording, kind: str, init: str, bank: bool, rng=None):
    settings = TrackManagerSettings(
        filter=kind,
        init=InitPolicy(name=init),
        keep_window_s=1e9,
        yaw_bank=YawBankSettings() if bank else None,
    )
    est = replay(rec, managers_for(rec, settings, rng=rng))
    pair = est.series("l", "c")
    nis = est.updates_of("l", "c").nis
    _assert_sane(pair.mean, pair.cov)
    assert nis.size and np.isfinite(nis).all()
    err = state_errors(pair.mean, rec.relative_truth("l", "c", pair.t))
    return pair, nis, np.linalg.norm(err[:, :3], axis=1)


# ------------------------------------------------------------------ (1) straight above / below


@pytest.mark.parametrize("api", ["tracker", "single", "batch"])
@pytest.mark.parametrize("estimate_xy", [(0.0, 0.0), (1e-12, -1e-12)])
def test_tekf_update_of_an_estimate_on_the_vertical_axis_is_finite(api, estimate_xy):
    # Used to raise ZeroDivisionError (one pair) or "not positive definite" (a batch, NaN).
    fs = _settings("tekf")
    mean = np.array([*estimate_xy, 3.0, 0.1])
    cov = np.diag([0.05**2] * 3 + [0.1**2])
    z = np.array([3.0, 0.3, math.pi / 2 - 1e-3])  # 3 mm off the axis, towards azimuth 0.3
    if api == "tracker":
        tr = RelativeTracker(Gaussian(mean=mean, cov=cov), fs)
        nis = tr.update(z).nis
        new_mean, new_cov = tr.belief.mean, tr.belief.cov
    elif api == "single":
        new_mean, new_cov, inn = fs.update_arrays(mean, cov, z)
        nis = inn.nis
    else:  # one entry on the axis, one far from it
        other = np.array([4.0, 1.0, 1.5, 0.0])
        means, covs, inn = fs.update_arrays(
            np.stack([mean, other]), np.stack([cov, cov]), np.stack([z, range_bearing(other)])
        )
        new_mean, new_cov, nis = means[0], covs[0], inn.nis[0]
        np.testing.assert_allclose(means[1], other, atol=1e-12)
    _assert_sane(new_mean, new_cov)
    assert math.isfinite(nis)
    # the elevation moves the estimate 3 mm off the axis along the measured azimuth
    rho = math.hypot(new_mean[0], new_mean[1])
    assert rho == pytest.approx(3.0 * 1e-3, rel=0.1)
    assert math.atan2(new_mean[1], new_mean[0]) == pytest.approx(0.3, abs=1e-6)
    # no collapse of the horizontal variance (the dropped azimuth row adds no information)
    assert np.linalg.eigvalsh(new_cov[:2, :2]).min() > 1e-5


def test_tekf_update_of_an_estimate_at_the_observer_moves_along_the_measured_ray():
    fs = _settings("tekf")
    tr = RelativeTracker(Gaussian(mean=np.zeros(4), cov=np.eye(4) * 0.01), fs)
    z = np.array([0.05, 0.5, 0.2])
    inn = tr.update(z)
    _assert_sane(tr.belief.mean, tr.belief.cov)
    assert math.isfinite(inn.nis)
    ray = np.array([math.cos(0.5) * math.cos(0.2), math.sin(0.5) * math.cos(0.2), math.sin(0.2)])
    p = tr.belief.mean[:3]
    assert np.linalg.norm(np.cross(p, ray)) < 1e-12 and p @ ray == pytest.approx(0.05, rel=0.01)


def test_tekf_terms_off_the_axis_are_the_model_jacobian():
    rng = np.random.default_rng(5)
    for _ in range(50):
        x = rng.normal(size=4) * 3.0
        z = tuple(range_bearing(x + rng.normal(size=4) * 0.01).tolist())
        A, _, _ = tekf_terms(tuple(x.tolist()), z, (1.0, 1.0, 1.0), SCALAR_OPS)
        np.testing.assert_allclose(
            np.array(A).reshape(3, 3), range_bearing_jacobian(x)[:, :3], rtol=1e-13, atol=1e-15
        )


def test_every_filter_hovering_exactly_overhead_from_the_true_start():
    # rng=None: the start is the truth itself, (0, 0, 3) — the TEKF divided by zero here.
    rec = _recording(lambda t: np.column_stack([0 * t, 0 * t, 3.0 + 0 * t]), duration=5.0)
    for kind in UPDATE_KINDS:
        _, nis, err = _run(rec, kind, "known", False, rng=None)
        # measured: PLKF/BC-PLKF 4 mm, TEKF 17 mm (its azimuth linearisation at ρ̂ ≈ 0)
        assert err.max() < (0.03 if kind == "tekf" else 0.01), (kind, err.max())
        if kind != "tekf":  # the TEKF is overconfident at ρ̂ ≈ 0: NIS mean 8, max 290
            assert nis.mean() < 4.0, (kind, nis.mean())


@pytest.mark.parametrize("height", [3.0, -3.0])
def test_every_filter_through_a_pass_straight_over_or_under_the_observer(height):
    # x from −2 to 2 m at 0.4 m/s: exactly overhead at t = 5 s
    rec = _recording(lambda t: np.column_stack([-2.0 + 0.4 * t, 0 * t, height + 0 * t]))
    for kind, init, bank in _RUNS:
        pair, nis, err = _run(rec, kind, init, bank, rng=np.random.default_rng(0))
        late = pair.t > 2.0
        # measured: PLKF/BC-PLKF ≤ 3 mm, NIS mean 2.5; TEKF ≤ 16 mm, NIS up to 340 overhead
        bound = 0.03 if kind == "tekf" else 0.006
        assert err[late].max() < bound, (kind, init, bank, err[late].max())
        if kind != "tekf":
            assert nis.mean() < 3.5, (kind, init, bank, nis.mean())


# ------------------------------------------------------------------ (2) nearly co-located


@pytest.mark.parametrize("distance", [1e-3, 1e-6])
def test_every_filter_with_the_robots_nearly_co_located(distance):
    rec = _recording(
        lambda t: np.column_stack([0.6 * distance + 0 * t, 0 * t, 0.8 * distance + 0 * t]),
        duration=3.0,
    )
    for kind, init, bank in _RUNS:
        _, _, err = _run(rec, kind, init, bank, rng=np.random.default_rng(0))
        # the range noise (6.8 mm) dominates; the TEKF reached 1 cm from a 2 cm start
        assert err[-10:].max() < (0.02 if kind == "tekf" else 0.01), (kind, init, bank)


# ------------------------------------------------------------------ (3) bearing at ±π


def test_every_filter_with_bearings_straddling_pi():
    rec = _recording(lambda t: np.column_stack([-5.0 + 0 * t, -1.0 + 0.2 * t, 1.0 + 0 * t]))
    z = rec.measurements.value[:, 1]
    assert z.max() > 3.0 and z.min() < -3.0  # the measured azimuth wraps
    for kind, init, bank in _RUNS:
        pair, nis, err = _run(rec, kind, init, bank, rng=np.random.default_rng(0))
        assert err[pair.t > 2.0].max() < 0.015, (kind, init, bank)
        assert nis.mean() < 3.5


# ------------------------------------------------------------------ (4) nearly singular / huge P


@pytest.mark.parametrize("kind", UPDATE_KINDS)
def test_many_very_precise_updates_keep_the_covariance_psd(kind):
    truth = np.array([4.0, 1.0, 1.5, 0.3])
    sigma = 1e-9
    fs = FilterSettings(
        kind=kind,  # type: ignore[arg-type]
        motion_noise=VelocityNoise(observer=(0.0,) * 4, observed=(0.0,) * 4),
        sensor_noise=RangeBearingNoise(sigma_r=sigma, sigma_azimuth=sigma, sigma_elevation=sigma),
    )
    tr = RelativeTracker(
        Gaussian(mean=truth + np.array([0.01, -0.01, 0.01, 0.0]), cov=np.eye(4) * 4e-4), fs
    )
    rng = np.random.default_rng(0)
    z0 = range_bearing(truth)
    for _ in range(5000 if kind == "bcplkf" else 20000):
        tr.predict((0.0,) * 4, (0.0,) * 4, 0.01)
        tr.update(z0 + sigma * rng.standard_normal(3))
    P = tr.belief.cov
    _assert_sane(tr.belief.mean, P)
    eig = np.linalg.eigvalsh(P)
    assert eig.min() > 0.0 and eig.max() / eig.min() > 1e14  # nearly singular, still PD
    assert np.abs(tr.belief.mean[:3] - truth[:3]).max() < 1e-8  # (measured ≤ 1.3e-9)


@pytest.mark.parametrize("kind", UPDATE_KINDS)
@pytest.mark.parametrize("bank", [False, True])
def test_a_huge_prior_after_a_million_seconds_of_prediction(kind, bank):
    truth = np.array([4.0, 1.0, 1.5, 0.3])
    prior = Gaussian(mean=truth, cov=np.diag([4e-4] * 3 + [4.0 if bank else 4e-4]))
    fs = _settings(kind)
    tr = YawBankTracker(prior, fs, YawBankSettings()) if bank else RelativeTracker(prior, fs)
    tr.predict((0.0,) * 4, (0.0,) * 4, 1e6)
    _assert_sane(tr.belief.mean, tr.belief.cov)
    assert np.linalg.eigvalsh(tr.belief.cov[:3, :3]).min() > 1e7  # (σ ≈ 10 km)
    for _ in range(5):
        inn = tr.update(range_bearing(truth))
        assert math.isfinite(inn.nis)
    _assert_sane(tr.belief.mean, tr.belief.cov)
    # exact for the PLKF and TEKF; the BC-PLKF subtracts its estimated bias (≈ 1e-5 m here)
    assert np.abs(tr.belief.mean[:3] - truth[:3]).max() < 1e-4
    assert np.linalg.eigvalsh(tr.belief.cov[:3, :3]).max() < 1e-4


# ------------------------------------------------------------------ (5) long spells at rest


@pytest.mark.parametrize("kind", UPDATE_KINDS)
def test_a_long_spell_at_rest_then_motion(kind):
    """1000 s at rest (yaw unobservable, its variance growing), then both robots move: finite,
    PSD and the yaw recovered."""
    truth = np.array([4.0, 1.0, 1.5, 0.3])
    tr = RelativeTracker(Gaussian(mean=truth, cov=np.eye(4) * 4e-4), _settings(kind))
    rng = np.random.default_rng(2)
    for _ in range(1000):
        tr.predict((0.0,) * 4, (0.0,) * 4, 1.0)
        tr.update(range_bearing(truth) + np.array(SIGMA_Z) * rng.standard_normal(3))
    _assert_sane(tr.belief.mean, tr.belief.cov)
    assert tr.belief.cov[3, 3] > 0.1  # 2 σ_ω² per second for 1000 s
    # the observed robot drives at 0.5 m/s along its body x for 10 s
    u_c = np.array([0.5, 0.0, 0.0, 0.0])
    x = truth.copy()
    for _ in range(100):
        tr.predict((0.0,) * 4, u_c, 0.1)
        x[:2] += 0.05 * np.array([math.cos(x[3]), math.sin(x[3])])
        tr.update(range_bearing(x) + np.array(SIGMA_Z) * rng.standard_normal(3))
    _assert_sane(tr.belief.mean, tr.belief.cov)
    assert np.abs(tr.belief.mean[:3] - x[:3]).max() < 0.02
    assert abs(math.remainder(tr.belief.mean[3] - x[3], 2 * math.pi)) < 0.05


# ------------------------------------------------------------------ (6) static range-only pair


@pytest.mark.parametrize("sigma_odometry", [(0.01, 0.0, 0.0, 0.01), (0.0, 0.0, 0.0, 0.0)])
def test_a_static_range_only_pair_stays_a_finite_ring(sigma_odometry):
    """Both robots at rest: the bearing and yaw are unobservable; every hypothesis stays on the
    measured circle, finite and PSD, and the merged belief covers the ring."""
    dt, duration = 0.02, 20.0
    t = np.arange(0.0, duration, dt)
    rng = np.random.default_rng(1)
    d = math.hypot(3.0, 1.0)
    tr = t[::5]
    rec = Recording(
        robots=("a", "b"),
        platforms=("ground", "ground"),
        truth=(
            GroundTruth(t=t, pose=np.zeros((t.size, 4))),
            GroundTruth(t=t, pose=np.tile([3.0, 1.0, 0.0, 0.7], (t.size, 1))),
        ),
        odometry=tuple(
            Odometry(t=t, velocity=np.zeros((t.size, 4)), sigma=sigma_odometry) for _ in range(2)
        ),
        measurements=measurement_rows(
            "range",
            t=tr,
            observer=0,
            target=1,
            value=d + rng.normal(0, 0.05, tr.size),
            sigma=[0.05],
        ),
    )
    noise = VelocityNoise(observer=sigma_odometry, observed=sigma_odometry)
    bank = RangePairBank(0, 1, rec.robots, noise, RangePairSettings(sigma_range=0.05))
    est = replay(rec, [bank], record_rate_hz=1.0)
    belief = est.series("a", "b")
    _assert_sane(belief.mean, belief.cov)
    means, covs, w = bank.mixture()
    _assert_sane(means, covs)
    assert np.isfinite(w).all() and w.max() < 0.1  # 96 hypotheses, none preferred yet
    np.testing.assert_allclose(np.linalg.norm(means[:, :3], axis=1), d, atol=0.05)
    assert np.linalg.eigvalsh(belief.cov[-1, :2, :2]).min() > 0.5 * (d**2 / 2) * 0.9
    assert np.isfinite(est.updates_of("a", "b").nis).all()


# ------------------------------------------------------------------ (7) a teammate 10 km away


def test_cooperative_filters_with_a_teammate_ten_km_away():
    far = 9990.0
    scenario = CooperativeScenario(
        start_poses=np.array([[0.0, 0.0, 0.0], [30.0, 10.0, 1.0], [far, 50.0, 2.0]]),
        waypoints=(
            np.array([[50.0, 0.0], [50.0, 50.0], [0.0, 50.0], [0.0, 0.0]]),
            np.array([[80.0, 10.0], [80.0, 60.0], [30.0, 60.0], [30.0, 10.0]]),
            np.array([[far + 50, 50.0], [far + 50, 100.0], [far, 100.0], [far, 50.0]]),
        ),
        landmarks_xy=np.array([[10.0, -10.0], [60.0, 70.0]]),
        duration=20.0,
        sensing_range=1e4,
        speed=2.0,
        initial_sigma=(2.0, 2.0, 0.1),
    )
    sim = simulate(scenario, np.random.default_rng(3))
    rec = sim.recording
    m = rec.measurements
    far_rows = (m.target == 2) | (m.observer == 2)
    assert far_rows.sum() > 100  # bearings across ~10 km
    sep = rec.truth[2].at(m.t[far_rows])[:, :2] - rec.truth[0].at(m.t[far_rows])[:, :2]
    assert np.linalg.norm(sep, axis=1).min() > 9900.0
    odo = OdometryModel(
        q_v0=scenario.sigma_v**2 * scenario.dt, q_w0=scenario.sigma_w**2 * scenario.dt
    )
    finals = {}
    for filt in ("eif", "ekf"):
        settings = CooperativeSettings(
            odometry=odo,
            sensor=SensorModel(sigma_bearing=scenario.sigma_bearing),
            anchors=(0, 1),
            filter=filt,  # type: ignore[arg-type]
        )
        est = CooperativeEstimator(rec.robots, sim.prior, settings, rec.landmarks)
        out = replay(rec, [est], record_rate_hz=1.0)
        finals[filt] = []
        for i, robot in enumerate(rec.robots):
            s = out.series("team", robot)
            _assert_sane(s.mean, s.cov, exactly_symmetric=False)  # (off by 1 ulp at times)
            err = state_errors(s.mean[-1], rec.truth[i].at(s.t[-1:])[0, [0, 1, 3]], (2,))
            assert nees(err, s.cov[-1]) < 16.27  # χ²₃(0.999)
            finals[filt].append(s.mean[-1])
        assert est.counts.used > 1000
    # the information form loses nothing to the 10 km coordinates
    np.testing.assert_allclose(finals["eif"], finals["ekf"], atol=1e-6)
