"""``--calibration-window`` picks the side of the run mrclam-cl fits its error models on; every
other reproduction refuses it, naming the flag and the one experiment that reads it, rather than
ignoring it; the MRCLAM-layout reproductions take ``--dataset``; ``--seed 0`` is a seed."""

from __future__ import annotations

from pathlib import Path

import pytest

from relloc.errors import ConfigError
from relloc.experiments.registry import EXPERIMENTS, ReproduceArgs, refuse_unread

ARGS = ReproduceArgs(out_dir=Path("unused"), calibration_window="second-half")


@pytest.mark.parametrize("name", [n for n in EXPERIMENTS if n != "mrclam-cl"])
def test_every_other_reproduction_refuses_a_calibration_window(name: str) -> None:
    with pytest.raises(ConfigError) as err:
        refuse_unread(name, ARGS)
    assert str(err.value) == f"--calibration-window: {name} does not read it; read by mrclam-cl"


def test_mrclam_cl_takes_a_calibration_window() -> None:
    assert refuse_unread("mrclam-cl", ARGS) is None  # not refused


@pytest.mark.parametrize(
    "name", ["wanasinghe2014", "wanasinghe2014-pairs", "mrclam-cl", "mrclam-association"]
)
def test_the_reproductions_on_a_mrclam_layout_folder_take_a_dataset(name: str) -> None:
    assert refuse_unread(name, ReproduceArgs(out_dir=Path("unused"), dataset=Path("run"))) is None


def test_seed_zero_is_a_master_seed_of_its_own_and_none_the_default() -> None:
    assert ReproduceArgs(out_dir=Path("unused"), seed=0).master_seed == 0
    assert ReproduceArgs(out_dir=Path("unused")).master_seed == 2026
