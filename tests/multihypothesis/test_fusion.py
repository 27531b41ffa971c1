"""Pose composition of beliefs, de-correlated fusion, covariance intersection, messages."""

from __future__ import annotations

import numpy as np
import pytest

from relloc.core.poses import compose
from relloc.errors import DataError
from relloc.fusion.covariance_intersection import covariance_intersection
from relloc.fusion.decorrelation import decorrelated_fusion
from relloc.fusion.messages import EquivalentMeasurement
from relloc.fusion.pose_beliefs import compose_beliefs, invert_beliefs, register_prior


def _spd(rng: np.random.Generator, scale: float = 1.0) -> np.ndarray:
    A = rng.normal(size=(4, 4))
    return scale * (A @ A.T + 4 * np.eye(4))


def test_inverse_round_trip_and_compose_with_inverse() -> None:
    rng = np.random.default_rng(0)
    means = rng.normal(size=(3, 4))
    covs = np.stack([_spd(rng, 0.01) for _ in range(3)])
    m2, P2 = invert_beliefs(*invert_beliefs(means, covs))
    np.testing.assert_allclose(m2, means, atol=1e-12)
    np.testing.assert_allclose(P2, covs, atol=1e-12)
    inv_m, _ = invert_beliefs(means, covs)
    for k in range(3):
        out, _, _ = compose(means[k], inv_m[k])
        np.testing.assert_allclose(out, np.zeros(4), atol=1e-12)
    # a ⊕ (⊖a ⊕ b) = b for means
    b = rng.normal(size=(1, 4))
    rel, _, _ = compose(inv_m[0], b[0])
    back, P, from_a = compose_beliefs(means[0], covs[0], rel[None], covs[:1])
    np.testing.assert_allclose(back[0], b[0], atol=1e-12)
    assert np.all(np.linalg.eigvalsh(P[0] - from_a[0]) > -1e-12)
    pm, pP = register_prior(means[0], rel[None], covs[:1], from_a)
    np.testing.assert_allclose(pm, back)
    np.testing.assert_allclose(pP, P)


def test_decorrelated_fusion_of_a_copy_adds_nothing() -> None:
    rng = np.random.default_rng(1)
    x = rng.normal(size=4)
    P = _spd(rng, 0.1)
    fused_x, fused_P = decorrelated_fusion(x, P, x, P, x, P)
    np.testing.assert_allclose(fused_P, P, atol=1e-12)
    np.testing.assert_allclose(fused_x, x, atol=1e-12)
    # never below the single copy even when the sender's prior is stale and wider
    fused_x, fused_P = decorrelated_fusion(x, P, x, P, x, 2.0 * P)
    assert np.all(np.linalg.eigvalsh(fused_P - 0.5 * P) > -1e-12)
    naive = np.linalg.inv(2.0 * np.linalg.inv(P))
    assert np.trace(fused_P) > np.trace(naive) - 1e-12


def test_decorrelated_fusion_adds_exactly_the_new_information() -> None:
    rng = np.random.default_rng(2)
    P_i = _spd(rng, 0.2)
    x_i = rng.normal(size=4)
    P_prior = _spd(rng, 0.3)
    x_prior = x_i + 0.1 * rng.normal(size=4)
    H = rng.normal(size=(2, 4))
    R = np.diag([0.05, 0.02])
    z = H @ x_prior + rng.normal(size=2) * 0.1
    Y_post = np.linalg.inv(P_prior) + H.T @ np.linalg.inv(R) @ H
    P_post = np.linalg.inv(Y_post)
    x_post = P_post @ (np.linalg.inv(P_prior) @ x_prior + H.T @ np.linalg.inv(R) @ z)
    fused_x, fused_P = decorrelated_fusion(
        x_i, P_i, x_post, P_post, x_prior, P_prior, angle_index=None
    )
    Y = np.linalg.inv(P_i) + H.T @ np.linalg.inv(R) @ H
    y = np.linalg.inv(P_i) @ x_i + (Y_post @ x_post - np.linalg.inv(P_prior) @ x_prior)
    np.testing.assert_allclose(fused_P, np.linalg.inv(Y), atol=1e-10)
    np.testing.assert_allclose(fused_x, np.linalg.solve(Y, y), atol=1e-10)


def test_covariance_intersection_is_conservative() -> None:
    rng = np.random.default_rng(4)
    x = rng.normal(size=4)
    P = _spd(rng, 0.1)
    fx, fP, omega = covariance_intersection(x, P, x, P)
    np.testing.assert_allclose(fP, P, atol=1e-10)
    np.testing.assert_allclose(fx, x, atol=1e-10)
    assert 0.0 <= omega <= 1.0
    P_b = np.diag([10.0, 10.0, 10.0, 0.01])
    _, fP, omega = covariance_intersection(x, P, x + 0.1, P_b)
    assert np.linalg.det(fP) <= min(np.linalg.det(P), np.linalg.det(P_b)) + 1e-12


def _message_fields() -> dict[str, object]:
    m = np.zeros((2, 4))
    P = np.broadcast_to(np.eye(4), (2, 4, 4))
    return {
        "sender": 0,
        "subject": 1,
        "time": 1.0,
        "means": m,
        "covs": P,
        "prior_means": m,
        "prior_covs": P,
        "weights": np.array([2.0, 2.0]),
    }


def test_equivalent_measurement_normalises_weights() -> None:
    msg = EquivalentMeasurement(**_message_fields())  # type: ignore[arg-type]
    np.testing.assert_allclose(msg.weights, [0.5, 0.5])


@pytest.mark.parametrize(
    ("field", "bad", "message"),
    [
        ("covs", np.broadcast_to(np.eye(4), (1, 4, 4)), "covs"),
        ("sender", 1, "differ"),
        ("means", np.full((2, 4), np.nan), "non-finite"),
    ],
)
def test_equivalent_measurement_rejects_bad_fields(field: str, bad: object, message: str) -> None:
    fields = _message_fields() | {field: bad}
    with pytest.raises(DataError, match=message):
        EquivalentMeasurement(**fields)  # type: ignore[arg-type]
