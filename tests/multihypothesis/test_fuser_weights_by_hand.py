"""Hand-computed weights and decisions of one Gaussian-sum fuser that the behaviour tests leave
free."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from gaussian_sum_samples import gs_settings

from relloc.estimators.gaussian_sum import GaussianSumFuser, Tracks


def _tracks(means: np.ndarray, covs: np.ndarray, groups: list[int], depth: int) -> Tracks:
    k = means.shape[0]
    return Tracks(
        groups=np.asarray(groups, dtype=np.int64),
        means=means.copy(),
        covs=covs.copy(),
        prior_means=means.copy(),
        prior_covs=covs.copy(),
        weights=np.full(k, 1.0 / k),
        history=np.repeat(np.arange(k)[:, None], depth + 1, axis=1),
        assoc=np.full(k, -1, dtype=np.int64),
    )


@pytest.mark.parametrize(("kind", "span"), [("height", 40.0), ("range", 20.0)])
def test_an_outlying_known_reading_leaves_the_uniform_outlier_density(
    kind: str, span: float
) -> None:
    # ε = 0.01 spread over [−20, 20] m (height difference) or [0, 20] m (range); the reading
    # is 250σ away, so its valid density is 0 and the track is not moved
    st = gs_settings()
    fus = GaussianSumFuser(0, [1], st)
    mean = np.array([3.0, 0.0, 0.0, 0.0])
    fus.tracks = _tracks(mean[None], (np.eye(4) * 1e-4)[None], [0], st.nscan_depth)
    fus.update_known(kind, [5.0 if kind == "height" else 8.0])  # type: ignore[arg-type]
    assert fus.tracks.weights[0] == pytest.approx(0.01 / span, rel=1e-12)
    np.testing.assert_array_equal(fus.tracks.means[0], mean)


def test_a_valid_height_reading_weighs_and_updates_the_track() -> None:
    # S = P_zz + σ_h² = 2·10⁻⁴; the reading 1 cm above: d² = 10⁻⁴ / S = 0.5, gain 1/2
    st = gs_settings()
    fus = GaussianSumFuser(0, [1], st)
    mean = np.array([3.0, 0.0, 0.0, 0.0])
    fus.tracks = _tracks(mean[None], (np.eye(4) * 1e-4)[None], [0], st.nscan_depth)
    fus.update_known("height", [0.01])
    S = 2e-4
    expected = 0.99 * np.exp(-0.25) / np.sqrt(2 * np.pi * S) + 0.01 / 40.0
    assert fus.tracks.weights[0] == pytest.approx(expected, rel=1e-12)
    assert fus.tracks.means[0, 2] == pytest.approx(0.005, rel=1e-12)
    assert fus.tracks.covs[0, 2, 2] == pytest.approx(0.5e-4, rel=1e-12)


def test_a_scan_without_bearings_weighs_tracks_by_their_in_view_probability() -> None:
    # field of view ±0.5 rad; tracks 3 m away at azimuths 0 (inside), 0.5 (on the edge: seen
    # with probability 1/2) and 0.45; the predicted azimuth's σ² = σ_θ² + P_xy/ρ²
    from scipy.stats import norm

    st = gs_settings(field_of_view=0.5)
    fus = GaussianSumFuser(0, [1], st)
    az = np.array([0.0, 0.5, 0.45])
    means = np.stack([3 * np.cos(az), 3 * np.sin(az), np.zeros(3), np.zeros(3)], axis=1)
    fus.tracks = _tracks(means, np.broadcast_to(np.eye(4) * 1e-4, (3, 4, 4)), [0, 0, 0], 3)
    fus.update_bearings(np.zeros((0, 2)), [3.0], [0.0])
    sd = np.sqrt(0.05**2 + 1e-4 / 9.0)
    p_in = norm.cdf((0.5 - az) / sd) - norm.cdf((-0.5 - az) / sd)
    assert p_in[1] == pytest.approx(0.5, abs=1e-12)
    expected = (1.0 - 0.95 * p_in * 0.95) / 3.0
    np.testing.assert_allclose(fus.tracks.weights, expected, rtol=1e-9)


def test_detected_weight_of_a_uniform_yaw_track_uses_the_update_covariance() -> None:
    # teammate 1: one track 3 m ahead with an unknown yaw, moving at 2 m/s (its gate widened
    # by the yaw disc); teammate 2: no track (uniform 1/V). One bearing at the prediction:
    #   w_fa = 1 − P_D P_G,  w_det = P_D N(0; 0, S) / κ,  κ = (10⁻³ + P_D) / V,
    # S = H P Hᵀ + R without the disc (the gate only decides which pairs exist)
    st = gs_settings()
    fus = GaussianSumFuser(0, [1, 2], st)
    cov = np.diag([1e-4, 1e-4, 1e-4, 4 * np.pi])
    fus.tracks = _tracks(np.array([[3.0, 0.0, 0.0, 0.0]]), cov[None], [0], st.nscan_depth)
    fus.predict(np.zeros(4), np.array([[2.0, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 0.0]]), 0.0)
    fus.update_bearings(np.array([[0.0, 0.0]]), [np.nan, np.nan], [np.nan, np.nan])
    s = 1e-4 / 9.0 + 0.05**2  # each bearing's variance: ‖∂(θ, α)/∂p‖² = 1/9 per axis
    density = 1.0 / (2 * np.pi * s)
    V = 2 * np.pi * np.pi
    kappa = (1e-3 + 0.95) / V
    np.testing.assert_allclose(
        np.sort(fus.tracks.weights), [1 - 0.95 * 0.95, 0.95 * density / kappa], rtol=1e-9
    )


def test_the_other_filters_bearing_density_is_their_normalised_mixture() -> None:
    # teammates 1 and 2 each hold one track at the same place, with unnormalised weight 0.3
    # (as after a known-correspondence update); the bearing at their prediction is explained
    # by teammate 2's mixture, whose weights sum to 1: κ₁ = (10⁻³/V) + P_D N(0; 0, S)
    st = gs_settings()
    fus = GaussianSumFuser(0, [1, 2], st)
    cov = np.diag([1e-4, 1e-4, 1e-4, 0.01])
    means = np.array([[3.0, 0.0, 0.0, 0.0], [3.0, 0.0, 0.0, 0.0]])
    fus.tracks = _tracks(means, np.stack([cov, cov]), [0, 1], st.nscan_depth)
    fus.tracks = replace(fus.tracks, weights=np.array([0.3, 0.3]))
    fus.update_bearings(np.array([[0.0, 0.0]]), [np.nan, np.nan], [np.nan, np.nan])
    s = 1e-4 / 9.0 + 0.05**2
    density = 1.0 / (2 * np.pi * s)
    kappa = 1e-3 / (2 * np.pi * np.pi) + 0.95 * density
    detected = fus.tracks.weights[fus.tracks.assoc == 0]
    np.testing.assert_allclose(detected, [0.3 * 0.95 * density / kappa] * 2, rtol=1e-9)


@pytest.mark.parametrize(("clutter", "decision"), [(0.0, 0), (5322.0, 0), (20000.0, -1)])
def test_decide_weighs_a_detection_against_a_miss(clutter: float, decision: int) -> None:
    # a bearing at the prediction of a sharp track (each bearing's variance s): the detection
    # costs log(2π s) − log P_D + log κ with κ = max(λ, 10⁻³)/V, a miss −log(1 − P_D P_G)
    #   λ = 0: −4.15 + 0.05 − 9.89 = −13.99 < 2.33;  λ = 5322: 1.50 < 2.33;  λ = 20000: 2.82 > 2.33
    st = gs_settings(expected_clutter=clutter)
    fus = GaussianSumFuser(0, [1], st)
    cov = np.diag([1e-4, 1e-4, 1e-4, 0.01])
    fus.tracks = _tracks(np.array([[3.0, 0.0, 0.0, 0.0]]), cov[None], [0], st.nscan_depth)
    s = 1e-4 / 9.0 + 0.05**2
    V = 2 * np.pi * np.pi
    cost = np.log(2 * np.pi * s) - np.log(0.95) + np.log(max(clutter, 1e-3) / V)
    assert (cost < -np.log(1 - 0.95 * 0.95)) == (decision == 0)
    np.testing.assert_array_equal(fus.decide(np.array([[0.0, 0.0]])), [decision])


def test_decide_prefers_the_sharper_explanation_of_a_bearing() -> None:
    # teammates 1 and 2 predicted at the same place, 1 sharp (s₁ = 0.0025) and 2 broad
    # (s₂ = 0.0125); a bearing 0.03 rad off: d²₁ = 0.36, d²₂ = 0.072, and the cost difference
    # c₂ − c₁ = log(s₂/s₁) + (d²₂ − d²₁)/2 = 1.61 − 0.14 > 0 gives the bearing to teammate 1
    st = gs_settings()
    fus = GaussianSumFuser(0, [1, 2], st)
    sharp = np.diag([1e-12, 1e-12, 1e-12, 0.01])
    broad = np.diag([0.09, 0.09, 0.09, 0.01])
    means = np.array([[3.0, 0.0, 0.0, 0.0], [3.0, 0.0, 0.0, 0.0]])
    fus.tracks = _tracks(means, np.stack([sharp, broad]), [0, 1], st.nscan_depth)
    np.testing.assert_array_equal(fus.decide(np.array([[0.03, 0.0]])), [0, -1])


def test_reduce_deletes_tracks_too_far_or_too_uncertain_in_three_dimensions() -> None:
    # max_range 20 m on ‖(x, y, z)‖, max_position_sigma 5 m on √tr P_xyz
    st = gs_settings(merge_threshold=0.0)
    fus = GaussianSumFuser(0, [1], st)
    means = np.array([[3.0, 0.0, 0.0, 0.0], [15.0, 0.0, 14.0, 0.0], [0.0, 6.0, 0.0, 0.0]])
    sharp = np.diag([0.01, 0.01, 0.01, 0.01])
    wide = np.diag([3.0, 3.0, 4.0, 0.01])  # σ = √10 ≈ 3.2 m: usable
    fus.tracks = _tracks(means, np.stack([sharp, sharp, wide]), [0, 0, 0], st.nscan_depth)
    fus.reduce()  # the track 20.5 m away is deleted, the other two share the weight
    np.testing.assert_allclose(fus.tracks.means[:, :3], means[[0, 2], :3])
    np.testing.assert_allclose(fus.tracks.weights, [0.5, 0.5])


@pytest.mark.parametrize(
    ("weight", "cov", "confirmed"),
    [
        (0.8, np.diag([0.01, 0.01, 0.01, 0.01]), True),  # weight exactly at confirm_weight
        (1.0, np.diag([0.01, 0.01, 0.08, 0.01]), False),  # √tr P_xyz = 0.316 > 0.3
        (1.0, np.diag([0.01, 0.01, 0.06, 0.01]), True),  # √0.08 = 0.28
    ],
)
def test_confirmation_thresholds(weight: float, cov: np.ndarray, confirmed: bool) -> None:
    st = gs_settings()
    fus = GaussianSumFuser(0, [1], st)
    means = np.array([[3.0, 0.0, 0.0, 0.0], [-3.0, 0.0, 0.0, 0.0]])
    fus.tracks = _tracks(means, np.stack([cov, cov]), [0, 0], st.nscan_depth)
    fus.tracks = replace(fus.tracks, weights=np.array([weight, 1.0 - weight]))
    summary = fus.summary(1)
    assert summary is not None and summary.confirmed == confirmed


def test_the_yaw_disc_uses_the_teammates_horizontal_speed() -> None:
    # teammate moving sideways at 2 m/s, τ = 0.1 s: disc radius 0.2 m adds 0.04/9 to the
    # azimuth variance of a track 3 m ahead; a bearing 0.2 rad off has d² = 0.04/0.0025 = 16
    # in the plain gate (outside χ²₂(0.95) = 5.99) and 0.04/(0.0025 + 0.0044) = 5.8 inside
    st = gs_settings()
    fus = GaussianSumFuser(0, [1], st)
    cov = np.diag([1e-8, 1e-8, 1e-8, 4 * np.pi])
    fus.tracks = _tracks(np.array([[3.0, 0.0, 0.0, 0.0]]), cov[None], [0], st.nscan_depth)
    fus.predict(np.zeros(4), np.array([[0.0, 2.0, 0.0, 0.0]]), 0.0)
    fus.update_bearings(np.array([[0.2, 0.0]]), [np.nan], [np.nan])
    assert sorted(fus.tracks.assoc.tolist()) == [-1, 0]


def _message_about_receiver(  # type: ignore[no-untyped-def]
    means: np.ndarray,
    covs: np.ndarray,
    weights: np.ndarray,
    prior_means: np.ndarray | None = None,
    prior_covs: np.ndarray | None = None,
):
    """Teammate 1's message that inverts to ``N(means, covs)`` in robot 0's frame, and to the
    prior ``N(prior_means, prior_covs)`` at its previous broadcast (default: the same, no
    information since then)."""
    from relloc.fusion.messages import EquivalentMeasurement
    from relloc.fusion.pose_beliefs import invert_beliefs

    m, P = invert_beliefs(means, covs)
    pm, pP = (
        (m.copy(), P.copy())
        if prior_means is None or prior_covs is None
        else invert_beliefs(prior_means, prior_covs)
    )
    return EquivalentMeasurement(
        sender=1,
        subject=0,
        time=0.0,
        means=m,
        covs=P,
        prior_means=pm,
        prior_covs=pP,
        weights=weights,
    )


def test_a_received_track_outside_every_gate_is_born_with_its_eq10_share() -> None:
    # local track h: N((3, 0, 0, 0), 0.01 I); received (weights ½, ½): b₁ 0.1 m from h (gated),
    # b₂ at (−3, 0, 0, 0) (in no gate, born). With N_γ(P) = e^{−γ/2}/√det(2πP):
    #   λ_h0 = (1 − P_G) N_γ(P_h + Σ w'_b P_b),  λ_h1 = w'₁ N(Δ; 0, P_h + P₁),
    #   β₂ = P_B w'₂ N_γ(P₂) / (λ_h0 + λ_h1);
    # b₁ adds no information (its prior is itself), so h's two outcomes merge back into h and
    # the filter ends with weights 1/(1 + β₂) and β₂/(1 + β₂)
    from scipy.stats import chi2

    st = gs_settings()
    fus = GaussianSumFuser(0, [1], st)
    P = np.eye(4) * 0.01
    fus.tracks = _tracks(np.array([[3.0, 0.0, 0.0, 0.0]]), P[None], [0], st.nscan_depth)
    received = np.array([[3.1, 0.0, 0.0, 0.0], [-3.0, 0.0, 0.0, 0.0]])
    assert fus.fuse(_message_about_receiver(received, np.stack([P, P]), np.ones(2))) == "mutual"
    gamma = chi2.ppf(0.95, 4)

    def edge(var: float) -> float:
        return float(np.exp(-gamma / 2) / np.sqrt((2 * np.pi * var) ** 4))

    lam0 = 0.05 * edge(0.02)
    lam1 = 0.5 * np.exp(-0.5 * 0.1**2 / 0.02) / np.sqrt((2 * np.pi * 0.02) ** 4)
    beta = 0.5 * 0.5 * edge(0.01) / (lam0 + lam1)
    order = np.argsort(-fus.tracks.means[:, 0])
    np.testing.assert_allclose(fus.tracks.means[order, 0], [3.0, -3.0], atol=1e-9)
    np.testing.assert_allclose(
        fus.tracks.weights[order], [1 / (1 + beta), beta / (1 + beta)], rtol=1e-6
    )


def test_tracks_are_merged_before_the_filter_is_capped() -> None:
    # max_components 2; A₁, A₂ and C₁, C₂ are close pairs, B stands alone. Merged, the pairs
    # weigh 0.55 (A) and 0.25 (C) against B's 0.2, so the cap keeps A and C
    st = gs_settings(max_components=2)
    fus = GaussianSumFuser(0, [1], st)
    x = np.array([3.0, 3.05, 0.0, -3.0, -3.05])
    means = np.stack([x, [0.0, 0.0, 3.0, 0.0, 0.0], np.zeros(5), np.zeros(5)], axis=1)
    covs = np.broadcast_to(np.diag([0.01, 0.01, 0.01, 0.01]), (5, 4, 4))
    fus.tracks = _tracks(means, covs, [0] * 5, st.nscan_depth)
    fus.tracks = replace(fus.tracks, weights=np.array([0.3, 0.25, 0.2, 0.15, 0.1]))
    fus.reduce()
    order = np.argsort(-fus.tracks.weights)
    np.testing.assert_allclose(fus.tracks.weights[order], [0.55 / 0.8, 0.25 / 0.8])
    np.testing.assert_allclose(
        fus.tracks.means[order, 0], [(0.3 * 3.0 + 0.25 * 3.05) / 0.55, -3.02], rtol=1e-12
    )


def test_indirect_tracks_carry_the_weight_of_their_registration() -> None:
    # robot 0 holds two hypotheses of teammate 1 (weights 0.6 / 0.4, same covariance, yaw 0)
    # and none of teammate 2; teammate 1's one-track belief of 2, registered through each,
    # gives two tracks of equal covariance, born with weights ∝ 0.6 w' and 0.4 w'
    from relloc.fusion.messages import EquivalentMeasurement

    st = gs_settings()
    fus = GaussianSumFuser(0, [1, 2], st)
    P = np.eye(4) * 0.01
    means = np.array([[3.0, 0.0, 0.0, 0.0], [-3.0, 0.0, 0.0, 0.0]])
    fus.tracks = _tracks(means, np.stack([P, P]), [0, 0], st.nscan_depth)
    fus.tracks = replace(fus.tracks, weights=np.array([0.6, 0.4]))
    m = np.array([[1.0, 0.0, 0.0, 0.0]])
    msg = EquivalentMeasurement(
        sender=1,
        subject=2,
        time=0.0,
        means=m,
        covs=P[None],
        prior_means=m.copy(),
        prior_covs=P[None].copy(),
        weights=np.ones(1),
    )
    assert fus.fuse(msg) == "indirect"
    mix = fus.mixture(2)
    assert mix is not None
    order = np.argsort(-mix.means[:, 0])
    np.testing.assert_allclose(mix.means[order, 0], [4.0, -2.0], atol=1e-12)
    np.testing.assert_allclose(mix.weights[order], [0.6, 0.4], rtol=1e-9)


def test_the_fused_increment_also_enters_the_tracks_broadcast_prior() -> None:
    # local track (and its prior) N(x_h, 0.02 I); the sender's track went from 0.02 I to
    # 0.01 I at x_h + 0.05 e_x: ΔY = 50 I, fused P = (50 + 50)⁻¹ I = 0.01 I and mean
    # x_h + 0.01 · 50 · 0.05 e_x, for the track and, alike, for its prior
    st = gs_settings(merge_threshold=0.0)
    fus = GaussianSumFuser(0, [1], st)
    x_h = np.array([3.0, 0.0, 0.0, 0.0])
    fus.tracks = _tracks(x_h[None], (np.eye(4) * 0.02)[None], [0], st.nscan_depth)
    x_b = (x_h + np.array([0.05, 0.0, 0.0, 0.0]))[None]
    fus.fuse(
        _message_about_receiver(
            x_b, (np.eye(4) * 0.01)[None], np.ones(1), x_b, (np.eye(4) * 0.02)[None]
        )
    )
    fused = np.flatnonzero(fus.tracks.means[:, 0] > 3.01)
    assert fused.size == 1
    k = int(fused[0])
    np.testing.assert_allclose(fus.tracks.means[k], x_h + np.array([0.025, 0, 0, 0]), atol=1e-9)
    np.testing.assert_allclose(fus.tracks.covs[k], np.eye(4) * 0.01, atol=1e-9)
    np.testing.assert_allclose(
        fus.tracks.prior_means[k], x_h + np.array([0.025, 0, 0, 0]), atol=1e-9
    )
    np.testing.assert_allclose(fus.tracks.prior_covs[k], np.eye(4) * 0.01, atol=1e-9)


def test_covariance_intersection_fusion_aligns_the_received_heading() -> None:
    # local heading 3.1, received −3.1 (0.083 rad apart across ±π): the fused heading stays
    # near ±π, not near 0
    st = gs_settings(fusion="ci", merge_threshold=0.0)
    fus = GaussianSumFuser(0, [1], st)
    x_h = np.array([3.0, 0.0, 0.0, 3.1])
    # the local track is better in position, the received one in heading: 0 < ω < 1
    P_h, P_b = np.diag([0.01, 0.01, 0.01, 0.04]), np.diag([0.04, 0.04, 0.04, 0.01])
    fus.tracks = _tracks(x_h[None], P_h[None], [0], st.nscan_depth)
    x_b = np.array([[3.0, 0.0, 0.0, -3.1]])
    fus.fuse(_message_about_receiver(x_b, P_b[None], np.ones(1)))
    heading = np.cos(fus.tracks.means[:, 3])
    assert np.all(heading < -0.99), fus.tracks.means


def test_merged_tracks_merge_their_broadcast_priors_with_the_same_weights() -> None:
    st = gs_settings()
    fus = GaussianSumFuser(0, [1], st)
    means = np.array([[3.0, 0.0, 0.0, 0.0], [3.05, 0.0, 0.0, 0.0]])
    P = np.eye(4) * 0.01
    fus.tracks = _tracks(means, np.stack([P, P]), [0, 0], st.nscan_depth)
    priors = np.array([[3.0, 0.0, 0.0, 0.0], [3.5, 0.0, 0.0, 0.0]])
    fus.tracks = replace(fus.tracks, weights=np.array([0.6, 0.4]), prior_means=priors)
    fus.reduce()
    assert fus.tracks.size == 1
    assert fus.tracks.means[0, 0] == pytest.approx(0.6 * 3.0 + 0.4 * 3.05, rel=1e-12)
    assert fus.tracks.prior_means[0, 0] == pytest.approx(0.6 * 3.0 + 0.4 * 3.5, rel=1e-12)
    # moment matching: P + the spread of the means, 0.6 · 0.4 · 0.5² on x
    assert fus.tracks.prior_covs[0, 0, 0] == pytest.approx(0.01 + 0.24 * 0.25, rel=1e-12)


def test_a_bearing_across_the_azimuth_wrap_is_gated() -> None:
    st = gs_settings()
    fus = GaussianSumFuser(0, [1], st)
    az = np.pi - 0.01
    mean = np.array([[3 * np.cos(az), 3 * np.sin(az), 0.0, 0.0]])
    fus.tracks = _tracks(mean, (np.eye(4) * 1e-4)[None], [0], st.nscan_depth)
    fus.update_bearings(np.array([[-np.pi + 0.01, 0.0]]), [np.nan], [np.nan])
    assert sorted(fus.tracks.assoc.tolist()) == [-1, 0]


def test_a_light_track_above_prune_weight_is_kept() -> None:
    st = gs_settings()
    fus = GaussianSumFuser(0, [1], st)
    means = np.array([[3.0, 0.0, 0.0, 0.0], [-3.0, 0.0, 0.0, 0.0]])
    P = np.eye(4) * 0.01
    fus.tracks = _tracks(means, np.stack([P, P]), [0, 0], st.nscan_depth)
    fus.tracks = replace(fus.tracks, weights=np.array([0.995, 0.005]))
    fus.reduce()
    np.testing.assert_allclose(fus.tracks.weights, [0.995, 0.005])


def test_with_ranges_marking_detections_an_unranged_teammate_gets_no_bearing() -> None:
    # one detector gives range and bearing: teammate 1 has no range in this scan, so none of
    # the bearings is its (P_D = 0), even one at its prediction; ranged, it gets that bearing
    st = gs_settings(ranges_mark_detections=True)
    for ranges, decision in (([np.nan], -1), ([3.0], 0)):
        fus = GaussianSumFuser(0, [1], st)
        cov = np.diag([1e-4, 1e-4, 1e-4, 0.01])
        fus.tracks = _tracks(np.array([[3.0, 0.0, 0.0, 0.0]]), cov[None], [0], st.nscan_depth)
        fus.direct_scan([np.nan], ranges, np.array([[0.0, 0.0]]))
        np.testing.assert_array_equal(fus.last_decision, [decision])
