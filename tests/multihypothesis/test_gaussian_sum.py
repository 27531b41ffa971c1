"""Gaussian-sum fusers: EKF equivalence, gating, formation, sharing, seeded short team runs."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from gaussian_sum_samples import NOISE, gs_settings

from relloc.core.angles import wrap_angle
from relloc.errors import ConfigError, DataError
from relloc.estimators.gaussian_sum import (
    GaussianSumFuser,
    Tracks,
    predict_fusers,
)
from relloc.estimators.relative import predict_arrays
from relloc.experiments.desilva2015 import (
    DURATION_S,
    FINAL_WINDOW_S,
    KIDNAP,
    RunConfig,
    _task,
    filter_settings,
)
from relloc.fusion.messages import EquivalentMeasurement
from relloc.fusion.pose_beliefs import invert_beliefs
from relloc.pipeline.montecarlo import spawn_seeds
from relloc.sim.multihypothesis import DeSilvaScenario


def _one_track(mean: np.ndarray, cov: np.ndarray, depth: int) -> Tracks:
    return Tracks(
        groups=np.zeros(1, dtype=np.int64),
        means=mean[None].copy(),
        covs=cov[None].copy(),
        prior_means=mean[None].copy(),
        prior_covs=cov[None].copy(),
        weights=np.ones(1),
        history=np.zeros((1, depth + 1), dtype=np.int64),
        assoc=np.full(1, -1, dtype=np.int64),
    )


def _ekf_update(x, P, z, h, H, R, wrap=()):  # type: ignore[no-untyped-def]
    """Textbook EKF update (independent of relloc's implementation)."""
    nu = z - h
    for i in wrap:
        nu[i] = wrap_angle(nu[i])
    S = H @ P @ H.T + R
    K = P @ H.T @ np.linalg.inv(S)
    I_KH = np.eye(4) - K @ H
    return x + K @ nu, I_KH @ P @ I_KH.T + K @ R @ K.T


def test_single_component_without_clutter_equals_the_ekf() -> None:
    st = gs_settings(prune_weight=0.5, merge_threshold=0.0)
    fus = GaussianSumFuser(0, [1], st)
    x0 = np.array([3.0, 1.0, 0.5, 0.3])
    P0 = np.diag([0.05, 0.05, 0.02, 0.1])
    fus.tracks = _one_track(x0, P0, st.nscan_depth)
    u_self, u_mate = np.array([0.3, 0.0, 0.0, 0.1]), np.array([0.2, 0.1, 0.0, -0.2])
    fus.predict(u_self, u_mate[None], 0.1)
    x, P = predict_arrays(x0, P0, u_self, u_mate, 0.1, NOISE)
    np.testing.assert_allclose(fus.tracks.means[0], x)
    true = np.array([3.05, 1.1, 0.52, 0.3])
    h_meas, r_meas = true[2] + 0.004, np.linalg.norm(true[:3]) - 0.01
    az = np.arctan2(true[1], true[0]) + 0.02
    el = np.arctan2(true[2], np.hypot(true[0], true[1])) - 0.01
    fus.direct_scan([h_meas], [r_meas], np.array([[az, el]]))
    # reference: sequential EKF on h, r, (α, β)
    x, P = _ekf_update(
        x, P, np.array([h_meas]), x[2:3], np.array([[0, 0, 1.0, 0]]), np.array([[0.01**2]])
    )
    r = np.linalg.norm(x[:3])
    x, P = _ekf_update(
        x,
        P,
        np.array([r_meas]),
        np.array([r]),
        np.array([[x[0] / r, x[1] / r, x[2] / r, 0.0]]),
        np.array([[0.02**2]]),
    )
    rho2 = x[0] ** 2 + x[1] ** 2
    rho, r2 = np.sqrt(rho2), rho2 + x[2] ** 2
    Hb = np.array(
        [
            [-x[1] / rho2, x[0] / rho2, 0.0, 0.0],
            [-x[0] * x[2] / (rho * r2), -x[1] * x[2] / (rho * r2), rho / r2, 0.0],
        ]
    )
    hb = np.array([np.arctan2(x[1], x[0]), np.arctan2(x[2], rho)])
    x, P = _ekf_update(x, P, np.array([az, el]), hb, Hb, np.diag([0.05**2, 0.05**2]), wrap=(0,))
    mix = fus.mixture(1)
    assert mix is not None and mix.size == 1
    np.testing.assert_allclose(mix.means[0], x, atol=1e-10)
    np.testing.assert_allclose(mix.covs[0], P, atol=1e-12)
    summary = fus.summary(1)
    assert summary is not None and summary.assoc == 0


def test_out_of_gate_known_measurement_leaves_the_track_alone() -> None:
    st = gs_settings()
    fus = GaussianSumFuser(0, [1], st)
    x0 = np.array([3.0, 0.0, 0.0, 0.0])
    fus.tracks = _one_track(x0, np.eye(4) * 0.01, st.nscan_depth)
    fus.update_known("range", [10.0])
    np.testing.assert_allclose(fus.tracks.means[0], x0)
    fus.update_known("range", [np.nan])
    np.testing.assert_allclose(fus.tracks.means[0], x0)
    with pytest.raises(DataError, match="one value per teammate"):
        fus.update_known("range", [1.0, 2.0])


def test_converged_track_survives_an_unlucky_scan_but_a_kidnapped_one_is_refound() -> None:
    """Teammate 1's bearing is missed and its height is a 2.6σ draw: its converged track must
    not lose to a track born from teammate 2's bearing (elevation consistent with teammate 1's
    range and height). When teammate 1 has jumped (range 1 m off its track, bearing far from its
    gate), the track born from its new bearing must win."""
    st = gs_settings(
        sigma_height=0.002, sigma_range=0.003, sigma_azimuth=0.06, sigma_elevation=0.06
    )
    x1 = np.array([0.2, 3.0, 0.85, 2.0])
    az2, el2, r2 = 0.1, 0.36, 3.0
    x2 = r2 * np.array([np.cos(el2) * np.cos(az2), np.cos(el2) * np.sin(az2), np.sin(el2), 0.0])
    cov = np.diag([0.07, 0.024, 0.022, 0.066]) ** 2
    jumped = (-1.0, float(np.arcsin(0.85 / 4.1)))
    cases = (
        (0.85 + 2.6 * 0.022, 3.12, [(az2, el2)], x1),
        (0.85, 4.1, [(az2, el2), jumped], 4.1 * np.cos(jumped[1]) * np.array([0.540, -0.841])),
    )
    for height, rng_m, bearings, expected_xy in cases:
        fus = GaussianSumFuser(0, [1, 2], st)
        second = replace(_one_track(x2, cov, st.nscan_depth), groups=np.ones(1, dtype=np.int64))
        fus.tracks = Tracks.concat([_one_track(x1, cov, st.nscan_depth), second])
        fus.direct_scan([height, x2[2]], [rng_m, r2], np.array(bearings))
        mix = fus.mixture(1)
        assert mix is not None
        near = np.linalg.norm(mix.means[:, :2] - expected_xy[:2], axis=1) < 0.05
        assert mix.weights[near].sum() > 0.9, (mix.means, mix.weights)


def test_births_from_unknown_bearings_and_clutter() -> None:
    st = gs_settings()
    fus = GaussianSumFuser(0, [1, 2], st)
    # teammate 1 at height 0 and 3 m, teammate 2 at height 1 m and 4 m; bearings shuffled
    b1 = (0.5, 0.0)
    b2 = (-1.0, float(np.arcsin(1.0 / 4.0)))
    fus.direct_scan([0.0, 1.0], [3.0, 4.0], np.array([b2, b1]))
    for robot, (az, el), r in ((1, b1, 3.0), (2, b2, 4.0)):
        s = fus.summary(robot)
        assert s is not None
        expected = r * np.array([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)])
        np.testing.assert_allclose(s.belief.mean[:3], expected, atol=1e-9)
        # the unknown yaw is a Gaussian sum: 8 equal components at 2πk/8 with σ = π/8
        assert s.components == 8 and s.weight == pytest.approx(1 / 8)
        assert s.belief.cov[3, 3] == pytest.approx((np.pi / 8) ** 2)
    # the joint decision maps each bearing to the teammate it came from, one to one
    np.testing.assert_array_equal(fus.decide(np.array([b1, b2])), [0, 1])
    np.testing.assert_array_equal(fus.decide(np.array([b2, (2.5, 0.0)])), [-1, 0])
    with pytest.raises(DataError, match="non-finite"):
        fus.update_bearings(np.array([[np.nan, 0.0]]), [1.0, 1.0], [0.0, 0.0])


def test_ranges_mark_detections_gives_each_scan_its_detection_probability() -> None:
    """One detector for range and bearing: only the ranged teammate can own a bearing."""
    st = gs_settings(ranges_mark_detections=True, use_elevation=False)
    fus = GaussianSumFuser(0, [1, 2], st)
    bearings = np.array([[0.5], [-1.0]])
    np.testing.assert_array_equal(fus.decide(bearings, [3.0, np.nan]), [-1, -1])  # no tracks
    fus.direct_scan([0.0, 0.0], [3.0, np.nan], bearings)
    assert fus.mixture(2) is None
    mix = fus.mixture(1)
    assert mix is not None
    # births from both bearings (the filter cannot tell which is teammate 1), 8 yaws each
    np.testing.assert_allclose(
        np.sort(np.unique(np.round(np.arctan2(mix.means[:, 1], mix.means[:, 0]), 9))),
        [-1.0, 0.5],
    )
    # a scan without teammate 1's range: no bearing can be teammate 1, nothing is born
    before = fus.tracks.size
    fus.direct_scan([0.0, 0.0], [np.nan, np.nan], np.array([[2.0]]))
    assert fus.tracks.size <= before and fus.mixture(2) is None
    np.testing.assert_array_equal(fus.decide(bearings, [np.nan, np.nan]), [-1, -1])


def test_fuse_dispatches_mutual_and_indirect_and_validates() -> None:
    # single-component births (Eq. 13), so that one scan gives registrable tracks
    st = gs_settings()
    st = replace(st, formation=replace(st.formation, birth_yaw_components=1))
    a, b = GaussianSumFuser(0, [1, 2], st), GaussianSumFuser(1, [0, 2], st)
    a.direct_scan([0.0, 0.0], [3.0, 2.0], np.array([[0.0, 0.0], [1.0, 0.0]]))
    b.direct_scan([0.0, 0.0], [3.0, 2.5], np.array([[np.pi, 0.0], [2.0, 0.0]]))
    kinds = sorted(a.fuse(m) for m in b.broadcast())
    assert kinds == ["indirect", "mutual"]
    with pytest.raises(DataError, match="own message"):
        a.fuse(a.broadcast()[0])
    with pytest.raises(DataError, match="not a teammate"):
        a.teammate_index(7)


def test_sharing_policies_send_only_confirmed_filters_and_can_skip_indirect_fusion() -> None:
    """``share_confirmed_only``: a filter whose dominant track is unconfirmed is not sent and
    keeps its broadcast prior (what it learns goes out once it is confirmed); the sent one's
    prior is reset. ``indirect_fusion=False``: a belief of a third robot is skipped, a mutual
    one still fused."""
    st = gs_settings(share_confirmed_only=True, indirect_fusion=False)
    fus = GaussianSumFuser(0, [1, 2], st)
    sure, vague = np.diag([0.05, 0.05, 0.01, 0.1]) ** 2, np.diag([1.0, 1.0, 0.01, 1.0]) ** 2
    one, two = np.array([3.0, 1.0, 0.0, 0.2]), np.array([-2.0, 2.0, 0.0, 1.0])
    old_prior = np.array([-1.5, 2.5, 0.0, 0.5])
    tracks = Tracks.concat(
        [_one_track(one, sure, st.nscan_depth), _one_track(two, vague, st.nscan_depth)]
    )
    prior_means = np.stack([one - 0.1, old_prior])
    fus.tracks = replace(tracks, groups=np.array([0, 1]), prior_means=prior_means)
    assert [fus.summary(r).confirmed for r in (1, 2)] == [True, False]  # type: ignore[union-attr]
    sent = fus.broadcast()
    assert [m.subject for m in sent] == [1]
    np.testing.assert_allclose(sent[0].prior_means, [one - 0.1])
    np.testing.assert_allclose(fus.tracks.prior_means, [one, old_prior])
    # every filter is sent by default (seed 002)
    fus_all = GaussianSumFuser(0, [1, 2], gs_settings())
    fus_all.tracks = fus.tracks
    assert [m.subject for m in fus_all.broadcast()] == [1, 2]
    # teammate 1's message about 2 is indirect: skipped; its message about 0 is mutual
    about_two = replace(sent[0], sender=1, subject=2)
    assert fus.fuse(about_two) == "skipped"
    assert fus_all.fuse(about_two) == "indirect"
    assert fus.fuse(_message_about_receiver(1, 0, one, sure)) == "mutual"
    with pytest.raises(ConfigError, match="indirect_fusion must be a bool"):
        gs_settings(indirect_fusion=1)


def _message_about_receiver(sender: int, receiver: int, mean: np.ndarray, cov: np.ndarray):  # type: ignore[no-untyped-def]
    """A one-track message of ``sender`` about ``receiver`` that inverts to ``N(mean, cov)``
    in the receiver's frame, carrying no information since the previous broadcast."""
    m, P = invert_beliefs(mean[None], cov[None])
    return EquivalentMeasurement(
        sender=sender,
        subject=receiver,
        time=0.0,
        means=m,
        covs=P,
        prior_means=m.copy(),
        prior_covs=P.copy(),
        weights=np.ones(1),
    )


def test_a_message_does_not_reweigh_the_receivers_own_hypotheses() -> None:
    """Two heading hypotheses of teammate 1, 0.4 / 0.6; teammate 1's message pairs with the
    first only. The weights of the two stay the receiver's (Eq. 10's product would cut the
    unpaired one by (1 − P_G) N_γ / N(Δ) and prune it)."""
    st = gs_settings()
    fus = GaussianSumFuser(0, [1], st)
    cov = np.diag([0.05, 0.05, 0.02, 0.1]) ** 2
    a, b = np.array([3.0, 1.0, 0.2, 0.0]), np.array([3.0, 1.0, 0.2, 1.5])
    fus.tracks = Tracks.concat(
        [_one_track(a, cov, st.nscan_depth), _one_track(b, cov, st.nscan_depth)]
    )
    fus.tracks = replace(fus.tracks, weights=np.array([0.4, 0.6]))
    assert fus.fuse(_message_about_receiver(1, 0, a + 0.01, cov)) == "mutual"
    mix = fus.mixture(1)
    assert mix is not None
    second = np.abs(wrap_angle(mix.means[:, 3] - 1.5)) < 0.2
    # up to the pruned, negligible branches (below prune_weight)
    assert mix.weights[second].sum() == pytest.approx(0.6, abs=st.prune_weight)


def test_a_received_track_is_born_only_if_the_receivers_scan_admits_it() -> None:
    """A confident received track 2 m off the range the receiver has just measured is not born;
    without a range of that teammate in the scan it is."""
    st = gs_settings()
    far = np.array([5.0, 0.0, 0.0, 0.3])
    for ranges, born in (([3.0], False), ([np.nan], True)):
        fus = GaussianSumFuser(0, [1], st)
        fus.direct_scan([0.0], ranges, np.array([[0.0, 0.0]]))
        fus.fuse(_message_about_receiver(1, 0, far, np.eye(4) * 0.01))
        mix = fus.mixture(1)
        assert mix is not None
        near_far = np.linalg.norm(mix.means[:, :3] - far[:3], axis=1) < 0.1
        assert near_far.any() == born, (ranges, mix.means)


def test_predict_fusers_equals_separate_predictions() -> None:
    st = gs_settings()
    fa, fb = GaussianSumFuser(0, [1], st), GaussianSumFuser(1, [0], st)
    ga, gb = GaussianSumFuser(0, [1], st), GaussianSumFuser(1, [0], st)
    for f in (fa, ga):
        f.tracks = _one_track(np.array([2.0, 0.0, 0.0, 0.1]), np.eye(4) * 0.1, st.nscan_depth)
    for f in (fb, gb):
        f.tracks = _one_track(np.array([-2.0, 0.5, 0.0, -0.1]), np.eye(4) * 0.2, st.nscan_depth)
    u0, u1 = np.array([0.3, 0, 0, 0.1]), np.array([0.1, 0, 0, -0.2])
    predict_fusers([fa, fb], [u0, u1], [u1[None], u0[None]], 0.05)
    ga.predict(u0, u1[None], 0.05)
    gb.predict(u1, u0[None], 0.05)
    np.testing.assert_allclose(fa.tracks.means, ga.tracks.means)
    np.testing.assert_allclose(fb.tracks.covs, gb.tracks.covs)


def test_settings_are_validated() -> None:
    with pytest.raises(ConfigError, match="sigma_range"):
        gs_settings(sigma_range=0.0)
    with pytest.raises(ConfigError, match="fusion"):
        gs_settings(fusion="naive")
    with pytest.raises(ConfigError, match="max_components"):
        gs_settings(max_components=0)
    with pytest.raises(ConfigError, match="ranges_mark_detections"):
        gs_settings(ranges_mark_detections="yes")
    with pytest.raises(ConfigError, match="known_outlier_probability"):
        gs_settings(known_outlier_probability=1.0)
    with pytest.raises(ConfigError, match="teammates"):
        GaussianSumFuser(0, [0, 1], gs_settings())


def _tracked_at_end(result, window: float = 4.0) -> np.ndarray:  # type: ignore[no-untyped-def]
    final = result.times >= result.times[-1] - window
    return result.tracked[:, final, :].mean(axis=1)


#: independent seeded runs (not hand-picked: the first children of one root seed). The root
#: 48611 was not used while developing the fuser (developed on the children of 2026). Its
#: runs 1 and 2 exposed the defect of Eq. 10's weights after a kidnap; they were instrumented
#: to find it, and the fix (``GaussianSumFuser._fuse_tracks``) follows from the model, with
#: no threshold or setting changed.
SHORT_RUN_SEEDS = spawn_seeds(48611, 4)


@pytest.mark.slow
@pytest.mark.parametrize("clutter_factor", [1.0, 100.0])
@pytest.mark.parametrize("run", range(len(SHORT_RUN_SEEDS)))
def test_seeded_short_run_finds_every_teammate(run: int, clutter_factor: float) -> None:
    base = DeSilvaScenario(duration=15.0)
    scenario = replace(base, clutter_density=base.clutter_density * clutter_factor)
    result = _task(SHORT_RUN_SEEDS[run], run, RunConfig(scenario=scenario))
    frac = _tracked_at_end(result)
    for li in range(2):
        others = [j for j in range(5) if j != li]
        assert np.all(frac[li, others] >= 0.9), frac


@pytest.mark.slow
@pytest.mark.parametrize("run", range(len(SHORT_RUN_SEEDS)))
def test_kidnapped_robot_is_refound(run: int) -> None:
    """The experiment's kidnap (P2 moved by 3 m, −2 m, 2 rad at 15 s of 30 s) and criterion."""
    scenario = DeSilvaScenario(duration=DURATION_S, kidnap=KIDNAP)
    result = _task(SHORT_RUN_SEEDS[run], run, RunConfig(scenario=scenario))
    frac = _tracked_at_end(result, window=FINAL_WINDOW_S)
    assert np.all(frac[:, KIDNAP[0]] >= 0.9), frac
    just_after = (result.times > KIDNAP[1]) & (result.times < KIDNAP[1] + 0.3)
    assert not result.tracked[:, just_after, KIDNAP[0]].all()


def test_filter_settings_follow_the_scenario() -> None:
    sc = DeSilvaScenario(p_detect=0.8, clutter_density=1e-5)
    st = filter_settings(sc)
    assert st.formation.p_detect == 0.8
    assert st.expected_clutter == pytest.approx(sc.expected_clutter)
    assert st.sigma_range == pytest.approx(np.sqrt(8.0) * 1e-3)
    assert replace(st, fusion="ci").fusion == "ci"
    # a run's configuration: the scenario's settings with its fusion and sharing policy
    assert RunConfig(scenario=sc).settings() == st  # seed 002's policy by default
    restricted = RunConfig(scenario=sc, fusion="ci", sharing_policy="mutual-confirmed")
    assert restricted.settings() == replace(
        st, fusion="ci", share_confirmed_only=True, indirect_fusion=False
    )
    with pytest.raises(ConfigError, match="sharing policy 'none': one of all, mutual-confirmed"):
        RunConfig(scenario=sc, sharing_policy="none")


def _two_tracks(depth: int) -> Tracks:
    """Two equally weighted tracks of one teammate: 2 m straight ahead and 2 m to the left."""
    cov = np.diag([0.01, 0.01, 0.01, 0.01])
    means = np.array([[2.0, 0.0, 0.0, 0.0], [0.0, 2.0, 0.0, 0.0]])
    return Tracks(
        groups=np.zeros(2, dtype=np.int64),
        means=means,
        covs=np.stack([cov, cov]),
        prior_means=means.copy(),
        prior_covs=np.stack([cov, cov]),
        weights=np.full(2, 0.5),
        history=np.zeros((2, depth + 1), dtype=np.int64),
        assoc=np.full(2, -1, dtype=np.int64),
    )


@pytest.mark.parametrize("fov", [None, 0.5])
def test_a_missed_detection_weighs_against_tracks_in_the_field_of_view(fov: float | None) -> None:
    st = gs_settings(use_elevation=False, field_of_view=fov)
    st = replace(st, formation=replace(st.formation, p_detect=0.8))
    fuser = GaussianSumFuser(0, [1], st)
    fuser.tracks = _two_tracks(st.nscan_depth)
    fuser.update_bearings(np.zeros((0, 1)), [np.nan], [np.nan])
    fuser.reduce()
    w = fuser.tracks.weights
    if fov is None:
        # a constant P_D: every track is equally likely to have been missed
        assert w == pytest.approx([0.5, 0.5])
    else:
        # the track ahead should have been seen (P_D 0.8 · P_G 0.95), the one to the left not
        assert w[0] / w[1] == pytest.approx(1.0 - 0.8 * 0.95, rel=1e-6)


def test_field_of_view_is_checked() -> None:
    with pytest.raises(ConfigError, match="field_of_view"):
        gs_settings(use_elevation=False, field_of_view=0.0)
    with pytest.raises(ConfigError, match="ranges_mark_detections"):
        gs_settings(use_elevation=False, field_of_view=0.5, ranges_mark_detections=True)


@pytest.mark.parametrize("ranged", [True, False])
def test_a_range_sensor_with_the_field_of_view_weighs_tracks_by_where_they_put_the_teammate(
    ranged: bool,
) -> None:
    """Two tracks at the same 2 m range, one ahead (in a ±0.5 rad view) and one to the left
    (out of it): a range of the teammate can only have come from the one in view, and no
    range is what the one out of view predicts. Expected ratios from the normal CDF of each
    track's azimuth, σ² = (∂α/∂p) P (∂α/∂p)ᵀ + σ_α² = 0.01/4 + 0.05²."""
    from scipy.stats import norm

    fov, p_d = 0.5, 0.8
    st = gs_settings(use_elevation=False, field_of_view=fov, range_in_view=True)
    st = replace(st, formation=replace(st.formation, p_detect=p_d))
    sd = np.sqrt(0.01 / 4 + 0.05**2)
    p_in = np.array([norm.cdf((fov - a) / sd) - norm.cdf((-fov - a) / sd) for a in (0, np.pi / 2)])
    for in_view in (True, False):
        fuser = GaussianSumFuser(0, [1], st if in_view else replace(st, range_in_view=False))
        fuser.tracks = _two_tracks(st.nscan_depth)
        fuser.update_known("range", [2.0 if ranged else np.nan])
        w = fuser.tracks.weights
        if not in_view:
            assert w[0] == pytest.approx(w[1], rel=1e-12)  # all-around ranging: no information
        elif ranged:
            assert w[0] / w[1] == pytest.approx(p_in[0] / p_in[1], rel=1e-9)
            assert w[0] / w[1] > 1e6
        else:
            assert w[0] / w[1] == pytest.approx((1 - p_d * p_in[0]) / (1 - p_d * p_in[1]))
            assert w[0] / w[1] == pytest.approx(1 - p_d, rel=1e-3)


def test_range_in_view_needs_a_field_of_view() -> None:
    with pytest.raises(ConfigError, match="range_in_view needs a field_of_view"):
        gs_settings(use_elevation=False, range_in_view=True)
    with pytest.raises(ConfigError, match="range_in_view must be a bool"):
        gs_settings(use_elevation=False, field_of_view=0.5, range_in_view=1)
