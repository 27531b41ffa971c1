"""MRCLAM folders another recording could give: a run too short to score after calibration,
and a log of one robot, refused naming the folder (cuts of run 6, skipped where absent)."""

from __future__ import annotations

from pathlib import Path

import pytest

from relloc.datasets.mrclam_cut import cut_mrclam
from relloc.errors import ConfigError, DataError
from relloc.experiments import mrclam_association
from relloc.experiments.registry import ReproduceArgs
from relloc.experiments.wanasinghe2014_pairs import chosen_pairs


@pytest.fixture(scope="module")
def short_run(tmp_path_factory: pytest.TempPathFactory, mrclam_run6: Path) -> Path:
    """The first 75 s of run 6, every robot."""
    dst = tmp_path_factory.mktemp("mrclam") / "first75s"
    cut_mrclam(mrclam_run6, dst, end_s=75.0)
    return dst


@pytest.fixture(scope="module")
def one_robot(short_run: Path) -> Path:
    dst = short_run.parent / "robot1"
    cut_mrclam(short_run, dst, robots=[1])
    return dst


def test_a_run_too_short_to_score_after_calibration_is_named(
    short_run: Path, tmp_path: Path
) -> None:
    args = ReproduceArgs(out_dir=tmp_path, dataset=short_run)
    with pytest.raises(
        DataError, match=rf"^{short_run}: too short for a 240 s evaluation after calibration"
    ):
        mrclam_association.reproduce(args)


def test_a_log_of_one_robot_is_refused(one_robot: Path, tmp_path: Path) -> None:
    args = ReproduceArgs(out_dir=tmp_path, dataset=one_robot)
    with pytest.raises(DataError, match=rf"^{one_robot}: needs odometry for at least two robots"):
        mrclam_association.reproduce(args)
    with pytest.raises(ConfigError, match=rf"--dataset: {one_robot} has 1 robot\(s\); pairs need"):
        chosen_pairs(one_robot, None)
