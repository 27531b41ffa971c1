"""relloc's models written once in SymPy, in control-affine form.

Every model is a :class:`SymbolicModel`::

    ẋ = f₀(x) + Σᵢ fᵢ(x) uᵢ,        y = h(x; c)

with named state symbols ``x``, scalar inputs ``uᵢ`` (each with its own vector field ``fᵢ``),
outputs ``h`` and optional constant parameters ``c`` (landmark positions, or the *measured*
bearings that the pseudo-linear model treats as known coefficients). The numeric models in
:mod:`relloc.models` are tested against these definitions
(``tests/equivalence/test_symbolic_vs_numeric.py``) and the observability tools
(:mod:`relloc.observability`) take them as input. A user model for ``relloc observability
package.module:function`` is any zero-argument function returning a :class:`SymbolicModel`.

Models (derivations in each constructor's docstring):

- :func:`relative_motion_fields` / :func:`relative_nonlinear` / :func:`relative_pseudo_linear`:
  seed 000's 4-DOF relative pair with range/azimuth/elevation (Eq. 2) or the pseudo-linear
  rows ``H_pmo(θ̃, α̃) p`` (Eq. 3);
- :func:`unicycle_landmarks`: one unicycle with bearing and/or range to known landmarks;
- :func:`unicycle_team`: n unicycles with inter-robot bearings, landmark bearings and GPS
  (seed 001 Eqs. 1–2, 13);
- :func:`airground_follower`: seed 003's follower relative model (Eq. 3) with the three
  measurement modes ``sw = 1, 2, 3`` (Eq. 4).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace

import numpy as np
import sympy as sp
from numpy.typing import NDArray

from relloc.errors import ModelError

Array = NDArray[np.float64]

ParameterRule = Callable[[Array], Array]


def _real(names: str) -> tuple[sp.Symbol, ...]:
    out = sp.symbols(names)
    return tuple(out) if isinstance(out, (tuple, list)) else (out,)


@dataclass(frozen=True, kw_only=True)
class SymbolicModel:
    """A control-affine model ``ẋ = f₀(x) + Σ fᵢ(x) uᵢ``, ``y = h(x; c)`` (module doc).

    Fields:

    - ``name``: short identifier; ``description``: one line for reports;
    - ``states``: state symbols (n); ``drift``: ``f₀`` as n expressions (zeros for driftless);
    - ``inputs``: scalar input symbols (q); ``input_fields``: q vector fields, n expressions each;
    - ``outputs``: measurement expressions (m); ``output_names``: m labels;
    - ``parameters``: constant symbols appearing in ``h`` or ``f`` (may be empty);
    - ``parameter_rule``: maps a numeric state (n,) to consistent parameter values (e.g. the
      true bearings for the pseudo-linear model); ``None`` → parameters are sampled freely in
      ``parameter_box``;
    - ``input_groups``: named groups of inputs used to phrase conditions (``"v_c"`` →
      ``(v_xc, v_yc, v_zc)``); inputs not in any group form their own group;
    - ``state_box``: per state ``(low, high)`` sampling range for generic-rank evaluation;
      ``parameter_box`` the same for parameters.
    """

    name: str
    description: str
    states: tuple[sp.Symbol, ...]
    drift: tuple[sp.Expr, ...]
    inputs: tuple[sp.Symbol, ...]
    input_fields: tuple[tuple[sp.Expr, ...], ...]
    outputs: tuple[sp.Expr, ...]
    output_names: tuple[str, ...]
    parameters: tuple[sp.Symbol, ...] = ()
    parameter_rule: ParameterRule | None = None
    input_groups: Mapping[str, tuple[sp.Symbol, ...]] = field(default_factory=dict)
    state_box: tuple[tuple[float, float], ...] = ()
    parameter_box: tuple[tuple[float, float], ...] = ()

    def __post_init__(self) -> None:
        n = len(self.states)
        if n == 0:
            raise ModelError(f"SymbolicModel {self.name!r}: states must not be empty")
        if len(set(self.states)) != n:
            raise ModelError(f"SymbolicModel {self.name!r}: duplicate state symbols")
        object.__setattr__(self, "drift", tuple(sp.sympify(e) for e in self.drift))
        if len(self.drift) != n:
            raise ModelError(f"SymbolicModel {self.name!r}: drift needs {n} entries")
        if len(self.input_fields) != len(self.inputs):
            raise ModelError(f"SymbolicModel {self.name!r}: one input field per input needed")
        fields = tuple(tuple(sp.sympify(e) for e in f) for f in self.input_fields)
        for u, f in zip(self.inputs, fields, strict=True):
            if len(f) != n:
                raise ModelError(f"SymbolicModel {self.name!r}: field of {u} needs {n} entries")
        object.__setattr__(self, "input_fields", fields)
        object.__setattr__(self, "outputs", tuple(sp.sympify(e) for e in self.outputs))
        if not self.outputs or len(self.output_names) != len(self.outputs):
            raise ModelError(f"SymbolicModel {self.name!r}: one output name per output needed")
        allowed = set(self.states) | set(self.parameters)
        for what, exprs in (("drift", self.drift), ("outputs", self.outputs)):
            for e in exprs:
                stray = e.free_symbols - allowed
                if stray:
                    raise ModelError(
                        f"SymbolicModel {self.name!r}: {what} uses undeclared symbols {stray}"
                    )
        for u, f in zip(self.inputs, fields, strict=True):
            for e in f:
                if e.free_symbols - allowed:
                    raise ModelError(
                        f"SymbolicModel {self.name!r}: field of {u} uses undeclared symbols "
                        f"{e.free_symbols - allowed} (fields may depend on states/parameters only)"
                    )
        box = self.state_box or tuple((-5.0, 5.0) for _ in self.states)
        if len(box) != n or any(lo >= hi for lo, hi in box):
            raise ModelError(f"SymbolicModel {self.name!r}: state_box needs {n} (low, high)")
        object.__setattr__(self, "state_box", tuple((float(a), float(b)) for a, b in box))
        pbox = self.parameter_box or tuple((-5.0, 5.0) for _ in self.parameters)
        if len(pbox) != len(self.parameters):
            raise ModelError(f"SymbolicModel {self.name!r}: parameter_box size mismatch")
        object.__setattr__(self, "parameter_box", tuple((float(a), float(b)) for a, b in pbox))
        grouped = {u for g in self.input_groups.values() for u in g}
        if grouped - set(self.inputs):
            raise ModelError(f"SymbolicModel {self.name!r}: input_groups name unknown inputs")
        groups = dict(self.input_groups)
        for u in self.inputs:
            if u not in grouped:
                groups[str(u)] = (u,)
        object.__setattr__(self, "input_groups", groups)

    # --- views -------------------------------------------------------------------------
    @property
    def n(self) -> int:
        return len(self.states)

    @property
    def state_names(self) -> tuple[str, ...]:
        return tuple(str(s) for s in self.states)

    @property
    def input_names(self) -> tuple[str, ...]:
        return tuple(str(u) for u in self.inputs)

    def rate(self) -> sp.Matrix:
        """``f(x, u) = f₀ + Σ fᵢ uᵢ`` as an n × 1 matrix."""
        out = sp.Matrix(self.drift)
        for u, f in zip(self.inputs, self.input_fields, strict=True):
            out += sp.Matrix(f) * u
        return out

    def output_matrix(self) -> sp.Matrix:
        return sp.Matrix(self.outputs)

    def output_jacobian(self) -> sp.Matrix:
        """``H = ∂h/∂x`` (m × n)."""
        return self.output_matrix().jacobian(sp.Matrix(self.states))

    def lambdify(self, expr: sp.Matrix, *, with_inputs: bool = False) -> Callable[..., Array]:
        """Numeric function ``g(x, [u,] c)`` of a matrix expression (cse, numpy)."""
        args: list[list[sp.Symbol]] = [list(self.states)]
        if with_inputs:
            args.append(list(self.inputs))
        args.append(list(self.parameters))
        return sp.lambdify(args, expr, modules="numpy", cse=True)  # type: ignore[no-any-return]

    def parameters_for(self, state: Array, rng: np.random.Generator | None = None) -> Array:
        """Parameter values for a numeric state: the rule, or a draw from ``parameter_box``."""
        if self.parameter_rule is not None:
            return np.asarray(self.parameter_rule(np.asarray(state, dtype=float)), dtype=float)
        if not self.parameters:
            return np.zeros(0)
        if rng is None:
            raise ModelError(f"model {self.name!r}: free parameters need an rng to be sampled")
        lo, hi = np.array(self.parameter_box).T
        return rng.uniform(lo, hi)

    def with_inputs(self, names: Sequence[str]) -> SymbolicModel:
        """The same model with only the named inputs excited (group or scalar input names);
        every other input is held at zero, i.e. its field is removed."""
        keep: set[sp.Symbol] = set()
        for name in names:
            if name in self.input_groups:
                keep |= set(self.input_groups[name])
            elif name in self.input_names:
                keep.add(self.inputs[self.input_names.index(name)])
            else:
                raise ModelError(
                    f"model {self.name!r}: unknown input {name!r}; groups: "
                    f"{sorted(self.input_groups)}, inputs: {list(self.input_names)}"
                )
        idx = [i for i, u in enumerate(self.inputs) if u in keep]
        groups = {
            g: tuple(u for u in us if u in keep)
            for g, us in self.input_groups.items()
            if any(u in keep for u in us)
        }
        return replace(
            self,
            name=f"{self.name}[{'+'.join(names) or 'no input'}]",
            inputs=tuple(self.inputs[i] for i in idx),
            input_fields=tuple(self.input_fields[i] for i in idx),
            input_groups=groups,
        )

    def sample_state(self, rng: np.random.Generator) -> Array:
        lo, hi = np.array(self.state_box).T
        return rng.uniform(lo, hi)


# ------------------------------------------------------------------------------------------
# Seed 000: 4-DOF relative pair
# ------------------------------------------------------------------------------------------
RELATIVE_STATES = _real("x y z phi")
RELATIVE_OBSERVER_INPUTS = _real("v_xl v_yl v_zl omega_l")
RELATIVE_OBSERVED_INPUTS = _real("v_xc v_yc v_zc omega_c")
RELATIVE_BEARINGS = _real("theta_m alpha_m")  # measured azimuth / elevation (pseudo-linear)
_REL_BOX = ((-6.0, 6.0), (-6.0, 6.0), (-2.0, 2.0), (-np.pi, np.pi))


def relative_motion_fields() -> tuple[tuple[sp.Expr, ...], ...]:
    """Input fields of seed 000's relative kinematics, order ``[v_l, ω_l, v_c, ω_c]`` scalars.

    With ``p = R(ψ_l)ᵀ (p_c − p_l)`` and ``φ = ψ_c − ψ_l``, differentiating gives
    ``ṗ = −ω_l e_z × p + C(φ) v_c − v_l`` and ``φ̇ = ω_c − ω_l`` (the paper's last row
    ``ω_l − ω_l`` is a typo; its Eq. 12 also omits the −1 that ``ω_l`` puts on ``φ̇``). Hence
    ``f_{v_l,j} = (−e_j, 0)``, ``f_{ω_l} = (y, −x, 0, −1)``, ``f_{v_c,j} = (C(φ) e_j, 0)``,
    ``f_{ω_c} = (0, 0, 0, 1)``; fields are returned in the order of
    ``RELATIVE_OBSERVER_INPUTS + RELATIVE_OBSERVED_INPUTS``.
    """
    x, y, _, phi = RELATIVE_STATES
    c, s = sp.cos(phi), sp.sin(phi)
    zero = sp.Integer(0)
    return (
        (-1, zero, zero, zero),
        (zero, -1, zero, zero),
        (zero, zero, -1, zero),
        (y, -x, zero, -1),
        (c, s, zero, zero),
        (-s, c, zero, zero),
        (zero, zero, 1, zero),
        (zero, zero, zero, 1),
    )


_RELATIVE_GROUPS = {
    "v_l": RELATIVE_OBSERVER_INPUTS[:3],
    "omega_l": RELATIVE_OBSERVER_INPUTS[3:],
    "v_c": RELATIVE_OBSERVED_INPUTS[:3],
    "omega_c": RELATIVE_OBSERVED_INPUTS[3:],
}
RELATIVE_MEASUREMENTS: tuple[str, ...] = ("range", "azimuth", "elevation")
_RELATIVE_PAIR = (
    "seed-000 4-DOF relative pair (robot l observes robot c; x, y, z, phi: c's position and "
    "heading in l's frame; inputs _l are l's, _c are c's)"
)


def _check_measured(measured: Sequence[str]) -> tuple[str, ...]:
    bad = [m for m in measured if m not in RELATIVE_MEASUREMENTS]
    if bad or not measured:
        raise ModelError(f"measured must be a non-empty subset of {RELATIVE_MEASUREMENTS}")
    return tuple(measured)


def relative_nonlinear(measured: Sequence[str] = RELATIVE_MEASUREMENTS) -> SymbolicModel:
    """Seed 000 pair with nonlinear range ``√(x²+y²+z²)``, azimuth ``atan2(y, x)`` and
    elevation ``atan2(z, √(x²+y²))`` (Eq. 2), any non-empty subset of them."""
    measured = _check_measured(measured)
    x, y, z, _ = RELATIVE_STATES
    rho = sp.sqrt(x**2 + y**2)
    exprs = {
        "range": sp.sqrt(x**2 + y**2 + z**2),
        "azimuth": sp.atan2(y, x),
        "elevation": sp.atan2(z, rho),
    }
    return SymbolicModel(
        name="relative-nonlinear",
        description=f"{_RELATIVE_PAIR}, nonlinear {'+'.join(measured)}",
        states=RELATIVE_STATES,
        drift=(0, 0, 0, 0),
        inputs=RELATIVE_OBSERVER_INPUTS + RELATIVE_OBSERVED_INPUTS,
        input_fields=relative_motion_fields(),
        outputs=tuple(exprs[m] for m in measured),
        output_names=measured,
        input_groups=_RELATIVE_GROUPS,
        state_box=_REL_BOX,
    )


def true_bearings(state: Array) -> Array:
    """Azimuth and elevation ``(θ, α)`` of a relative state (the pseudo-linear coefficients).

    A ModelError at ``x = y = z = 0`` (the robots at one point), where neither bearing is
    defined: ``atan2(0, 0) = 0`` would pick the direction ``+x`` and give a rank of that
    arbitrary choice. Straight above or below (``ρ = 0, z ≠ 0``) the elevation is ``±π/2`` and
    the azimuth ``θ`` any value; the rows of ``H_pmo`` then span the same space for every ``θ``,
    so ``θ = 0`` is kept there.
    """
    x, y, z = float(state[0]), float(state[1]), float(state[2])
    if x == 0.0 and y == 0.0 and z == 0.0:
        raise ModelError(
            "relative position (x, y, z) = 0 (the robots at one point): azimuth and elevation, "
            "the pseudo-linear coefficients, are undefined there"
        )
    return np.array([np.arctan2(y, x), np.arctan2(z, np.hypot(x, y))])


def pseudo_linear_rows() -> dict[str, tuple[sp.Expr, ...]]:
    """Rows of ``H_pmo(θ̃, α̃)`` (seed 000 Eq. 3): unit vectors ``u_r, u_θ, u_α`` (+ φ column 0)."""
    th, al = RELATIVE_BEARINGS
    ct, st, ca, sa = sp.cos(th), sp.sin(th), sp.cos(al), sp.sin(al)
    return {
        "range": (ct * ca, st * ca, sa, sp.Integer(0)),
        "azimuth": (-st, ct, sp.Integer(0), sp.Integer(0)),
        "elevation": (-ct * sa, -st * sa, ca, sp.Integer(0)),
    }


def relative_pseudo_linear(measured: Sequence[str] = RELATIVE_MEASUREMENTS) -> SymbolicModel:
    """Seed 000 pair with pseudo-linear outputs ``h = H_pmo(θ̃, α̃) x`` (Eqs. 3, 14, 22).

    ``measured`` picks the rows: ``("range", "azimuth", "elevation")`` is Case 1 (Eq. 14),
    ``("azimuth", "elevation")`` Case 2 (Eq. 22). Like the paper, the measured bearings
    ``θ̃, α̃`` are constant coefficients of the output (parameters ``theta_m, alpha_m``), set to
    the true bearings of the evaluated state by ``parameter_rule``.
    """
    measured = _check_measured(measured)
    rows = pseudo_linear_rows()
    X = sp.Matrix(RELATIVE_STATES)
    return SymbolicModel(
        name="relative-pseudo-linear",
        description=f"{_RELATIVE_PAIR}, pseudo-linear rows {'+'.join(measured)}",
        states=RELATIVE_STATES,
        drift=(0, 0, 0, 0),
        inputs=RELATIVE_OBSERVER_INPUTS + RELATIVE_OBSERVED_INPUTS,
        input_fields=relative_motion_fields(),
        outputs=tuple((sp.Matrix([rows[m]]) * X)[0, 0] for m in measured),
        output_names=tuple(f"pl_{m}" for m in measured),
        parameters=RELATIVE_BEARINGS,
        parameter_rule=true_bearings,
        input_groups=_RELATIVE_GROUPS,
        state_box=_REL_BOX,
    )


# ------------------------------------------------------------------------------------------
# Unicycles (seed 001) and planar measurements
# ------------------------------------------------------------------------------------------
def unicycle_fields(x: sp.Symbol, y: sp.Symbol, psi: sp.Symbol) -> tuple[tuple[sp.Expr, ...], ...]:
    """``ẋ = v cos ψ, ẏ = v sin ψ, ψ̇ = ω`` (seed 001 Eq. 1): fields of ``v`` and ``ω``."""
    zero = sp.Integer(0)
    return ((sp.cos(psi), sp.sin(psi), zero), (zero, zero, sp.Integer(1)))


def planar_bearing(xi: sp.Expr, yi: sp.Expr, psii: sp.Expr, xj: sp.Expr, yj: sp.Expr) -> sp.Expr:
    """Relative bearing ``η_ij = atan2(y_j − y_i, x_j − x_i) − ψ_i`` (seed 001 Eq. 2)."""
    return sp.atan2(yj - yi, xj - xi) - psii


def planar_range(xi: sp.Expr, yi: sp.Expr, xj: sp.Expr, yj: sp.Expr) -> sp.Expr:
    """Planar range ``√((x_j − x_i)² + (y_j − y_i)²)``."""
    return sp.sqrt((xj - xi) ** 2 + (yj - yi) ** 2)


UNICYCLE_STATES = _real("x y psi")
UNICYCLE_INPUTS = _real("v omega")


def unicycle_landmarks(
    n_landmarks: int = 1, measured: Sequence[str] = ("bearing",)
) -> SymbolicModel:
    """One unicycle measuring bearing and/or range to ``n_landmarks`` known landmarks.

    Landmark positions are parameters ``lx_k, ly_k`` (sampled freely).
    """
    if n_landmarks < 1:
        raise ModelError("unicycle_landmarks: n_landmarks must be ≥ 1")
    bad = [m for m in measured if m not in ("bearing", "range")]
    if bad or not measured:
        raise ModelError("unicycle_landmarks: measured must be a subset of ('bearing', 'range')")
    x, y, psi = UNICYCLE_STATES
    params: list[sp.Symbol] = []
    outputs: list[sp.Expr] = []
    names: list[str] = []
    for k in range(n_landmarks):
        lx, ly = _real(f"lx_{k} ly_{k}")
        params += [lx, ly]
        if "bearing" in measured:
            outputs.append(planar_bearing(x, y, psi, lx, ly))
            names.append(f"bearing_L{k}")
        if "range" in measured:
            outputs.append(planar_range(x, y, lx, ly))
            names.append(f"range_L{k}")
    return SymbolicModel(
        name="unicycle-landmarks",
        description=f"unicycle with {'+'.join(measured)} to {n_landmarks} landmark(s)",
        states=UNICYCLE_STATES,
        drift=(0, 0, 0),
        inputs=UNICYCLE_INPUTS,
        input_fields=unicycle_fields(x, y, psi),
        outputs=tuple(outputs),
        output_names=tuple(names),
        parameters=tuple(params),
        state_box=((-10.0, 10.0), (-10.0, 10.0), (-np.pi, np.pi)),
        parameter_box=tuple((-10.0, 10.0) for _ in params),
    )


def team_symbols(n: int) -> tuple[tuple[sp.Symbol, ...], tuple[sp.Symbol, ...]]:
    """States ``(x_i, y_i, psi_i)`` and inputs ``(v_i, omega_i)`` of robots ``i = 1..n``."""
    states: list[sp.Symbol] = []
    inputs: list[sp.Symbol] = []
    for i in range(1, n + 1):
        states += list(_real(f"x_{i} y_{i} psi_{i}"))
        inputs += list(_real(f"v_{i} omega_{i}"))
    return tuple(states), tuple(inputs)


def unicycle_team(
    n: int,
    robot_edges: Sequence[tuple[int, int]] = (),
    landmark_edges: Sequence[tuple[int, int]] = (),
    n_landmarks: int = 0,
    gps: Sequence[int] = (),
) -> SymbolicModel:
    """Seed 001 team (Eqs. 1, 2, 13): n unicycles, bearings along RPMG edges.

    Robots and landmarks are numbered from 1 (as in the paper). ``robot_edges (i, j)``: robot i
    measures the bearing of robot j; ``landmark_edges (i, k)``: robot i measures landmark k
    (``1 ≤ k ≤ n_landmarks``, positions are parameters); ``gps``: robots whose full pose is
    measured. Each robot's speed ``V_i`` and turn rate ``ω_i`` are its own inputs.
    """
    if n < 1:
        raise ModelError("unicycle_team: n must be ≥ 1")
    states, inputs = team_symbols(n)
    fields: list[tuple[sp.Expr, ...]] = []
    zero = sp.Integer(0)
    for i in range(n):
        fv, fw = unicycle_fields(*states[3 * i : 3 * i + 3])
        for f in (fv, fw):
            full = [zero] * (3 * n)
            full[3 * i : 3 * i + 3] = f
            fields.append(tuple(full))
    params: list[sp.Symbol] = []
    for k in range(1, n_landmarks + 1):
        params += list(_real(f"lx_{k} ly_{k}"))
    outputs: list[sp.Expr] = []
    names: list[str] = []

    def pose(i: int) -> tuple[sp.Symbol, ...]:
        if not 1 <= i <= n:
            raise ModelError(f"unicycle_team: robot index {i} outside 1..{n}")
        return states[3 * (i - 1) : 3 * i]

    for i, j in robot_edges:
        if i == j:
            raise ModelError(f"unicycle_team: robot {i} cannot measure itself")
        xi, yi, pi = pose(i)
        xj, yj, _ = pose(j)
        outputs.append(planar_bearing(xi, yi, pi, xj, yj))
        names.append(f"eta_{i}_{j}")
    for i, k in landmark_edges:
        if not 1 <= k <= n_landmarks:
            raise ModelError(f"unicycle_team: landmark {k} outside 1..{n_landmarks}")
        xi, yi, pi = pose(i)
        outputs.append(planar_bearing(xi, yi, pi, params[2 * k - 2], params[2 * k - 1]))
        names.append(f"eta_{i}_L{k}")
    for i in gps:
        for s, label in zip(pose(i), ("x", "y", "psi"), strict=True):
            outputs.append(s)
            names.append(f"gps_{label}_{i}")
    if not outputs:
        raise ModelError("unicycle_team: no measurements (give edges, landmarks or gps)")
    return SymbolicModel(
        name="unicycle-team",
        description=f"{n} unicycles, {len(outputs)} measurement(s)",
        states=states,
        drift=tuple([0] * (3 * n)),
        inputs=inputs,
        input_fields=tuple(fields),
        outputs=tuple(outputs),
        output_names=tuple(names),
        parameters=tuple(params),
        input_groups={f"robot_{i}": inputs[2 * i - 2 : 2 * i] for i in range(1, n + 1)},
        state_box=tuple(
            b for _ in range(n) for b in ((-50.0, 50.0), (-50.0, 50.0), (-np.pi, np.pi))
        ),
        parameter_box=tuple((-50.0, 50.0) for _ in params),
    )


# ------------------------------------------------------------------------------------------
# Seed 003: air-ground follower
# ------------------------------------------------------------------------------------------
AIRGROUND_STATES = _real("r_x r_y theta_i theta_0")
AIRGROUND_INPUTS = _real("v_i omega_i v_0 omega_0")
AIRGROUND_MODES: tuple[int, ...] = (1, 2, 3)


def airground_follower(mode: int) -> SymbolicModel:
    """Seed 003 follower model, continuous form of Eq. 3, with measurement mode ``sw`` (Eq. 4).

    State ``(r_x, r_y, θ_i, θ_0)`` with ``r = p_0 − p_i`` in the drones' common frame:
    ``ṙ = v_0 (cos θ_0, sin θ_0) − v_i (cos θ_i, sin θ_i)``, ``θ̇_i = ω_i``, ``θ̇_0 = ω_0``.
    Outputs: ``sw=1``: ``[d, φ, θ_i, θ_0]``; ``sw=2``: ``[d, φ̄, θ_0]`` (φ̄ is the triangle bearing,
    the same function ``atan2(r_y, r_x)`` of the state, only noisier); ``sw=3``: ``[d]``, with
    ``d = ‖r‖`` and ``φ = atan2(r_y, r_x)``.
    """
    if mode not in AIRGROUND_MODES:
        raise ModelError(f"airground_follower: mode must be one of {AIRGROUND_MODES}, got {mode}")
    rx, ry, thi, th0 = AIRGROUND_STATES
    zero = sp.Integer(0)
    fields = (
        (-sp.cos(thi), -sp.sin(thi), zero, zero),
        (zero, zero, sp.Integer(1), zero),
        (sp.cos(th0), sp.sin(th0), zero, zero),
        (zero, zero, zero, sp.Integer(1)),
    )
    d = sp.sqrt(rx**2 + ry**2)
    phi = sp.atan2(ry, rx)
    outputs: dict[int, tuple[tuple[str, sp.Expr], ...]] = {
        1: (("d", d), ("phi", phi), ("theta_i", thi), ("theta_0", th0)),
        2: (("d", d), ("phi_bar", phi), ("theta_0", th0)),
        3: (("d", d),),
    }
    return SymbolicModel(
        name=f"airground-sw{mode}",
        description=f"seed-003 follower relative model, measurement mode sw={mode}",
        states=AIRGROUND_STATES,
        drift=(0, 0, 0, 0),
        inputs=AIRGROUND_INPUTS,
        input_fields=fields,
        outputs=tuple(e for _, e in outputs[mode]),
        output_names=tuple(nm for nm, _ in outputs[mode]),
        input_groups={
            "v_i": (AIRGROUND_INPUTS[0],),
            "omega_i": (AIRGROUND_INPUTS[1],),
            "v_0": (AIRGROUND_INPUTS[2],),
            "omega_0": (AIRGROUND_INPUTS[3],),
        },
        state_box=((-8.0, 8.0), (-8.0, 8.0), (-np.pi, np.pi), (-np.pi, np.pi)),
    )
