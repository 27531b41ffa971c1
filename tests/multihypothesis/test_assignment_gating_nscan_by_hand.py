"""Hand-computed cases of assignment, gating and N-scan pruning that the behaviour tests leave
free."""

from __future__ import annotations

import numpy as np

from relloc.association.assignment import assign
from relloc.association.gating import GateSettings, modified_gate_covariance
from relloc.association.mixture_reduction import merge_groups, prune_mask
from relloc.association.nscan import branch, family_keep_mask


def test_each_target_pays_its_own_miss_cost() -> None:
    # one measurement, equally good for both targets: the target whose miss is cheap goes
    # without it (2 + 0.5 < 2 + 3)
    out = assign(np.array([[2.0], [2.0]]), np.array([3.0, 0.5]))
    np.testing.assert_array_equal(out, [0, -1])
    out = assign(np.array([[2.0], [2.0]]), np.array([0.5, 3.0]))
    np.testing.assert_array_equal(out, [-1, 0])


def test_a_row_of_inf_leaves_its_target_missed_even_with_a_huge_miss_cost() -> None:
    # the forbidden pairing (stand-in 1e12) is cheaper than this miss, yet is never reported
    out = assign(np.array([[np.inf, 1.0]]), np.array([2e12]))
    np.testing.assert_array_equal(out, [1])
    out = assign(np.array([[np.inf, np.inf]]), np.array([2e12]))
    np.testing.assert_array_equal(out, [-1])


def _gate(yaw_var: float, H: np.ndarray, speed: float = 2.0) -> np.ndarray:
    S = np.eye(H.shape[0])[None] * 0.01
    return modified_gate_covariance(
        S, H[None], np.array([yaw_var]), np.array([speed]), GateSettings(horizon=0.5)
    )[0]


def test_uniform_yaw_is_judged_by_the_standard_deviation() -> None:
    H = np.array([[1.0, 0.0, 0.0, 0.0]])
    # σ_φ = √0.3 ≈ 0.55 > 0.5 (yaw_sigma_uniform): widened by (|v| τ)² = 1
    np.testing.assert_allclose(_gate(0.3, H), [[1.01]])
    # σ_φ = √0.2 ≈ 0.45 < 0.5: untouched
    np.testing.assert_allclose(_gate(0.2, H), [[0.01]])


def test_the_yaw_disc_is_horizontal() -> None:
    # a height measurement (∂h/∂z = 1 only) is not widened by a horizontal disc
    H = np.array([[0.0, 0.0, 1.0, 0.0], [0.0, 1.0, 0.5, 0.0]])
    out = _gate(4 * np.pi, H)
    np.testing.assert_allclose(out, 0.01 * np.eye(2) + np.array([[0.0, 0.0], [0.0, 1.0]]))


def test_branch_drops_the_oldest_ancestor_and_appends_the_child() -> None:
    history = np.array([[1, 2, 3, 4], [5, 6, 7, 8]])
    out = branch(history, np.array([1, 0, 1]), np.array([10, 11, 12]))
    np.testing.assert_array_equal(out, [[6, 7, 8, 10], [2, 3, 4, 11], [6, 7, 8, 12]])


def test_a_family_exactly_at_the_threshold_is_kept() -> None:
    history = np.array([[1, 9], [1, 8], [2, 7], [3, 6]])
    weights = np.array([0.125, 0.125, 0.5, 0.0625])
    keep = family_keep_mask(history, weights, 0.25)
    np.testing.assert_array_equal(keep, [True, True, True, False])


def test_components_exactly_at_the_merge_threshold_merge() -> None:
    means = np.array([[0.0, 0.0, 0.0, 0.0], [2.0, 0.0, 0.0, 0.0], [5.0, 0.0, 0.0, 0.0]])
    covs = np.broadcast_to(np.eye(4), (3, 4, 4)).copy()
    groups = merge_groups(means, covs, np.array([0.5, 0.3, 0.2]), 4.0)
    assert [g.tolist() for g in groups] == [[0, 1], [2]]


def test_greedy_merging_partitions_the_components() -> None:
    # B lies within the threshold of both A and C, A and C do not: A (heaviest) takes B, and C,
    # processed next, must not take B again (each component belongs to exactly one group)
    means = np.zeros((3, 4))
    means[:, 0] = [0.0, 1.5, 3.0]
    covs = np.broadcast_to(np.eye(4), (3, 4, 4)).copy()
    groups = merge_groups(means, covs, np.array([0.5, 0.2, 0.3]), 4.0)
    assert [g.tolist() for g in groups] == [[0, 1], [2]]


def test_a_weight_exactly_at_the_prune_threshold_is_kept() -> None:
    keep = prune_mask(np.array([0.125, 0.5, 0.25]), 0.25)
    np.testing.assert_array_equal(keep, [False, True, True])
