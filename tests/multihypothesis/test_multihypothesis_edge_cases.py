"""Degenerate-but-valid and hostile inputs of the Gaussian-sum fuser and its association stages.

Each test either pins behaviour verified to be right (long coasting, all-clutter scans, bursts of
detections, duplicates, extreme ``P_D``, zero clutter, identical components, N-scan depth beyond
the history) or guards a fixed defect: a track on the observer's vertical axis (NaN Jacobian),
a singular covariance in the merge (raw ``LinAlgError``), subnormal or huge weights in the
moment merge (wrong or NaN moments), a degenerate received covariance (NaN weights emptying the
receiver's filter).
"""

from __future__ import annotations

import time
from dataclasses import replace

import numpy as np
import pytest
from gaussian_sum_samples import gs_settings, one_track_message

from relloc.association.assignment import assign
from relloc.association.hypotheses import FormationSettings, birth_tracks, formation_weights
from relloc.association.mixture_reduction import (
    merge_groups,
    merge_moments,
    pairwise_mahalanobis,
)
from relloc.association.nscan import branch, family_keep_mask, new_history
from relloc.errors import ConfigError, DataError, ModelError
from relloc.estimators.gaussian_sum import (
    RHO_FLOOR,
    GaussianSumFuser,
    GaussianSumSettings,
    Tracks,
)
from relloc.fusion.messages import EquivalentMeasurement

X1 = np.array([3.0, 1.0, 0.5, 0.3])
X2 = np.array([-2.0, 1.0, 0.2, 0.0])
COV = np.diag([0.01, 0.01, 0.01, 0.01])


def _with_pd(st: GaussianSumSettings, p_detect: float) -> GaussianSumSettings:
    return replace(st, formation=replace(st.formation, p_detect=p_detect))


def _track(mean: np.ndarray, depth: int, group: int = 0, cov: np.ndarray = COV) -> Tracks:
    m = np.asarray(mean, dtype=float)[None]
    return Tracks(
        groups=np.full(1, group, dtype=np.int64),
        means=m.copy(),
        covs=cov[None].copy(),
        prior_means=m.copy(),
        prior_covs=cov[None].copy(),
        weights=np.ones(1),
        history=np.full((1, depth + 1), group, dtype=np.int64),
        assoc=np.full(1, -1, dtype=np.int64),
    )


def _two_teammates(st: GaussianSumSettings) -> GaussianSumFuser:
    fus = GaussianSumFuser(0, [1, 2], st)
    fus.tracks = Tracks.concat([_track(X1, st.nscan_depth), _track(X2, st.nscan_depth, 1)])
    fus._next_id = 2
    return fus


def _bearing(p: np.ndarray) -> np.ndarray:
    return np.array([np.arctan2(p[1], p[0]), np.arctan2(p[2], np.hypot(p[0], p[1]))])


def _assert_sane(fus: GaussianSumFuser) -> None:
    """Finite tracks, and the weights of every non-empty filter sum to 1."""
    t = fus.tracks
    assert np.isfinite(t.weights).all() and np.isfinite(t.means).all()
    assert np.isfinite(t.covs).all()
    totals = np.bincount(t.groups, weights=t.weights)
    np.testing.assert_allclose(totals[np.bincount(t.groups) > 0], 1.0, rtol=1e-12)


def _ranges(*points: np.ndarray) -> list[float]:
    return [float(np.linalg.norm(p[:3])) for p in points]


# ---------------------------------------------------------------- scans without detections


def test_a_coasting_track_keeps_its_weight_until_it_is_too_uncertain() -> None:
    """No detection for a long time: the covariance grows every prediction, the lone track's
    weight stays 1 (a missed scan's factor 1 − P_D P_G cancels in the normalisation), and the
    track is deleted once √tr P_xyz exceeds ``max_position_sigma`` (5 m: measured after 7345
    steps of 0.1 s at this process noise, here after 74 steps of 1 s)."""
    st = gs_settings()
    fus = GaussianSumFuser(0, [1], st)
    fus.tracks = _track(X1, st.nscan_depth)
    sigma, steps = [], 0
    while fus.tracks.size:
        fus.predict(np.zeros(4), np.zeros((1, 4)), 1.0)
        fus.direct_scan([np.nan], [np.nan], np.zeros((0, 2)))
        steps += 1
        if fus.tracks.size:
            assert fus.tracks.weights.tolist() == [1.0]
            sigma.append(float(np.sqrt(np.trace(fus.tracks.covs[0, :3, :3]))))
        assert steps < 200
    assert np.all(np.diff(sigma) > 0.0) and sigma[-1] <= st.max_position_sigma
    assert 60 <= steps <= 90  # deleted, neither at once nor never
    assert fus.summary(1) is None


def test_a_scan_of_only_clutter_leaves_the_tracks_where_they_are() -> None:
    """Every bearing far outside every gate: no track is updated, the births (height mismatch)
    are pruned, each filter still sums to 1 and the decision gives no teammate a bearing."""
    st = gs_settings(expected_clutter=20.0)
    fus = _two_teammates(st)
    clutter = np.array([[2.5, 0.3], [-2.0, -0.5], [1.5, 1.0]])
    fus.direct_scan([0.5, 0.2], _ranges(X1, X2), clutter)
    _assert_sane(fus)
    assert fus.tracks.size == 2
    np.testing.assert_allclose(fus.tracks.means, np.stack([X1, X2]), rtol=0, atol=1e-12)
    np.testing.assert_array_equal(fus.last_decision, [-1, -1])


# ---------------------------------------------------------------- many or repeated detections


def test_a_burst_of_a_thousand_detections_stays_bounded() -> None:
    """1000 bearings in one scan, all inside the gates of 16 tracks per teammate: the branches
    grow as tracks × detections (linear in the detections; the joint decision is a 2 × 1002
    assignment) and the reduction caps each filter at ``max_components``. Measured: about
    40 ms and 20 MB for the scan (130 ms for 3000)."""
    st = gs_settings(expected_clutter=20.0)
    fus = GaussianSumFuser(0, [1, 2], st)
    parts = []
    for j, p in enumerate((X1, X2)):
        for c in range(16):
            q = p.copy()
            q[3] = 2.0 * np.pi * c / 16
            parts.append(_track(q, st.nscan_depth, j))
    tracks = Tracks.concat(parts)
    fus.tracks = tracks.with_arrays(
        weights=np.full(tracks.size, 1.0 / 16),
        history=np.repeat(np.arange(tracks.size)[:, None], st.nscan_depth + 1, axis=1),
    )
    fus._next_id = tracks.size
    rng = np.random.default_rng(7)
    Z = _bearing(X1) + 0.05 * rng.standard_normal((1000, 2))
    start = time.perf_counter()
    fus.direct_scan([0.5, 0.2], _ranges(X1, X2), Z)
    elapsed = time.perf_counter() - start
    _assert_sane(fus)
    assert np.bincount(fus.tracks.groups).max() <= st.max_components
    assert elapsed < 5.0  # ~0.04 s; a blow-up (quadratic or worse in 1000) would be far above
    s = fus.summary(1)
    assert s is not None and np.linalg.norm(s.belief.mean[:3] - X1[:3]) < 0.2


def test_two_detections_at_the_same_place_act_as_one() -> None:
    """Duplicated bearing: its two detected branches are identical and merge, so the posterior
    is the one of the single detection (the duplicate only doubles a weight that the
    normalisation removes)."""
    st = gs_settings(expected_clutter=2.0)
    b = _bearing(X1) + 0.01
    out = []
    for Z in (np.array([b]), np.array([b, b])):
        fus = _two_teammates(st)
        fus.direct_scan([0.5, 0.2], _ranges(X1, X2), Z)
        _assert_sane(fus)
        s = fus.summary(1)
        assert s is not None and s.components == 1 and s.weight == 1.0
        out.append(s.belief)
        assert fus.last_decision[0] == 0
    np.testing.assert_allclose(out[1].mean, out[0].mean, rtol=0, atol=1e-12)
    np.testing.assert_allclose(out[1].cov, out[0].cov, rtol=0, atol=1e-15)
    fus = GaussianSumFuser(0, [1], st)  # duplicated births merge per yaw component as well
    fus.direct_scan([0.5], _ranges(X1), np.array([_bearing(X1), _bearing(X1)]))
    s = fus.summary(1)
    assert s is not None and s.components == st.formation.birth_yaw_components


# ---------------------------------------------------------------- the observer's vertical axis


@pytest.mark.parametrize(
    "mean",
    [[0.0, 0.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [1e-200, 0.0, 1.0, 0.0]],
    ids=["at-the-observer", "straight-above", "next-to-the-axis"],
)
@pytest.mark.parametrize("sensor", ["range", "bearing", "all", "field-of-view"])
def test_a_track_on_the_observers_vertical_axis_stays_finite(
    mean: list[float], sensor: str
) -> None:
    """The range/bearing Jacobian divides by ρ (and r); at ρ = 0 it was NaN/∞: a range update
    raised ModelError, a bearing's NaN likelihood made κ NaN (ConfigError) and the field of
    view's NaN P_D a NaN assignment cost. Now the track is linearised at ρ ≥ RHO_FLOOR."""
    fov = sensor == "field-of-view"
    st = gs_settings(
        expected_clutter=2.0, field_of_view=1.0 if fov else None, use_elevation=not fov
    )
    fus = GaussianSumFuser(0, [1], st)
    fus.tracks = _track(np.array(mean), st.nscan_depth)
    nb = len(st.bearing_rows)
    bearings = np.array([[0.1, 1.4][:nb]])
    if sensor == "range":
        fus.direct_scan([np.nan], [0.05], np.zeros((0, nb)))
    elif sensor == "bearing":
        fus.direct_scan([np.nan], [np.nan], bearings)
    else:
        fus.direct_scan([1.0], [1.0], bearings)
    _assert_sane(fus)
    assert fus.tracks.size >= 1
    assert fus.decide(bearings).tolist() in ([0], [-1])


def test_births_at_a_vanishing_range_are_finite_at_the_next_scan() -> None:
    """A range of 1e-300 m is accepted (> 0) and gives births at the observer; their next
    range update divided 0 by 0 (ModelError)."""
    st = gs_settings(expected_clutter=2.0)
    fus = GaussianSumFuser(0, [1], st)
    for _ in range(2):
        fus.direct_scan([0.0], [1e-300], np.array([[0.3, 0.0]]))
        _assert_sane(fus)
        fus.predict(np.zeros(4), np.zeros((1, 4)), 0.1)
    assert fus.tracks.size > 0 and RHO_FLOOR == 1e-6


# ---------------------------------------------------------------- detection and clutter extremes


@pytest.mark.parametrize("p_detect", [1.0, 1e-6, 1e-300])
def test_extreme_detection_probabilities(p_detect: float) -> None:
    """P_D = 1 with a missed detection: the false-alarm branch keeps 1 − P_G = 0.05 of the
    weight, never 0. A tiny P_D: detections and births carry tiny but positive weights."""
    st = _with_pd(gs_settings(expected_clutter=1.0), p_detect)
    fus = _two_teammates(st)
    fus.direct_scan([0.5, 0.2], _ranges(X1, X2), np.zeros((0, 2)))  # both missed
    _assert_sane(fus)
    assert fus.tracks.size == 2
    fus.direct_scan([0.5, 0.2], _ranges(X1, X2), np.array([_bearing(X1), [-2.5, 0.3]]))
    _assert_sane(fus)
    assert fus.last_decision.tolist() == ([0, -1] if p_detect == 1.0 else [-1, -1])
    births = GaussianSumFuser(0, [1], st)
    births.direct_scan([0.5], _ranges(X1), np.array([_bearing(X1)]))
    _assert_sane(births)
    assert births.tracks.size == st.formation.birth_yaw_components


def test_a_detection_probability_whose_births_underflow_leaves_the_filter_empty() -> None:
    """P_D = 5e-324 (the smallest subnormal): every birth weight underflows to 0; the filter
    stays empty (no NaN) instead of holding zero-weight tracks."""
    st = _with_pd(gs_settings(expected_clutter=1.0), 5e-324)
    fus = GaussianSumFuser(0, [1], st)
    fus.direct_scan([0.5], _ranges(X1), np.array([_bearing(X1)]))
    assert fus.tracks.size == 0 and fus.summary(1) is None


@pytest.mark.parametrize(
    ("r", "alpha", "beta", "h", "match"),
    [
        (np.nan, [0.1], [0.0], 0.0, "a bearing, range or height is NaN"),
        (2.0, [0.1, np.inf], [0.0, 0.0], 0.0, "a bearing, range or height is NaN"),
        (2.0, [0.1], [0.0], [np.nan], "a bearing, range or height is NaN"),
        ([2.0, 3.0, 4.0], [0.1, 0.2], [0.0, 0.0], 0.0, "2 azimuths need"),
        (2.0, [0.1, 0.2], [0.0, 0.0, 0.0], 0.0, "2 azimuths need"),
    ],
)
def test_births_from_a_bad_bearing_are_refused(r, alpha, beta, h, match) -> None:
    """These gave NaN means and weights, or a raw broadcasting ValueError."""
    with pytest.raises(DataError, match=f"birth_tracks: {match}"):
        birth_tracks(
            r,
            alpha,
            beta,
            h,
            FormationSettings(),
            volume=1.0,
            range_volume=5.0,
            false_density=0.1,
        )


def test_zero_clutter_uses_the_documented_floor() -> None:
    """expected_clutter = 0: κ uses MIN_EXPECTED_CLUTTER (1e-3 per scan), so an unexplained
    bearing has a finite density and log κ is finite; the bearing is the teammate's. A zero κ
    passed to the formation directly is refused."""
    st = gs_settings(expected_clutter=0.0)
    fus = GaussianSumFuser(0, [1], st)
    fus.tracks = _track(X1, st.nscan_depth)
    fus.direct_scan([0.5], _ranges(X1), np.array([[-2.5, 0.3], _bearing(X1)]))
    _assert_sane(fus)
    assert fus.last_decision.tolist() == [1] and fus.tracks.size == 1
    with pytest.raises(ConfigError, match="false_density must be > 0"):
        formation_weights(
            np.ones(1), np.ones((1, 1)), np.ones((1, 1), bool), FormationSettings(), 0.0
        )


@pytest.mark.parametrize(
    ("outlier", "off", "kept"), [(0.01, 10.0, 1), (0.0, 3.0, 1), (0.0, 10.0, 0)]
)
def test_weights_that_underflow_empty_the_filter_without_nan(
    outlier: float, off: float, kept: int
) -> None:
    """A range 10 m off the track: with the outlier density ε/V_z (ε = 0.01) the weight keeps
    that floor; with ε = 0 the Gaussian density exp(−d²/2) underflows to exactly 0 for every
    track, and the filter is emptied (documented in ``reduce``: it waits for births) rather
    than normalised by a zero sum."""
    st = gs_settings(known_outlier_probability=outlier)
    fus = GaussianSumFuser(0, [1], st)
    fus.tracks = _track(X1, st.nscan_depth)
    fus.direct_scan([np.nan], [float(np.linalg.norm(X1[:3])) + off], np.zeros((0, 2)))
    _assert_sane(fus)
    assert fus.tracks.size == kept


# ---------------------------------------------------------------- assignment


def test_assignment_without_feasible_pairs_or_measurements() -> None:
    np.testing.assert_array_equal(assign(np.full((2, 3), np.inf), np.array([0.1, 0.2])), [-1, -1])
    np.testing.assert_array_equal(assign(np.zeros((2, 0)), np.array([0.1, 0.2])), [-1, -1])
    with pytest.raises(ModelError, match="NaN cost"):
        assign(np.array([[np.nan]]), np.array([0.1]))


# ---------------------------------------------------------------- mixture reduction


def test_identical_and_single_components_merge_exactly() -> None:
    means = np.stack([X1, X1, X1])
    covs = np.stack([COV] * 3)
    w = np.array([0.2, 0.3, 0.5])
    groups = merge_groups(means, covs, w, 3.0, angle_index=3)
    assert len(groups) == 1 and sorted(groups[0].tolist()) == [0, 1, 2]
    mean, cov, total = merge_moments(means, covs, w, groups[0], angle_index=3)
    np.testing.assert_array_equal(mean, X1)
    np.testing.assert_allclose(cov, COV, rtol=1e-15)
    assert total == pytest.approx(1.0)
    one = merge_groups(X1[None], COV[None], np.ones(1), 3.0)
    assert [g.tolist() for g in one] == [[0]]
    assert merge_groups(np.zeros((0, 4)), np.zeros((0, 4, 4)), np.zeros(0), 3.0) == []


def test_a_singular_covariance_merges_only_with_an_exact_duplicate() -> None:
    """np.linalg.inv raised LinAlgError for a singular covariance. Now its component is at
    distance 0 from an identical mean and ∞ from any other; regular pairs are unchanged."""
    singular = np.diag([0.01, 0.01, 0.01, 0.0])
    covs = np.stack([COV, singular, COV])
    means = np.stack([X1, X1 + 0.001, X1 + 0.002])
    D = pairwise_mahalanobis(means, covs, angle_index=3)
    assert np.isinf(D[0, 1]) and np.isinf(D[1, 2]) and D[1, 1] == 0.0
    regular = pairwise_mahalanobis(means[[0, 2]], covs[[0, 2]], angle_index=3)
    assert D[0, 2] == regular[0, 1]
    groups = merge_groups(means, covs, np.array([0.5, 0.3, 0.2]), 3.0, angle_index=3)
    assert sorted(g.tolist() for g in groups) == [[0, 2], [1]]
    same = merge_groups(np.stack([X1, X1]), np.stack([COV, singular]), np.ones(2), 3.0)
    assert [g.tolist() for g in same] == [[0, 1]]
    nearly = np.diag([0.01, 0.01, 0.01, 1e-300])  # invertible: the ordinary test applies
    assert (
        len(merge_groups(np.stack([X1, X1 + 0.001]), np.stack([COV, nearly]), np.ones(2), 3.0)) == 2
    )


@pytest.mark.parametrize("scale", [5e-324, 1e-310, 1e308])
def test_merge_moments_do_not_depend_on_the_scale_of_the_weights(scale: float) -> None:
    """Subnormal weights made every product w·m underflow to 0 (merged mean [3, 1, 0, 0] for
    [3, 1, 0.5, 0.3]); huge ones overflowed the sum (NaN mean)."""
    means = np.stack([X1, X1, X1 + np.array([1.0, 0.0, 0.0, 0.0])])
    covs = np.stack([COV] * 3)
    ref = merge_moments(means, covs, np.ones(3) / 3, np.arange(3), angle_index=3)
    with np.errstate(over="ignore"):
        got = merge_moments(means, covs, np.full(3, scale), np.arange(3), angle_index=3)
    np.testing.assert_allclose(got[0], ref[0], rtol=1e-15)
    np.testing.assert_allclose(got[1], ref[1], rtol=1e-14, atol=1e-17)
    with pytest.raises(ModelError, match="total weight must be > 0"):
        merge_moments(means, covs, np.zeros(3), np.arange(3))


def test_nscan_depth_larger_than_the_history() -> None:
    """Tracks younger than N scans have their own id as root (new_history repeats it), so a
    family is the descendants of one birth and pruning works before N scans have passed."""
    h = new_history(np.array([0, 1]), 10)
    assert h.shape == (2, 11) and (h == np.array([[0], [1]])).all()
    children = branch(h, np.array([0, 0, 1]), np.array([2, 3, 4]))
    np.testing.assert_array_equal(children[:, 0], [0, 0, 1])
    keep = family_keep_mask(children, np.array([4e-4, 4e-4, 0.9992]), 1e-3)
    np.testing.assert_array_equal(keep, [False, False, True])
    keep = family_keep_mask(children, np.array([6e-4, 6e-4, 0.9988]), 1e-3)
    np.testing.assert_array_equal(keep, [True, True, True])
    with pytest.raises(ModelError, match="depth"):
        new_history(np.array([0]), 0)


# ---------------------------------------------------------------- received beliefs


def _from_robot_1(cov: np.ndarray) -> EquivalentMeasurement:
    """Robot 1's one-track message to robot 0: its track at ``X1`` with covariance ``cov``."""
    return one_track_message(
        sender=1,
        subject=0,
        means=X1[None],
        covs=cov[None],
        prior_means=X1[None],
        prior_covs=cov[None],
    )


@pytest.mark.parametrize(
    "cov",
    [np.zeros((4, 4)), np.diag([0.01, 0.01, 0.01, 0.0]), np.eye(4) * 1e-200],
    ids=["zero", "singular", "determinant-underflows"],
)
def test_a_degenerate_received_covariance_is_refused(cov: np.ndarray) -> None:
    """A received track with such a covariance was born with weight e^{−γ/2}/√det(2πP) = ∞;
    normalised to NaN it emptied every track of the receiver's filter. Now the message is
    refused (DataError) and the receiver keeps its tracks."""
    st = gs_settings()
    fus = GaussianSumFuser(0, [1, 2], st)
    fus.tracks = _track(-X1, st.nscan_depth)
    with pytest.raises(DataError, match="positive definite"):
        _from_robot_1(cov)
    msg = _from_robot_1(COV)
    assert fus.fuse(msg) == "mutual"
    _assert_sane(fus)
    assert fus.tracks.size == 2
