"""``relloc observability MODEL [--measurements ...] [--order K] [...]``

Symbolic nonlinear observability of a built-in model or of a user model given as
``package.module:function`` (a zero-argument callable returning a
:class:`relloc.models.symbolic.SymbolicModel`). Prints the generic rank of the
observability matrix, the input conditions needed to reach it, the unobservable directions
when the rank is deficient, and a witness state; ``--json FILE`` writes the same. With
``--at-state``/``--at-inputs`` it also prints the rank at that state with constant inputs
(Lie derivatives of the combined field up to ``--order``; a model's free parameters, such as
landmark positions, are given in ``--at-state`` too).
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import TYPE_CHECKING

from relloc.errors import ConfigError, ModelError

if TYPE_CHECKING:
    from relloc.models.symbolic import SymbolicModel

MAX_SAMPLES = 1000
"""Most random states for the generic rank (each is a numeric rank of the whole matrix)."""
MAX_LANDMARKS = 10
"""Most landmarks of the symbolic unicycle models (the Lie derivatives grow with each)."""


def _builtin_help() -> str:
    from relloc.observability.builtin import BUILTIN_MODELS

    lines = ["built-in models:"]
    lines += [f"  {name:24s} {desc}" for name, desc in BUILTIN_MODELS.items()]
    lines.append("  package.module:function  a user model (returns a SymbolicModel)")
    return "\n".join(lines)


def add_parser(subparsers: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    p = subparsers.add_parser(
        "observability",
        help="symbolic nonlinear observability: rank, input conditions, unobservable directions",
        description="Lie-derivative observability analysis of a relloc model.",
        epilog=_builtin_help(),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("model", help="a built-in model (listed below) or package.module:function")
    p.add_argument("--measurements", nargs="+", default=None, help="measured outputs to use")
    p.add_argument(
        "--order", type=int, default=2, help="highest Lie-derivative order (2; also --at-state)"
    )
    p.add_argument("--inputs", nargs="*", default=None, help="only these inputs/groups excited")
    p.add_argument("--landmarks", type=int, default=None, help="landmarks (unicycle models; 1)")
    p.add_argument("--robots", type=int, default=None, help="robots (unicycle-team, ≤ 6; 3)")
    p.add_argument("--gps", type=int, nargs="*", default=None, help="GPS robots (unicycle-team)")
    p.add_argument("--mode", type=int, nargs="+", default=None, help="airground modes sw")
    p.add_argument("--samples", type=int, default=5, help="random states for the generic rank")
    p.add_argument("--seed", type=int, default=0, help="seed of the random states")
    p.add_argument("--precise", action="store_true", help="re-check the rank with 50 digits")
    p.add_argument(
        "--at-state",
        default=None,
        help="NAME=VALUE,... rank at this state (unset states 0; free parameters such as "
        "landmark positions lx_0, ly_0 must be given)",
    )
    p.add_argument("--at-inputs", default=None, help="NAME=VALUE,... constant inputs for it")
    p.add_argument("--json", type=Path, default=None, help="also write the results here")
    p.set_defaults(func=run)


def _assignments(text: str | None, names: tuple[str, ...], what: str) -> list[float]:
    values = dict.fromkeys(names, 0.0)
    if not text:
        return list(values.values())
    given: set[str] = set()
    for item in text.split(","):
        key, sep, val = item.partition("=")
        key = key.strip()
        if key in given:
            raise ConfigError(f"--{what}: {key} is given twice in {text!r}")
        given.add(key)
        if not sep or key not in values:
            raise ConfigError(
                f"--{what}: expected NAME=VALUE with NAME in {list(names)}, got {item!r}"
            )
        try:
            number = float(val)
        except ValueError as exc:
            raise ConfigError(f"--{what}: {key} must be a number, got {val!r}") from exc
        if not math.isfinite(number):
            raise ConfigError(f"--{what}: {key} must be finite, got {val!r}")
        values[key] = number
    return list(values.values())


def _state_and_parameters(
    text: str | None, model: SymbolicModel
) -> tuple[list[float], list[float] | None]:
    """``--at-state`` values: the states (0 where not given) and, for a model whose parameters
    are free constants (landmark positions ``lx_0, ly_0, …``; no rule derives them from the
    state), those parameters too, every one of them required. ``None`` parameters: the model's
    rule gives them."""
    states = model.state_names
    if model.parameter_rule is not None or not model.parameters:
        return _assignments(text, states, "at-state"), None
    names = tuple(str(p) for p in model.parameters)
    given = {item.partition("=")[0].strip() for item in (text or "").split(",")}
    missing = [p for p in names if p not in given]
    if missing:
        raise ConfigError(
            f"--at-state: {model.name!r} has free parameters; give them too: {', '.join(missing)}"
        )
    values = _assignments(text, states + names, "at-state")
    return values[: len(states)], values[len(states) :]


def run(args: argparse.Namespace) -> int:
    from relloc.core.checks import refuse_unread
    from relloc.models.symbolic import AIRGROUND_MODES
    from relloc.observability.analysis import analyse, rank_at
    from relloc.observability.builtin import READ_BY, ModelOptions, resolve_models
    from relloc.pipeline.output import write_json_file

    if args.order < 0:
        raise ConfigError(f"--order: must be ≥ 0, got {args.order}")
    if not 1 <= args.samples <= MAX_SAMPLES:
        raise ConfigError(f"--samples: must be in 1…{MAX_SAMPLES}, got {args.samples}")
    if args.seed < 0:
        raise ConfigError(f"--seed: must be ≥ 0, got {args.seed}")
    given = {
        "measurements": args.measurements,
        "landmarks": args.landmarks,
        "robots": args.robots,
        "gps": args.gps,
        "mode": args.mode,
    }
    refuse_unread(args.model, [k for k, v in given.items() if v is not None], READ_BY)
    landmarks = 1 if args.landmarks is None else args.landmarks
    if not 0 <= landmarks <= MAX_LANDMARKS:
        raise ConfigError(f"--landmarks: must be in 0…{MAX_LANDMARKS}, got {landmarks}")
    opts = ModelOptions(
        measurements=tuple(args.measurements) if args.measurements else None,
        landmarks=landmarks,
        robots=3 if args.robots is None else args.robots,
        gps=tuple(args.gps or ()),
        modes=tuple(args.mode) if args.mode else AIRGROUND_MODES,
        inputs=tuple(args.inputs) if args.inputs is not None else None,
    )
    results = []
    for model in resolve_models(args.model, opts):
        probe = args.at_state is not None or args.at_inputs is not None
        if probe:  # before the (longer) analysis
            state, params = _state_and_parameters(args.at_state, model)
            inputs = _assignments(args.at_inputs, model.input_names, "at-inputs")
            try:
                rank_there = rank_at(model, state, inputs, params=params, order=args.order)
            except ModelError as exc:
                raise ConfigError(
                    f"--at-state/--at-inputs: no rank of {model.name!r} there ({exc})"
                ) from None
        r = analyse(
            model, order=args.order, samples=args.samples, seed=args.seed, precise=args.precise
        )
        out = r.to_dict()
        print(f"model      {r.model}: {r.description}")
        print(f"states     {', '.join(r.state_names)}")
        rank_line = f"rank       {r.rank} of {r.state_dim}"
        rank_line += " (observable)" if r.full_rank else " (NOT fully observable)"
        if r.precise_rank is not None:
            rank_line += f"; 50-digit check: {r.precise_rank}"
        print(rank_line + f"   [order {r.order}, {r.n_rows} rows, {r.elapsed_s:.2f} s]")
        print(f"conditions {r.conditions_text()}")
        if r.input_conditions is not None:
            alts = " | ".join(" & ".join(c) or "none" for c in r.input_conditions)
            print(f"  scalar   minimal excited inputs: {alts}")
        for d in r.unobservable_directions:
            print(f"unobservable {d}")
        print("witness    " + ", ".join(f"{k}={v:.4g}" for k, v in r.witness.state.items()))
        if probe:
            out["rank_at"] = {
                "state": state,
                "parameters": params,
                "inputs": inputs,
                "rank": rank_there,
            }
            print(f"rank at the given state and constant inputs: {out['rank_at']['rank']}")
        for note in r.notes:
            print(f"note       {note}")
        print()
        results.append(out)
    if args.json is not None:
        write_json_file(args.json, results, "--json")
    return 0
