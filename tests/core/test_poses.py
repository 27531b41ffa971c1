"""Pose algebra: ⊕/⊖ round trips and analytic Jacobians against finite differences."""

import numpy as np
import pytest

from relloc.core import compose, inverse, relative, wrap_angle
from relloc.core.recording import compose_pose, relative_pose
from relloc.errors import ModelError


def numeric_jacobian(f, x, eps=1e-6):
    x = np.asarray(x, dtype=float)
    f0 = f(x)
    J = np.zeros((f0.size, x.size))
    for i in range(x.size):
        dx = np.zeros_like(x)
        dx[i] = eps
        J[:, i] = (f(x + dx) - f(x - dx)) / (2 * eps)
    return J


@pytest.mark.parametrize("n", [3, 4])
@pytest.mark.parametrize("trial", range(10))
def test_round_trip_and_jacobians(n, trial):
    rng = np.random.default_rng(trial)
    a = rng.normal(size=n) * 3
    b = rng.normal(size=n) * 3

    ab, Ja, Jb = compose(a, b)
    inv_a, Jinv = inverse(a)
    back, _, _ = compose(inv_a, ab)
    assert np.allclose(back[:-1], b[:-1])
    assert np.isclose(wrap_angle(back[-1] - b[-1]), 0.0, atol=1e-12)
    identity, _, _ = compose(a, inv_a)
    assert np.allclose(identity, 0.0, atol=1e-12)
    assert np.allclose(Ja, numeric_jacobian(lambda x: compose(x, b)[0], a), atol=1e-6)
    assert np.allclose(Jb, numeric_jacobian(lambda x: compose(a, x)[0], b), atol=1e-6)
    assert np.allclose(Jinv, numeric_jacobian(lambda x: inverse(x)[0], a), atol=1e-6)
    rel, Ra, Rb = relative(a, b)
    assert np.allclose(rel, compose(inv_a, b)[0])
    assert np.allclose(Ra, numeric_jacobian(lambda x: relative(x, b)[0], a), atol=1e-6)
    assert np.allclose(Rb, numeric_jacobian(lambda x: relative(a, x)[0], b), atol=1e-6)


def test_bad_layout_is_a_clear_error():
    with pytest.raises(ModelError, match=r"3 .* or 4"):
        compose(np.zeros(2), np.zeros(2))
    with pytest.raises(ModelError, match="differ"):
        compose(np.zeros(3), np.zeros(4))


def test_vectorised_compose_pose_matches_compose_and_inverts_relative_pose() -> None:
    """``core.recording.compose_pose`` is :func:`compose` row by row (heading wrapped), and
    ``a ⊕ (⊖a ⊕ b) = b`` with ``relative_pose``."""
    rng = np.random.default_rng(91)
    a = rng.uniform(-4.0, 4.0, size=(50, 4))
    b = rng.uniform(-4.0, 4.0, size=(50, 4))
    out = compose_pose(a, b)
    for k in range(a.shape[0]):
        expected = compose(a[k], b[k])[0]
        np.testing.assert_allclose(out[k, :3], expected[:3], atol=1e-12)
        assert abs(wrap_angle(out[k, 3] - expected[3])) < 1e-12 and abs(out[k, 3]) <= np.pi
    back = compose_pose(a, relative_pose(a, b))
    np.testing.assert_allclose(back[:, :3], b[:, :3], atol=1e-12)
    np.testing.assert_allclose(wrap_angle(back[:, 3] - b[:, 3]), 0.0, atol=1e-12)
