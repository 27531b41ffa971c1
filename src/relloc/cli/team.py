r"""``relloc team up SCENARIO|default|DATASET_DIR|REPRODUCTION --out DIR`` — the whole team as
processes.

Every robot runs as its own ``relloc node`` process and a ``relloc team clock`` process drives
simulated time (faster than real time unless ``--realtime``); the launcher collects every
robot's estimates and writes ``summary.json`` and ``report.md`` (see
:mod:`relloc.runtime.summary`). Faults (all in simulated time)::

    --drop P  --delay MS  --jitter MS  --duplicate P  --reorder P
    --kill ROBOT@SECONDS  --restart ROBOT@SECONDS  --partition A,B@T1-T2

``--secure`` runs every process with mutual TLS only and Zenoh access control: each robot may
publish only under its own key prefix, only the launcher's certificate may send ``tick``/``ctl``
(certificates from ``--certs DIR``, see ``relloc certs``, or made in ``OUT/certs``; a
reproduction's team makes them in each run's folder ``OUT/runI/certs``). Every target takes it:
a scenario, ``default``, a dataset folder and every reproduction.

A reproduction's team (``desilva2015``, ``desilva2015-kidnapped``: seed 002's leaders and pods,
see :mod:`relloc.experiments.desilva2015_team`) runs ``--runs N`` Monte-Carlo runs of
``--duration S`` simulated seconds each and is scored beside the in-process reproduction on the
same seeds; for these two only, ``--sharing-policy NAME`` sets the leaders' sharing policy and
``--sensing all|L1,P2,...`` the simulated robots that sense and run the fusers (default the
paper's leaders L1, L2, as for ``relloc reproduce desilva2015``). ``guler2023`` (seed 003's
air-ground team in closed loop: a world process, the leader, followers and drones as processes,
``--case`` one of its paper scenarios, default ``two_drones``; see
:mod:`relloc.experiments.guler2023_team`) takes the same flags but those two; its tick is the
scenario's 0.05 s, so it refuses ``--tick``. ``--port`` and ``--mcap``/``--tum`` are read by the
track managers of a scenario, ``default`` or a dataset only. A flag the target does not read
(:data:`READ_BY`) is refused, not ignored.

``relloc team clock`` runs only the clock/simulator process (for robots started by hand).
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from relloc.cli.console import plain_text
from relloc.cli.export_args import add_export_arguments, export_request, print_export
from relloc.cli.flags import nonempty_path
from relloc.cli.node import (
    COOPERATIVE,
    TRACKS,
    add_network_fault_arguments,
    add_sensing_argument,
    add_sharing_policy_argument,
    add_transport_arguments,
    network_faults_from_args,
    refuse_desilva_only,
    target_kind,
    transport_from_args,
)
from relloc.runtime import CLOCK_TICK_S


def add_parser(subparsers: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    p = subparsers.add_parser(
        "team",
        help="run a whole team as separate processes over Zenoh",
        description=plain_text(__doc__),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    actions = p.add_subparsers(dest="team_command", metavar="ACTION", required=True)

    up = actions.add_parser("up", help="launch a team, collect its estimates, write a report")
    up.add_argument(
        "scenario",
        help="scenario TOML file, 'default' (built-in team), an MRCLAM-layout dataset folder, "
        "or a reproduction: desilva2015, desilva2015-kidnapped, sharma2013, guler2023",
    )
    up.add_argument("--runs", type=int, default=None, help="a reproduction's Monte-Carlo runs (1)")
    up.add_argument(
        "--case",
        default=None,
        help="the team EIF's case: sharma2013's (default two_landmarks), or MODE/ANCHORS of "
        "mrclam-cl with --estimator cooperative (default range_bearing/2_landmarks)",
    )
    up.add_argument(
        "--fit",
        default=None,
        metavar="FILE",
        help="--estimator cooperative: the fit.json of an earlier run (skip the fit)",
    )
    up.add_argument(
        "--estimator",
        choices=("track", "cooperative"),
        default=None,
        help="with a dataset folder: seed 000's track managers, or seed 001's team EIF in "
        "every robot (the mrclam-cl reproduction)",
    )
    up.add_argument(
        "--duration", type=float, default=None, help="a reproduction's simulated seconds per run"
    )
    up.add_argument("--out", type=nonempty_path, required=True, help="output folder")
    up.add_argument(
        "--seed",
        type=int,
        default=0,
        help="simulation and fault seed (default 0; the team is run 0 of `relloc run --seed SEED`)",
    )
    up.add_argument("--team", default="team", help="team id (key-expression prefix)")
    up.add_argument(
        "--filter", default=None, help="a scenario's or a dataset's tracks: plkf | tekf | bcplkf"
    )
    up.add_argument(
        "--gate",
        type=float,
        default=None,
        metavar="P",
        help="a scenario's or a dataset's tracks: reject a measurement whose NIS exceeds the "
        "χ²(3) quantile P (as relloc run --gate; default off)",
    )
    up.add_argument(
        "--tick",
        type=float,
        default=None,
        help=f"clock tick (publication period), s (default {CLOCK_TICK_S:g}; guler2023: the "
        "scenario's)",
    )
    up.add_argument(
        "--realtime",
        type=float,
        default=0.0,
        metavar="FACTOR",
        help="pace ticks at FACTOR x real time (0: as fast as the team can go)",
    )
    up.add_argument(
        "--port",
        type=int,
        default=None,
        help="a scenario's or a dataset's tracks: hub port on 127.0.0.1 (default free)",
    )
    up.add_argument("--timeout", type=float, default=300.0, help="wall-clock limit, s")
    up.add_argument(
        "--secure",
        action="store_true",
        help="mutual TLS only, one certificate per robot, Zenoh access control by identity",
    )
    up.add_argument(
        "--certs",
        type=Path,
        default=None,
        metavar="DIR",
        help="certificate folder of 'relloc certs' (default with --secure: made in OUT/certs)",
    )
    add_sharing_policy_argument(up)
    add_sensing_argument(up)
    up.add_argument("--quiet", action="store_true", help="print nothing")
    faults = add_network_fault_arguments(up)
    faults.add_argument("--kill", action="append", default=[], metavar="ROBOT@SECONDS")
    faults.add_argument("--restart", action="append", default=[], metavar="ROBOT@SECONDS")
    add_export_arguments(up, "the distributed estimates (a scenario's or a dataset's tracks)")
    up.set_defaults(func=run_up)

    clock = actions.add_parser("clock", help="run only the clock/simulator process")
    clock.add_argument("--roster", required=True, help="comma-separated robot ids")
    clock.add_argument("--tick", type=float, default=CLOCK_TICK_S, help="tick period, simulated s")
    clock.add_argument("--duration", type=float, required=True, help="simulated duration, s")
    clock.add_argument("--realtime", type=float, default=0.0, metavar="FACTOR")
    clock.add_argument("--ack-timeout", type=float, default=10.0, help="wall s per tick barrier")
    clock.add_argument("--kill", action="append", default=[], metavar="ROBOT@SECONDS")
    clock.add_argument("--restart", action="append", default=[], metavar="ROBOT@SECONDS")
    clock.add_argument("--report", type=Path, default=None, help="write the clock report here")
    add_transport_arguments(clock)
    clock.set_defaults(func=run_clock, team_process=True)


def _robot_events(args: argparse.Namespace) -> dict[str, tuple[object, ...]]:
    from relloc.runtime.faults import parse_robot_event

    return {
        "kills": tuple(parse_robot_event(k, "--kill") for k in args.kill),
        "restarts": tuple(parse_robot_event(r, "--restart") for r in args.restart),
    }


READ_BY: dict[str, tuple[str, ...]] = {
    "runs": ("guler2023", "desilva2015", "sharma2013"),
    "duration": ("guler2023", "desilva2015", "sharma2013", COOPERATIVE),
    "case": ("guler2023", "sharma2013", COOPERATIVE),
    "fit": (COOPERATIVE,),
    "estimator": (COOPERATIVE, TRACKS),
    "filter": (TRACKS,),
    "gate": (TRACKS,),
    "tick": ("desilva2015", "sharma2013", COOPERATIVE, TRACKS),  # guler2023: its scenario's
    "port": (TRACKS,),
    "mcap": (TRACKS,),
    "tum": (TRACKS,),
}
"""The kinds of target (:func:`up_target_kind`) that read each of these flags; another is refused,
never ignored (:func:`relloc.core.checks.refuse_unread`)."""


def up_target_kind(args: argparse.Namespace) -> str:
    """The kind of ``team up``'s target (:data:`READ_BY`, :func:`relloc.cli.node.target_kind`):
    its reproductions include guler2023, whose robots are not ``relloc node`` processes."""
    from relloc.runtime.scenario import REPRODUCTIONS

    return target_kind(args.scenario, args.estimator, (*REPRODUCTIONS, "guler2023"))


def run_up(args: argparse.Namespace) -> int:
    from relloc.core.checks import refuse_unread
    from relloc.runtime.scenario import REPRODUCTIONS

    refuse_desilva_only(args)
    given = [name for name in READ_BY if getattr(args, name) is not None]
    refuse_unread(up_target_kind(args), given, READ_BY, label=args.scenario)
    if args.runs is None:  # the defaults of the targets that read them
        args.runs = 1
    if args.tick is None:
        args.tick = CLOCK_TICK_S
    if args.scenario == "guler2023":
        from relloc.cli.airground import run_team_up

        return run_team_up(args, _reproduction_team_args(args))
    if args.scenario in REPRODUCTIONS:
        return run_reproduction(args)
    if args.estimator == "cooperative":
        return run_mrclam(args)
    from relloc.runtime.launcher import DEFAULT_FILTER, TeamSettings
    from relloc.runtime.team import run_team

    settings = TeamSettings(
        scenario=args.scenario,
        out_dir=args.out,
        seed=args.seed,
        team=args.team,
        tick_s=args.tick,
        faults=network_faults_from_args(args, **_robot_events(args)),
        realtime_factor=args.realtime,
        port=args.port,
        wall_timeout_s=args.timeout,
        filter_kind=args.filter or DEFAULT_FILTER,
        gate_probability=args.gate,
        secure=args.secure,
        certs_dir=args.certs,
    )
    summary = run_team(settings, export=export_request(args))
    if not args.quiet:
        from relloc.runtime.team import print_summary

        print_summary(summary)
        print_export(summary.get("export"))
    return 0


def run_clock(args: argparse.Namespace) -> int:
    from relloc.pipeline.output import check_writable_file
    from relloc.runtime.clock import ClockSettings, run_clock

    if args.report is not None:  # checked before the run, not after it
        check_writable_file(args.report, "--report")
    events = _robot_events(args)
    settings = ClockSettings(
        team=args.team,
        roster=tuple(args.roster.split(",")),  # an empty id is refused, not dropped
        tick_s=args.tick,
        duration_s=args.duration,
        transport=transport_from_args(args),
        realtime_factor=args.realtime,
        ack_timeout_s=args.ack_timeout,
        kills=events["kills"],  # type: ignore[arg-type]
        restarts=events["restarts"],  # type: ignore[arg-type]
    )
    run_clock(settings, args.report)
    return 0


def _reproduction_team_args(args: argparse.Namespace) -> dict[str, Any]:
    """The settings every reproduction's team takes from the command line (clock step, faults,
    team name, wall-time limit, pacing, ``--secure`` and ``--certs``)."""
    return {
        "tick_s": args.tick,
        "faults": network_faults_from_args(args, **_robot_events(args)),
        "team": args.team,
        "wall_timeout_s": args.timeout,
        "realtime_factor": args.realtime,
        "secure": args.secure,
        "certs_dir": args.certs,
    }


def run_reproduction(args: argparse.Namespace) -> int:
    """``team up desilva2015`` / ``sharma2013``: the runs, scored beside the in-process
    reproduction."""
    from relloc.errors import ConfigError
    from relloc.experiments.desilva2015 import sensing_robots
    from relloc.experiments.desilva2015_team import DeSilvaTeamSettings, run_desilva_team
    from relloc.pipeline.output import fmt
    from relloc.runtime.outcomes import agreement_text

    if args.runs < 1:
        raise ConfigError(f"--runs: {args.runs} must be ≥ 1")
    if args.scenario == "sharma2013":
        return run_sharma(args)
    summary = run_desilva_team(
        DeSilvaTeamSettings(
            name=args.scenario,
            out_dir=args.out,
            seed=args.seed,
            runs=args.runs,
            duration_s=args.duration,
            sharing_policy=args.sharing_policy or "all",
            sensing=sensing_robots(args.sensing),
            **_reproduction_team_args(args),
        )
    )
    if not args.quiet:
        d, r = summary["distributed"], summary["in_process"]
        print(
            f"{summary['experiment']}: success rate {fmt(d['success_rate'])} (in-process "
            f"{fmt(r['success_rate'])}), position RMSE {fmt(d['pos_rmse_m'])} m (in-process "
            f"{fmt(r['pos_rmse_m'])} m); {agreement_text(summary)}"
        )
    return 0


def run_sharma(args: argparse.Namespace) -> int:
    """``team up sharma2013``: every agent's team EIF beside the in-process one."""
    from relloc.experiments.sharma2013_team import SharmaTeamSettings, run_sharma_team
    from relloc.pipeline.output import fmt

    summary = run_sharma_team(
        SharmaTeamSettings(
            out_dir=args.out,
            seed=args.seed,
            runs=args.runs,
            duration_s=args.duration,
            case=args.case or "two_landmarks",
            **_reproduction_team_args(args),
        )
    )
    if not args.quiet:
        for run in summary["per_run"]:
            ref = run["in_process"]["pos_rmse_m"]
            for robot, a in run["agents"].items():
                print(
                    f"run {run['run']} agent {robot}: position RMSE {fmt(a['pos_rmse_m'])} m "
                    f"(in-process {fmt(ref)} m), max |Δ| of a mean entry "
                    f"{fmt(a['max_abs_mean_diff'])}"
                )
    return 0


def run_mrclam(args: argparse.Namespace) -> int:
    """``team up MRCLAM_DIR --estimator cooperative``: every agent's team EIF beside the
    in-process one."""
    from pathlib import Path

    from relloc.errors import ConfigError
    from relloc.experiments.mrclam_team import DEFAULT_CASE, MrclamTeamSettings, run_mrclam_team
    from relloc.pipeline.output import fmt

    if not Path(args.scenario).is_dir():
        raise ConfigError(f"--estimator cooperative: {args.scenario} is not a dataset folder")
    summary = run_mrclam_team(
        MrclamTeamSettings(
            folder=Path(args.scenario),
            out_dir=args.out,
            seed=args.seed,
            duration_s=args.duration,
            case=args.case or DEFAULT_CASE,
            **_reproduction_team_args(args),
            fit_path=Path(args.fit) if args.fit else None,
        )
    )
    if not args.quiet:
        run = summary["per_run"][0]
        for robot, a in run["agents"].items():
            print(
                f"agent {robot}: position RMSE {fmt(a['pos_rmse_m'])} m (in-process "
                f"{fmt(run['in_process']['pos_rmse_m'])} m), max |Δ| of a mean entry "
                f"{fmt(a['max_abs_mean_diff'])}"
            )
    return 0
