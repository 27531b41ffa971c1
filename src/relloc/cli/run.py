"""``relloc run [SCENARIO.toml] --out DIR [--seed S] [--runs N] [--filter plkf|tekf|bcplkf]``

plus ``--init`` (track initialisation policy), ``--yaw-bank K`` (yaw hypotheses for an unknown
initial yaw), ``--keep-window`` (seconds a track survives without measurements), ``--gate P``
(reject measurements beyond the χ²(3, P) NIS gate), ``--settle``
(track age from which samples count as steady state), ``--duration`` (shorten the scenario),
``--executor``, ``--no-plots`` and ``--mcap FILE`` / ``--tum DIR`` (run 0's estimates for ROS
tools and evo). The defaults are the library's
(:func:`relloc.estimators.track_manager.default_tracker`, :class:`TeamRunSettings`).

Runs a team scenario (default: the built-in seed-000 air-ground team), prints the key figures
per pair in a table that fits the terminal (:mod:`relloc.cli.console`; the full table is in
``report.md``), writes ``DIR/summary.json``, ``DIR/report.md`` and figures, and lists every
file written. Without matplotlib (a core install) it writes no figures and says so. A bad
scenario file is a configuration error (exit code 2) naming the field. A bag (``relloc run BAG
--map MAP``) is one replay whose UWB ranges go to the range-only filter: it refuses the options it
does not read (``--runs``, ``--duration``, ``--executor`` and the track managers' ``--seed``,
``--filter``, ``--init``, ``--yaw-bank``, ``--keep-window``, ``--gate``).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import TYPE_CHECKING

from relloc.cli.export_args import add_export_arguments, export_request, print_export
from relloc.cli.flags import nonempty_path

if TYPE_CHECKING:
    from relloc.estimators.initialisation import FieldOfView
    from relloc.estimators.yaw_bank import YawBankSettings
    from relloc.sim.scenario import Scenario

DEFAULT_OUT = Path("out/run")


def add_parser(subparsers: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    from relloc.estimators.initialisation import POLICY_NAMES
    from relloc.estimators.relative import UPDATE_KINDS
    from relloc.estimators.track_manager import DEFAULT_YAW_BANK
    from relloc.experiments.team_run import TeamRunSettings

    defaults = TeamRunSettings()
    tracker = defaults.tracker

    p = subparsers.add_parser(
        "run",
        help="relative localization of a team scenario (default: the built-in air-ground team)",
        description=(
            "Simulate a team scenario, track every observed robot from every observing robot, "
            "print accuracy and consistency per robot, write summary.json, report.md and figures."
        ),
    )
    p.add_argument(
        "scenario",
        nargs="?",
        type=Path,
        default=None,
        help="scenario TOML file (default: the built-in seed-000 air-ground team), or a ROS 2 "
        "bag with --map",
    )
    p.add_argument(
        "--map", type=Path, default=None, help="the bag's topic mapping TOML (SCENARIO is a bag)"
    )
    p.add_argument(
        "--out", type=nonempty_path, default=DEFAULT_OUT, help=f"output folder ({DEFAULT_OUT})"
    )
    p.add_argument("--seed", type=int, default=None, help=f"master seed (default {defaults.seed})")
    p.add_argument(
        "--runs",
        type=int,
        default=None,
        help=f"Monte-Carlo runs (default {defaults.runs}; a bag is one replay)",
    )
    p.add_argument(
        "--filter",
        choices=UPDATE_KINDS,
        default=None,
        help=f"relative filter (default {tracker.filter})",
    )
    p.add_argument(
        "--init",
        choices=POLICY_NAMES,
        default=None,
        help="track initialisation (default: from the first measurement, yaw unknown)",
    )
    p.add_argument(
        "--yaw-bank",
        type=int,
        default=None,
        metavar="K",
        help=(
            "start tracks whose yaw is unknown as a bank of K yaw hypotheses "
            f"(default {DEFAULT_YAW_BANK}; 0 = a single filter, as in seed 000)"
        ),
    )
    p.add_argument(
        "--duration",
        type=float,
        default=None,
        help="override the scenario's duration in seconds (a quick look)",
    )
    p.add_argument(
        "--keep-window",
        type=float,
        default=None,
        metavar="S",
        help=(
            "seconds a track is predicted without measurements before deletion "
            f"(default {tracker.keep_window_s:g})"
        ),
    )
    p.add_argument(
        "--gate",
        type=float,
        default=None,
        metavar="P",
        help=(
            "reject a relative measurement whose NIS exceeds the χ²(3) quantile P as an "
            "outlier, counted in rows_not_used as rows_gated (default: fuse every measurement, "
            "as seed 000)"
        ),
    )
    p.add_argument(
        "--settle",
        type=float,
        default=defaults.settle_s,
        metavar="S",
        help=(
            "track age in seconds from which samples count as steady state for RMSE, NEES, NIS "
            f"(default {defaults.settle_s:g})"
        ),
    )
    p.add_argument(
        "--no-plots",
        action="store_true",
        help="write summary.json and report.md only (the default when matplotlib is missing)",
    )
    p.add_argument(
        "--executor",
        default=None,
        help="'process' (default, all cores), 'serial', or 'dask://HOST:PORT'",
    )
    p.add_argument("--quiet", action="store_true", help="no progress display and no table")
    add_export_arguments(p, "run 0's estimates and truth")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    import dataclasses

    from relloc.cli import console
    from relloc.cli.extras import available
    from relloc.cli.flags import flag_errors
    from relloc.errors import ConfigError
    from relloc.estimators.initialisation import InitPolicy
    from relloc.estimators.track_manager import TrackManagerSettings
    from relloc.experiments.team_run import TeamRunSettings, run_scenario, write_run_report
    from relloc.sim.scenario import default_scenario, load_scenario
    from relloc.sim.simulate import checked_motions

    if args.map is not None:
        return _run_bag(args)
    _tracker_defaults(args)
    if args.scenario is not None:
        _refuse_bag_without_map(args.scenario)
    scenario = default_scenario() if args.scenario is None else load_scenario(args.scenario)
    if args.duration is not None:
        try:
            scenario = dataclasses.replace(scenario, duration_s=args.duration)
        except ConfigError as exc:
            raise ConfigError(f"--duration: {exc}") from None
    try:  # the motions are the file's: an error names it, before any run starts
        checked_motions(scenario)
    except ConfigError as exc:
        raise ConfigError(f"{args.scenario or 'default.toml'}: {exc}") from None
    fov = _guess_view(scenario)
    with flag_errors():
        settings = TeamRunSettings(
            runs=TeamRunSettings().runs if args.runs is None else args.runs,
            seed=args.seed,
            tracker=TrackManagerSettings(
                filter=args.filter,
                keep_window_s=args.keep_window,
                init=InitPolicy(name=args.init, fov=fov),
                yaw_bank=_yaw_bank(args.yaw_bank),
                gate_probability=args.gate,
            ),
            settle_s=args.settle,
            executor=args.executor,
            quiet=args.quiet,
        )
    plots = not args.no_plots and available("plot")
    if not args.no_plots and not plots:
        print(
            "relloc: note: matplotlib is not installed, so no figures are drawn "
            "(pip install 'relloc[plot]' for them)",
            file=sys.stderr,
        )
    summary, results = run_scenario(scenario, settings, export=export_request(args))
    files = write_run_report(scenario, summary, results, args.out, plots=plots)
    if summary["team"]["samples"] == 0:
        _no_steady_state_note(
            settings.settle_s, f"the {scenario.duration_s:g} s run", "run longer or lower --settle"
        )
    if not args.quiet:
        width = console.terminal_width()
        title = (
            f"{scenario.name}: {args.filter.upper()}, {settings.runs} run(s), seed "
            f"{settings.seed}, init {args.init}, yaw bank {args.yaw_bank or 'off'}, gate "
            f"{args.gate or 'off'}, steady state from track age {settings.settle_s:g} s (--settle)"
        )
        print(console.wrap_line(title, width))
        print(console.team_summary_table(summary, width=width))
        print(
            console.wrap_line(
                "pos/yaw: steady-state RMSE (± std over runs); ANEES, ANIS: ideal 1; in band: "
                "share of times the run-averaged NEES is in its 95 % band; conv: median time "
                "to converge from the unknown start. Full table: report.md",
                width,
            )
        )
        print(console.wrote_line(files, width))
        print_export(summary.get("export"))
    return 0


TRACKER_OPTIONS = ("seed", "filter", "init", "yaw_bank", "keep_window", "gate")
"""The options read by a scenario's track managers only: a bag's rows are UWB ranges
(:mod:`relloc.datasets.rosbag`), which the range-only filter tracks, so ``relloc run BAG --map``
refuses them (:func:`relloc.core.checks.refuse_unread`) instead of recording settings it never
used."""


def _tracker_defaults(args: argparse.Namespace) -> None:
    """Set the options of :data:`TRACKER_OPTIONS` not given to the library's defaults
    (:class:`TeamRunSettings`, :data:`DEFAULT_YAW_BANK`; ``--gate``: off)."""
    from relloc.estimators.track_manager import DEFAULT_YAW_BANK
    from relloc.experiments.team_run import TeamRunSettings

    defaults = TeamRunSettings()
    tracker = defaults.tracker
    for name, value in (
        ("seed", defaults.seed),
        ("filter", tracker.filter),
        ("init", tracker.init.name),
        ("yaw_bank", DEFAULT_YAW_BANK),
        ("keep_window", tracker.keep_window_s),
    ):
        if getattr(args, name) is None:
            setattr(args, name, value)


def _guess_view(scenario: Scenario) -> FieldOfView:
    """Where arbitrary initial guesses are drawn: inside the narrowest sensor view, out to the
    shortest maximum range (capped by the arena's diagonal when a sensor is unlimited)."""
    import numpy as np

    from relloc.errors import ConfigError
    from relloc.estimators.initialisation import FieldOfView

    sensors = [r.sensor for r in scenario.robots if r.sensor is not None]
    a = scenario.arena
    diagonal = float(np.hypot(a.x[1] - a.x[0], a.y[1] - a.y[0]))
    near = max(s.min_range for s in sensors)
    far = min(min(s.max_range for s in sensors), diagonal)
    try:
        return FieldOfView(fov_deg=min(s.fov_deg for s in sensors), range_limits=(near, far))
    except ConfigError as exc:
        raise ConfigError(
            f"robots[*].sensor.min_range, max_range, arena: initial guesses are drawn between "
            f"the largest min_range ({near:g} m) and the smallest max_range or arena diagonal "
            f"({far:g} m), which leaves no room ({exc})"
        ) from None


def _yaw_bank(n_components: int) -> YawBankSettings | None:
    """``--yaw-bank K``: K yaw hypotheses, or ``None`` (a single filter) for 0."""
    from relloc.errors import ConfigError
    from relloc.estimators.yaw_bank import YawBankSettings

    if n_components == 0:
        return None
    try:
        return YawBankSettings(n_components=n_components)
    except ConfigError as exc:
        reason = str(exc).partition(":")[2].strip()
        raise ConfigError(f"--yaw-bank: 0 (off) or {reason}") from None


def _refuse_bag_without_map(path: Path) -> None:
    """ConfigError when SCENARIO is a bag (a folder, ``.db3`` or ``.mcap``) given without
    ``--map``: it is not a scenario file, and a bag is run through its topic mapping."""
    from relloc.datasets.bag_mapping import shipped_mappings
    from relloc.errors import ConfigError

    if path.is_dir():
        what, bag = "a folder", "a bag folder"
    elif path.suffix.lower() in (".db3", ".mcap"):
        what, bag = "a bag", "a bag"
    else:
        return
    raise ConfigError(
        f"{path}: {what}, not a scenario TOML file; {bag} needs --map MAP, its topic mapping "
        f"(a file, or shipped: {', '.join(shipped_mappings())})"
    )


def _no_steady_state_note(settle_s: float, where: str, remedy: str) -> None:
    """The note (stderr) of a run whose tracks never reached the settle time in ``where``."""
    print(
        f"relloc: note: no steady-state results: no track reached the settle time "
        f"({settle_s:g} s) in {where}, so accuracy and consistency are NaN; {remedy}",
        file=sys.stderr,
    )


def _run_bag(args: argparse.Namespace) -> int:
    """``relloc run BAG --map MAP.toml``: one replay of a recorded bag (no Monte Carlo)."""
    from relloc.cli import console
    from relloc.cli.extras import available
    from relloc.core.checks import number, refuse_unread
    from relloc.datasets.bag_mapping import load_mapping
    from relloc.errors import ConfigError
    from relloc.experiments.bag_run import run_bag
    from relloc.pipeline.output import bag_rows_source, skipped_rows_line

    if args.scenario is None:
        raise ConfigError("--map: give the bag to run as SCENARIO (relloc run BAG --map MAP)")
    for flag, value in (("--runs", args.runs), ("--duration", args.duration)):
        if value is not None:  # a recording is replayed once, whole
            raise ConfigError(f"{flag}: a bag is replayed once and whole; leave {flag} out")
    if args.executor is not None:
        raise ConfigError("--executor: a bag is one replay in this process; leave it out")
    refuse_unread(
        "bag",
        [name for name in TRACKER_OPTIONS if getattr(args, name) is not None],
        dict.fromkeys(TRACKER_OPTIONS, ("a scenario's track managers",)),
        label="a bag (its UWB ranges go to the range-only filter)",
    )
    settle_s = number(args.settle, "--settle", low=0.0)
    summary, files = run_bag(
        args.scenario,
        load_mapping(args.map),
        args.out,
        settle_s=settle_s,
        export=export_request(args),
        plots=not args.no_plots and available("plot"),
    )
    if summary["team"]["samples"] == 0:
        _no_steady_state_note(settle_s, "the bag", "lower --settle")
    if summary["antenna_offset_not_modelled_m"] > 0:
        print(
            f"relloc: note: the mapping's antenna offsets (up to "
            f"{summary['antenna_offset_not_modelled_m']:.3g} m) are not modelled by this range "
            "filter; relloc reproduce tiers-uwb uses them",
            file=sys.stderr,
        )
    for pair, ranges in summary["range_pairs_without_odometry"].items():
        print(
            f"relloc: note: {pair} not tracked: one of them reports fewer than two odometry "
            f"samples ({ranges} ranges unused)",
            file=sys.stderr,
        )
    if not args.quiet:
        skips = summary["loader"]["skips"]
        print(console.team_summary_table(summary, width=console.terminal_width()))
        aside = summary["loader"]["uwb_readings_not_in_recording"]
        line = skipped_rows_line(skips["rows_skipped"], skips["by_reason"], bag_rows_source(aside))
        print(console.wrap_line(line, console.terminal_width()))
        print(console.wrote_line(files, console.terminal_width()))
        print_export(summary.get("export"))
    return 0
