"""Refusals of malformed scalar rows and symbolic models (each naming where), the empty
concatenation, and the range and GPS outputs of the symbolic unicycle models."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
import sympy as sp

from relloc.errors import ModelError
from relloc.models import symbolic as S
from relloc.models.planar_measurement import RowKind, ScalarRows, empty_rows, linearise_rows

X, Y = sp.symbols("x y", real=True)
U, C = sp.symbols("u c", real=True)


def _rows(**changes: Any) -> ScalarRows:
    """One range row of robot 0 to robot 1."""
    fields: dict[str, Any] = dict(
        kind=np.array([RowKind.RANGE]),
        observer=np.array([0]),
        target=np.array([1]),
        landmark_xy=np.zeros((1, 2)),
        z=np.array([1.0]),
        sigma=np.array([0.1]),
        group=np.array([0]),
    )
    fields.update(changes)
    return ScalarRows(**fields)


@pytest.mark.parametrize(
    ("changes", "match"),
    [
        ({"landmark_xy": np.zeros(2)}, r"ScalarRows\.landmark_xy: expected shape \(1, 2\)"),
        ({"z": np.array([np.nan])}, "ScalarRows: z must be finite and sigma > 0"),
        ({"sigma": np.array([0.0])}, "ScalarRows: z must be finite and sigma > 0"),
    ],
)
def test_malformed_scalar_rows_are_refused(changes: dict[str, Any], match: str) -> None:
    with pytest.raises(ModelError, match=match):
        _rows(**changes)


def test_no_batches_concatenate_to_no_rows_and_a_foreign_robot_is_refused() -> None:
    assert ScalarRows.concatenate([]).size == 0
    assert ScalarRows.concatenate([empty_rows(), _rows()]).size == 1
    X2 = np.zeros((2, 3))
    with pytest.raises(
        ModelError, match="linearise_rows: robot index out of range for a team of 2"
    ):
        linearise_rows(X2, _rows(target=np.array([2])))
    with pytest.raises(
        ModelError, match="linearise_rows: robot index out of range for a team of 2"
    ):
        linearise_rows(X2, _rows(observer=np.array([-1])))


#: The toy model's fields here: ``h = x + c`` with the free parameter ``c``.
WITH_C: dict[str, Any] = {"outputs": (X + C,), "parameters": (C,)}


@pytest.mark.parametrize(
    ("changes", "match"),
    [
        ({"states": ()}, "states must not be empty"),
        ({"states": (X, X)}, "duplicate state symbols"),
        ({"drift": (0,)}, "drift needs 2 entries"),
        ({"input_fields": ()}, "one input field per input needed"),
        ({"input_fields": ((1,),)}, "field of u needs 2 entries"),
        ({"output_names": ()}, "one output name per output needed"),
        ({"input_fields": ((U, 0),)}, "field of u uses undeclared symbols"),
        ({"state_box": ((0.0, 1.0),)}, r"state_box needs 2 \(low, high\)"),
        ({"state_box": ((0.0, 1.0), (1.0, 1.0))}, r"state_box needs 2 \(low, high\)"),
        ({"parameter_box": ((0.0, 1.0), (0.0, 1.0))}, "parameter_box size mismatch"),
        ({"input_groups": {"w": (C,)}}, "input_groups name unknown inputs"),
    ],
)
def test_malformed_symbolic_models_are_refused(
    changes: dict[str, Any], match: str, toy_symbolic_model
) -> None:
    with pytest.raises(ModelError, match=f"SymbolicModel 'toy': {match}"):
        toy_symbolic_model(**{**WITH_C, **changes})


def test_free_parameters_need_an_rng(toy_symbolic_model) -> None:
    model = toy_symbolic_model(**WITH_C)
    with pytest.raises(ModelError, match="model 'toy': free parameters need an rng"):
        model.parameters_for(np.zeros(2))
    c = model.parameters_for(np.zeros(2), np.random.default_rng(0))
    assert c.shape == (1,) and -5.0 <= c[0] <= 5.0
    assert toy_symbolic_model().parameters_for(np.zeros(2)).size == 0


def test_landmark_ranges_are_the_distances_to_the_landmarks() -> None:
    model = S.unicycle_landmarks(1, measured=("range",))
    assert model.output_names == ("range_L0",)
    x, y, psi = S.UNICYCLE_STATES
    lx, ly = model.parameters
    value = model.outputs[0].subs({x: 1.0, y: 2.0, psi: 0.3, lx: 4.0, ly: 6.0})
    assert float(value) == pytest.approx(5.0)  # a 3-4-5 triangle
    with pytest.raises(ModelError, match="unicycle_landmarks: n_landmarks must be ≥ 1"):
        S.unicycle_landmarks(0)
    with pytest.raises(ModelError, match="unicycle_landmarks: measured must be a subset"):
        S.unicycle_landmarks(1, measured=("height",))
    with pytest.raises(ModelError, match="unicycle_landmarks: measured must be a subset"):
        S.unicycle_landmarks(1, measured=())


def test_a_gps_robot_measures_its_own_pose() -> None:
    model = S.unicycle_team(2, gps=(2,))
    assert model.output_names == ("gps_x_2", "gps_y_2", "gps_psi_2")
    assert model.outputs == model.states[3:6]


@pytest.mark.parametrize(
    ("args", "match"),
    [
        ({"n": 0}, "unicycle_team: n must be ≥ 1"),
        ({"n": 2, "robot_edges": ((1, 3),)}, r"unicycle_team: robot index 3 outside 1\.\.2"),
        ({"n": 2, "robot_edges": ((1, 1),)}, "unicycle_team: robot 1 cannot measure itself"),
        (
            {"n": 2, "landmark_edges": ((1, 2),), "n_landmarks": 1},
            r"unicycle_team: landmark 2 outside 1\.\.1",
        ),
        ({"n": 2}, "unicycle_team: no measurements"),
    ],
)
def test_malformed_teams_are_refused(args: dict[str, Any], match: str) -> None:
    with pytest.raises(ModelError, match=match):
        S.unicycle_team(**args)


def test_an_unknown_air_ground_mode_is_refused() -> None:
    with pytest.raises(ModelError, match="airground_follower: mode must be one of"):
        S.airground_follower(4)
