"""Malformed beliefs and arguments of :func:`relloc.pipeline.replay.replay`, and records
:func:`relloc.pipeline.evaluation.evaluate` cannot score, are refused by a relloc error naming
where — never a raw numpy error, nor a NaN passed on to the pooled figures."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
import pytest

from relloc.core.contract import Belief, HeldOdometry
from relloc.core.recording import GroundTruth, Measurements, Odometry, Recording, measurement_rows
from relloc.errors import ConfigError, DataError, ModelError
from relloc.pipeline.evaluation import convergence_time, evaluate
from relloc.pipeline.replay import replay

FRAME = "world_position2"


def _recording(truth_end: float = 1.0, **meta: Any) -> Recording:
    still = Odometry(t=np.zeros(0), velocity=np.zeros((0, 4)), sigma=(0, 0, 0, 0))
    rows = measurement_rows("range", t=np.arange(10) * 0.1, observer=1, target=0, value=np.ones(10))
    truth = GroundTruth(t=np.array([0.0, truth_end]), pose=np.zeros((2, 4)))
    return Recording(
        robots=("a", "b"),
        platforms=("ground",) * 2,
        odometry=(still, still),
        measurements=rows,
        truth=(truth, truth),
        meta=meta,
    )


class _Scripted:
    """An estimator of ``a`` whose beliefs at its ``k``-th record are ``beliefs(k)``."""

    name = "scripted"
    owner = "a"

    def __init__(self, beliefs: Callable[[int], Any]) -> None:
        self._beliefs = beliefs
        self._k = 0

    def advance(self, t: float, odometry: HeldOdometry) -> None:
        pass

    def measure(self, batch: Measurements) -> None:
        pass

    def beliefs(self) -> Sequence[Belief]:
        self._k += 1
        return self._beliefs(self._k)  # type: ignore[no-any-return]

    def outbox(self) -> list[Any]:
        return []

    def receive(self, messages: Sequence[Any]) -> None:
        pass

    def take_updates(self) -> list[Any]:
        return []

    def take_events(self) -> list[Any]:
        return []


def _belief(mean: Any = (0.0, 0.0), age: float = 0.0, **info: Any) -> Belief:
    m = np.asarray(mean, dtype=float)
    return Belief("b", FRAME, m, np.eye(m.size), age=age, info=info)


def _replay(beliefs: Callable[[int], Any], **kwargs: Any) -> Any:
    return replay(_recording(), [_Scripted(beliefs)], **kwargs)


def test_a_state_dimension_that_changes_within_a_series_is_a_data_error():
    """It raised numpy's "inhomogeneous shape" ValueError when the results were stacked."""
    with pytest.raises(DataError, match=r"a->b: state dimension changed from 2 to 3 at t=0\.2"):
        _replay(lambda k: [_belief((0.0,) * (2 if k < 3 else 3))])


@pytest.mark.parametrize(
    "beliefs",
    [lambda k: None, lambda k: [None], lambda k: [_belief(w="heavy")]],
    ids=["none", "not-a-belief", "text-info"],
)
def test_beliefs_that_break_the_contract_are_a_model_error(beliefs):
    """They raised TypeError, AttributeError and ValueError from inside the recorder."""
    with pytest.raises(ModelError, match=r"beliefs of a at t=0: not a sequence of Belief"):
        _replay(beliefs)


@pytest.mark.parametrize(
    "kwargs",
    [{"start": "0"}, {"end": "1"}, {"record_rate_hz": "10"}, {"record_rate_hz": True}],
)
def test_window_and_rate_of_the_wrong_type_are_refused_by_name(kwargs):
    """A string raised a raw ValueError or TypeError; ``True`` was taken for 1 Hz."""
    (name,) = kwargs
    with pytest.raises(ConfigError, match=name):
        _replay(lambda k: [_belief()], **kwargs)


@pytest.mark.parametrize(
    "belief", [_belief((np.nan, 0.0)), _belief(age=np.nan)], ids=["nan-mean", "nan-age"]
)
def test_a_belief_that_is_not_finite_is_refused_when_scored(belief):
    """A NaN mean made every RMSE NaN; a NaN age dropped the record from the steady state."""
    est = _replay(lambda k: [belief if k == 4 else _belief()])
    with pytest.raises(ModelError, match=r"a->b: belief at t=0\.3 has a mean or age that is not"):
        evaluate(est, _recording())


@pytest.mark.parametrize("threshold", [np.nan, 0.0, -1.0])
def test_a_convergence_threshold_that_can_never_be_met_is_refused(threshold):
    """It read as a run that never converged."""
    (ev,) = evaluate(_replay(lambda k: [_belief()]), _recording())
    with pytest.raises(ConfigError, match=r"convergence_time: thresholds\[1\]"):
        convergence_time(ev, [1.0, threshold])
    assert convergence_time(ev, [1.0, 1.0]) == 0.0


@pytest.mark.parametrize("yaw", [np.nan, "north"])
def test_a_common_frame_yaw_that_is_not_a_finite_number_is_a_data_error(yaw):
    """NaN made every true state NaN without a word; text raised a raw ValueError."""
    rec = _recording(common_frame_yaw=yaw)
    est = _replay(lambda k: [Belief("b", "airground_follower", np.zeros(4), np.eye(4))])
    with pytest.raises(DataError, match=r"recording\.meta: common_frame_yaw"):
        evaluate(est, rec)


@pytest.mark.parametrize("cov", [np.zeros((2, 2)), np.full((2, 2), np.inf)], ids=["0", "inf"])
def test_a_covariance_nees_cannot_use_is_a_model_error_naming_the_series(cov):
    """The error said what was wrong, but not of which series."""
    est = _replay(lambda k: [Belief("b", FRAME, np.zeros(2), cov)])
    with pytest.raises(ModelError, match=r"^a->b: covariance is not"):
        evaluate(est, _recording())


def test_a_truth_the_recording_cannot_give_is_a_data_error_naming_the_series():
    """The error named the robot or the span, but not which series asked for it."""
    est = _replay(lambda k: [Belief("ghost", FRAME, np.zeros(2), np.eye(2))])
    with pytest.raises(DataError, match=r"^a->ghost: unknown robot 'ghost'; the recording has"):
        evaluate(est, _recording())
    est = _replay(lambda k: [_belief()])
    with pytest.raises(DataError, match=r"^a->b: truth: query time outside the recorded span"):
        evaluate(est, _recording(truth_end=0.5))
