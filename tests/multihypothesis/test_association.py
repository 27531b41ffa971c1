"""Gating, formation, assignment, mixture reduction and N-scan pruning."""

from __future__ import annotations

import numpy as np
import pytest

from relloc.association.assignment import assign
from relloc.association.gating import GateSettings, modified_gate_covariance
from relloc.association.hypotheses import FormationSettings, birth_tracks, formation_weights
from relloc.association.mixture_reduction import (
    absorb_weights,
    cap_mask,
    heaviest_mask,
    merge_groups,
    merge_moments,
    prune_mask,
)
from relloc.association.nscan import branch, family_keep_mask, new_history
from relloc.errors import ConfigError, ModelError


def _random_spd(rng: np.random.Generator, n: int) -> np.ndarray:
    A = rng.normal(size=(n, n))
    return A @ A.T + n * np.eye(n)


def test_gate_settings_are_validated() -> None:
    with pytest.raises(ConfigError, match="p_gate"):
        GateSettings(p_gate=0.0)


def test_modified_gate_only_widens_uniform_yaw_tracks() -> None:
    S = np.broadcast_to(np.eye(2) * 0.01, (2, 2, 2)).copy()
    H = np.zeros((2, 2, 4))
    H[:, 0, 0] = H[:, 1, 1] = 1.0
    out = modified_gate_covariance(
        S, H, np.array([4 * np.pi, 0.01]), np.array([0.5, 0.5]), GateSettings(horizon=0.1)
    )
    np.testing.assert_allclose(out[1], S[1])
    np.testing.assert_allclose(out[0], S[0] + 0.05**2 * np.eye(2))


def test_merge_preserves_first_two_moments() -> None:
    rng = np.random.default_rng(3)
    k, n = 5, 4
    means = rng.normal(size=(k, n))
    covs = np.stack([_random_spd(rng, n) for _ in range(k)])
    w = rng.random(k)
    mean, cov, total = merge_moments(means, covs, w, np.arange(k))
    ref_mean = np.average(means, axis=0, weights=w)
    spread = np.einsum("k,ki,kj->ij", w, means - ref_mean, means - ref_mean) / w.sum()
    ref_cov = np.average(covs, axis=0, weights=w) + spread
    np.testing.assert_allclose(mean, ref_mean, atol=1e-12)
    np.testing.assert_allclose(cov, ref_cov, atol=1e-12)
    assert total == pytest.approx(w.sum())


def test_merge_aligns_headings_across_the_wrap() -> None:
    means = np.array([[0.0, 0.0, 0.0, np.pi - 0.05], [0.0, 0.0, 0.0, -np.pi + 0.05]])
    covs = np.broadcast_to(np.eye(4) * 0.1, (2, 4, 4))
    mean, _, _ = merge_moments(means, covs, np.array([0.5, 0.5]), np.arange(2), angle_index=3)
    assert abs(abs(mean[3]) - np.pi) < 1e-9
    groups = merge_groups(means, covs, np.array([0.6, 0.4]), 4.0, angle_index=3)
    assert len(groups) == 1


def test_merge_groups_separates_far_and_broad_components() -> None:
    sharp = np.eye(4) * 0.01
    broad = np.diag([0.1, 0.1, 0.05, 4 * np.pi])
    means = np.array([[0, 0, 0, 0.0], [0.01, 0, 0, 0.0], [5, 0, 0, 0.0], [0, 0, 0, 1.0]])
    covs = np.stack([sharp, sharp, sharp, broad])
    groups = merge_groups(means, covs, np.array([0.4, 0.3, 0.2, 0.1]), 4.0, angle_index=3)
    assert [sorted(g.tolist()) for g in groups] == [[0, 1], [2], [3]]
    with pytest.raises(ModelError):
        merge_groups(means, covs, np.ones(4), -1.0)


def test_prune_and_cap_keep_the_heaviest_per_group() -> None:
    w = np.array([1e-5, 2e-5, 0.5, 0.2])
    groups = np.array([0, 0, 1, 1])
    np.testing.assert_array_equal(prune_mask(w, 1e-3, groups), [False, True, True, True])
    np.testing.assert_array_equal(cap_mask(w, 2), [False, False, True, True])
    np.testing.assert_array_equal(cap_mask(w, 1, groups), [False, True, True, False])
    with pytest.raises(ModelError, match="max_components"):
        cap_mask(w, 0)


def test_both_layouts_reduce_alike() -> None:
    """A rectangular batch ``(B, K)`` and the same components flat with ``groups`` give the same
    heaviest, prune and cap masks (ties: the lower index first)."""
    rng = np.random.default_rng(5)
    w = rng.random((4, 6))
    w[1, 2] = w[1, 4] = w[1].max() + 0.1  # a tie for the heaviest
    w[2, :] = 0.0
    w[2, 3] = 1.0  # a single live component
    flat, groups = w.reshape(-1), np.repeat(np.arange(4), 6)
    threshold = 0.3 * w.max(axis=-1, keepdims=True)
    np.testing.assert_array_equal(heaviest_mask(w).reshape(-1), heaviest_mask(flat, groups))
    assert heaviest_mask(w)[1, 2] and not heaviest_mask(w)[1, 4]
    np.testing.assert_array_equal(
        prune_mask(w, threshold).reshape(-1),
        prune_mask(flat, np.repeat(threshold[:, 0], 6), groups),
    )
    for cap in (1, 2, 5, 6):
        np.testing.assert_array_equal(cap_mask(w, cap).reshape(-1), cap_mask(flat, cap, groups))
        assert (cap_mask(w, cap).sum(axis=-1) == cap).all()


def test_absorb_moves_the_weights_into_the_chosen_component() -> None:
    w = np.array([[0.2, 0.5, 0.1, 0.2], [0.4, 0.3, 0.2, 0.1]])
    into = heaviest_mask(w)
    members = np.array([[True, True, False, True], [False, False, False, False]])
    out = absorb_weights(w, into, members)
    np.testing.assert_allclose(out, [[0.0, 0.9, 0.1, 0.0], [0.4, 0.3, 0.2, 0.1]])
    np.testing.assert_allclose(out.sum(axis=-1), w.sum(axis=-1))


def test_nscan_prunes_light_families_but_keeps_the_best() -> None:
    hist = new_history(np.array([10, 11, 12]), 2)
    assert hist.shape == (3, 3)
    kids = branch(hist, np.array([0, 0, 1, 2]), np.array([20, 21, 22, 23]))
    np.testing.assert_array_equal(kids[:, 0], [10, 10, 11, 12])
    np.testing.assert_array_equal(kids[:, -1], [20, 21, 22, 23])
    w = np.array([0.5, 0.45, 0.0004, 0.0496])
    np.testing.assert_array_equal(family_keep_mask(kids, w, 0.01), [True, True, False, True])
    # a lone heaviest family below the threshold is still kept
    np.testing.assert_array_equal(family_keep_mask(kids[:1], np.array([0.001]), 0.01), [True])


def test_assignment_one_to_one_with_missed_targets() -> None:
    cost = np.array([[1.0, 5.0, np.inf], [1.5, np.inf, np.inf], [np.inf, np.inf, np.inf]])
    out = assign(cost, np.array([10.0, 10.0, 10.0]))
    np.testing.assert_array_equal(out, [1, 0, -1])
    np.testing.assert_array_equal(assign(cost, np.array([0.1, 0.1, 0.1])), [-1, -1, -1])
    with pytest.raises(ModelError):
        assign(cost, np.ones(2))


def test_formation_and_birth_weights_follow_eq7_and_eq13() -> None:
    st = FormationSettings(birth_yaw_components=1)
    w_fa, w_det = formation_weights(
        np.array([0.7, 0.3]),
        np.array([[2.0, 4.0], [1.0, 8.0]]),
        np.array([[True, False], [True, True]]),
        st,
        0.5,
    )
    np.testing.assert_allclose(w_fa, np.array([0.7, 0.3]) * (1 - 0.95 * 0.95))
    np.testing.assert_allclose(
        w_det, [[0.7 * 0.95 * 4.0, 0.0], [0.3 * 0.95 * 2.0, 0.3 * 0.95 * 16]]
    )
    r, alpha, beta = 3.0, np.array([0.3, 0.3]), np.array([0.2, 0.6])
    h = r * np.sin(0.2)
    means, covs, w = birth_tracks(
        r, alpha, beta, h, st, volume=2.0, range_volume=10.0, false_density=0.25
    )
    np.testing.assert_allclose(
        means[0], [r * np.cos(0.2) * np.cos(0.3), r * np.cos(0.2) * np.sin(0.3), h, 0.0]
    )
    np.testing.assert_allclose(covs[0], np.diag([0.1, 0.1, 0.05, 4 * np.pi]))
    # P_B · (1/V_r) · N(h; r sin β, 0.05) · P_D / (V κ), the height exactly consistent
    assert w[0] == pytest.approx(0.5 / 10.0 / np.sqrt(2 * np.pi * 0.05) * 0.95 / (2.0 * 0.25))
    assert w[1] < 1e-3 * w[0]
    # K yaw components: same position block, yaw 2πk/K with σ = π/K, weight split K ways
    m4, c4, w4 = birth_tracks(
        r,
        alpha,
        beta,
        h,
        FormationSettings(birth_yaw_components=4),
        volume=2.0,
        range_volume=10.0,
        false_density=0.25,
    )
    assert m4.shape == (8, 4) and c4.shape == (8, 4, 4)
    np.testing.assert_allclose(m4[:4, 3], [0.0, np.pi / 2, np.pi, 3 * np.pi / 2])
    np.testing.assert_allclose(m4[:4, :3], np.repeat(means[:1, :3], 4, axis=0))
    np.testing.assert_allclose(c4[:, 3, 3], (np.pi / 4) ** 2)
    np.testing.assert_allclose(w4.reshape(2, 4).sum(axis=1), w)
    with pytest.raises(ConfigError, match="p_birth"):
        FormationSettings(p_birth=0.0)
    with pytest.raises(ConfigError, match="birth_yaw_components"):
        FormationSettings(birth_yaw_components=0)
