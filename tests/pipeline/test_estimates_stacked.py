"""Estimates.stacked: one owner's beliefs of several subjects side by side."""

import numpy as np
import pytest

from relloc.core.contract import Belief
from relloc.core.estimates import Recorder
from relloc.errors import ConfigError


def test_stacked_orders_subjects_and_requires_common_times():
    rec = Recorder("x")
    for t in (0.0, 1.0):
        rec.record(
            t,
            "team",
            [
                Belief(s, "world_pose2", np.full(3, k + t), np.eye(3) * (k + 1))
                for k, s in enumerate("ab")
            ],
        )
    t, mean, cov = rec.results().stacked("team", ["b", "a"])
    assert np.array_equal(t, [0.0, 1.0])
    assert mean.shape == (2, 2, 3) and np.array_equal(mean[1, :, 0], [2.0, 1.0])
    assert np.array_equal(cov[0, :, 0, 0], [2.0, 1.0])
    rec.record(2.0, "team", [Belief("a", "world_pose2", np.zeros(3), np.eye(3))])
    with pytest.raises(ConfigError, match="other times"):
        rec.results().stacked("team", ["a", "b"])
    with pytest.raises(ConfigError, match="no estimates"):
        rec.results().stacked("team", ["c"])
