"""tiers-uwb's pairs on hand-built recordings: which pairs are tracked (odometry on both robots,
a range between them, one moving by its odometry's linear speed), how a pair's series is scored
(3-D position RMSE, 4-DOF NEES share, convergence within 0.3 m per axis and 0.5 rad)."""

from __future__ import annotations

import numpy as np
import pytest

from relloc.core.recording import Odometry, Recording, measurement_rows
from relloc.experiments.tiers_uwb_pairs import _pair_score, moving_pairs
from relloc.pipeline.evaluation import SeriesEvaluation

T = np.arange(0.0, 3.01, 0.1)
SIGMA = np.array([0.05, 0.0, 0.0, 0.05])


def _odometry(v: float, w: float, t: np.ndarray = T) -> Odometry:
    return Odometry(t=t, velocity=np.tile([v, 0.0, 0.0, w], (t.size, 1)), sigma=SIGMA)


def _ranges(*links: tuple[int, int]) -> object:
    t = np.arange(len(links), dtype=float)
    observer = [a for a, _ in links]
    target = [b for _, b in links]
    return measurement_rows(
        "range", t=t, observer=observer, target=target, value=np.ones((len(links), 1))
    )


def test_a_pair_is_tracked_when_both_have_odometry_a_range_links_them_and_one_drives() -> None:
    """a drives 0.3 m; b turns in place (1 rad/s, no path); c reports odometry once; d stands.
    Ranges link a–b, b–d and a–c: only a–b is tracked (b–d: neither drives; a–c: c has one
    odometry sample, too few to integrate)."""
    rec = Recording(
        robots=("a", "b", "c", "d"),
        platforms=("ground",) * 4,
        odometry=(
            _odometry(0.1, 0.0),
            _odometry(0.0, 1.0),
            _odometry(0.1, 0.0, np.zeros(1)),
            _odometry(0.0, 0.0),
        ),
        measurements=_ranges((0, 1), (3, 1), (0, 2)),
    )
    assert moving_pairs(rec) == [(0, 1)]


def _series(error: list[list[float]], nees: list[float]) -> SeriesEvaluation:
    k = len(nees)
    t = np.arange(float(k))
    empty = np.zeros(0)
    return SeriesEvaluation(
        owner="a",
        subject="b",
        track="b",
        platform="ground",
        frame="a",
        t=t,
        error=np.array(error),
        sigma=np.ones((k, 4)),
        nees=np.array(nees),
        age=t,
        cond_p=np.ones(k),
        update_t=empty,
        update_age=empty,
        nis=empty,
        nis_dof=np.zeros(0, dtype=np.int64),
        cond_r=empty,
        cond_s=empty,
    )


def test_a_pair_series_is_scored_in_3d_with_a_4_dof_nees_and_per_axis_convergence() -> None:
    """Errors (x, y, z, yaw): 5 m off, then 0.4 m in z, then 0.1 m per axis with 0.4 rad of yaw
    (within 0.3 m and 0.5 rad), then none; NEES 10, 9, 1, 0 against χ²₄(0.95) ≈ 9.49."""
    got = _pair_score(
        _series(
            [[3.0, 4.0, 0.0, 0.1], [0.0, 0.0, 0.4, 0.0], [0.1, 0.1, 0.1, 0.4], [0.0] * 4],
            [10.0, 9.0, 1.0, 0.0],
        )
    )
    assert got["pos_rmse_m"] == pytest.approx(np.sqrt((25.0 + 0.16 + 0.03) / 4))
    assert got["nees_pct_beyond"] == 25.0
    assert got["converged_after_s"] == 2.0
    assert got["records"] == 4
