"""``relloc reproduce guler2023``'s scenario block (``summarise``) from two hand-made runs of
two followers: means and largest values over the right axes, mode shares over every tick,
block counts and NIS per degree of freedom summed over the runs, the NEES truncated to the
ticks every run has and kept per run for the run-averaged band."""

from __future__ import annotations

import numpy as np
import pytest

from relloc.experiments.guler2023 import RunSummary, summarise


def _run(
    rmse: list[list[float]],
    formation: list[list[float]],
    heading: list[float],
    modes: list[float],
    nees: list[list[float]],
    accepted: dict[str, int],
    rejected: dict[str, int],
    nis: dict[str, float],
    refusals: int,
    examples: tuple[str, ...],
) -> RunSummary:
    return RunSummary(
        rmse=np.array(rmse),
        formation_rmse=np.array(formation),
        heading_rmse=np.array(heading),
        mode_ticks=np.array(modes),
        nees_position=np.array(nees),
        accepted=accepted,
        rejected=rejected,
        nis_sums=nis,
        triangle_refusals=refusals,
        refusal_examples=examples,
        traces=None,
    )


def _blocks(r: int, c: int, t: int, h: int = 0) -> dict[str, int]:
    return {"range": r, "camera": c, "triangle": t, "leader_heading": h}


RUNS = [
    _run(
        [[0.1, 0.2], [0.3, 0.4]],
        [[0.05, 0.06], [0.07, 0.08]],
        [0.01, 0.02],
        [6, 3, 1],
        [[1, 2], [3, 4], [5, 6]],
        _blocks(10, 4, 2),
        _blocks(2, 1, 0),
        {"range": 12.0, "camera": 30.0, "triangle": 8.0, "leader_heading": 0.0},
        2,
        ("a", "b"),
    ),
    _run(
        [[0.3, 0.2], [0.1, 0.6]],
        [[0.01, 0.02], [0.03, 0.09]],
        [0.03, 0.04],
        [2, 5, 3],
        [[3, 2], [1, 0], [1, 2], [9, 9]],  # one tick more than the other run
        _blocks(6, 2, 0),
        _blocks(2, 0, 0),
        {"range": 4.0, "camera": 6.0, "triangle": 0.0, "leader_heading": 0.0},
        1,
        ("c", "d"),
    ),
]


def test_scenario_block_of_two_runs_by_hand() -> None:
    b = summarise(RUNS)
    assert b["runs"] == 2
    assert b["rmse_m"]["R1"] == pytest.approx({"x": 0.2, "y": 0.2})
    assert b["rmse_m"]["R2"] == pytest.approx({"x": 0.2, "y": 0.5})
    assert b["rmse_m_max_over_runs"] == {"R1": {"x": 0.3, "y": 0.2}, "R2": {"x": 0.3, "y": 0.6}}
    # the largest and the mean over followers, axes and runs: 0.6 and 2.2/8
    assert b["rmse_m_worst"] == 0.6 and b["rmse_m_mean"] == pytest.approx(0.275)
    assert b["heading_rmse_rad"] == pytest.approx({"R1": 0.02, "R2": 0.03})
    assert b["formation_rmse_m"]["R1"] == pytest.approx({"x": 0.03, "y": 0.04})
    assert b["formation_rmse_m"]["R2"] == pytest.approx({"x": 0.05, "y": 0.085})
    assert b["formation_rmse_m_worst"] == 0.09
    # ticks 8, 8 and 4 of 20
    assert b["mode_fraction"] == pytest.approx({"sw1": 0.4, "sw2": 0.4, "sw3": 0.2})
    # the first three ticks of each run: NEES sums 21 and 9 over 12 values, per 2 DOF
    assert b["anees_position"] == pytest.approx(1.25)
    assert b["nees_run_average"]["runs"] == 2 and b["nees_run_average"]["instants"] == 6
    assert b["gate_rejections"] == {
        "range": {"rejected": 4, "applied": 16},
        "camera": {"rejected": 1, "applied": 6},
        "triangle": {"rejected": 0, "applied": 2},
        "leader_heading": {"rejected": 0, "applied": 0},
    }
    # NIS over every block of the kind, applied or gated out, per dimension (1, 3, 2, 1); no
    # leader-heading block ran, so its mean is undefined, not 0
    nis = b["mean_nis_per_dof"]
    assert nis.pop("leader_heading") is None
    assert nis == pytest.approx(
        {"range": 16.0 / 20.0, "camera": 36.0 / 21.0, "triangle": 8.0 / 4.0}
    )
    assert b["triangle_refusals"] == 3
    assert b["triangle_refusal_examples"] == ["a", "b", "c"]
