"""Symbolic observability analysis: known answers (linear, unicycle) and the seed cases."""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

from relloc.errors import ModelError
from relloc.models import symbolic as S
from relloc.observability.analysis import analyse, rank_at
from relloc.observability.lie import lie_rows


def _linear_model(A: np.ndarray, C: np.ndarray) -> S.SymbolicModel:
    n = A.shape[0]
    xs = sp.symbols(f"q0:{n}")
    X = sp.Matrix(xs)
    Am = sp.Matrix(A.astype(int).tolist())
    Cm = sp.Matrix(C.astype(int).tolist())
    return S.SymbolicModel(
        name="linear",
        description="linear test system",
        states=tuple(xs),
        drift=tuple(Am * X),
        inputs=(),
        input_fields=(),
        outputs=tuple(Cm * X),
        output_names=tuple(f"y{i}" for i in range(C.shape[0])),
    )


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_linear_system_rank_equals_kalman_rank(seed: int) -> None:
    rng = np.random.default_rng(seed)
    n = 5
    # a block-triangular A with an unobservable block of random size
    k = int(rng.integers(0, 3))
    A = rng.integers(-3, 4, size=(n, n))
    A[: n - k, n - k :] = 0  # the last k states never feed the observed ones
    C = np.zeros((1, n), dtype=int)
    C[0, : n - k] = rng.integers(1, 4, size=n - k)
    kalman = np.linalg.matrix_rank(
        np.vstack([C @ np.linalg.matrix_power(A, i) for i in range(n)]).astype(float)
    )
    result = analyse(_linear_model(A, C), order=n - 1, samples=2)
    assert result.rank == kalman
    assert result.conditions == ((),)  # no inputs involved


def test_unicycle_one_landmark_bearing_has_rank_two_and_rotation_direction() -> None:
    r = analyse(S.unicycle_landmarks(1), order=2)
    assert r.rank == 2 and r.state_dim == 3
    assert r.conditions == (("v",),)
    (direction,) = r.unobservable_directions
    # rotation about the landmark: (ly − y, x − lx, 1) up to sign
    assert "ly_0 - y" in direction and "lx_0" in direction
    assert analyse(S.unicycle_landmarks(2), order=2).rank == 3


def test_seed000_pseudo_linear_lemmas_and_appendix() -> None:
    case1 = analyse(S.relative_pseudo_linear(), order=2)
    assert case1.rank == 4 and case1.conditions == (("v_c",),)  # Lemma 1
    assert case1.input_conditions == (("v_xc",), ("v_yc",))  # horizontal part only
    case2 = analyse(S.relative_pseudo_linear(("azimuth", "elevation")), order=2)
    assert case2.rank == 4 and case2.conditions == (("omega_l", "v_c"),)  # Lemma 2
    app = analyse(S.relative_pseudo_linear(("azimuth", "elevation")).with_inputs(["v_c", "v_l"]))
    assert app.rank == 3  # Appendix 1
    (direction,) = app.unobservable_directions  # along the measured line of sight
    assert "cos(alpha_m)*cos(theta_m)" in direction and "sin(alpha_m)" in direction


def test_seed000_nonlinear_cases() -> None:
    case3 = analyse(S.relative_nonlinear(("range",)), order=2)
    assert case3.rank == 4 and case3.conditions == (("v_l", "v_c"),)
    rot = analyse(
        S.relative_nonlinear(("range",)).with_inputs(["v_c", "omega_l", "omega_c"]), samples=2
    )
    assert rot.rank == 3
    assert rot.unobservable_directions[0].endswith("(-y, x, 0, 1)")  # yaw about the observer
    bearing = analyse(S.relative_nonlinear(("azimuth", "elevation")), order=1, samples=2)
    assert bearing.rank == 4 and bearing.conditions == (("v_c",),)  # first order suffices


def test_rank_at_constant_inputs_refutes_vertical_only_motion() -> None:
    model = S.relative_pseudo_linear()
    state = [2.0, -1.0, 0.7, 0.4]
    climb = [0, 0, 0, 0, 0, 0, 1.0, 0]  # observed robot only climbs: v_c ≠ 0
    drive = [0, 0, 0, 0, 1.0, 0, 0, 0]
    assert rank_at(model, state, climb) == 3
    assert rank_at(model, state, drive) == 4


def test_seed003_modes() -> None:
    ranks = {m: analyse(S.airground_follower(m), order=2, samples=2) for m in S.AIRGROUND_MODES}
    assert ranks[1].rank == 4 and ranks[1].conditions == ((),)
    assert ranks[2].rank == 4 and ranks[2].conditions == (("v_i",),)
    assert ranks[3].rank == 3 and ranks[3].conditions == (("v_i", "v_0"),)
    assert ranks[3].unobservable_directions[0].endswith("(-r_y, r_x, 1, 1)")


def test_pruning_keeps_every_subset_rank() -> None:
    model = S.relative_nonlinear(("range",))
    full = analyse(model, order=2)
    pruned_rows = lie_rows(model, 2)
    all_rows = lie_rows(model, 2, prune=False)
    assert len(pruned_rows) < len(all_rows)
    assert full.subset_ranks["v_l+v_c"] == 4 and full.subset_ranks["v_c"] == 3


def test_model_validation_names_the_problem() -> None:
    x, y = sp.symbols("x y")
    with pytest.raises(ModelError, match="undeclared"):
        S.SymbolicModel(
            name="bad",
            description="",
            states=(x,),
            drift=(0,),
            inputs=(),
            input_fields=(),
            outputs=(x + y,),
            output_names=("h",),
        )
    with pytest.raises(ModelError, match="unknown input"):
        S.relative_nonlinear().with_inputs(["v_q"])
    with pytest.raises(ModelError, match="measured"):
        S.relative_nonlinear(("heading",))
