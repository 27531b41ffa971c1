"""``relloc reproduce wanasinghe-observability``: seed 000 §4 (and seed 003's modes), re-derived.

Runs the Lie-derivative analysis of :mod:`relloc.observability.analysis` on the SymPy models of
:mod:`relloc.models.symbolic` and compares each result with the paper's claim:

- seed 000 (Wanasinghe et al. 2014) Case 1 range + bearing with pseudo-linear rows (Lemma 1),
  Case 2 bearing only (Lemma 2), Appendix 1 (only ``v_c`` and ``v_l`` excited → rank 3), Case 3
  nonlinear range only; the same cases with the *nonlinear* range/azimuth/elevation; and
  counter-examples with a purely vertical ``v_c`` (rank at given constant inputs,
  :func:`~relloc.observability.analysis.rank_at`), which the lemmas' "v_c ≠ 0" admits;
- the printed determinants of Eqs. 20, 21, 30, 31 and the gradient of Eq. 16, checked
  symbolically;
- seed 003 (Güler et al.) measurement modes ``sw = 1, 2, 3`` (the paper leaves their
  observability as future work).

``--runs`` is the number of random states used for each generic rank (default 5; no Monte
Carlo is involved, the analysis is deterministic given ``--seed``).

summary.json keys: ``experiment``, ``seed``, ``runs``, ``cases`` (name → ``rank``,
``state_dim``, ``conditions`` (minimal sets of input groups that must be non-zero),
``conditions_text``, ``input_conditions`` (the same over scalar inputs),
``unobservable_directions``, ``paper_claim``, ``agrees`` (true/false, null where the paper makes
no claim), ``evidence``, ``note`` (empty when none), ``elapsed_s`` (s)), ``equation_checks``
(equation → ``paper``, the printed expression, ``ours``, the derived one, ``agrees``,
``witness``, a text naming where they differ or that the identity holds), ``total_symbolic_s``
(s, every case and check).

The cases, in the summary's order: ``case1_range_bearing_pseudo_linear``,
``case2_bearing_pseudo_linear``, ``case2_bearing_pseudo_linear_eq12_as_printed``,
``appendix1_bearing_pseudo_linear_only_v_c_v_l``, ``case3_range_nonlinear``,
``case3_range_nonlinear_without_v_l``, ``case1_range_bearing_nonlinear``,
``case2_bearing_nonlinear``, ``appendix1_bearing_nonlinear_only_v_c_v_l``, seed 003's
``guler_sw1_range_bearing_headings``, ``guler_sw2_range_triangle_bearing_leader_heading``,
``guler_sw3_range_only``, then the counter-examples ``lemma1_vertical_v_c_only`` and
``lemma2_vertical_v_c_with_omega_l``. The equation checks: ``eq16_gradient_row1``,
``eq20_det_H_pmo``, ``eq21_gram_grad_phi_L_f2_h``, ``eq30_gram_bearing_rows``,
``eq31_gram_grad_phi_L_f2_h2``.

The analysed cases' ``evidence``: ``witness_state`` (state name → value) and
``witness_parameters`` (the measured bearings the pseudo-linear rows take as constants, name →
value; empty for the other models) of the state at which the generic rank is attained,
``singular_values`` of the observability matrix there, ``precise_rank`` (its rank re-checked in
50-digit arithmetic) and ``subset_ranks`` (``"v_l+v_c"``, …, ``"none"`` → the generic rank with
only those input groups non-zero). The two counter-examples differ: ``rank`` is the rank at
:data:`WITNESS_STATE` with a purely vertical ``v_c`` (and, for Lemma 2, ``omega_l`` = 0.3;
:func:`~relloc.observability.analysis.rank_at`), ``conditions`` are scalar inputs (``v_xc`` or
``v_yc``), ``input_conditions`` is null, and ``unobservable_directions`` are those of the
generic analysis with the inputs ``v_l``, ``omega_l``, ``v_zc``, ``omega_c``; their
``evidence``: ``witness_state``, ``inputs_vertical`` and ``inputs_horizontal`` (scalar input
→ value), ``rank_vertical`` and ``rank_horizontal`` (the rank at each),
``generic_rank_with_vertical_v_c_and_all_other_inputs``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace
from typing import Any

import sympy as sp

from relloc.experiments.registry import ReproduceArgs
from relloc.models import symbolic as S
from relloc.observability.analysis import ObservabilityResult, analyse, rank_at
from relloc.pipeline.output import (
    figure_md,
    markdown_table,
    prepare_out_dir,
    save_figure,
    write_report,
    write_summary,
)

#: A generic relative state used as the witness of the rank-at-inputs counter-examples.
WITNESS_STATE = (2.0, -1.0, 0.7, 0.4)
_INPUTS = S.RELATIVE_OBSERVER_INPUTS + S.RELATIVE_OBSERVED_INPUTS


@dataclass(frozen=True)
class _Case:
    name: str
    model: S.SymbolicModel
    paper_claim: str
    judge: Any  # (ObservabilityResult) -> bool | None
    note: str = ""


def _inputs(**values: float) -> list[float]:
    names = [str(u) for u in _INPUTS]
    out = [0.0] * len(names)
    for k, v in values.items():
        out[names.index(k)] = v
    return out


def _eq12_as_printed(model: S.SymbolicModel) -> S.SymbolicModel:
    """The model with the ω_l field of Eq. 12 as printed: no −1 on φ̇."""
    x, y = S.RELATIVE_STATES[:2]
    fields = list(model.input_fields)
    fields[3] = (y, -x, sp.Integer(0), sp.Integer(0))
    return replace(model, name=f"{model.name}[Eq. 12 as printed]", input_fields=tuple(fields))


def _cases() -> list[_Case]:
    pl1 = S.relative_pseudo_linear()
    pl2 = S.relative_pseudo_linear(("azimuth", "elevation"))
    nl1 = S.relative_nonlinear()
    nl2 = S.relative_nonlinear(("azimuth", "elevation"))
    nl3 = S.relative_nonlinear(("range",))
    return [
        _Case(
            "case1_range_bearing_pseudo_linear",
            pl1,
            "Lemma 1: rank 4 (locally weakly observable) if v_c ≠ 0",
            lambda r: r.rank == 4 and r.conditions == (("v_c",),),
        ),
        _Case(
            "case2_bearing_pseudo_linear",
            pl2,
            "Lemma 2: rank 4 if v_c ≠ 0 and ω_l ≠ 0",
            lambda r: r.rank == 4 and r.conditions == (("omega_l", "v_c"),),
        ),
        _Case(
            "case2_bearing_pseudo_linear_eq12_as_printed",
            _eq12_as_printed(pl2),
            "Lemma 2 derived with Eq. 12, whose ω_l field lacks the −1 on φ̇",
            lambda r: r.rank == 4 and r.conditions == (("omega_l", "v_c"),),
            "the omission changes no rank: same conditions and input-subset ranks as case 2",
        ),
        _Case(
            "appendix1_bearing_pseudo_linear_only_v_c_v_l",
            pl2.with_inputs(["v_l", "v_c"]),
            "Appendix 1: with only v_c ≠ 0 and v_l ≠ 0, rank 3 (not observable)",
            lambda r: r.rank == 3,
        ),
        _Case(
            "case3_range_nonlinear",
            nl3,
            "Case 3: nonlinear range only is observable if v_c ≠ 0 and v_l ≠ 0 (citing Martinelli)",
            lambda r: r.rank == 4 and r.conditions == (("v_l", "v_c"),),
        ),
        _Case(
            "case3_range_nonlinear_without_v_l",
            nl3.with_inputs(["omega_l", "v_c", "omega_c"]),
            "Case 3: v_l ≠ 0 is part of the sufficient condition",
            lambda r: r.rank == 3,
            "without v_l the yaw of the whole pair about the observer's z-axis is unobservable",
        ),
        _Case(
            "case1_range_bearing_nonlinear",
            nl1,
            "not analysed (§4 asks whether the pseudo-linear form changes observability)",
            lambda r: None,
            "same condition as Lemma 1: for range + bearing the pseudo-linear rows change nothing",
        ),
        _Case(
            "case2_bearing_nonlinear",
            nl2,
            "§4: with nonlinear bearings v_c ≠ 0 and v_l ≠ 0 is sufficient (citing Martinelli)",
            lambda r: r.rank == 4 and r.subset_ranks.get("v_l+v_c") == 4,
            "v_c ≠ 0 alone suffices generically (known speed fixes the bearing-only scale)",
        ),
        _Case(
            "appendix1_bearing_nonlinear_only_v_c_v_l",
            nl2.with_inputs(["v_l", "v_c"]),
            "§4: nonlinear bearings with v_c ≠ 0 and v_l ≠ 0 are observable",
            lambda r: r.rank == 4,
            "the Appendix-1 rank loss comes from treating the measured bearings as constants",
        ),
        _Case(
            "guler_sw1_range_bearing_headings",
            S.airground_follower(1),
            "not analysed (seed 003 leaves observability to future work)",
            lambda r: None,
        ),
        _Case(
            "guler_sw2_range_triangle_bearing_leader_heading",
            S.airground_follower(2),
            "not analysed (seed 003 leaves observability to future work)",
            lambda r: None,
        ),
        _Case(
            "guler_sw3_range_only",
            S.airground_follower(3),
            "not analysed (seed 003 leaves observability to future work)",
            lambda r: None,
        ),
    ]


def _case_entry(case: _Case, r: ObservabilityResult) -> dict[str, Any]:
    verdict = case.judge(r)
    return {
        "rank": r.rank,
        "state_dim": r.state_dim,
        "conditions": [list(c) for c in r.conditions] if r.conditions is not None else None,
        "conditions_text": r.conditions_text(),
        "input_conditions": [list(c) for c in r.input_conditions]
        if r.input_conditions is not None
        else None,
        "unobservable_directions": list(r.unobservable_directions),
        "paper_claim": case.paper_claim,
        "agrees": verdict,
        "evidence": {
            "witness_state": r.witness.state,
            "witness_parameters": r.witness.parameters,
            "singular_values": list(r.witness.singular_values),
            "precise_rank": r.precise_rank,
            "subset_ranks": r.subset_ranks,
        },
        "note": case.note,
        "elapsed_s": r.elapsed_s,
    }


def _vertical_counterexamples(samples: int, seed: int) -> dict[str, dict[str, Any]]:
    """Lemmas 1–2 say ``v_c ≠ 0``; a purely vertical ``v_c`` satisfies that and loses φ."""
    out: dict[str, dict[str, Any]] = {}
    specs = (
        (
            "lemma1_vertical_v_c_only",
            S.relative_pseudo_linear(),
            "Lemma 1: v_c ≠ 0 is sufficient",
            _inputs(v_zc=1.0),
            _inputs(v_xc=1.0),
            ["v_l", "omega_l", "v_zc", "omega_c"],
        ),
        (
            "lemma2_vertical_v_c_with_omega_l",
            S.relative_pseudo_linear(("azimuth", "elevation")),
            "Lemma 2: v_c ≠ 0 and ω_l ≠ 0 are sufficient",
            _inputs(v_zc=1.0, omega_l=0.3),
            _inputs(v_xc=1.0, omega_l=0.3),
            ["v_l", "omega_l", "v_zc", "omega_c"],
        ),
    )
    for name, model, claim, vertical, horizontal, excited in specs:
        t0 = time.perf_counter()
        r_vert = rank_at(model, WITNESS_STATE, vertical)
        r_horiz = rank_at(model, WITNESS_STATE, horizontal)
        restricted = analyse(model.with_inputs(excited), samples=samples, seed=seed)
        out[name] = {
            "rank": r_vert,
            "state_dim": model.n,
            "conditions": [["v_xc"], ["v_yc"]],
            "conditions_text": "needs the horizontal part (v_xc, v_yc) of v_c ≠ 0",
            "input_conditions": None,
            "unobservable_directions": list(restricted.unobservable_directions),
            "paper_claim": claim,
            "agrees": r_vert == model.n,
            "evidence": {
                "witness_state": dict(zip(model.state_names, WITNESS_STATE, strict=True)),
                "inputs_vertical": dict(zip(model.input_names, vertical, strict=True)),
                "rank_vertical": r_vert,
                "inputs_horizontal": dict(zip(model.input_names, horizontal, strict=True)),
                "rank_horizontal": r_horiz,
                "generic_rank_with_vertical_v_c_and_all_other_inputs": restricted.rank,
            },
            "note": "φ enters only through the horizontal velocity of the observed robot",
            "elapsed_s": time.perf_counter() - t0,
        }
    return out


def _trig_reduce(expr: sp.Expr, angles: tuple[sp.Symbol, ...]) -> sp.Expr:
    """Canonical form of a polynomial in sines and cosines: expand, then replace every
    ``sin(a)²`` by ``1 − cos(a)²`` (exact, and far cheaper than ``simplify``)."""
    out = sp.expand(expr)
    for a in angles:
        out = sp.expand(out.subs(sp.sin(a) ** 2, 1 - sp.cos(a) ** 2))
    return out


def _equation_checks() -> dict[str, dict[str, Any]]:
    """Symbolic checks of the determinants and gradient printed in seed 000 §4."""
    th, al = S.RELATIVE_BEARINGS
    phi = S.RELATIVE_STATES[3]

    def same(a: sp.Expr, b: sp.Expr) -> bool:
        return bool(_trig_reduce(a - b, (th, al, phi)) == 0)

    def canon(e: sp.Expr) -> sp.Expr:
        return sp.factor(_trig_reduce(e, (th, al, phi)))

    rows = S.pseudo_linear_rows()
    H = sp.Matrix([list(rows[k][:3]) for k in ("range", "azimuth", "elevation")])
    ct, st, ca, sa = sp.cos(th), sp.sin(th), sp.cos(al), sp.sin(al)
    checks: dict[str, dict[str, Any]] = {}

    grad = sp.Matrix([S.relative_pseudo_linear().outputs[0]]).jacobian(sp.Matrix(S.RELATIVE_STATES))
    paper16 = sp.Matrix([[ct * ca, st * sa, sa, 0]])
    w16 = {th: sp.pi / 4, al: sp.pi / 6}
    checks["eq16_gradient_row1"] = {
        "paper": sp.sstr(list(paper16)),
        "ours": sp.sstr(list(grad)),
        "agrees": all(same(p, g) for p, g in zip(paper16, grad, strict=True)),
        "witness": f"θ=π/4, α=π/6, entry (1,2): paper {sp.nsimplify(paper16[1].subs(w16))}, "
        f"ours {sp.nsimplify(grad[1].subs(w16))} (Eq. 3 and Eq. 14 give sθ·cα)",
    }
    det_h = canon(H.det())
    paper20 = ca**2 * ct**2 + ca * sa * st**2 + sa**2 * ct**2 + sa**2 * st**2
    w20 = {th: sp.pi / 2, al: -sp.pi / 4}
    checks["eq20_det_H_pmo"] = {
        "paper": sp.sstr(paper20),
        "ours": sp.sstr(det_h),
        "agrees": same(paper20, det_h),
        "witness": f"θ=π/2, α=−π/4: paper {sp.nsimplify(paper20.subs(w20))}, ours {det_h}",
    }
    C = sp.Matrix([[sp.cos(phi), -sp.sin(phi), 0], [sp.sin(phi), sp.cos(phi), 0], [0, 0, 1]])
    d1 = (H * C).diff(phi)
    gram1 = canon(sum(e**2 for e in d1))
    paper21 = 2 * sa**2 * st**2 - st**2 + 2
    w21 = {th: sp.pi / 2, al: 0}
    checks["eq21_gram_grad_phi_L_f2_h"] = {
        "paper": sp.sstr(paper21),
        "ours": sp.sstr(gram1),
        "agrees": same(paper21, gram1),
        "witness": f"θ=π/2, α=0: paper {paper21.subs(w21)}, ours {gram1} (both non-zero: "
        "the lemma's conclusion stands)",
    }
    a = sp.Matrix([rows["azimuth"][:3]])
    b = sp.Matrix([rows["elevation"][:3]])
    c = sp.Matrix([[-ct, -st, 0]])
    d = sp.Matrix([[sa * st, -sa * ct, 0]])
    B = sp.Matrix.vstack(a, b, c, d)
    gram30 = canon((B.T * B).det())
    checks["eq30_gram_bearing_rows"] = {
        "paper": "1 - sin(alpha)**4",
        "ours": sp.sstr(gram30),
        "agrees": same(gram30, 1 - sa**4),
        "witness": "identity holds for all θ, α",
    }
    H2 = sp.Matrix([rows["azimuth"][:3], rows["elevation"][:3]])
    d2 = (H2 * C).diff(phi)
    gram31 = canon(sum(e**2 for e in d2))
    checks["eq31_gram_grad_phi_L_f2_h2"] = {
        "paper": "1 + sin(alpha)**2",
        "ours": sp.sstr(gram31),
        "agrees": same(gram31, 1 + sa**2),
        "witness": "identity holds for all θ, α, φ",
    }
    return checks


def _figures(out_dir: Any, cases: dict[str, dict[str, Any]]) -> list[str]:
    from relloc.plotting.observability import plot_case_ranks, plot_subset_ranks
    from relloc.plotting.setup import pyplot

    plt = pyplot()

    files = []
    fig, ax = plt.subplots(figsize=(8, 5.5))
    names = list(cases)
    plot_case_ranks(
        ax,
        names,
        [cases[c]["rank"] for c in names],
        [cases[c]["state_dim"] for c in names],
        [cases[c]["agrees"] for c in names],
    )
    ax.set_title("Observability rank per case (bar) vs state dimension (|)")
    files.append(save_figure(fig, out_dir, "observability_ranks"))
    table = {
        c: cases[c]["evidence"]["subset_ranks"]
        for c in names
        if cases[c]["evidence"].get("subset_ranks") and c.startswith("case")
    }
    fig, ax = plt.subplots(figsize=(11, 3.8))
    plot_subset_ranks(ax, table)
    ax.set_title("Rank when only the listed input groups are non-zero (seed 000 model)")
    files.append(save_figure(fig, out_dir, "observability_input_subsets"))
    return files


def reproduce(args: ReproduceArgs) -> dict[str, Any]:
    out_dir = prepare_out_dir(args.out_dir)
    samples = args.runs or 5
    t0 = time.perf_counter()
    cases: dict[str, dict[str, Any]] = {}
    for case in _cases():
        r = analyse(case.model, order=2, samples=samples, seed=args.master_seed, precise=True)
        cases[case.name] = _case_entry(case, r)
        if not args.quiet:
            print(f"{case.name}: rank {r.rank}/{r.state_dim}, {r.conditions_text()}")
    cases.update(_vertical_counterexamples(samples, args.master_seed))
    checks = _equation_checks()
    total = time.perf_counter() - t0
    summary = {
        "experiment": "wanasinghe-observability",
        "seed": args.master_seed,
        "runs": samples,
        "cases": cases,
        "equation_checks": checks,
        "total_symbolic_s": total,
    }
    figures = _figures(out_dir, cases)
    write_summary(out_dir, summary)
    write_report(out_dir, _report(cases, checks, figures, args.master_seed, samples, total))
    return summary


def _report(
    cases: dict[str, dict[str, Any]],
    checks: dict[str, dict[str, Any]],
    figures: list[str],
    seed: int,
    samples: int,
    total: float,
) -> str:
    rows = [
        [
            name,
            f"{c['rank']}/{c['state_dim']}",
            c["conditions_text"],
            "; ".join(c["unobservable_directions"]) or "—",
            c["paper_claim"],
            {True: "agrees", False: "DISAGREES", None: "no claim"}[c["agrees"]],
        ]
        for name, c in cases.items()
    ]
    eq_rows = [[k, v["paper"], v["ours"], v["agrees"], v["witness"]] for k, v in checks.items()]
    vert = cases["lemma1_vertical_v_c_only"]["evidence"]
    parts = [
        "# Observability of the seed-000 relative models (and seed-003 modes), re-derived",
        "",
        f"Seed {seed}; generic ranks from {samples} random states each, double precision with "
        f"a 50-digit re-check at the witness; Lie derivatives up to order 2 along every input "
        f"field (pruned, see `relloc.observability.lie`). Total symbolic time {total:.1f} s.",
        "",
        "Models: `relloc.models.symbolic` (derived, not copied: the relative yaw obeys "
        "φ̇ = ω_c − ω_l, and ω_l also acts on φ, which Eq. 12 omits; the case "
        "`case2_bearing_pseudo_linear_eq12_as_printed` shows the omission changes no rank). "
        "Conditions are the minimal sets of input groups whose Lie derivatives reach the "
        "generic rank (an input held at zero contributes none).",
        "",
        markdown_table(
            ["case", "rank", "conditions (ours)", "unobservable directions", "paper", "verdict"],
            rows,
        ),
        "",
        "## Where we disagree, with evidence",
        "",
        '* **Lemmas 1 and 2 ("v_c ≠ 0")**: the relative yaw φ enters the dynamics only through '
        "the *horizontal* velocity of the observed robot, so a purely vertical v_c (a drone "
        "climbing) satisfies the lemmas' condition yet leaves φ unobservable. Witness: state "
        f"{vert['witness_state']}, v_zc = 1 and all else zero → rank {vert['rank_vertical']}; "
        f"v_xc = 1 instead → rank {vert['rank_horizontal']}. The scalar-input conditions found "
        "are v_xc ≠ 0 or v_yc ≠ 0.",
        "* **Printed determinants**: Eq. 20 and Eq. 21 do not match the matrices they are "
        "computed from. The rows of H_pmo are orthonormal, so det H_pmo ≡ 1, whereas the printed "
        "Eq. 20 even vanishes at θ = π/2, α = −π/4; the Gram determinant of Eq. 21 is the "
        "constant 2, not the printed expression. The true values are never zero, so the lemmas' "
        "conclusions stand. Eqs. 30 and 31 check out. Eq. 16 has a typo (sθ·sα for sθ·cα).",
        "",
        markdown_table(["equation", "paper", "ours", "agrees", "witness"], eq_rows),
        "",
        "## What the nonlinear measurements add",
        "",
        "With the nonlinear azimuth/elevation the pair is observable as soon as the observed "
        "robot moves horizontally (case2_bearing_nonlinear): its known speed fixes the scale "
        "that bearings alone leave free. The Appendix-1 rank loss (rank 3 with only v_c, v_l) is "
        "specific to treating the measured bearings θ̃, α̃ as constant coefficients of the "
        "pseudo-linear rows; the unobservable direction is exactly the measured line of sight "
        "(range). A PLKF re-linearises on fresh bearings every step, so in practice it receives "
        "the information of the nonlinear model.",
        "",
        "## Seed 003 measurement modes (future work in the paper)",
        "",
        "sw = 1 (range, bearing, both headings) is observable without any motion; sw = 2 (range, "
        "triangle bearing, leader heading) needs the follower to move (v_i ≠ 0) for its own "
        "heading; sw = 3 (UWB range only) has rank 3: the rotation of the whole pair about the "
        "follower, (r_x, r_y, θ_i, θ_0) ∝ (−r_y, r_x, 1, 1), is never observable, and the other "
        "three states need both robots to move (v_i ≠ 0 and v_0 ≠ 0).",
        "",
    ]
    captions = {
        "observability_ranks.png": "Rank found per case; colour = agreement with the paper.",
        "observability_input_subsets.png": "Rank for every set of non-zero input groups.",
    }
    for f in figures:
        parts.append(figure_md(f, captions.get(f, f)))
    return "\n".join(parts)
