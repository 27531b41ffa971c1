"""``relloc run BAG``'s choice of range filters on a hand-built recording: one per pair of
robots with odometry (two samples or more) linked by ranges in either direction, the ranges of
a pair lacking odometry counted by pair, the ranges to a static radio counted apart."""

from __future__ import annotations

import numpy as np

from relloc.core.recording import Measurements, Odometry, Recording, measurement_rows
from relloc.experiments.bag_run import landmark_range_rows, range_pairs

SIGMA = np.array([0.05, 0.0, 0.0, 0.05])


def _odometry(samples: int) -> Odometry:
    t = np.arange(float(samples))
    return Odometry(t=t, velocity=np.zeros((samples, 4)), sigma=SIGMA)


def _recording() -> Recording:
    """a, b and d report odometry twice, c once. Ranges: a→b twice, b→a and d→b once, c→a
    three times, b to static radio 0 twice."""
    robots = [
        measurement_rows(
            "range",
            t=[0.1, 0.2, 0.3, 0.4],
            observer=[0, 0, 1, 3],
            target=[1, 1, 0, 1],
            value=np.ones((4, 1)),
        ),
        measurement_rows("range", t=[0.5, 0.6, 0.7], observer=2, target=0, value=np.ones((3, 1))),
        measurement_rows("range", t=[0.8, 0.9], observer=1, landmark=0, value=np.ones((2, 1))),
    ]
    return Recording(
        robots=("a", "b", "c", "d"),
        platforms=("ground",) * 4,
        odometry=(_odometry(2), _odometry(2), _odometry(1), _odometry(2)),
        measurements=Measurements.concatenate(robots),
        landmarks=np.array([[0.0, 5.0, 0.0]]),
    )


def test_pairs_with_odometry_on_both_robots_get_a_filter_each() -> None:
    filters, without = range_pairs(_recording(), 0.2)
    assert [(f.owner, f.subject) for f in filters] == [("a", "b"), ("b", "d")]
    assert all(f.settings.sigma_range == 0.2 for f in filters)
    assert without == {"a-c": 3}


def test_ranges_to_a_static_radio_are_counted_apart() -> None:
    assert landmark_range_rows(_recording()) == 2
