"""``relloc observability``: built-ins listed, smoke runs, user entry points, bad input."""

from __future__ import annotations

import json
import textwrap
from pathlib import Path

import pytest

from relloc.cli import main
from relloc.observability.builtin import BUILTIN_MODELS


def test_help_lists_every_builtin(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exc:
        main(["observability", "--help"])
    assert exc.value.code == 0
    out = capsys.readouterr().out
    for name in BUILTIN_MODELS:
        assert name in out
    assert "package.module:function" in out


def test_airground_mode3_reports_rank_direction_and_json(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out_file = tmp_path / "obs.json"
    code = main(["observability", "airground", "--mode", "3", "--json", str(out_file)])
    assert code == 0
    text = capsys.readouterr().out
    assert "rank       3 of 4" in text and "needs v_i ≠ 0 and v_0 ≠ 0" in text
    (result,) = json.loads(out_file.read_text())
    assert result["rank"] == 3 and result["state_dim"] == 4
    assert result["unobservable_directions"] == ["(r_x, r_y, theta_i, theta_0) ∝ (-r_y, r_x, 1, 1)"]


def test_relative_models_say_who_observes_whom(capsys: pytest.CaptureFixture[str]) -> None:
    """The conditions read "needs v_c ≠ 0": the model line says that c is the observed robot,
    l the observer, and the state c's pose in l's frame."""
    assert main(["observability", "relative-nonlinear", "--measurements", "range"]) == 0
    model_line = capsys.readouterr().out.splitlines()[0]
    assert "robot l observes robot c" in model_line
    assert "c's position and heading in l's frame" in model_line


def test_rank_at_given_state_and_inputs(capsys: pytest.CaptureFixture[str]) -> None:
    code = main(
        [
            "observability",
            "relative-pseudo-linear",
            "--at-state",
            "x=2,y=-1,z=0.5,phi=0.3",
            "--at-inputs",
            "v_zc=1",
        ]
    )
    assert code == 0
    assert "rank at the given state and constant inputs: 3" in capsys.readouterr().out


def test_user_entry_point(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    (tmp_path / "my_obs_model.py").write_text(
        textwrap.dedent(
            """
            import sympy as sp
            from relloc.models.symbolic import SymbolicModel

            def model():
                p, v = sp.symbols("p v")
                u = sp.Symbol("a")
                return SymbolicModel(
                    name="double-integrator", description="position measured",
                    states=(p, v), drift=(v, 0), inputs=(u,), input_fields=((0, 1),),
                    outputs=(p,), output_names=("p",),
                )

            def not_a_model():
                return 42
            """
        )
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    assert main(["observability", "my_obs_model:model", "--order", "1"]) == 0
    out = capsys.readouterr().out
    assert "rank       2 of 2 (observable)" in out and "no input needed" in out
    assert main(["observability", "my_obs_model:not_a_model"]) == 4
    assert main(["observability", "no_such_module_xyz:model"]) == 2


def test_unknown_model_and_bad_options_exit_2() -> None:
    assert main(["observability", "teleporter"]) == 2
    assert main(["observability", "airground", "--mode", "7"]) == 2
    assert main(["observability", "relative-nonlinear", "--at-state", "q=1"]) == 2
