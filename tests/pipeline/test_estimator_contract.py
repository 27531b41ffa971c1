"""One contract test for every estimator; each linear special case against a plain Kalman filter.

Registry (:data:`CASES`): every estimator relloc ships, each on a short recording it is meant
for, as ``(recording, estimators built fresh from a recording, the kinds it models, the NIS
degrees of freedom it may report)``. Parametrised over every case, through the one loop
:func:`relloc.pipeline.replay.replay`:

- each estimator is an :class:`~relloc.core.contract.Estimator` (runtime-checked Protocol);
- every recorded belief has its frame's dimension (:mod:`relloc.pipeline.frames`), a finite
  mean and a symmetric positive semi-definite covariance (eigenvalues ≥ −1e-9·scale);
- every update record has a finite NIS ≥ 0 and a dof ≥ 1 that the modelled kinds allow, and is
  stamped at a time with a reading of one of those kinds;
- replay is deterministic (same recording, fresh estimators → identical
  :class:`~relloc.core.estimates.Estimates`) and never reads ``Measurements.origin`` (a
  recording whose origin column is scrambled gives identical Estimates);
- :func:`relloc.pipeline.evaluation.evaluate` and ``accuracy_and_consistency`` run on the result.

Linear special cases, each compared with a Kalman filter written out here with the textbook
equations (``x⁻ = F x``, ``P⁻ = F P Fᵀ + Q``; ``S = H P⁻ Hᵀ + R``, ``K = P⁻ Hᵀ S⁻¹``,
``x⁺ = x⁻ + K ν``, ``P⁺ = (I − K H) P⁻ (I − K H)ᵀ + K R Kᵀ``):

- the PLKF of :class:`~relloc.estimators.track_manager.TrackManager` with both robots still:
  ``f`` is the identity, ``Q = G Σ_u Gᵀ`` (:mod:`relloc.models.motion`) and, given the measured
  bearings, ``[r̃, 0, 0] = H_pmo(θ̃, α̃) p + noise`` is linear (:mod:`relloc.models.measurement`);
  the noise covariances ``Q`` and ``R_pmo`` are evaluated at the estimate, as the PLKF does;
- the cooperative EIF and EKF of :class:`~relloc.estimators.cooperative.CooperativeEstimator`
  with only absolute pose fixes of still unicycles (``f`` the identity, ``H = I`` on the fixed
  robot's block);
- the one Joseph-form update itself (:func:`relloc.core.kalman.kalman_update`) and its χ²-gated
  form (:func:`relloc.core.kalman.gated_update`: the update inside the gate, the prior outside).

No linear special case exists for: the TEKF (``h(x) = (r, θ, α)`` is nonlinear in the state);
the bias-compensated PLKF (its correction ``b̂`` is a nonlinear function of the estimate); a
yaw bank (a Gaussian mixture whose weights depend on the likelihoods); the Gaussian-sum
estimator of seed 002 (bearings are nonlinear and the correspondence is unknown, so it is a
mixture); the switching EKF of seed 003 (the UWB range ``d = ‖r‖`` and the camera bearing are
nonlinear in ``r``, and Eq. 3 is nonlinear in the headings); the cooperative filter with
detections (range and bearing between robots are nonlinear in both poses) or moving robots (the
unicycle step is nonlinear in the heading).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping
from functools import cache, partial
from typing import Any

import numpy as np
import pytest
from numpy.typing import NDArray

from relloc.core.angles import wrap_angle
from relloc.core.checks import MAX_TIME_STEP_S
from relloc.core.contract import Estimator, HeldOdometry
from relloc.core.estimates import Estimates
from relloc.core.events import TIME_TOL
from relloc.core.gaussian import Gaussian
from relloc.core.kalman import chi2_threshold, gated_update, kalman_update
from relloc.core.recording import (
    CLUTTER,
    KINDS,
    ORIGIN_UNKNOWN,
    GroundTruth,
    Measurements,
    Odometry,
    Recording,
    kind_code,
    measurement_rows,
    relative_pose,
)
from relloc.errors import DataError
from relloc.estimators.cooperative import (
    CooperativeEstimator,
    CooperativeSettings,
    OdometryModel,
    SensorModel,
)
from relloc.estimators.initialisation import InitPolicy
from relloc.estimators.relative_batch import RelativeFilterBatch, TrackSpec
from relloc.estimators.track_manager import TrackManagerSettings, managers_for
from relloc.estimators.yaw_bank import YawBankSettings
from relloc.experiments.desilva2015 import filter_settings
from relloc.experiments.guler2023 import FilterFactory, build_cases, simulate_case
from relloc.fusion.gaussian_sum_estimator import scan_times, team
from relloc.models.measurement import (
    RangeBearingNoise,
    pseudo_linear_covariance,
    pseudo_linear_matrix,
    pseudo_linear_measurement,
)
from relloc.models.motion import VelocityNoise, process_noise, relative_jacobians, relative_step
from relloc.models.unicycle import unicycle_jacobians, unicycle_step
from relloc.models.uwb_noise import TIERS_ROUNDED
from relloc.pipeline.evaluation import accuracy_and_consistency, evaluate
from relloc.pipeline.frames import frame
from relloc.pipeline.replay import replay
from relloc.sim import cooperative, multihypothesis
from relloc.sim.airground import robot_names
from relloc.sim.scenario import default_scenario
from relloc.sim.sensors import range_azimuth_elevation
from relloc.sim.simulate import simulate

Array = NDArray[np.float64]
RecordTimes = Array | Mapping[str, Array] | None


@dataclasses.dataclass(frozen=True)
class Case:
    """One estimator on one recording.

    ``build(recording)`` makes fresh estimators for a recording; ``kinds`` are the measurement
    kinds they model; ``dofs`` the NIS degrees of freedom their updates may have (empty: the
    estimator reports no updates); ``record_times(recording)`` the record times for
    :func:`replay` (``None``: its default grid).
    """

    recording: Recording
    build: Callable[[Recording], list[Estimator]]
    kinds: tuple[str, ...]
    dofs: frozenset[int]
    record_times: Callable[[Recording], RecordTimes] = lambda rec: None

    def replay(self, recording: Recording | None = None) -> Estimates:
        rec = self.recording if recording is None else recording
        return replay(rec, self.build(rec), record_times=self.record_times(rec))


# ---------------------------------------------------------------------------------- the cases
def _track_manager_case(filter_name: str, *, yaw_bank: bool, init: str = "measurement") -> Case:
    """Seed 000: one manager per observing robot on the first 3 s of the default scenario."""
    rec = simulate(
        dataclasses.replace(default_scenario(), duration_s=3.0), np.random.default_rng(0)
    )
    settings = TrackManagerSettings(
        filter=filter_name,
        yaw_bank=YawBankSettings() if yaw_bank else None,
        init=InitPolicy(name=init),
    )
    return Case(
        recording=rec,
        build=lambda r: list(managers_for(r, settings)),
        kinds=("range_bearing_elevation",),
        dofs=frozenset({KINDS["range_bearing_elevation"].dim}),
    )


def _relative_batch_case() -> Case:
    """Seed 000's batched filters: the observer of the default scenario runs, per teammate, a
    PLKF, a TEKF, a BC-PLKF and a PLKF yaw bank from the true relative pose at the first event
    (plus a 0.5 m, 0.3 rad offset) with a broad prior, over the first 3 s."""
    rec = simulate(
        dataclasses.replace(default_scenario(), duration_s=3.0), np.random.default_rng(0)
    )
    assert rec.truth is not None
    t0 = float(rec.measurements.t.min())
    poses = [g.at(t0).reshape(-1) for g in rec.truth]
    prior_cov = np.diag([1.0, 1.0, 0.25, 0.5])
    offset = np.array([0.5, -0.5, 0.0, 0.3])
    specs = [
        TrackSpec(
            label=f"{kind}{'-bank' if bank else ''}",
            subject=subject,
            kind=kind,  # type: ignore[arg-type]
            prior_mean=relative_pose(poses[0], poses[j]).reshape(4) + offset,
            prior_cov=prior_cov,
            bank=bank,
        )
        for j, subject in enumerate(rec.robots)
        if j > 0
        for kind, bank in (("plkf", False), ("tekf", False), ("bcplkf", False), ("plkf", True))
    ]

    def build(r: Recording) -> list[Estimator]:
        sigma = [od.sigma for od in r.odometry]
        return [
            RelativeFilterBatch(specs, owner=r.robots[0], robots=r.robots, odometry_sigma=sigma)
        ]

    return Case(
        recording=rec,
        build=build,
        kinds=("range_bearing_elevation",),
        dofs=frozenset({KINDS["range_bearing_elevation"].dim}),
    )


def _gaussian_sum_case(*, sharing: bool) -> Case:
    """Seed 002: the two leaders' Gaussian-sum estimators on 3 s of the paper's scenario."""
    scenario = multihypothesis.DeSilvaScenario(duration=3.0)
    settings = filter_settings(scenario)
    rec = multihypothesis.simulate(scenario, np.random.default_rng(1))
    sensing = (0, 1)
    return Case(
        recording=rec,
        build=lambda r: list(team(r.robots, sensing, settings, sharing=sharing)),
        kinds=("height", "range", "bearing_elevation"),
        dofs=frozenset(),
        record_times=lambda r: scan_times(r.measurements, r.robots, sensing, settings),
    )


def _switching_ekf_case(name: str) -> Case:
    """Seed 003: the recording of a 3 s closed-loop run, replayed through fresh followers'
    filters started from the run's priors."""
    case = build_cases(TIERS_ROUNDED)[name].with_scenario(duration=3.0)
    run, _ = simulate_case(case, np.random.default_rng(7))
    assert run.recording.robots == robot_names(case.scenario)
    factory = FilterFactory(case)
    record_t = run.estimates.beliefs[0].t

    def build(rec: Recording) -> list[Estimator]:
        return [factory(rec.robots, owner, prior) for owner, prior in run.priors.items()]

    return Case(
        recording=run.recording,
        build=build,
        kinds=("range", "pair_sighting"),
        dofs=frozenset({1, 2, 3}),  # BLOCK_DIMS of relloc.estimators.switching_ekf
        record_times=lambda rec: record_t,
    )


def _cooperative_case(kind: str, *, use_range: bool) -> Case:
    """Seed 001: the team's joint filter on 6 s of the paper's scenario — bearings (and ranges)
    of robots and of the anchor landmarks, and one robot's GPS-like pose fixes."""
    scenario = cooperative.sharma2013_scenario(
        duration=6.0, gps_robots=(0,), sigma_range=1.0 if use_range else None
    )
    sim = cooperative.simulate(scenario, np.random.default_rng(3))
    settings = CooperativeSettings(
        odometry=OdometryModel.from_discrete(scenario.sigma_v, scenario.sigma_w, scenario.dt),
        sensor=SensorModel(sigma_bearing=scenario.sigma_bearing, sigma_range0=1.0),
        anchors=(0, 1),
        use_range=use_range,
        use_fixes=True,
        filter=kind,  # type: ignore[arg-type]
    )
    return Case(
        recording=sim.recording,
        build=lambda r: [CooperativeEstimator(r.robots, sim.prior, settings, r.landmarks)],
        kinds=("range_bearing", "bearing", "pose"),
        # one NIS per detection (bearing, or range and bearing) and per x-y-ψ fix
        dofs=frozenset({2, 3} if use_range else {1, 3}),
    )


def _range_only_recording() -> Recording:
    """Three unicycles for 3 s (odometry at 20 Hz, σ 1 cm/s) with UWB ranges (σ 5 cm) at 10 Hz
    between every pair."""
    from relloc.core.recording import GroundTruth, Measurements, Odometry, measurement_rows

    rng = np.random.default_rng(5)
    t = np.arange(0.0, 3.0, 0.05)
    starts = np.array([[0.0, 0.0, 0.0], [3.0, 1.0, 2.0], [1.0, 4.0, -1.0]])
    u = np.array([[0.3, 0.2], [0.2, -0.1], [0.0, 0.0]])
    truth, odometry = [], []
    for k in range(3):
        yaw = starts[k, 2] + u[k, 1] * t
        # chord of the arc driven so far: v t sin(ωt/2)/(ωt/2), along the mean heading
        arc = u[k, 0] * t * np.sinc(u[k, 1] * t / (2 * np.pi))
        mid = starts[k, 2] + 0.5 * u[k, 1] * t
        xy = starts[k, :2] + np.column_stack([arc * np.cos(mid), arc * np.sin(mid)])
        truth.append(GroundTruth(t=t, pose=np.column_stack([xy, np.zeros(t.size), yaw])))
        vel = np.tile([u[k, 0], 0.0, 0.0, u[k, 1]], (t.size, 1))
        odometry.append(Odometry(t=t, velocity=vel, sigma=(0.01, 0.0, 0.0, 0.01)))
    tr = t[::2] + 0.01
    parts = []
    for i, j in ((0, 1), (0, 2), (1, 2)):
        d = np.linalg.norm(truth[i].at(tr)[:, :3] - truth[j].at(tr)[:, :3], axis=1)
        value = d + rng.normal(0.0, 0.05, d.size)
        parts.append(
            measurement_rows("range", t=tr, observer=i, target=j, value=value, sigma=[0.05])
        )
    return Recording(
        robots=("a", "b", "c"),
        platforms=("ground",) * 3,
        odometry=tuple(odometry),
        measurements=Measurements.concatenate(parts),
        truth=tuple(truth),
    )


def _range_only_case(name: str) -> Case:
    """UWB ranges only: the relative pair bank (range + both odometries), the constant-velocity
    team filter (robot c an anchor) and the odometry-alone pair baseline."""
    from relloc.estimators.uwb_range import (
        RangePairBank,
        RangePairSettings,
        RangeTeamFilter,
        RangeTeamSettings,
        RelativeDeadReckoning,
    )
    from relloc.models.motion import VelocityNoise

    rec = _range_only_recording()
    noise = VelocityNoise(observer=(0.01, 0.0, 0.0, 0.01), observed=(0.01, 0.0, 0.0, 0.01))
    truth0 = np.array([g.at(0.0)[0, :2] for g in rec.require_truth("case")])

    def build(r: Recording) -> list[Estimator]:
        if name == "pair":
            return [RangePairBank(0, 1, r.robots, noise, RangePairSettings(sigma_range=0.05))]
        if name == "team":
            start = truth0 + np.array([[0.3, -0.2], [-0.2, 0.3], [0.0, 0.0]])
            return [RangeTeamFilter(r.robots, start, RangeTeamSettings(), anchors=(2,))]
        start = (0.0, r.relative_truth(0, 1, 0.0)[0], np.eye(4) * 1e-4)
        return [RelativeDeadReckoning(0, 1, r.robots, noise, start)]

    return Case(
        recording=rec,
        build=build,
        kinds=("range",),
        dofs=frozenset() if name == "odometry_alone" else frozenset({1}),
    )


CASES: dict[str, Callable[[], Case]] = {
    **{
        f"track_manager-{f}{'-yaw_bank' if bank else ''}": partial(
            _track_manager_case, f, yaw_bank=bank
        )
        for f in ("plkf", "tekf", "bcplkf")
        for bank in (False, True)
    },
    "track_manager-plkf-known_init": lambda: _track_manager_case(
        "plkf", yaw_bank=False, init="known"
    ),
    "relative_batch-four_kinds": _relative_batch_case,
    "gaussian_sum-sharing": lambda: _gaussian_sum_case(sharing=True),
    "gaussian_sum-alone": lambda: _gaussian_sum_case(sharing=False),
    "switching_ekf-one_drone": lambda: _switching_ekf_case("one_drone"),
    "switching_ekf-two_drones": lambda: _switching_ekf_case("two_drones"),
    "cooperative-eif-bearings": lambda: _cooperative_case("eif", use_range=False),
    "cooperative-ekf-range_bearing": lambda: _cooperative_case("ekf", use_range=True),
    **{f"uwb_range-{n}": partial(_range_only_case, n) for n in ("pair", "team", "odometry_alone")},
}


@cache
def _case(name: str) -> Case:
    return CASES[name]()


@cache
def _estimates(name: str) -> Estimates:
    return _case(name).replay()


NAMES = sorted(CASES)


# ---------------------------------------------------------------------------------- helpers
def assert_same_estimates(a: Estimates, b: Estimates) -> None:
    """Every array, event and count of ``a`` and ``b`` identical (NaN equal to NaN)."""
    assert a.estimator == b.estimator
    assert [s.key for s in a.beliefs] == [s.key for s in b.beliefs]
    for x, y in zip(a.beliefs, b.beliefs, strict=True):
        assert x.frame == y.frame
        for field in ("t", "mean", "cov", "age"):
            np.testing.assert_array_equal(getattr(x, field), getattr(y, field), err_msg=x.label)
        assert sorted(x.info) == sorted(y.info)
        for k in x.info:
            np.testing.assert_array_equal(x.info[k], y.info[k], err_msg=f"{x.label} {k}")
    assert [u.key for u in a.updates] == [u.key for u in b.updates]
    for u, v in zip(a.updates, b.updates, strict=True):
        for field in ("t", "age", "nis", "dof", "cond_r", "cond_s"):
            np.testing.assert_array_equal(getattr(u, field), getattr(v, field), err_msg=u.label)
    assert a.events == b.events
    assert dict(a.counts) == dict(b.counts)


def scrambled_origin(rec: Recording, rng: np.random.Generator) -> Recording:
    """``rec`` with every reading's ``origin`` replaced by a random robot, clutter or unknown."""
    m = rec.measurements
    origin = rng.integers(ORIGIN_UNKNOWN, rec.n_robots, size=m.size).astype(np.int64)
    assert m.origin is not None and np.any(origin != m.origin)
    assert {CLUTTER, ORIGIN_UNKNOWN} <= set(origin.tolist())
    return dataclasses.replace(rec, measurements=dataclasses.replace(m, origin=origin))


# ---------------------------------------------------------------------------------- the contract
@pytest.mark.parametrize("name", NAMES)
def test_every_estimator_implements_the_contract(name: str) -> None:
    case = _case(name)
    estimators = case.build(case.recording)
    assert estimators
    for est in estimators:
        assert isinstance(est, Estimator), type(est).__name__
        assert isinstance(est.name, str) and est.name
        assert est.owner == "team" or est.owner in case.recording.robots


@pytest.mark.parametrize("name", NAMES)
def test_beliefs_have_the_frame_dimension_finite_means_and_psd_covariances(name: str) -> None:
    rec, estimates = _case(name).recording, _estimates(name)
    assert estimates.beliefs and sum(s.t.size for s in estimates.beliefs) > 0
    for s in estimates.beliefs:
        d = frame(s.frame).dim
        assert s.owner == "team" or s.owner in rec.robots
        assert s.subject in rec.robots
        assert s.mean.shape == (s.t.size, d), s.label
        assert s.cov.shape == (s.t.size, d, d), s.label
        assert s.age.shape == s.t.shape and np.all(np.isfinite(s.age)) and np.all(s.age >= 0)
        assert np.all(np.isfinite(s.t)) and np.all(np.diff(s.t) > 0), s.label
        assert np.all(np.isfinite(s.mean)), s.label
        assert np.all(np.isfinite(s.cov)), s.label
        scale = np.maximum(1.0, np.abs(s.cov).max(axis=(1, 2)))
        asym = np.abs(s.cov - np.swapaxes(s.cov, 1, 2)).max(axis=(1, 2))
        assert np.all(asym <= 1e-12 * scale), f"{s.label}: asymmetry {asym.max()}"
        eig_min = np.linalg.eigvalsh(0.5 * (s.cov + np.swapaxes(s.cov, 1, 2)))[:, 0]
        assert np.all(eig_min >= -1e-9 * scale), f"{s.label}: λmin {eig_min.min()}"
        for k, v in s.info.items():
            assert np.asarray(v).shape == s.t.shape, f"{s.label} info {k}"


@pytest.mark.parametrize("name", NAMES)
def test_update_records_have_valid_nis_of_the_modelled_kinds(name: str) -> None:
    case, estimates = _case(name), _estimates(name)
    m = case.recording.measurements
    assert np.any(np.isin(m.kind, [kind_code(k) for k in case.kinds])), "no modelled rows"
    n_updates = sum(u.t.size for u in estimates.updates)
    if not case.dofs:
        assert n_updates == 0
        return
    assert n_updates > 0
    stamps = np.unique(m.of_kind(*case.kinds).t)
    for u in estimates.updates:
        assert u.subject in case.recording.robots
        assert np.all(np.isfinite(u.nis)) and np.all(u.nis >= 0.0), u.label
        assert np.all(u.dof >= 1), u.label
        assert set(u.dof.tolist()) <= case.dofs, f"{u.label}: dof {set(u.dof.tolist())}"
        assert np.all(np.isfinite(u.age)) and np.all(u.age >= 0.0), u.label
        for cond in (u.cond_r, u.cond_s):  # log10(λmax/λmin), NaN where not computed
            assert not np.any(cond < 0.0), u.label
        # every update is at the stamp of a reading of a modelled kind
        at = np.clip(np.searchsorted(stamps, u.t), 1, stamps.size - 1)
        gap = np.minimum(np.abs(stamps[at] - u.t), np.abs(stamps[at - 1] - u.t))
        assert np.all(gap <= TIME_TOL) if stamps.size > 1 else np.all(u.t == stamps[0])


@pytest.mark.parametrize("name", NAMES)
def test_replay_is_deterministic(name: str) -> None:
    assert_same_estimates(_case(name).replay(), _estimates(name))


@pytest.mark.parametrize("name", NAMES)
def test_estimators_never_read_the_origin_of_a_reading(name: str) -> None:
    case = _case(name)
    scrambled = scrambled_origin(case.recording, np.random.default_rng(11))
    assert_same_estimates(case.replay(scrambled), _estimates(name))


@pytest.mark.parametrize("name", NAMES)
def test_evaluation_runs_on_the_estimates(name: str) -> None:
    rec, estimates = _case(name).recording, _estimates(name)
    evals = evaluate(estimates, rec)
    assert [e.label for e in evals] == list(estimates.labels)
    for e, s in zip(evals, estimates.beliefs, strict=True):
        assert e.error.shape == s.mean.shape and np.all(np.isfinite(e.error)), e.label
        assert np.all(np.isfinite(e.nees)) and np.all(e.nees >= 0.0), e.label
        np.testing.assert_array_equal(e.nis, estimates.updates_of(*s.key).nis)
    for f in {e.frame for e in evals}:
        summary = accuracy_and_consistency([e for e in evals if e.frame == f], settle_s=0.0)
        assert summary["samples"] > 0
        assert np.isfinite(summary["position_rmse_m"]) and np.isfinite(summary["anees"])


@pytest.mark.parametrize("name", NAMES)
def test_an_estimator_advanced_back_in_time_or_to_nan_is_a_data_error(name: str) -> None:
    """One rule (:func:`relloc.core.events.elapsed`): some estimators refused a step back as a
    ConfigError, the UWB range filters and the Gaussian-sum estimator not at all (they set their
    clock back, or predicted with a negative step), and a NaN time slipped through some. A step
    beyond ``MAX_TIME_STEP_S`` was accepted by all but one, which raised a raw OverflowError;
    the others' beliefs overflowed silently at 1e150 s."""
    case = _case(name)
    still = HeldOdometry.still(case.recording.n_robots)
    t0 = case.recording.span[0]
    for est in case.build(case.recording):
        est.advance(t0, still)
        est.advance(t0 + 1.0, still)
        with pytest.raises(DataError, match=r": time went back from .* to "):
            est.advance(t0 + 0.5, still)
    for est in case.build(case.recording):
        with pytest.raises(DataError, match=r": time nan is not a finite number"):
            est.advance(float("nan"), still)
    for est in case.build(case.recording):
        est.advance(t0, still)
        est.advance(t0 + MAX_TIME_STEP_S, still)  # the longest step is taken
        with pytest.raises(DataError, match=r": time jumped 1e\+150 s from "):
            est.advance(t0 + MAX_TIME_STEP_S + 1e150, still)


# ---------------------------------------------------------------------------------- linear cases
def textbook_predict(x: Array, P: Array, F: Array, Q: Array) -> tuple[Array, Array]:
    """``x⁻ = F x``, ``P⁻ = F P Fᵀ + Q``."""
    return F @ x, F @ P @ F.T + Q


def textbook_update(
    x: Array, P: Array, nu: Array, H: Array, R: Array
) -> tuple[Array, Array, Array, float]:
    """``S = H P Hᵀ + R``, ``K = P Hᵀ S⁻¹``, ``x⁺ = x + K ν``,
    ``P⁺ = (I − K H) P (I − K H)ᵀ + K R Kᵀ``; also returns ``S`` and the NIS ``νᵀ S⁻¹ ν``."""
    S = H @ P @ H.T + R
    K = P @ H.T @ np.linalg.inv(S)
    A = np.eye(P.shape[0]) - K @ H
    return x + K @ nu, A @ P @ A.T + K @ R @ K.T, S, float(nu @ np.linalg.solve(S, nu))


def _still_team(rng: np.random.Generator) -> tuple[Recording, RangeBearingNoise]:
    """An observer and two observed robots standing still for 3 s: zero odometry at 20 Hz
    (with stated noise), noisy range/azimuth/elevation readings of both at 10 Hz."""
    dt, duration = 0.05, 3.0
    t: Array = np.linspace(0.0, duration, round(duration / dt) + 1)
    poses = np.array([[1.0, 2.0, 0.0, 0.4], [4.0, 3.5, 1.5, -1.0], [-1.5, 5.0, -0.2, 2.5]])
    sigma_u = np.array([0.05, 0.04, 0.02, 0.03])
    noise = RangeBearingNoise(sigma_r=0.05, sigma_azimuth=0.02, sigma_elevation=0.03)
    sensor_sigma = np.sqrt(noise.variances)
    tm = t[2::2]
    rows = []
    for j in (1, 2):
        rel = np.tile(relative_pose(poses[0], poses[j]), (tm.size, 1))
        z = range_azimuth_elevation(rel[:, :3]) + sensor_sigma * rng.standard_normal((tm.size, 3))
        rows.append(
            measurement_rows(
                "range_bearing_elevation", t=tm, observer=0, target=j, value=z, sigma=sensor_sigma
            )
        )
    rec = Recording(
        robots=("observer", "a", "b"),
        platforms=("ground", "aerial", "ground"),
        truth=tuple(GroundTruth(t=t, pose=np.tile(p, (t.size, 1))) for p in poses),
        odometry=tuple(
            Odometry(t=t[:-1], velocity=np.zeros((t.size - 1, 4)), sigma=sigma_u) for _ in poses
        ),
        measurements=Measurements.concatenate(rows),
    )
    return rec, noise


Beliefs = dict[float, tuple[Array, Array]]


def plain_still_plkf(
    rec: Recording,
    j: int,
    noise: RangeBearingNoise,
    covariance: str,
    prior: tuple[float, Array, Array],
) -> tuple[Beliefs, list[float]]:
    """Robot 0's PLKF of robot ``j`` of a still team (:func:`_still_team`) as a textbook
    Kalman filter from ``prior = (t, x, P)``, stepping through the replay's event times: the
    belief after each event (keyed by the time rounded to µs) and the NIS of each update."""
    zero = np.zeros(4)
    m = rec.measurements
    motion = VelocityNoise(
        observer=tuple(rec.odometry[0].sigma),  # type: ignore[arg-type]
        observed=tuple(rec.odometry[j].sigma),  # type: ignore[arg-type]
    )
    rows = np.flatnonzero(m.target == j)
    t_prev, x, P = prior
    beliefs: Beliefs = {}
    nis: list[float] = []
    events = np.unique(np.concatenate([rec.odometry[0].t, m.t, [rec.span[1]]]))
    for t in events[events >= t_prev - TIME_TOL]:
        step = float(t) - t_prev
        if step > 0:
            F, G = relative_jacobians(x, zero, zero, step)
            np.testing.assert_array_equal(F, np.eye(4))  # still robots: f is the identity
            np.testing.assert_allclose(relative_step(x, zero, zero, step), x, atol=1e-15)
            x, P = textbook_predict(x, P, F, process_noise(G, motion))
        t_prev = float(t)
        for q in rows[np.abs(m.t[rows] - t) <= TIME_TOL]:
            z = m.value[q]
            H = pseudo_linear_matrix(z)
            R = pseudo_linear_covariance(x, z, noise, covariance)  # type: ignore[arg-type]
            nu = pseudo_linear_measurement(z) - H @ x
            x, P, _, e = textbook_update(x, P, nu, H, R)
            nis.append(e)
        beliefs[round(float(t), 6)] = (x, P)
    return beliefs, nis


def assert_plain_kalman(
    estimates: Estimates, key: tuple[str, str, str], reference: tuple[Beliefs, list[float]]
) -> None:
    """The series ``key`` of ``estimates`` and its NIS equal the reference to 1e-9."""
    beliefs, nis = reference
    series = estimates.series(*key)
    assert series.t.size >= 29
    for k, t in enumerate(series.t):
        x_ref, P_ref = beliefs[round(float(t), 6)]
        np.testing.assert_allclose(series.mean[k], x_ref, rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(series.cov[k], P_ref, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(estimates.updates_of(*key).nis, nis, rtol=1e-9, atol=1e-12)
    # the estimate moved away from its start: the comparison is not of two constants
    assert np.linalg.norm(series.mean[-1, :3] - series.mean[0, :3]) > 1e-3


@pytest.mark.parametrize("covariance", ["simplified", "full"])
def test_track_manager_plkf_of_still_robots_is_a_plain_kalman_filter(covariance: str) -> None:
    rec, noise = _still_team(np.random.default_rng(5))
    init = InitPolicy(name="known", sigma_known_position=0.5, sigma_known_yaw=0.3)
    settings = TrackManagerSettings(
        filter="plkf",
        init=init,
        pseudo_linear_covariance=covariance,  # type: ignore[arg-type]
    )
    estimates = replay(rec, managers_for(rec, settings))
    m = rec.measurements
    for j, subject in ((1, "a"), (2, "b")):
        # the track starts at its first reading from the true relative pose (no random draw)
        t0 = float(m.t[np.flatnonzero(m.target == j)[0]])
        prior = (t0, rec.relative_truth(0, j, t0)[0], np.diag([0.5**2] * 3 + [0.3**2]))
        reference = plain_still_plkf(rec, j, noise, covariance, prior)
        assert_plain_kalman(estimates, ("observer", subject, ""), reference)


def _still_planar_team(rng: np.random.Generator) -> Recording:
    """Three unicycles standing still for 3 s: zero odometry at 10 Hz; GPS-like pose fixes of
    robots 0 and 2 at 2 Hz (robot 1 has none: it is only predicted)."""
    dt, duration = 0.1, 3.0
    t: Array = np.linspace(0.0, duration, round(duration / dt) + 1)
    poses = np.array([[1.0, 2.0, 0.0, 0.4], [4.0, -3.5, 0.0, -1.0], [-1.5, 5.0, 0.0, 2.5]])
    sigma_fix = np.array([0.3, 0.2, 0.05])
    tf = t[5::5]
    rows = [
        measurement_rows(
            "pose",
            t=tf,
            observer=i,
            value=poses[i, [0, 1, 3]] + sigma_fix * rng.standard_normal((tf.size, 3)),
            sigma=sigma_fix,
        )
        for i in (0, 2)
    ]
    sigma_u = np.array([0.1, 0.0, 0.0, 0.05])
    return Recording(
        robots=("0", "1", "2"),
        platforms=("ground",) * 3,
        truth=tuple(GroundTruth(t=t, pose=np.tile(p, (t.size, 1))) for p in poses),
        odometry=tuple(
            Odometry(t=t[:-1], velocity=np.zeros((t.size - 1, 4)), sigma=sigma_u) for _ in poses
        ),
        measurements=Measurements.concatenate(rows),
    )


@pytest.mark.parametrize("kind", ["eif", "ekf"])
def test_cooperative_filter_with_pose_fixes_of_still_robots_is_a_plain_kalman_filter(
    kind: str,
) -> None:
    """Still unicycles: ``f`` is the identity and ``Q_i = G diag(q_v, q_ω)/Δt Gᵀ``
    (:mod:`relloc.models.unicycle`, the odometry model of the cooperative estimator); a pose fix
    of robot ``i`` is ``z = x_i + noise`` (``H`` selects robot ``i``'s block), all fixes of an
    epoch in one update, the NIS of each fix at the epoch's prior."""
    rec = _still_planar_team(np.random.default_rng(8))
    odometry = OdometryModel(q_v0=0.04, q_w0=0.01)
    settings = CooperativeSettings(
        odometry=odometry,
        sensor=SensorModel(sigma_bearing=0.05),
        use_fixes=True,
        p_gate=None,
        filter=kind,  # type: ignore[arg-type]
    )
    n = rec.n_robots
    assert rec.truth is not None
    truth = np.stack([g.pose[0, [0, 1, 3]] for g in rec.truth])
    x = (truth + np.array([0.5, -0.4, 0.2])).reshape(-1)
    P = np.diag(np.tile([0.6**2, 0.5**2, 0.3**2], n))
    estimates = replay(rec, [CooperativeEstimator(rec.robots, Gaussian(mean=x, cov=P), settings)])
    m = rec.measurements
    zero = np.zeros(2)
    q_u = np.diag([odometry.q_v0, odometry.q_w0])
    beliefs: Beliefs = {}
    nis: dict[str, list[float]] = {r: [] for r in rec.robots}
    events = np.unique(np.concatenate([rec.odometry[0].t, m.t, [rec.span[1]]]))
    t_prev = float(events[0])
    for t in events:
        step = float(t) - t_prev
        if step > 0:
            F, Q = np.zeros((3 * n, 3 * n)), np.zeros((3 * n, 3 * n))
            for i in range(n):
                b = slice(3 * i, 3 * i + 3)
                np.testing.assert_allclose(unicycle_step(x[b], zero, step), x[b], atol=1e-15)
                F[b, b], G = unicycle_jacobians(x[b], zero, step)
                Q[b, b] = G @ (q_u / step) @ G.T
            np.testing.assert_array_equal(F, np.eye(3 * n))  # still robots: f is the identity
            x, P = textbook_predict(x, P, F, Q)
        t_prev = float(t)
        fixes = np.flatnonzero(np.abs(m.t - t) <= TIME_TOL)
        if fixes.size:
            H = np.zeros((3 * fixes.size, 3 * n))
            for k, q in enumerate(fixes):
                i = int(m.observer[q])
                H[3 * k : 3 * k + 3, 3 * i : 3 * i + 3] = np.eye(3)
            nu = m.value[fixes].reshape(-1) - H @ x
            nu[2::3] = wrap_angle(nu[2::3])
            R = np.diag(np.square(m.sigma[fixes]).reshape(-1))
            for k, q in enumerate(fixes):
                g = slice(3 * k, 3 * k + 3)
                S = H[g] @ P @ H[g].T + R[g, g]
                nis[rec.robots[int(m.observer[q])]].append(float(nu[g] @ np.linalg.solve(S, nu[g])))
            x, P, _, _ = textbook_update(x, P, nu, H, R)
        beliefs[round(float(t), 6)] = (x, P)
    for i, robot in enumerate(rec.robots):
        series = estimates.series("team", robot)
        b = slice(3 * i, 3 * i + 3)
        assert series.t.size == 31
        for k, t in enumerate(series.t):
            x_ref, P_ref = beliefs[round(float(t), 6)]
            np.testing.assert_allclose(series.mean[k], x_ref[b], rtol=1e-9, atol=1e-12)
            np.testing.assert_allclose(series.cov[k], P_ref[b, b], rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(
            estimates.updates_of("team", robot).nis, nis[robot], rtol=1e-9, atol=1e-12
        )
    assert not nis["1"] and nis["0"] and nis["2"]


def _random_problem(rng: np.random.Generator, n: int, m: int, batch: tuple[int, ...]) -> Any:
    """A random PSD ``P (…, n, n)``, ``H (…, m, n)``, PD ``R (…, m, m)``, ``ν (…, m)``, ``x``."""
    A = rng.standard_normal((*batch, n, n))
    B = rng.standard_normal((*batch, m, m))
    P = A @ np.swapaxes(A, -1, -2)
    R = B @ np.swapaxes(B, -1, -2) + 0.1 * np.eye(m)
    return (
        rng.standard_normal((*batch, n)),
        P,
        rng.standard_normal((*batch, m)),
        rng.standard_normal((*batch, m, n)),
        R,
    )


@pytest.mark.parametrize("m", [1, 2, 3, 4])
def test_the_core_kalman_update_is_the_textbook_update(m: int) -> None:
    rng = np.random.default_rng(100 + m)
    x, P, nu, H, R = _random_problem(rng, 4, m, (6,))
    mean, cov, inn = kalman_update(x, P, nu, H, R)
    decisions: set[bool] = set()
    for k in range(6):
        x_ref, P_ref, S_ref, nis_ref = textbook_update(x[k], P[k], nu[k], H[k], R[k])
        np.testing.assert_allclose(mean[k], x_ref, rtol=1e-10, atol=1e-12)
        np.testing.assert_allclose(cov[k], P_ref, rtol=1e-10, atol=1e-10)
        np.testing.assert_allclose(inn.cov[k], S_ref, rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(np.asarray(inn.nis)[k], nis_ref, rtol=1e-10)
        # the gated update: the textbook update inside the gate, the prior outside it (a
        # residual 100 times larger is far outside)
        for scale in (1.0, 100.0):
            r = scale * nu[k]
            r_mean, r_cov, _, r_nis = textbook_update(x[k], P[k], r, H[k], R[k])
            g_mean, g_cov, g_inn, accepted = gated_update(x[k], P[k], r, H[k], R[k], 0.99)
            assert accepted == (r_nis <= chi2_threshold(m, 0.99))
            decisions.add(accepted)
            np.testing.assert_allclose(g_inn.nis, r_nis, rtol=1e-10)
            np.testing.assert_allclose(g_mean, r_mean if accepted else x[k], rtol=1e-10, atol=1e-9)
            np.testing.assert_allclose(g_cov, r_cov if accepted else P[k], rtol=1e-10, atol=1e-10)
        o_mean, o_cov, _, always = gated_update(x[k], P[k], nu[k], H[k], R[k], None)
        assert always
        np.testing.assert_allclose(o_mean, x_ref, rtol=1e-10, atol=1e-12)
        np.testing.assert_allclose(o_cov, P_ref, rtol=1e-10, atol=1e-10)
    assert decisions == {True, False}
