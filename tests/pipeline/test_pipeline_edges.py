"""Arguments of the evaluation, replay and output helpers that name what is wrong, and the
empty series they answer without a record."""

from __future__ import annotations

import dataclasses
import sys
from pathlib import Path

import numpy as np
import pytest

from relloc.core.estimates import BeliefSeries
from relloc.errors import ConfigError
from relloc.pipeline.evaluation import (
    accuracy_and_consistency,
    convergence_time,
    nees_band_check,
    series_errors,
)
from relloc.pipeline.export import ExportRequest
from relloc.pipeline.frames import frame
from relloc.pipeline.montecarlo import MAX_RUNS, spawn_seeds
from relloc.pipeline.output import check_writable_file, to_jsonable
from relloc.pipeline.replay import replay

sys.path.insert(0, str(Path(__file__).parent))
from test_evaluation_bad_input import RUNS, T, _run
from test_replay_arguments import _filter, _recording


def _series(frame_name: str, n: int, dim: int) -> BeliefSeries:
    return BeliefSeries(
        owner="a",
        subject="b",
        frame=frame_name,
        t=T[:n],
        mean=np.zeros((n, dim)),
        cov=np.broadcast_to(np.eye(dim), (n, dim, dim)),
        age=T[:n],
    )


def test_an_unknown_frame_is_named_with_the_known_ones() -> None:
    with pytest.raises(ConfigError, match=r"unknown frame 'nope'; known: relative_pose4, "):
        frame("nope")


def test_a_series_of_another_frame_size_is_named() -> None:
    with pytest.raises(ConfigError, match=r"a->b: frame world_pose2 has 3 states, the series"):
        series_errors(_series("world_pose2", 3, 2), _recording())


def test_an_empty_series_has_no_error_and_no_convergence_time() -> None:
    errors = series_errors(_series("world_position2", 0, 2), _recording())
    assert errors.shape == (0, 2)
    empty = dataclasses.replace(RUNS[0], t=np.zeros(0), error=np.zeros((0, 2)))
    assert convergence_time(empty, [1.0, 1.0]) is None


def test_pooling_nothing_or_mixed_frames_is_refused() -> None:
    with pytest.raises(ConfigError, match="accuracy_and_consistency: nothing to pool"):
        accuracy_and_consistency([], settle_s=1.0)
    pose = dataclasses.replace(_run(1), frame="world_pose2", error=np.zeros((T.size, 3)))
    with pytest.raises(ConfigError, match=r"mixed frames \['world_pose2', 'world_position2'\]"):
        accuracy_and_consistency([RUNS[0], pose], settle_s=1.0)


def test_a_band_check_of_one_run_and_thresholds_of_another_size_are_refused() -> None:
    with pytest.raises(ConfigError, match="nees_band_check: needs at least two independent runs"):
        nees_band_check(RUNS[:1], rate_hz=10.0, settle_s=1.0)
    with pytest.raises(ConfigError, match="convergence_time: 1 thresholds for 2 states"):
        convergence_time(RUNS[0], [1.0])


def test_replay_arguments_that_leave_nothing_to_do_are_refused() -> None:
    rec = _recording()
    with pytest.raises(ConfigError, match="replay: no estimators given"):
        replay(rec, [])
    with pytest.raises(ConfigError, match=r"replay: the window \[2\.0, 1\.0\] is empty"):
        replay(rec, [_filter()], start=2.0, end=1.0)
    for clock in (np.zeros(0), np.array([0.0, np.nan]), np.zeros((2, 2))):
        with pytest.raises(ConfigError, match="replay: clock must be a non-empty 1-D array"):
            replay(rec, [_filter()], clock=clock)


def test_numpy_scalars_and_paths_become_json_values() -> None:
    value = {"n": np.int64(3), "x": np.float32(0.5), "bad": np.float64(np.nan), "p": Path("a/b")}
    out = to_jsonable(value)
    assert out == {"n": 3, "x": 0.5, "bad": None, "p": "a/b"}
    assert type(out["n"]) is int and type(out["x"]) is float


def test_a_folder_is_no_file_to_write(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match=rf"--out-file: {tmp_path} is a folder; give a file"):
        check_writable_file(tmp_path, "--out-file")
    file = tmp_path / "x.txt"
    file.write_text("")
    with pytest.raises(ConfigError, match=rf"--tum: {file} exists and is not a folder"):
        ExportRequest(tum=file)


def test_more_runs_than_seeding_can_hold_are_refused() -> None:
    with pytest.raises(ConfigError, match=rf"runs: must be in 1…{MAX_RUNS}, got {MAX_RUNS + 1}"):
        spawn_seeds(0, MAX_RUNS + 1)
