"""Observability analysis of a :class:`~relloc.models.symbolic.SymbolicModel`.

:func:`analyse` answers the questions a user asks before building a team:

1. **Generic rank.** The observability matrix (:mod:`.lie`, all fields, words up to ``order``)
   is evaluated at ``samples`` random states (parameters from the model's rule or box); its
   generic rank is the largest numeric rank found (:mod:`.rank`), optionally re-checked with
   50-digit arithmetic at the witness. Rank ``n`` means the observability rank condition holds
   and the system is locally weakly observable (Hermann & Krener 1977; seed 000 Theorem 1).
2. **Input conditions.** An input held at zero contributes no Lie derivatives, so the rows a
   set ``S`` of excited inputs generates are those whose word uses only fields of ``S`` (and the
   drift). The minimal input sets (over the model's input groups, and over scalar inputs) whose
   rows reach the generic rank are the conditions: e.g. ``[["v_c", "omega_l"]]`` reads "needs
   v_c ≠ 0 and ω_l ≠ 0". An empty set among them means no input is needed.
3. **Unobservable directions.** When the rank is deficient, the null space of the matrix at a
   generic witness state, expressed on the state names: symbolically (solving ``O_sel v = 0``
   on ``rank`` independent rows by Cramer's rule, then simplified and verified at the witness)
   for models with at most six states and a null space of dimension ≤ 2, numerically (reduced
   row-echelon basis at the witness) otherwise.

:func:`rank_at` gives the rank at a given state and constant inputs: the Lie derivatives of
``h`` along the *combined* field ``f₀ + Σ fᵢ uᵢ`` (orders ``0 … order``).
"""

from __future__ import annotations

import itertools
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import sympy as sp
from numpy.typing import NDArray

from relloc.errors import ModelError
from relloc.models.symbolic import SymbolicModel
from relloc.observability.lie import DRIFT, ObservabilityMatrix, along, gradient, model_fields
from relloc.observability.rank import (
    null_space,
    numeric_rank,
    precise_rank,
    singular_values,
)

Array = NDArray[np.float64]

#: Largest number of inputs (or groups) for which every subset is enumerated.
MAX_CONDITION_INPUTS = 10
#: Rank of every subset of input groups is tabulated for at most this many groups.
MAX_SUBSET_TABLE_GROUPS = 6
#: Symbolic null-space only for models with at most this many states and null dimensions
#: (Cramer's rule on larger systems makes SymPy slow; numeric directions are used instead).
MAX_SYMBOLIC_NULL_STATES = 6
MAX_SYMBOLIC_NULL_DIM = 2


@dataclass(frozen=True)
class Witness:
    """A generic state at which the reported rank is attained (evidence for a claim)."""

    state: dict[str, float]
    parameters: dict[str, float]
    rank: int
    singular_values: tuple[float, ...]


@dataclass(frozen=True)
class ObservabilityResult:
    """What :func:`analyse` found (module doc). ``to_dict()`` is JSON-ready."""

    model: str
    description: str
    state_names: tuple[str, ...]
    order: int
    rank: int
    conditions: tuple[tuple[str, ...], ...] | None
    input_conditions: tuple[tuple[str, ...], ...] | None
    rank_without: dict[str, int]
    subset_ranks: dict[str, int]
    unobservable_directions: tuple[str, ...]
    witness: Witness
    precise_rank: int | None
    n_rows: int
    elapsed_s: float
    notes: tuple[str, ...] = field(default=())

    @property
    def state_dim(self) -> int:
        return len(self.state_names)

    @property
    def full_rank(self) -> bool:
        return self.rank == self.state_dim

    def conditions_text(self) -> str:
        """Human reading of the conditions, e.g. ``needs v_c ≠ 0 and omega_l ≠ 0``."""
        return describe_conditions(self.conditions)

    def to_dict(self) -> dict[str, Any]:
        return {
            "model": self.model,
            "description": self.description,
            "state_names": list(self.state_names),
            "state_dim": self.state_dim,
            "order": self.order,
            "rank": self.rank,
            "full_rank": self.full_rank,
            "precise_rank": self.precise_rank,
            "conditions": None if self.conditions is None else [list(c) for c in self.conditions],
            "conditions_text": self.conditions_text(),
            "input_conditions": None
            if self.input_conditions is None
            else [list(c) for c in self.input_conditions],
            "rank_without": self.rank_without,
            "subset_ranks": self.subset_ranks,
            "unobservable_directions": list(self.unobservable_directions),
            "witness": {
                "state": self.witness.state,
                "parameters": self.witness.parameters,
                "rank": self.witness.rank,
                "singular_values": list(self.witness.singular_values),
            },
            "n_rows": self.n_rows,
            "elapsed_s": self.elapsed_s,
            "notes": list(self.notes),
        }


def describe_conditions(conditions: Sequence[Sequence[str]] | None) -> str:
    """``[["a", "b"], ["c"]]`` → ``needs a ≠ 0 and b ≠ 0, or c ≠ 0``."""
    if conditions is None:
        return "not enumerated (too many inputs)"
    if not conditions:
        return "the generic rank is never reached with any input"
    if any(len(c) == 0 for c in conditions):
        return "no input needed"
    alts = [" and ".join(f"{g} ≠ 0" for g in c) for c in conditions]
    return "needs " + ", or ".join(alts)


def _sample_points(
    model: SymbolicModel, om: ObservabilityMatrix, samples: int, rng: np.random.Generator
) -> list[tuple[Array, Array, Array]]:
    points: list[tuple[Array, Array, Array]] = []
    tries = 0
    while len(points) < samples:
        tries += 1
        if tries > 20 * samples:
            raise ModelError(
                f"model {model.name!r}: could not find finite evaluation points "
                "(every sampled state is singular)"
            )
        state = model.sample_state(rng)
        params = model.parameters_for(state, rng)
        with np.errstate(all="ignore"):
            M = om.evaluate(state, params)
        if np.all(np.isfinite(M)):
            points.append((state, params, M))
    return points


def _minimal_sets(
    names: Sequence[str],
    fields_of: Mapping[str, frozenset[int]],
    rank_with: Any,
    target: int,
) -> tuple[tuple[str, ...], ...]:
    found: list[frozenset[str]] = []
    for size in range(len(names) + 1):
        for combo in itertools.combinations(names, size):
            s = frozenset(combo)
            if any(f <= s for f in found):
                continue
            allowed = frozenset().union(*(fields_of[g] for g in combo)) if combo else frozenset()
            if rank_with(allowed) == target:
                found.append(s)
    return tuple(tuple(g for g in names if g in f) for f in found)


def _independent_rows(M: Array, rank: int) -> list[int]:
    chosen: list[int] = []
    norms = np.linalg.norm(M, axis=1)
    for i in np.argsort(-norms):
        if norms[i] <= 0:
            break
        trial = [*chosen, int(i)]
        if numeric_rank(M[trial]) == len(trial):
            chosen = trial
        if len(chosen) == rank:
            break
    return sorted(chosen)


def _pivot_columns(A: Array, rank: int) -> list[int]:
    n = A.shape[1]
    best: tuple[float, tuple[int, ...]] = (-1.0, tuple(range(rank)))
    for cols in itertools.combinations(range(n), rank):
        sv = np.linalg.svd(A[:, cols], compute_uv=False)
        score = float(sv[-1] / sv[0]) if sv[0] > 0 else 0.0
        if score > best[0]:
            best = (score, cols)
    return list(best[1])


def _format_vector(names: Sequence[str], values: Sequence[Any]) -> str:
    return f"({', '.join(names)}) ∝ ({', '.join(str(v) for v in values)})"


def _row_polynomial(grad: Sequence[sp.Expr]) -> list[sp.Expr]:
    """A gradient row times the lcm of its denominators (same direction, no fractions)."""
    parts = [sp.fraction(sp.together(e)) for e in grad]
    den = sp.lcm_list([d for _, d in parts])
    return [sp.cancel(num * den / d) if num != 0 else sp.Integer(0) for num, d in parts]


def _symbolic_directions(
    om: ObservabilityMatrix, M: Array, rank: int, state: Array, params: Array
) -> list[str] | None:
    """Null-space vectors in closed form by Cramer's rule, or None when that fails.

    On ``rank`` independent rows ``A`` (denominators cleared), pivot columns ``p`` and a free
    column ``f``: ``v_f = det A_p`` and ``v_{p_j} = −det(A_p with column j replaced by a_f)``
    solve ``A v = 0``; the common polynomial factor is divided out and the result verified
    numerically at the witness.
    """
    model = om.model
    if rank == 0:  # nothing to solve: every state direction is unobservable (numeric basis)
        return None
    rows = _independent_rows(normalise_rows_keep_index(M), rank)
    A_num = normalise_rows_keep_index(M[rows])
    piv = _pivot_columns(A_num, rank)
    free = [j for j in range(model.n) if j not in piv]
    A = sp.Matrix([_row_polynomial(om.rows[i].gradient) for i in rows])
    if sum(sp.count_ops(e) for e in A) > 600:
        return None
    Ap = A[:, piv]
    subs = dict(zip(model.states, state, strict=True)) | dict(
        zip(model.parameters, params, strict=True)
    )
    out = []
    for f in free:
        vec: list[sp.Expr] = [sp.Integer(0)] * model.n
        vec[f] = sp.expand(Ap.det(method="berkowitz"))
        for j, col in enumerate(piv):
            Aj = Ap.copy()
            Aj[:, j] = A[:, f]
            vec[col] = -sp.expand(Aj.det(method="berkowitz"))
        nonzero = [e for e in vec if e != 0]
        if not nonzero:
            return None
        common = sp.gcd_list(nonzero)
        vec = [sp.trigsimp(sp.factor(sp.cancel(e / common))) for e in vec]
        constants = [e for e in vec if e.is_Number and e != 0]
        if constants and constants[0] < 0:  # sign convention: first constant entry positive
            vec = [-e for e in vec]
        num = np.array([complex(sp.N(e.subs(subs))).real for e in vec])
        Mn = normalise_rows_keep_index(M)
        if not np.all(np.isfinite(num)) or np.linalg.norm(num) == 0:
            return None
        if np.linalg.norm(Mn @ num) > 1e-6 * np.sqrt(Mn.shape[0]) * np.linalg.norm(num):
            return None
        out.append(_format_vector(model.state_names, [sp.sstr(e) for e in vec]))
    return out


def normalise_rows_keep_index(M: Array) -> Array:
    """Row-normalised copy of ``M`` that keeps zero rows (so row indices are preserved)."""
    norms = np.linalg.norm(M, axis=1, keepdims=True)
    return np.where(norms > 0, M / np.where(norms > 0, norms, 1.0), 0.0)


def _numeric_directions(names: Sequence[str], M: Array, rank: int) -> list[str]:
    N = null_space(M, rank)
    if N.shape[0] == 0:
        return []
    R = np.asarray(sp.Matrix(np.round(N, 12)).rref(iszerofunc=lambda e: abs(e) < 1e-9)[0])
    out = []
    for row in R.astype(float):
        if np.max(np.abs(row)) < 1e-9:
            continue
        row = row / row[np.argmax(np.abs(row) > 1e-9)]
        out.append(
            _format_vector(names, [f"{v:.4g}" if abs(v) > 1e-9 else "0" for v in row])
            + " (numeric, at the witness)"
        )
    return out


def analyse(
    model: SymbolicModel,
    *,
    order: int = 2,
    samples: int = 5,
    seed: int = 0,
    precise: bool = False,
    directions: str = "auto",
) -> ObservabilityResult:
    """Generic rank, input conditions and unobservable directions (module doc).

    ``directions``: ``"auto"`` (symbolic when small, else numeric), ``"numeric"`` or ``"none"``.
    """
    if samples < 1:
        raise ModelError(f"analyse: samples must be ≥ 1, got {samples}")
    if directions not in ("auto", "numeric", "none"):
        raise ModelError(f"analyse: directions must be auto|numeric|none, got {directions!r}")
    t0 = time.perf_counter()
    om = ObservabilityMatrix.build(model, order)
    rng = np.random.default_rng(seed)
    points = _sample_points(model, om, samples, rng)
    fields = frozenset(model_fields(model))
    cache: dict[frozenset[int], int] = {}

    def rank_with(allowed_inputs: frozenset[int]) -> int:
        allowed = (allowed_inputs | {DRIFT}) & fields
        if allowed not in cache:
            mask = om.row_mask(allowed)
            cache[allowed] = max(numeric_rank(M[mask]) for _, _, M in points)
        return cache[allowed]

    rank = rank_with(fields)
    notes: list[str] = []
    group_fields = {
        g: frozenset(model.inputs.index(u) + 1 for u in us) for g, us in model.input_groups.items()
    }
    scalar_fields = {str(u): frozenset({i + 1}) for i, u in enumerate(model.inputs)}
    conditions: tuple[tuple[str, ...], ...] | None = None
    input_conditions: tuple[tuple[str, ...], ...] | None = None
    if len(group_fields) <= MAX_CONDITION_INPUTS:
        conditions = _minimal_sets(list(group_fields), group_fields, rank_with, rank)
    else:
        notes.append(f"{len(group_fields)} input groups: condition enumeration skipped")
    if len(scalar_fields) <= MAX_CONDITION_INPUTS:
        input_conditions = _minimal_sets(list(scalar_fields), scalar_fields, rank_with, rank)
    rank_without = {g: rank_with(fields - f) for g, f in group_fields.items()}
    subset_ranks: dict[str, int] = {}
    if len(group_fields) <= MAX_SUBSET_TABLE_GROUPS:
        names = list(group_fields)
        for size in range(len(names) + 1):
            for combo in itertools.combinations(names, size):
                allowed = (
                    frozenset().union(*(group_fields[g] for g in combo)) if combo else frozenset()
                )
                subset_ranks["+".join(combo) or "none"] = rank_with(allowed)

    best = next(i for i, (_, _, M) in enumerate(points) if numeric_rank(M) == rank)
    w_state, w_params, w_M = points[best]
    witness = Witness(
        state=dict(zip(model.state_names, map(float, w_state), strict=True)),
        parameters={str(p): float(v) for p, v in zip(model.parameters, w_params, strict=True)},
        rank=rank,
        singular_values=tuple(float(s) for s in singular_values(w_M)),
    )
    dirs: list[str] = []
    if rank < model.n and directions != "none":
        symbolic = None
        small = model.n <= MAX_SYMBOLIC_NULL_STATES and model.n - rank <= MAX_SYMBOLIC_NULL_DIM
        if directions == "auto" and small:
            symbolic = _symbolic_directions(om, w_M, rank, w_state, w_params)
        dirs = (
            symbolic if symbolic is not None else _numeric_directions(model.state_names, w_M, rank)
        )
    p_rank = precise_rank(om.mpmath_evaluator(), w_state, w_params) if precise else None
    if p_rank is not None and p_rank != rank:
        notes.append(f"double-precision rank {rank} differs from the 50-digit rank {p_rank}")
    return ObservabilityResult(
        model=model.name,
        description=model.description,
        state_names=model.state_names,
        order=order,
        rank=rank,
        conditions=conditions,
        input_conditions=input_conditions,
        rank_without=rank_without,
        subset_ranks=subset_ranks,
        unobservable_directions=tuple(dirs),
        witness=witness,
        precise_rank=p_rank,
        n_rows=len(om.rows),
        elapsed_s=time.perf_counter() - t0,
        notes=tuple(notes),
    )


@dataclass(frozen=True)
class InputRankEvaluator:
    """Rank at given states *and constant inputs*: gradients of ``L^k_f h``, ``k = 0 … order``,
    along the combined field ``f = f₀ + Σ fᵢ uᵢ`` (inputs kept as symbols, lambdified once)."""

    model: SymbolicModel
    order: int
    _fn: Any

    @classmethod
    def build(cls, model: SymbolicModel, order: int | None = None) -> InputRankEvaluator:
        k_max = model.n - 1 if order is None else order
        if k_max < 0:
            raise ModelError(f"rank_at: order must be ≥ 0, got {k_max}")
        f = tuple(model.rate())
        grads = []
        for h in model.outputs:
            e = h
            for _ in range(k_max + 1):
                g = gradient(e, model.states)
                grads.append(list(g))
                e = along(g, f)
        fn = sp.lambdify(
            [list(model.states), list(model.inputs), list(model.parameters)],
            sp.Matrix(grads),
            "numpy",
            cse=True,
        )
        return cls(model=model, order=k_max, _fn=fn)

    def matrix(self, state: Array, inputs: Array, params: Array | None = None) -> Array:
        p = self.model.parameters_for(np.asarray(state, float)) if params is None else params
        out = np.asarray(self._fn(list(state), list(inputs), list(p)), dtype=float)
        return out.reshape(-1, self.model.n)

    def rank(self, state: Array, inputs: Array, params: Array | None = None) -> int:
        return numeric_rank(self.matrix(state, inputs, params))


def rank_at(
    model: SymbolicModel,
    state: Sequence[float],
    inputs: Sequence[float],
    *,
    params: Sequence[float] | None = None,
    order: int | None = None,
) -> int:
    """Rank of the combined-field observability matrix at ``state`` with constant ``inputs``;
    a ModelError where the matrix is not finite there (a singular configuration, such as two
    robots at one point)."""
    s = np.asarray(state, dtype=float)
    u = np.asarray(inputs, dtype=float)
    if s.shape != (model.n,) or u.shape != (len(model.inputs),):
        raise ModelError(
            f"rank_at: state needs {model.n} values {model.state_names}, inputs "
            f"{len(model.inputs)} values {model.input_names}"
        )
    p = None if params is None else np.asarray(params, dtype=float)
    with np.errstate(all="ignore"):  # a division by zero there: reported as one error
        return InputRankEvaluator.build(model, order).rank(s, u, p)
