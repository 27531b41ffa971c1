"""Hand-computed cases of covariance intersection and information de-correlation that the
behaviour tests leave free."""

from __future__ import annotations

import numpy as np
import pytest

from relloc.fusion.covariance_intersection import covariance_intersection
from relloc.fusion.decorrelation import decorrelated_fusion


def test_ci_with_an_estimate_better_in_every_direction_returns_it_exactly() -> None:
    # Y_a ≥ Y_b: det(ω Y_a + (1 − ω) Y_b) grows with ω, the optimum is the end point ω = 1
    P_a = np.diag([0.1, 0.2, 0.3])
    P_b = np.diag([1.0, 2.0, 3.0])
    x_a, x_b = np.array([1.0, 2.0, 3.0]), np.array([0.0, 0.0, 0.0])
    x, P, omega = covariance_intersection(x_a, P_a, x_b, P_b)
    assert omega == 1.0
    np.testing.assert_allclose(P, P_a, rtol=1e-12)
    np.testing.assert_allclose(x, x_a, rtol=1e-12)


def test_ci_interior_optimum_matches_the_closed_form() -> None:
    # Y_a = diag(4, 1), Y_b = diag(1, 2): d/dω log det = 3/(1 + 3ω) − 1/(2 − ω) = 0 → ω = 5/6
    P_a, P_b = np.diag([0.25, 1.0]), np.diag([1.0, 0.5])
    _, P, omega = covariance_intersection(np.zeros(2), P_a, np.ones(2), P_b)
    assert omega == pytest.approx(5.0 / 6.0, abs=1e-4)
    np.testing.assert_allclose(P, np.diag([1 / 3.5, 1 / (7 / 6)]), rtol=1e-4)


def test_information_lost_by_the_sender_is_not_removed_from_the_receiver() -> None:
    # the sender's track is less certain now than at its previous broadcast (ΔY = I − 2I < 0):
    # its increment is clipped to 0, the receiver keeps its estimate unchanged
    x_i, P_i = np.array([1.0, 2.0, 0.5, 0.1]), np.eye(4) * 0.3
    x_post, P_post = np.array([1.2, 2.1, 0.4, 0.2]), np.eye(4)
    x_prior, P_prior = x_post.copy(), np.eye(4) * 0.5
    x, P = decorrelated_fusion(x_i, P_i, x_post, P_post, x_prior, P_prior)
    np.testing.assert_allclose(P, P_i, atol=1e-12)
    np.testing.assert_allclose(x, x_i, atol=1e-12)


def test_decorrelated_fusion_is_unaffected_by_a_heading_wrap() -> None:
    # the same estimates with the received headings written 2π apart fuse to the same result
    x_i, P_i = np.array([1.0, 2.0, 0.5, 3.0]), np.eye(4) * 0.3
    x_post, P_post = np.array([1.2, 2.1, 0.4, -3.1]), np.eye(4) * 0.1
    x_prior, P_prior = np.array([1.1, 2.0, 0.4, 3.1]), np.eye(4) * 0.2
    x, P = decorrelated_fusion(x_i, P_i, x_post, P_post, x_prior, P_prior)
    shift = np.array([0.0, 0.0, 0.0, 2 * np.pi])
    x2, P2 = decorrelated_fusion(x_i, P_i, x_post + shift, P_post, x_prior, P_prior)
    np.testing.assert_allclose(x, x2, atol=1e-12)
    np.testing.assert_allclose(P, P2, atol=1e-12)
    # and the fused heading lies between the two (on the circle), near ±π
    assert abs(x[3]) > 3.0
