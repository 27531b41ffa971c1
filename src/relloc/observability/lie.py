"""Lie derivatives of the outputs along a model's vector fields and the observability matrix.

For ``ẋ = f₀(x) + Σ fᵢ(x) uᵢ``, ``y = h(x)`` (Hermann & Krener 1977; seed 000 Eqs. 10–11,
seed 001 Eqs. 13–17)::

    L⁰h = h,    L_{f_a} L^{k}_{w} h = ∇(L^{k}_{w} h) · f_a,    w = (a₁ … a_k) a word of fields

and the observability matrix stacks the gradients ``∇ L_w h`` of every word up to a chosen
order. Each row remembers its word, so a caller can keep only the rows that a given set of
*excited* inputs generates (an input held at zero contributes no Lie derivatives): this is how
the input conditions are found (:mod:`.analysis`).

Words whose Lie derivative is a constant are not expanded further (their gradient and every
further derivative vanish); identical expressions are kept once. Numeric evaluation goes
through one ``lambdify(..., cse=True)`` of all gradient rows.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property

import numpy as np
import sympy as sp
from numpy.typing import NDArray

from relloc.errors import ModelError
from relloc.models.symbolic import SymbolicModel
from relloc.observability.rank import numeric_rank

Array = NDArray[np.float64]

DRIFT = 0  # field index of f₀; input i (0-based) has field index i + 1


@dataclass(frozen=True)
class LieRow:
    """One Lie derivative ``L_w h_k``: its word (field indices, first applied first), output
    index, expression and gradient (n expressions)."""

    word: tuple[int, ...]
    output: int
    expr: sp.Expr
    gradient: tuple[sp.Expr, ...]

    @property
    def fields(self) -> frozenset[int]:
        return frozenset(self.word)


def gradient(expr: sp.Expr, states: tuple[sp.Symbol, ...]) -> tuple[sp.Expr, ...]:
    """``∇g`` with respect to ``states``."""
    return tuple(sp.diff(expr, s) for s in states)


def along(grad: tuple[sp.Expr, ...], field: tuple[sp.Expr, ...]) -> sp.Expr:
    """``L_f g = ∇g · f`` from a precomputed gradient ``∇g``."""
    return sp.Add(*(g * f for g, f in zip(grad, field, strict=True) if f != 0 and g != 0))


def model_fields(model: SymbolicModel) -> dict[int, tuple[sp.Expr, ...]]:
    """Field index → vector field (the drift only when it is not identically zero)."""
    fields: dict[int, tuple[sp.Expr, ...]] = {}
    if any(e != 0 for e in model.drift):
        fields[DRIFT] = model.drift
    for i, f in enumerate(model.input_fields):
        if any(e != 0 for e in f):
            fields[i + 1] = f
    return fields


class _Probe:
    """Numeric gradients of kept rows at a few random points (for the redundancy test)."""

    def __init__(self, model: SymbolicModel, points: int, seed: int) -> None:
        rng = np.random.default_rng(seed)
        self.model = model
        self.points: list[tuple[Array, Array]] = []
        for _ in range(50 * points):
            state = model.sample_state(rng)
            self.points.append((state, model.parameters_for(state, rng)))
            if len(self.points) == points:
                break
        self.kept: list[tuple[frozenset[int], Array]] = []

    def values(self, grads: list[tuple[sp.Expr, ...]]) -> Array:
        """Numeric gradients ``(len(grads), points, n)`` (one lambdify with cse per batch)."""
        n = self.model.n
        if not grads:
            return np.zeros((0, len(self.points), n))
        fn = sp.lambdify(
            [list(self.model.states), list(self.model.parameters)],
            sp.Matrix([list(g) for g in grads]),
            "numpy",
            cse=True,
        )
        with np.errstate(all="ignore"):
            out = [
                np.asarray(fn(list(s), list(p)), dtype=float).reshape(len(grads), n)
                for s, p in self.points
            ]
        return np.stack(out, axis=1)

    def adds_information(self, fields: frozenset[int], vals: Array) -> bool:
        """Is this gradient independent of the kept rows available whenever it is?

        With no such rows, any non-zero gradient adds information: a fixed threshold would
        prune every row of a model whose outputs are simply small numbers (the rank tests of
        :mod:`.rank` are scale-free, so this one is too).
        """
        base = [v for f, v in self.kept if f <= fields]
        for p in range(vals.shape[0]):
            if not np.all(np.isfinite(vals[p])):
                return True  # cannot judge at this point: keep the row
            B = np.array([b[p] for b in base]) if base else np.zeros((0, vals.shape[1]))
            if not np.all(np.isfinite(B)):
                return True
            if (
                numeric_rank(np.vstack([B, vals[p]])) > numeric_rank(B)
                if base
                else np.any(vals[p] != 0.0)  # no absolute floor: the model's scale is free
            ):
                return True
        return False


def lie_rows(
    model: SymbolicModel, order: int, *, prune: bool = True, probe_points: int = 3, seed: int = 7
) -> list[LieRow]:
    """Lie derivatives of every output along words of length ≤ ``order`` (module doc).

    With ``prune`` (default) a derivative whose gradient is, at ``probe_points`` random
    points, linearly dependent on the gradients of already kept rows whose fields are a subset
    of its own is dropped and not expanded: such a function is locally a function of those rows,
    so every further Lie derivative of it lies in the span of theirs (chain rule). The rank for
    every set of excited inputs is therefore unchanged, at a fraction of the symbolic work.
    """
    if order < 0:
        raise ModelError(f"Lie derivative order must be ≥ 0, got {order}")
    states = model.states
    state_set = set(states)
    fields = model_fields(model)
    probe = _Probe(model, probe_points, seed) if prune else None
    rows: list[LieRow] = []
    seen: set[sp.Expr] = set()

    def keep(candidates: list[tuple[tuple[int, ...], int, sp.Expr]]) -> list[LieRow]:
        fresh: list[LieRow] = []
        for word, output, e in candidates:
            if e == 0 or not (e.free_symbols & state_set) or e in seen:
                continue
            seen.add(e)
            fresh.append(LieRow(word=word, output=output, expr=e, gradient=gradient(e, states)))
        if probe is None:
            rows.extend(fresh)
            return fresh
        vals = probe.values([r.gradient for r in fresh])
        kept = []
        for r, v in zip(fresh, vals, strict=True):
            if probe.adds_information(r.fields, v):
                probe.kept.append((r.fields, v))
                kept.append(r)
        rows.extend(kept)
        return kept

    frontier = keep([((), k, h) for k, h in enumerate(model.outputs)])
    for _ in range(order):
        frontier = keep(
            [
                ((*row.word, a), row.output, along(row.gradient, f))
                for row in frontier
                for a, f in fields.items()
            ]
        )
    return rows


@dataclass(frozen=True)
class ObservabilityMatrix:
    """The stacked gradients of :func:`lie_rows` with a numeric evaluator.

    ``evaluate(state, params) -> (len(rows), n)``; ``mpmath_evaluator(dps)`` gives the same at
    arbitrary precision (for rank checks independent of double rounding).
    """

    model: SymbolicModel
    order: int
    rows: tuple[LieRow, ...]
    _fn: Callable[..., object]

    @classmethod
    def build(cls, model: SymbolicModel, order: int, *, prune: bool = True) -> ObservabilityMatrix:
        """Rows of :func:`lie_rows` (``prune=False`` keeps every word, needed to evaluate the
        matrix at *special* states where the generic redundancy test does not apply)."""
        rows = tuple(lie_rows(model, order, prune=prune))
        matrix = sp.Matrix([list(r.gradient) for r in rows]) if rows else sp.zeros(0, model.n)
        fn = sp.lambdify([list(model.states), list(model.parameters)], matrix, "numpy", cse=True)
        return cls(model=model, order=order, rows=rows, _fn=fn)

    def symbolic(self) -> sp.Matrix:
        return sp.Matrix([list(r.gradient) for r in self.rows])

    def evaluate(self, state: Array, params: Array) -> Array:
        n = self.model.n
        if not self.rows:
            return np.zeros((0, n))
        out = np.asarray(self._fn(list(np.asarray(state, float)), list(params)), dtype=float)
        return out.reshape(len(self.rows), n)

    @cached_property
    def batch_evaluator(self) -> Callable[[Array, Array], Array]:
        """Vectorised evaluator ``(states (E, n), params (E, p)) -> (E, rows, n)`` (built once)."""
        n, k = self.model.n, len(self.rows)
        flat = [g for r in self.rows for g in r.gradient]
        fn = sp.lambdify(
            [list(self.model.states), list(self.model.parameters)], flat, "numpy", cse=True
        )

        def evaluate(states: Array, params: Array) -> Array:
            states = np.asarray(states, dtype=float)
            params = np.asarray(params, dtype=float).reshape(states.shape[0], -1)
            E = states.shape[0]
            vals = fn(list(states.T), list(params.T))
            out = np.stack([np.broadcast_to(np.asarray(v, float), (E,)) for v in vals], axis=-1)
            return out.reshape(E, k, n)

        return evaluate

    def row_mask(self, allowed_fields: frozenset[int]) -> NDArray[np.bool_]:
        """Rows whose word uses only ``allowed_fields`` (field indices, :data:`DRIFT` = 0)."""
        return np.array([r.fields <= allowed_fields for r in self.rows], dtype=bool)

    def mpmath_evaluator(self) -> Callable[..., object]:
        return sp.lambdify(
            [list(self.model.states), list(self.model.parameters)], self.symbolic(), "mpmath"
        )
