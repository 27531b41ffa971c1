"""Degenerate inputs of the team summary (:func:`relloc.pipeline.team_report.build_summary`)."""

from __future__ import annotations

import numpy as np
import pytest

from relloc.core.estimates import BeliefSeries, Estimates
from relloc.core.recording import GroundTruth, Odometry, Recording, measurement_rows
from relloc.errors import ConfigError
from relloc.pipeline.team_report import build_summary


def _run() -> tuple[Estimates, Recording]:
    still = Odometry(t=np.zeros(0), velocity=np.zeros((0, 4)), sigma=(0, 0, 0, 0))
    rows = measurement_rows("range", t=np.arange(3) * 0.1, observer=1, target=0, value=np.ones(3))
    truth = GroundTruth(t=np.array([0.0, 1.0]), pose=np.zeros((2, 4)))
    rec = Recording(
        robots=("a", "b"),
        platforms=("ground",) * 2,
        odometry=(still, still),
        measurements=rows,
        truth=(truth, truth),
    )
    k = 3
    series = BeliefSeries(
        owner="a",
        subject="b",
        frame="relative_pose4",
        t=np.arange(k) * 0.1,
        mean=np.zeros((k, 4)),
        cov=np.tile(np.eye(4), (k, 1, 1)),
        age=np.zeros(k),
    )
    return Estimates(estimator="x", beliefs=(series,)), rec


@pytest.mark.parametrize("rate", ["10", 0.0, np.nan])
def test_a_record_rate_that_is_not_a_positive_number_is_refused_for_one_run_too(rate):
    """With one run nothing read it, and the summary stated it as given."""
    est, rec = _run()
    with pytest.raises(ConfigError, match="summarise: record_rate_hz"):
        build_summary([est], [rec], record_rate_hz=rate)
    summary, _ = build_summary([est], [rec], settle_s=0.0, record_rate_hz=10.0)
    assert summary["record_rate_hz"] == 10.0
    assert summary["pairs"]["a->b"]["samples"] == 3
