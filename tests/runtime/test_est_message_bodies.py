"""``est`` bodies and the estimates rebuilt from them: info columns by name, and a restarted
sender's records of one time kept in arrival order."""

from __future__ import annotations

import numpy as np

from relloc.core.estimates import BeliefSeries, Estimates
from relloc.runtime.messages import decode, encode, est_bodies, estimates_from_bodies

ROSTER = ("obs", "air1")


def _series(
    t: list[float],
    x: list[float],
    info: dict[str, list[float]] | None = None,
    *,
    owner: str = "obs",
    subject: str = "air1",
) -> BeliefSeries:
    """A belief series of ``owner`` about ``subject`` with x = ``x`` at ``t`` (the rest 0,
    unit covariances) and ``info`` columns."""
    mean = np.zeros((len(t), 4))
    mean[:, 0] = x
    return BeliefSeries(
        owner=owner,
        subject=subject,
        track="",
        frame="relative_pose4",
        t=np.array(t),
        mean=mean,
        cov=np.stack([np.eye(4)] * len(t)),
        age=np.zeros(len(t)),
        info={k: np.array(v) for k, v in (info or {}).items()},
    )


def _wire(body: dict) -> dict:
    return decode(encode("est", "obs", 0, 1.0, body), roster=ROSTER).body


def test_info_travels_row_major_with_its_names_sorted():
    series = _series([0.1, 0.2], [1.0, 2.0], {"b": [1.0, 2.0], "a": [10.0, 20.0]})
    (body,) = est_bodies(Estimates(estimator="ekf", beliefs=(series,)), frame="relative_pose4")
    assert body["info_names"] == ["a", "b"]
    assert np.asarray(body["info"]).tolist() == [10.0, 1.0, 20.0, 2.0]


def test_info_columns_are_rebuilt_by_name():
    series = _series([0.1, 0.2, 0.3], [1.0, 2.0, 3.0], {"b": [1.0, 2.0, 3.0], "a": [4.0, 5, 6]})
    (body,) = est_bodies(Estimates(estimator="ekf", beliefs=(series,)), frame="relative_pose4")
    (back,) = estimates_from_bodies("ekf", [("obs", _wire(body))]).beliefs
    assert back.info["a"].tolist() == [4.0, 5.0, 6.0]
    assert back.info["b"].tolist() == [1.0, 2.0, 3.0]


def test_records_of_one_time_stay_in_arrival_order():
    t = [round(0.1 * k, 10) for k in range(20)]
    parts = []
    for x in (1.0, 2.0):  # a sender's first life, then its second over the same times
        series = _series(t, [x] * 20, {})
        (body,) = est_bodies(Estimates(estimator="ekf", beliefs=(series,)), frame="relative_pose4")
        parts.append(("obs", _wire(body)))
    (back,) = estimates_from_bodies("ekf", parts).beliefs
    assert back.t.tolist() == sorted(t + t)
    assert back.mean[:, 0].tolist() == [1.0, 2.0] * 20
