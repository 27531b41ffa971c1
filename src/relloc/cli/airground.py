r"""``relloc airground world|robot`` — one process of seed 003's air-ground team (closed loop).

``relloc team up guler2023`` starts these itself (see
:mod:`relloc.experiments.guler2023_team`); by hand, start one world and one robot per team
member (``R_0`` leader, ``R_1 … R_N`` followers, ``D_1 … D_M`` drones), all connected to one Zenoh
endpoint::

    relloc airground world --case two_drones --seed 0 --run 0 --connect tcp/127.0.0.1:7447 \
        --world-out world.npz
    relloc airground robot --robot R_1 --case two_drones --seed 0 --run 0 \
        --connect tcp/127.0.0.1:7447

``world`` steps the world and announces ``--kill``/``--restart`` events (a launcher executes
them); ``robot`` runs the leader's path, a follower's switching EKF and formation controller, or
a drone's guidance (:mod:`relloc.runtime.airground`).
"""

from __future__ import annotations

import argparse
from pathlib import Path

from relloc.cli.console import plain_text
from relloc.cli.node import (
    add_network_fault_arguments,
    add_transport_arguments,
    network_faults_from_args,
    transport_from_args,
)


def add_parser(subparsers: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    p = subparsers.add_parser(
        "airground",
        help="one process of seed 003's air-ground team (world or robot)",
        description=plain_text(__doc__),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    actions = p.add_subparsers(dest="airground_command", metavar="ACTION", required=True)
    world = actions.add_parser("world", help="the world process (simulator and clock)")
    _run_arguments(world)
    world.add_argument("--world-out", type=Path, required=True, help="truth file (.npz)")
    world.add_argument("--report", type=Path, default=None, help="the world's report (JSON)")
    world.add_argument("--cmd-timeout", type=float, default=10.0, help="wall s per command wait")
    world.add_argument("--realtime", type=float, default=0.0, metavar="FACTOR", help="pace ticks")
    world.add_argument("--kill", action="append", default=[], metavar="ROBOT@SECONDS")
    world.add_argument("--restart", action="append", default=[], metavar="ROBOT@SECONDS")
    world.set_defaults(func=run_world, team_process=True)
    robot = actions.add_parser("robot", help="one robot's process")
    robot.add_argument("--robot", required=True, help="R_0 (leader), R_i (follower), D_j (drone)")
    _run_arguments(robot)
    robot.add_argument("--input-timeout", type=float, default=10.0, help="wall s per input wait")
    add_network_fault_arguments(robot)
    robot.set_defaults(func=run_robot, team_process=True)


def _run_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--case", default="two_drones", help="one_drone | two_drones | formation")
    p.add_argument("--seed", type=int, default=0, help="the reproduction's master seed")
    p.add_argument("--run", type=int, default=0, help="Monte-Carlo run of that seed")
    p.add_argument("--duration", type=float, default=None, help="simulated seconds")
    add_transport_arguments(p)


def run_world(args: argparse.Namespace) -> int:
    from relloc.experiments.guler2023_team import run_seed, start_world, team_case
    from relloc.pipeline.output import check_writable_file
    from relloc.runtime.airground import WorldProcess, WorldSettings, save_world, write_report
    from relloc.runtime.faults import parse_robot_event

    for path, flag in ((args.world_out, "--world-out"), (args.report, "--report")):
        if path is not None:  # checked before the run, not after it
            check_writable_file(path, flag)
    case = team_case(args.case, args.duration)
    world = start_world(case, run_seed(args.seed, args.case, args.run))
    settings = WorldSettings(
        team=args.team,
        transport=transport_from_args(args),
        kills=tuple(parse_robot_event(k, "--kill") for k in args.kill),
        restarts=tuple(parse_robot_event(r, "--restart") for r in args.restart),
        cmd_timeout_s=args.cmd_timeout,
        realtime_factor=args.realtime,
    )
    report = WorldProcess(settings, world).run()
    save_world(world, args.world_out)
    if args.report is not None:
        write_report(args.report, report)
    return 0


def run_robot(args: argparse.Namespace) -> int:
    import numpy as np

    from relloc.experiments.guler2023_team import role_of, run_seed, team_case
    from relloc.runtime.airground import RobotProcess, RobotSettings
    from relloc.sim.airground import robot_names

    case = team_case(args.case, args.duration)
    seed_seq = run_seed(args.seed, args.case, args.run)
    role = role_of(case, args.robot, seed_seq)
    faults = network_faults_from_args(args)
    faults.check_robots(tuple(robot_names(case.scenario)))  # as relloc node: a typo
    settings = RobotSettings(
        team=args.team,
        robot=args.robot,
        transport=transport_from_args(args),
        faults=faults,
        fault_seed=int(np.random.SeedSequence([args.seed, args.run]).generate_state(1)[0]),
        input_timeout_s=args.input_timeout,
    )
    RobotProcess(settings, case.scenario, role).run()
    return 0


def run_team_up(args: argparse.Namespace, team_args: dict[str, object]) -> int:
    """``relloc team up guler2023``: the runs, scored beside the in-process reproduction."""
    from relloc.experiments.guler2023_team import DEFAULT_CASE, GulerTeamSettings, run_guler_team
    from relloc.pipeline.output import fmt
    from relloc.runtime.outcomes import agreement_text

    summary = run_guler_team(
        GulerTeamSettings(
            out_dir=args.out,
            seed=args.seed,
            runs=args.runs,
            duration_s=args.duration,
            case=args.case or DEFAULT_CASE,
            **team_args,  # type: ignore[arg-type]
        )
    )
    if not args.quiet:
        d, r = summary["distributed"], summary["in_process"]
        print(
            f"guler2023 {summary['case']}: RMSE mean {fmt(d['rmse_m_mean'])} m (in-process "
            f"{fmt(r['rmse_m_mean'])} m), worst {fmt(d['rmse_m_worst'])} m (in-process "
            f"{fmt(r['rmse_m_worst'])} m); {agreement_text(summary)}"
        )
    return 0
