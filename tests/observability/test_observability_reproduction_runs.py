"""The two observability reproductions run end to end from the command line, at small sizes
(``wanasinghe-observability`` with one witness run, ``sharma-observability`` with two random
teams per case): their summary, report and figures are written, the summary's top-level keys
are named in the module docstring, and the findings hold — the ranks the papers state, the
counter-examples and printed-equation typos found by the symbolic checks, β = 1 ⇔ rank 3n
along Fig. 2, and a PCRLB that more absolute information lowers. Until now only their building
blocks were tested (``test_reproductions``)."""

from __future__ import annotations

import importlib
import json
import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from relloc.cli import main
from relloc.cli.extras import available
from relloc.experiments import registry

#: Cases whose rank the seed-000 paper states and the analysis reproduces.
WANASINGHE_AGREE = (
    "case1_range_bearing_pseudo_linear",
    "case2_bearing_pseudo_linear",
    "case2_bearing_pseudo_linear_eq12_as_printed",
    "appendix1_bearing_pseudo_linear_only_v_c_v_l",
    "case3_range_nonlinear",
    "case3_range_nonlinear_without_v_l",
    "case2_bearing_nonlinear",
    "appendix1_bearing_nonlinear_only_v_c_v_l",
)
#: The lemmas' conditions that a vertical observed-robot velocity alone does not meet.
WANASINGHE_COUNTER_EXAMPLES = ("lemma1_vertical_v_c_only", "lemma2_vertical_v_c_with_omega_l")


def _run(name: str, out: Path, *flags: str) -> dict[str, Any]:
    assert main(["reproduce", name, "--out", str(out), "--quiet", *flags]) == 0
    assert (out / "report.md").is_file()
    summary: dict[str, Any] = json.loads((out / "summary.json").read_text())
    doc = importlib.import_module(registry.EXPERIMENTS[name]).__doc__ or ""
    named = {w for s in re.findall(r"``(.+?)``", doc, flags=re.S) for w in re.findall(r"\w+", s)}
    assert [key for key in summary if key not in named] == []
    return summary


@pytest.fixture(scope="module")
def wanasinghe(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict[str, Any]]:
    out = tmp_path_factory.mktemp("wanasinghe_observability")
    return out, _run("wanasinghe-observability", out, "--runs", "1")


@pytest.fixture(scope="module")
def sharma(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict[str, Any]]:
    out = tmp_path_factory.mktemp("sharma_observability")
    return out, _run("sharma-observability", out, "--runs", "2", "--executor", "serial")


def test_wanasinghe_observability_reproduces_the_stated_ranks(wanasinghe) -> None:
    _, summary = wanasinghe
    cases = summary["cases"]
    for name in WANASINGHE_AGREE:
        assert cases[name]["agrees"] is True, (name, cases[name]["rank"])
    for name in WANASINGHE_COUNTER_EXAMPLES:  # rank 3 of 4: a vertical v_c alone is not enough
        assert cases[name]["agrees"] is False and cases[name]["rank"] == 3, name
    # the printed Eqs. 16, 20 and 21 are wrong at a stated witness; Eqs. 30 and 31 hold
    checks = summary["equation_checks"]
    assert [k for k, v in checks.items() if v["agrees"]] == [
        "eq30_gram_bearing_rows",
        "eq31_gram_grad_phi_L_f2_h2",
    ]
    assert all(v["witness"] for v in checks.values())


def test_sharma_observability_agrees_with_the_graph_theorems(sharma) -> None:
    _, summary = sharma
    assert {k: v["agrees"] for k, v in summary["cases"].items() if v["agrees"] is not True} == {}
    assert summary["cases"]["twenty_robots"]["rank"] == 60  # 3n: connected, with landmarks
    fig2 = summary["fig2"]
    assert fig2["agreement_fraction"] == 1.0
    assert len(fig2["t"]) == len(fig2["beta"]) == len(fig2["rank"]) > 100


def test_sharma_observability_bound_falls_with_absolute_information(sharma) -> None:
    _, summary = sharma
    final = {k: np.asarray(v["sqrt_bound_final"]) for k, v in summary["pcrlb_robot2"].items()}
    assert all(np.all(np.isfinite(b) & (b > 0)) for b in final.values())
    position = {k: float(np.hypot(*b[:2])) for k, b in final.items()}
    assert position["two landmarks"] < position["one landmark"] < position["no landmarks"]
    assert position["GPS on robot 1"] < position["no landmarks"]


@pytest.mark.skipif(not available("plot"), reason="figures need relloc[plot]")
def test_observability_reproductions_write_their_figures(wanasinghe, sharma) -> None:
    for out, names in (
        (wanasinghe[0], ("observability_ranks.png", "observability_input_subsets.png")),
        (sharma[0], ("fig2_beta_sigma_min.png", "fig2_team_snapshots.png", "pcrlb_robot2.png")),
    ):
        for name in names:
            assert (out / name).stat().st_size > 1000, name
