"""Planar measurement models: values, Jacobians against finite differences, joint rows."""

import numpy as np
import pytest

from relloc.errors import ModelError
from relloc.models.planar_measurement import (
    RowKind,
    ScalarRows,
    bearing,
    bearing_jacobians,
    linearise_rows,
    planar_range,
    range_bearing,
    range_bearing_jacobians,
    range_jacobians,
)


def _numeric(fun, x, eps=1e-6):
    cols = []
    for k in range(x.size):
        d = np.zeros_like(x)
        d[k] = eps
        diff = np.asarray(fun(x + d)) - np.asarray(fun(x - d))
        cols.append(diff / (2 * eps))
    return np.stack(cols, axis=-1)


def test_bearing_and_range_values():
    obs = np.array([1.0, 2.0, np.pi / 2])
    tgt = np.array([1.0, 5.0])
    assert bearing(obs, tgt) == pytest.approx(0.0, abs=1e-12)
    assert planar_range(obs, tgt) == pytest.approx(3.0)
    assert np.allclose(range_bearing(obs, np.array([0.0, 2.0])), [1.0, np.pi / 2])


def test_jacobians_match_finite_differences_batched():
    rng = np.random.default_rng(3)
    obs = rng.normal(size=(6, 3)) * [5, 5, 1]
    tgt = rng.normal(size=(6, 2)) * 5 + 20
    Bo, Bt = bearing_jacobians(obs, tgt)
    Ro, Rt = range_jacobians(obs, tgt)
    RBo, RBt = range_bearing_jacobians(obs, tgt)
    for k in range(6):
        o_k, t_k = obs[k], tgt[k]
        assert np.allclose(Bo[k], _numeric(lambda o, t_k=t_k: bearing(o, t_k), o_k), atol=1e-7)
        assert np.allclose(Bt[k], _numeric(lambda t, o_k=o_k: bearing(o_k, t), t_k), atol=1e-7)
        assert np.allclose(Ro[k], _numeric(lambda o, t_k=t_k: planar_range(o, t_k), o_k), atol=1e-7)
        assert np.allclose(Rt[k], _numeric(lambda t, o_k=o_k: planar_range(o_k, t), t_k), atol=1e-7)
    assert np.allclose(RBo[:, 0], Ro) and np.allclose(RBo[:, 1], Bo)
    assert np.allclose(RBt[:, 0], Rt) and np.allclose(RBt[:, 1], Bt)


def test_coincident_points_raise_model_error():
    with pytest.raises(ModelError):
        bearing(np.zeros(3), np.zeros(2))


def test_linearised_rows_match_dense_numeric_jacobian():
    rng = np.random.default_rng(4)
    X = rng.normal(size=(3, 3)) * [10, 10, 1]
    rows = ScalarRows(
        kind=np.array([RowKind.BEARING, RowKind.RANGE, RowKind.BEARING, RowKind.POSE_HEADING]),
        observer=np.array([0, 1, 2, 2]),
        target=np.array([1, 2, -1, -1]),
        landmark_xy=np.array([[0.0, 0.0], [0.0, 0.0], [30.0, -4.0], [0.0, 0.0]]),
        z=np.array([0.3, 12.0, -1.0, 3.1]),
        sigma=np.array([0.1, 0.5, 0.1, 0.05]),
        group=np.array([0, 0, 1, 2]),
    )
    lin = linearise_rows(X, rows)

    def h(x):
        return rows.z - linearise_rows(x.reshape(3, 3), rows).residual

    H_num = _numeric(h, X.reshape(-1))
    assert np.allclose(lin.dense_jacobian(3), H_num, atol=1e-6)
    # residuals of angular rows are wrapped
    assert np.all(np.abs(lin.residual[[0, 2, 3]]) <= np.pi)


def test_scalar_rows_validate_shapes():
    with pytest.raises(ModelError, match="sigma"):
        ScalarRows(
            kind=np.zeros(2, dtype=np.int64),
            observer=np.zeros(2, dtype=np.int64),
            target=np.zeros(2, dtype=np.int64),
            landmark_xy=np.zeros((2, 2)),
            z=np.zeros(2),
            sigma=np.ones(3),
            group=np.zeros(2, dtype=np.int64),
        )
