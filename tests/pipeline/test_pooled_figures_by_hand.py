"""Pooled figures of :mod:`relloc.pipeline.evaluation` on hand-made evaluations whose every number
is worked out by hand: the steady-state cut (age ≥ settle_s), position / yaw RMSE, the ±3σ share
at its boundary, ANIS and the NIS share with mixed degrees of freedom, the most common NIS dof,
the run-averaged NEES table and the convergence time at its edges."""

from __future__ import annotations

import math

import numpy as np
import pytest

from relloc.core.estimates import BeliefSeries
from relloc.errors import ConfigError
from relloc.pipeline.evaluation import (
    SeriesEvaluation,
    accuracy_and_consistency,
    at_times,
    convergence_time,
    run_averaged_nees,
)


def _evaluation(
    frame: str,
    t: list[float],
    error: list[list[float]],
    *,
    sigma: list[list[float]] | None = None,
    nees: list[float] | None = None,
    age: list[float] | None = None,
    update_age: list[float] = (),
    nis: list[float] = (),
    nis_dof: list[int] = (),
) -> SeriesEvaluation:
    k = len(t)
    err = np.array(error, dtype=float).reshape(k, -1)
    return SeriesEvaluation(
        owner="a",
        subject="b",
        track="",
        platform="ground",
        frame=frame,
        t=np.array(t, dtype=float),
        error=err,
        sigma=np.ones_like(err) if sigma is None else np.array(sigma, dtype=float),
        nees=np.ones(k) if nees is None else np.array(nees, dtype=float),
        age=np.array(t if age is None else age, dtype=float),
        cond_p=np.zeros(k),
        update_t=np.array(update_age, dtype=float),
        update_age=np.array(update_age, dtype=float),
        nis=np.array(nis, dtype=float),
        nis_dof=np.array(nis_dof, dtype=np.int64),
        cond_r=np.zeros(len(nis)),
        cond_s=np.zeros(len(nis)),
    )


def test_accuracy_and_consistency_by_hand() -> None:
    ev = _evaluation(
        "world_pose2",
        [0.0, 1.0, 2.0, 3.0],
        [[9.0, 9.0, 9.0], [3.0, 4.0, 0.1], [0.0, 0.0, -0.2], [1.0, 2.0, 0.2]],
        sigma=[[1.0, 1.0, 1.0], [1.0, 1.0, 0.1], [1.0, 1.0, 1.0], [1 / 3, 1.0, 1.0]],
        nees=[50.0, 1.0, 2.0, 3.0],
        update_age=[0.5, 1.0, 2.0, 3.0],
        nis=[100.0, 2.0, 4.0, 1.0],
        nis_dof=[2, 2, 1, 1],
    )
    out = accuracy_and_consistency([ev], settle_s=1.0)
    # steady state: the records with age ≥ 1 s (three of four)
    assert out["samples"] == 3
    # position: mean over records of ex² + ey² = (25 + 0 + 5) / 3
    assert out["position_rmse_m"] == pytest.approx(math.sqrt(10.0))
    assert out["yaw_rmse_rad"] == pytest.approx(math.sqrt((0.01 + 0.04 + 0.04) / 3))
    assert out["rmse"]["y"] == pytest.approx(math.sqrt((16 + 0 + 4) / 3))
    # |e| = 3σ exactly (x of the last record) counts as inside; y = 4 at σ = 1 is outside
    share = out["within_3sigma_percent"]
    assert share["x"] == 100.0
    assert share["y"] == pytest.approx(200 / 3)
    assert share["theta"] == 100.0
    assert out["anees"] == pytest.approx((1 + 2 + 3) / 3 / 3)
    # steady NIS 2 (dof 2), 4 (dof 1), 1 (dof 1): mixed dofs → mean of NIS/dof = (1 + 4 + 1)/3
    assert out["anis"] == pytest.approx(2.0)
    # beyond χ²(dof, 0.95) of its own dof: only 4 > 3.84 (dof 1); 2 < 5.99 (dof 2)
    assert out["nis_percent_beyond"] == pytest.approx(100 / 3)
    # the most common steady dof is 1 (not the largest, 2)
    assert out["nis_bound"] == pytest.approx(3.841458820694124)


def test_single_dof_anis_and_share() -> None:
    ev = _evaluation(
        "world_position2",
        [0.0, 1.0],
        [[0.1, 0.1], [0.2, 0.2]],
        update_age=[0.0, 1.0, 2.0],
        nis=[9.0, 2.0, 7.0],
        nis_dof=[2, 2, 2],
    )
    # a NIS exactly at its bound χ²(1, 0.95) = 3.8414588206941 is not beyond it
    mixed = _evaluation(
        "world_position2",
        [0.0],
        [[0.0, 0.0]],
        update_age=[1.0, 1.0, 1.0],
        nis=[3.841458820694124, 6.0, 1.0],
        nis_dof=[1, 2, 2],
    )
    assert accuracy_and_consistency([mixed], settle_s=0.0)["nis_percent_beyond"] == pytest.approx(
        100 / 3
    )
    out = accuracy_and_consistency([ev], settle_s=0.0)
    assert out["anis"] == pytest.approx((9 + 2 + 7) / 3 / 2)
    assert out["nis_percent_beyond"] == pytest.approx(200 / 3)  # 9 and 7 > 5.99
    assert math.isnan(out["yaw_rmse_rad"])


def _nees_run(t: list[float], age: list[float], nees: list[float]) -> SeriesEvaluation:
    return _evaluation("world_position2", t, [[0.0, 0.0]] * len(t), nees=nees, age=age)


def test_run_averaged_nees_by_hand() -> None:
    runs = [
        _nees_run([0.0, 0.1, 0.2, 0.3], [0.0, 0.1, 0.2, 0.3], [1.0, 2.0, 3.0, 4.0]),
        _nees_run([0.1, 0.2, 0.3], [0.05, 0.1, 0.2], [10.0, 20.0, 30.0]),
        _nees_run([0.2, 0.3], [1.0, 1.0], [100.0, 200.0]),
    ]
    t, mean, n = run_averaged_nees(runs, rate_hz=10.0, settle_s=0.1)
    # every run is steady (age ≥ 0.1 s) at 0.2 s and 0.3 s only
    np.testing.assert_allclose(t, [0.2, 0.3])
    np.testing.assert_allclose(mean, [(3 + 20 + 100) / 3, (4 + 30 + 200) / 3])
    assert n == 3


def test_run_averaged_nees_refuses_a_record_off_the_grid() -> None:
    runs = [
        _nees_run([0.0, 0.1, 0.2], [1.0, 1.0, 1.0], [1.0, 1.0, 1.0]),
        _nees_run([0.0, 0.14, 0.2], [1.0, 1.0, 1.0], [1.0, 1.0, 1.0]),
    ]
    with pytest.raises(ConfigError, match=r"off the 10\.0 Hz grid"):
        run_averaged_nees(runs, rate_hz=10.0, settle_s=0.0)


def test_convergence_time_edges() -> None:
    t = [10.0, 11.0, 12.0, 13.0, 14.0]
    # |e| = threshold exactly is not below it: the error settles at the third record
    ev = _evaluation("world_position2", t, [[5, 0], [1.0, 0], [0.5, 0], [0.9, 0], [0.1, 0.1]])
    assert convergence_time(ev, [1.0, 1.0]) == pytest.approx(2.0)
    # always below: converged from the first record
    ok = _evaluation("world_position2", t, [[0.5, 0.5]] * 5)
    assert convergence_time(ok, [1.0, 1.0]) == 0.0
    # above at the last record: never settles
    late = _evaluation("world_position2", t, [[0.5, 0.5]] * 4 + [[0.5, 2.0]])
    assert convergence_time(late, [1.0, 1.0]) is None


def test_at_times_finds_a_record_within_the_tolerance_on_either_side() -> None:
    t = np.array([0.0, 0.5, 1.0])
    series = BeliefSeries(
        owner="a",
        subject="b",
        frame="world_position2",
        t=t,
        mean=np.arange(6.0).reshape(3, 2),
        cov=np.broadcast_to(np.eye(2), (3, 2, 2)).copy(),
        age=t.copy(),
    )
    got = at_times(series, np.array([0.5 + 5e-10, 1.0 - 5e-10, 0.0]))
    np.testing.assert_array_equal(got.t, [0.5, 1.0, 0.0])
    np.testing.assert_array_equal(got.mean[:, 0], [2.0, 4.0, 0.0])
    with pytest.raises(ConfigError, match="not recorded at every requested time"):
        at_times(series, np.array([0.5 + 1e-6]))
