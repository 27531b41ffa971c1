"""``relloc reproduce wanasinghe-observability``
(:mod:`relloc.experiments.wanasinghe_observability`): each case's verdict against the paper's
claim follows the rank *and* the conditions found (a full rank reached under other input
conditions than the claim's is a disagreement), and the Eq.-12-as-printed model differs from
the derived one exactly by the missing −1 of ω_l on φ̇."""

from __future__ import annotations

import sympy as sp

from relloc.experiments import wanasinghe_observability as wo
from relloc.models import symbolic as S
from relloc.observability.analysis import ObservabilityResult, Witness


def _result(rank: int, conditions: tuple[tuple[str, ...], ...]) -> ObservabilityResult:
    return ObservabilityResult(
        model="hand",
        description="hand-built",
        state_names=("x", "y", "z", "phi"),
        order=2,
        rank=rank,
        conditions=conditions,
        input_conditions=None,
        rank_without={},
        subset_ranks={"v_l+v_c": rank},
        unobservable_directions=(),
        witness=Witness(state={}, parameters={}, rank=rank, singular_values=()),
        precise_rank=rank,
        n_rows=8,
        elapsed_s=0.0,
    )


def _case(name: str) -> wo._Case:
    (case,) = [c for c in wo._cases() if c.name == name]
    return case


def test_verdicts_need_the_claimed_conditions_not_only_the_rank() -> None:
    case3 = _case("case3_range_nonlinear")
    assert wo._case_entry(case3, _result(4, (("v_l", "v_c"),)))["agrees"] is True
    assert wo._case_entry(case3, _result(4, (("v_c",),)))["agrees"] is False
    assert wo._case_entry(case3, _result(3, (("v_l", "v_c"),)))["agrees"] is False
    lemma1 = _case("case1_range_bearing_pseudo_linear")
    assert wo._case_entry(lemma1, _result(4, (("v_c",),)))["agrees"] is True
    assert wo._case_entry(lemma1, _result(4, (("v_l", "v_c"),)))["agrees"] is False
    lemma2 = _case("case2_bearing_pseudo_linear")
    assert wo._case_entry(lemma2, _result(4, (("omega_l", "v_c"),)))["agrees"] is True
    assert wo._case_entry(lemma2, _result(4, (("v_c",),)))["agrees"] is False
    unclaimed = _case("guler_sw3_range_only")
    entry = wo._case_entry(unclaimed, _result(3, ()))
    assert entry["agrees"] is None and entry["rank"] == 3 and entry["state_dim"] == 4


def test_eq12_as_printed_drops_only_the_minus_one_on_phi() -> None:
    """The derived ω_l field is (y, −x, 0, −1): φ̇ = ω_c − ω_l; Eq. 12 prints (y, −x, 0, 0)."""
    x, y = S.RELATIVE_STATES[:2]
    derived = S.relative_pseudo_linear(("azimuth", "elevation"))
    printed = wo._eq12_as_printed(derived)
    assert tuple(derived.input_fields[3]) == (y, -x, sp.Integer(0), sp.Integer(-1))
    assert tuple(printed.input_fields[3]) == (y, -x, sp.Integer(0), sp.Integer(0))
    assert printed.input_fields[:3] == derived.input_fields[:3]
    assert printed.name.endswith("[Eq. 12 as printed]")
