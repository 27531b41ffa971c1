"""Bad input to the models (relloc.models) and to core's beliefs, recorder, event loop, angles and
poses is refused naming where, never a raw TypeError/IndexError/ValueError, a silent NaN or a
silently dropped reading."""

from __future__ import annotations

import numpy as np
import pytest

from relloc.core.angles import circular_interp
from relloc.core.contract import UpdateRecord
from relloc.core.estimates import Estimates, Recorder, concatenate
from relloc.core.events import run_events
from relloc.core.gaussian import Gaussian, GaussianMixture
from relloc.core.poses import compose, inverse
from relloc.core.recording import (
    FileSkips,
    GroundTruth,
    Odometry,
    Recording,
    SkipReport,
    empty_measurements,
    measurement_rows,
)
from relloc.errors import ConfigError, DataError, ModelError
from relloc.models.airground import Mode, mode_measurement
from relloc.models.measurement import RangeBearingNoise
from relloc.models.motion import VelocityNoise, relative_jacobians, relative_step
from relloc.models.planar_measurement import ScalarRows, linearise_rows
from relloc.models.uwb_noise import TIERS_ROUNDED, sample_range_errors

X4 = np.array([1.0, 2.0, 0.5, 0.3])
U_L = np.array([1.0, 0.0, 0.0, 0.1])
U_C = np.array([0.5, 0.1, 0.0, 0.2])
SIGMAS = (0.05, 0.05, 0.01, 0.02)


# ------------------------------------------------------------------------------------- models
@pytest.mark.parametrize("value", [None, "0.1", "abc", True, [0.1], np.array([0.1, 0.2])])
def test_range_bearing_noise_of_the_wrong_type_names_the_field(value) -> None:
    with pytest.raises(ConfigError, match=r"RangeBearingNoise\.sigma_azimuth"):
        RangeBearingNoise(sigma_r=0.1, sigma_azimuth=value, sigma_elevation=0.1)


@pytest.mark.parametrize("dt", [None, "0.1", "abc", True])
@pytest.mark.parametrize("f", [relative_step, relative_jacobians])
def test_relative_motion_dt_that_is_not_a_number_is_a_config_error(f, dt) -> None:
    with pytest.raises(ConfigError, match="relative motion: dt"):
        f(X4, U_L, U_C, dt)


@pytest.mark.parametrize(
    "observer", ["abcd", (True, 0.1, 0.1, 0.1), ("1", 1, 1, 1), np.ones((2, 2))]
)
def test_velocity_noise_of_refuses_what_is_not_four_sigmas(observer) -> None:
    assert VelocityNoise.of(np.array(SIGMAS), list(SIGMAS)).observer == SIGMAS
    with pytest.raises(ConfigError, match=r"VelocityNoise\.observer"):
        VelocityNoise.of(observer, SIGMAS)


def _rows(**changes: object) -> ScalarRows:
    fields: dict[str, object] = dict(
        kind=np.array([0, 1]),
        observer=np.array([0, 0]),
        target=np.array([1, -1]),
        landmark_xy=np.full((2, 2), 5.0),
        z=np.array([0.1, 1.0]),
        sigma=np.array([0.1, 0.1]),
        group=np.array([0, 0]),
    )
    fields.update(changes)
    return ScalarRows(**fields)  # type: ignore[arg-type]


@pytest.mark.parametrize("z", [None, 3.0, "ab", np.zeros((2, 2))])
def test_scalar_rows_with_z_not_one_dimensional_is_a_model_error(z) -> None:
    with pytest.raises(ModelError, match=r"ScalarRows\.z: expected shape \(m,\)"):
        _rows(z=z)


@pytest.mark.parametrize("field", ["kind", "observer", "target", "group"])
def test_scalar_rows_with_float_indices_are_refused_not_truncated(field) -> None:
    with pytest.raises(ModelError, match=rf"ScalarRows\.{field}: expected integers"):
        _rows(**{field: np.array([0.5, 1.0])})


@pytest.mark.parametrize("X", [np.zeros(3), np.zeros((2, 2)), np.zeros((2, 3, 1))])
def test_linearise_rows_refuses_a_team_mean_that_is_not_n_by_3(X) -> None:
    with pytest.raises(ModelError, match=r"linearise_rows: expected a team mean \(n, 3\)"):
        linearise_rows(X, _rows())


def test_linearise_rows_refuses_rows_that_are_not_scalar_rows() -> None:
    with pytest.raises(ModelError, match=r"linearise_rows: .* NoneType"):
        linearise_rows(np.zeros((2, 3)), None)  # type: ignore[arg-type]


@pytest.mark.parametrize("mode", [1, 2, 0, "PAIR_SEEN", None])
def test_mode_measurement_refuses_a_mode_that_is_not_a_mode(mode) -> None:
    z, H, angles = mode_measurement(X4, Mode.PAIR_SEEN)
    assert z.shape == (4,) and H.shape == (4, 4) and angles == (False, True, True, True)
    with pytest.raises(ConfigError, match="mode_measurement: mode must be a Mode"):
        mode_measurement(X4, mode)  # (a plain 1 gave the range alone)


@pytest.mark.parametrize(
    "x",
    [np.array([np.nan, 0.0, 0.0, 0.0]), np.zeros(3), np.zeros(0), None, 1.0, "abcd", list("abcd")],
)
def test_mode_measurement_refuses_a_state_that_is_not_four_finite_numbers(x) -> None:
    with pytest.raises(DataError, match=r"mode_measurement: x must be a finite state \(4,\)"):
        mode_measurement(x, Mode.NONE_SEEN)


@pytest.mark.parametrize(
    ("args", "where"),
    [
        ((10.5, 2, 0.1), "n_steps"),
        (("10", 2, 0.1), "n_steps"),
        ((None, 2, 0.1), "n_steps"),
        ((True, 2, 0.1), "n_steps"),
        ((10, 2.0, 0.1), "n_links"),
        ((10, -1, 0.1), "n_links"),
        ((10, 2, "0.1"), "dt"),
        ((10, 2, None), "dt"),
        ((10, 2, np.inf), "dt"),
        ((10, 2, 0.0), "dt"),
    ],
)
def test_sample_range_errors_names_a_bad_size_or_period(args, where) -> None:
    with pytest.raises(ConfigError, match=f"sample_range_errors: {where}"):
        sample_range_errors(TIERS_ROUNDED, *args, np.random.default_rng(0))


def test_sample_range_errors_names_a_bad_model_or_generator() -> None:
    rng = np.random.default_rng(0)
    with pytest.raises(ConfigError, match="sample_range_errors: model"):
        sample_range_errors(None, 10, 2, 0.1, rng)  # type: ignore[arg-type]
    with pytest.raises(ConfigError, match="sample_range_errors: rng"):
        sample_range_errors(TIERS_ROUNDED, 10, 2, 0.1, 3)  # type: ignore[arg-type]


# --------------------------------------------------------------------------------------- core
@pytest.mark.parametrize("f", [lambda p: compose(p, np.zeros(3)), inverse])
def test_pose_algebra_refuses_a_pose_that_is_not_numbers(f) -> None:
    with pytest.raises(ModelError, match="expected real numbers"):
        f("abc")


@pytest.mark.parametrize(
    ("t", "t_known", "angles"),
    [
        (np.nan, [0.0, 1.0], [0.0, 1.0]),
        (0.5, [0.0, 1.0], [0.0, np.nan]),
        (0.5, [0.0, 1.0], [0.0, np.inf]),
        (0.5, [0.0, np.inf], [0.0, 1.0]),
        (0.5, [-np.inf, 1.0], [0.0, 1.0]),
        ("a", [0.0, 1.0], [0.0, 1.0]),
        (0.5, "ab", [0.0, 1.0]),
    ],
)
def test_circular_interp_refuses_nan_infinite_or_non_numeric_input(t, t_known, angles) -> None:
    with pytest.raises(DataError, match="circular_interp"):
        circular_interp(t, t_known, angles)


@pytest.mark.parametrize(
    ("mean", "cov"),
    [("ab", np.eye(2)), (np.zeros(2), "ab"), ([[1.0], [1.0, 2.0]], np.eye(2))],
)
def test_a_gaussian_of_what_is_not_numbers_is_a_model_error(mean, cov) -> None:
    with pytest.raises(
        ModelError,
        match=r"Gaussian: (mean|covariance): expected (real numbers|an array of numbers)",
    ):
        Gaussian(mean=mean, cov=cov)


def test_a_mixture_of_what_is_not_numbers_is_a_model_error() -> None:
    with pytest.raises(ModelError, match="GaussianMixture: means: expected real numbers"):
        GaussianMixture(means="ab", covs=np.eye(2)[None], weights=np.ones(1))


def test_a_mixture_refuses_group_labels_that_are_not_integers() -> None:
    with pytest.raises(ModelError, match="GaussianMixture: groups must be integers"):
        GaussianMixture(
            means=np.zeros((2, 2)),
            covs=np.stack([np.eye(2)] * 2),
            weights=np.ones(2),
            groups=np.array([0.5, 1.0]),
        )


@pytest.mark.parametrize("t", [None, "a"])
def test_recorder_refuses_a_record_time_that_is_not_a_number(t) -> None:
    with pytest.raises(ModelError, match=r"beliefs of obs: the time .* is not a number"):
        Recorder("x").record(t, "obs", [])


@pytest.mark.parametrize("updates", [None, [1], [UpdateRecord(0.0, "a", "x", 3, 1.0, 1.0)]])
def test_recorder_refuses_updates_that_are_not_update_records_and_stores_none(updates) -> None:
    rec = Recorder("x")
    with pytest.raises(ModelError, match="updates of obs: not a sequence of UpdateRecord"):
        rec.add_updates("obs", updates)
    assert rec.results().updates == ()


@pytest.mark.parametrize("events", [None, [1]])
def test_recorder_refuses_events_that_are_not_track_events(events) -> None:
    with pytest.raises(ModelError, match="track events"):
        Recorder("x").add_events(events)


@pytest.mark.parametrize(
    ("counts", "match"),
    [
        (None, "expected a mapping"),
        ({"kept": np.nan}, "counter 'kept'"),
        ({"kept": "x"}, "counter 'kept'"),
        ({"kept": 1.7}, "counter 'kept'"),
        ({"kept": -1}, "counter 'kept'"),
    ],
)
def test_recorder_counts_must_be_integers(counts, match) -> None:
    with pytest.raises(ConfigError, match=f"Recorder.count: {match}"):
        Recorder("x").count(counts)


def test_concatenate_refuses_a_part_that_is_not_estimates() -> None:
    with pytest.raises(ConfigError, match="concatenate: part 1 is a int"):
        concatenate([Estimates(estimator="x"), 1])  # type: ignore[list-item]


class _Idle:
    """An estimator that does nothing but note the times it is advanced to."""

    owner = "a"

    def __init__(self) -> None:
        self.times: list[float] = []

    def advance(self, t: float, odometry: object) -> None:
        self.times.append(t)

    def measure(self, batch: object) -> None: ...

    def outbox(self) -> list[object]:
        return []

    def receive(self, messages: object) -> None: ...

    def beliefs(self) -> list[object]:
        return []

    def take_updates(self) -> list[object]:
        return []

    def take_events(self) -> list[object]:
        return []


def _run(times: object, *, k: int = 3, **changes: object) -> list[float]:
    est = _Idle()
    args: dict[str, object] = dict(
        estimators=[est],
        times=times,
        held=np.zeros((k, 1, 4)),
        stamps=np.zeros((k, 1)),
        measurements=empty_measurements(),
        record_times=np.zeros(0),
        recorder=Recorder("x"),
    )
    args.update(changes)
    run_events(**args)  # type: ignore[arg-type]
    return est.times


@pytest.mark.parametrize(
    "times", [np.array([0.0, 2.0, 1.0]), np.array([0.0, np.nan, 2.0]), np.array([0.0, 1.0, np.inf])]
)
def test_run_events_refuses_event_times_that_go_back_or_are_not_finite(times) -> None:
    assert _run(np.array([0.0, 1.0, 1.0])) == [0.0, 1.0, 1.0]  # repeated times are fine
    with pytest.raises(
        DataError,
        match=r"run_events: event \d at t=.*; event times must be finite and non-decreasing",
    ):
        _run(times)


def test_run_events_refuses_a_single_nan_event_time() -> None:
    with pytest.raises(
        DataError, match=r"run_events: event 0 at t=nan after t=-inf; event times must be finite"
    ):
        _run(np.array([np.nan]), k=1)


@pytest.mark.parametrize(
    ("changes", "error", "match"),
    [
        ({"times": np.zeros((1, 3))}, DataError, "event times must be 1-D"),
        ({"times": "abc"}, DataError, "event times: expected real numbers"),
        (
            {"held": np.zeros((2, 1, 4))},
            DataError,
            r"held velocities \(2, 1, 4\) and stamps \(3, 1\)",
        ),
        (
            {"stamps": np.zeros((5, 1))},
            DataError,
            r"held velocities \(3, 1, 4\) and stamps \(5, 1\)",
        ),
        (
            {"held": None},
            DataError,
            r"held velocities \(\) and stamps \(3, 1\) need one row per event",
        ),
        ({"estimators": []}, ConfigError, "no estimators"),
        ({"measurements": None}, ConfigError, "measurements must be a Measurements table"),
        ({"recorder": None}, ConfigError, "recorder must be a Recorder"),
        ({"record_times": "a"}, ConfigError, "record times: expected real numbers"),
    ],
)
def test_run_events_names_a_bad_argument(changes, error, match) -> None:
    times = changes.pop("times", np.array([0.0, 1.0, 2.0]))
    with pytest.raises(error, match=f"run_events: {match}"):
        _run(times, **changes)


# ---------------------------------------------------------------------------------- recording
T3 = np.array([0.0, 1.0, 2.0])
TRUTH = GroundTruth(t=T3, pose=np.zeros((3, 4)))
ODOMETRY = Odometry(t=T3, velocity=np.zeros((3, 4)), sigma=np.ones(4))


@pytest.mark.parametrize("gap_s", ["1", None, True])
def test_ground_truth_gap_that_is_not_a_number_is_a_data_error(gap_s) -> None:
    with pytest.raises(DataError, match=r"truth\.gap_s: must be a number > 0"):
        GroundTruth(t=T3, pose=np.zeros((3, 4)), gap_s=gap_s)


@pytest.mark.parametrize(
    "query",
    [
        lambda t: TRUTH.at(t),
        lambda t: TRUTH.valid_at(t),
        lambda t: ODOMETRY.held_at(t),
        lambda t: ODOMETRY.stamp_at(t),
    ],
)
@pytest.mark.parametrize("t", ["a", None, np.zeros((2, 2))])
def test_query_times_that_are_not_numbers_or_not_1d_are_a_data_error(query, t) -> None:
    with pytest.raises(
        DataError,
        match=r"(truth|odometry): query times(: expected real numbers| must be a number or 1-D)",
    ):
        query(t)


def test_a_bool_is_not_a_robot_index_nor_a_row_index() -> None:
    rows = measurement_rows("range", t=[0.0], observer=0, target=1, value=[[1.0]])
    rec = Recording(
        robots=["a", "b"], platforms=["ground"] * 2, odometry=[ODOMETRY] * 2, measurements=rows
    )
    with pytest.raises(DataError, match="unknown robot True"):
        rec.index(True)
    with pytest.raises(
        DataError, match="measurement_rows: observer: expected real numbers, got bool"
    ):
        measurement_rows("range", t=[0.0], observer=True, target=0, value=[[1.0]])


@pytest.mark.parametrize(
    ("make", "match"),
    [
        (lambda: FileSkips("f", "3", 1), r"FileSkips\('f'\)\.rows_read"),
        (lambda: FileSkips("f", 3, 1.5), r"FileSkips\('f'\)\.rows_kept"),
        (lambda: FileSkips("f", 3, 1, {"bad": "x"}), r"FileSkips\('f'\)\.skipped\['bad'\]"),
        (lambda: FileSkips("f", 3, 1, None), r"FileSkips\('f'\)\.skipped"),
        (lambda: FileSkips("f", 3, 1, {}, (1,)), r"FileSkips\('f'\)\.examples\[0\]"),
        (lambda: SkipReport(files=(1,)), r"SkipReport\.files\[0\]"),
    ],
)
def test_skip_reports_of_the_wrong_types_name_the_field(make, match) -> None:
    with pytest.raises(ConfigError, match=match):
        make()
