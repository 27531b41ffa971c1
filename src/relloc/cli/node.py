r"""``relloc node --robot ID --scenario FILE|default | --dataset DIR`` — one robot as a process.

The robot simulates the (seeded) scenario — or replays the recorded team of a dataset folder in
MRCLAM layout (:mod:`relloc.runtime.dataset`) — keeps only its own sensor slice, joins the team over
Zenoh on the given endpoints, and runs until the clock process ends the run (see
:mod:`relloc.runtime.node`). Usually started by ``relloc team up``; by hand::

    relloc team clock --team demo --roster observer,aerial1 --duration 20 \
        --listen tcp/127.0.0.1:7447
    relloc node --robot observer --scenario team.toml --team demo --connect tcp/127.0.0.1:7447

Live operation (``--realtime``, :mod:`relloc.runtime.realtime`): the node ticks on wall time,
its sensors replayed in real time through the live sensor API
(:class:`relloc.runtime.sources.LiveSource`), its teammates' odometry replayed from the same
recording (``--teammates replay``) or taken from their processes (``--teammates network``);
it prints measurement-to-estimate latency and missed deadlines::

    relloc node --realtime --robot robot1 --dataset MRCLAM_Dataset6 --duration 3

A flag that the team source (:data:`READ_BY`) or the mode (:data:`MODE_READ_BY`: the clock's
ticks or ``--realtime``) does not read is refused, not ignored.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import sys
from collections.abc import Collection
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from relloc.runtime.node import NodeParts, NodeSettings

from relloc.cli.console import plain_text


def add_network_fault_arguments(p: argparse.ArgumentParser) -> argparse._ArgumentGroup:
    """Network fault options (applied by each receiving robot, in simulated time)."""
    g = p.add_argument_group("network faults (see relloc.runtime.faults)")
    g.add_argument("--drop", type=float, default=0.0, metavar="P", help="message loss probability")
    g.add_argument("--delay", type=float, default=0.0, metavar="MS", help="delay, ms")
    g.add_argument("--jitter", type=float, default=0.0, metavar="MS", help="delay std, ms")
    g.add_argument("--duplicate", type=float, default=0.0, metavar="P", help="duplicate prob.")
    g.add_argument("--reorder", type=float, default=0.0, metavar="P", help="reorder prob.")
    g.add_argument(
        "--partition",
        action="append",
        default=[],
        metavar="A,B@T1-T2",
        help="robots A,B cut off from the rest of the team from T1 to T2 s (repeatable)",
    )
    g.add_argument(
        "--stall",
        action="append",
        default=[],
        metavar="SENDER,RECEIVER@T:WALL_S",
        help="from T s on, what RECEIVER gets from SENDER is held WALL_S wall seconds, then "
        "delivered in order (nothing lost: still a perfect network; repeatable)",
    )
    return g


def network_faults_from_args(args: argparse.Namespace, **robot_events: object):  # type: ignore[no-untyped-def]
    """:class:`FaultSettings` from the flags above (plus kills/restarts from ``team up``)."""
    from relloc.runtime.faults import FaultSettings, parse_partition, parse_stall

    return FaultSettings(
        drop=args.drop,
        delay_ms=args.delay,
        jitter_ms=args.jitter,
        duplicate=args.duplicate,
        reorder=args.reorder,
        partitions=tuple(parse_partition(p) for p in args.partition),
        stalls=tuple(parse_stall(st) for st in args.stall),
        **robot_events,  # type: ignore[arg-type]
    )


def add_transport_arguments(p: argparse.ArgumentParser) -> None:
    """Zenoh endpoint options shared by ``node`` and ``team clock``."""
    g = p.add_argument_group("Zenoh transport")
    g.add_argument("--team", default="team", help="team id: the key-expression prefix")
    g.add_argument("--connect", action="append", default=[], metavar="ENDPOINT")
    g.add_argument("--listen", action="append", default=[], metavar="ENDPOINT")
    g.add_argument("--mode", choices=("peer", "client", "router"), default="peer")
    g.add_argument(
        "--zenoh-config",
        default=None,
        metavar="FILE",
        help="Zenoh JSON5 config loaded first (TLS, access control); flags override it",
    )
    g.add_argument(
        "--multicast-scouting",
        action="store_true",
        help="also discover peers by UDP multicast (off: only the explicit endpoints)",
    )


def transport_from_args(args: argparse.Namespace):  # type: ignore[no-untyped-def]
    from pathlib import Path

    from relloc.runtime.transport import TransportSettings

    return TransportSettings(
        mode=args.mode,
        listen=tuple(args.listen),
        connect=tuple(args.connect),
        multicast_scouting=args.multicast_scouting,
        config_file=Path(args.zenoh_config) if args.zenoh_config else None,
    )


def add_parser(subparsers: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    p = subparsers.add_parser(
        "node",
        help="run one robot as its own process over Zenoh",
        description=plain_text(__doc__),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("--robot", required=True, help="this robot's name in the scenario")
    source = p.add_mutually_exclusive_group()
    source.add_argument(
        "--scenario", default="default", help="scenario TOML file, or 'default' (built-in team)"
    )
    source.add_argument(
        "--dataset", default=None, metavar="DIR", help="replay the team of an MRCLAM-layout folder"
    )
    p.add_argument("--seed", type=int, default=0, help="simulation seed (same for the team)")
    p.add_argument(
        "--run",
        type=int,
        default=None,
        help="Monte-Carlo run of a reproduction's team (desilva2015, sharma2013; default 0)",
    )
    p.add_argument(
        "--case",
        default=None,
        help="the team EIF's case: sharma2013's (default two_landmarks), or MODE/ANCHORS of "
        "mrclam-cl with --estimator cooperative (default range_bearing/2_landmarks)",
    )
    p.add_argument(
        "--estimator",
        choices=("track", "cooperative"),
        default=None,
        help="with --dataset: seed 000's track manager (default), or seed 001's team EIF "
        "(mrclam-cl)",
    )
    add_sharing_policy_argument(p)
    add_sensing_argument(p)
    p.add_argument(
        "--fit", default=None, metavar="FILE", help="--estimator cooperative: fitted models"
    )
    p.add_argument(
        "--duration",
        type=float,
        default=None,
        help="simulated seconds of a reproduction's team (default: the paper's); with "
        "--realtime, wall seconds to run (default: the whole recording)",
    )
    p.add_argument(
        "--filter", default=None, help="seed 000's track manager: plkf (default) | tekf | bcplkf"
    )
    p.add_argument(
        "--init",
        default=None,
        help="seed 000's track manager: track initialisation policy (default measurement)",
    )
    p.add_argument(
        "--gate",
        type=float,
        default=None,
        metavar="P",
        help="the track manager's NIS gate: reject a measurement beyond the χ²(3) quantile P "
        "(default off)",
    )
    p.add_argument(
        "--realtime",
        action="store_true",
        help="run on wall time (the dataset/scenario replayed in real time through the live "
        "sensor API) instead of the clock process' ticks; reports latency and deadlines",
    )
    p.add_argument(
        "--tick", type=float, default=None, help="--realtime: wall seconds per tick (0.1)"
    )
    p.add_argument(
        "--teammates",
        choices=("replay", "network"),
        default=None,
        help="--realtime: teammates' odometry replayed from the recording (default), or from "
        "their processes on the network",
    )
    p.add_argument(
        "--only-needed-streams",
        action="store_true",
        help="subscribe to teammates' data only if this robot uses it (it makes readings, "
        "talks or shares readings): large teams of robots that only move",
    )
    p.add_argument(
        "--paced",
        type=float,
        default=None,
        metavar="FACTOR",
        help="the clock paces its ticks at FACTOR x real time (team up --realtime): report "
        "measurement-to-estimate latency and missed deadlines (not with --realtime)",
    )
    p.add_argument("--eqm-period", type=float, default=1.0, help="equivalent-measurement period, s")
    p.add_argument("--max-bytes", type=int, default=65_536, help="message size limit")
    p.add_argument(
        "--clock-timeout",
        type=float,
        default=None,
        help="exit after this long without a tick, s (60; not with --realtime)",
    )
    add_transport_arguments(p)
    add_network_fault_arguments(p)
    p.set_defaults(func=run, team_process=True)


def run(args: argparse.Namespace) -> int:
    from relloc.errors import RellocError
    from relloc.runtime.launcher import DEFAULT_FILTER
    from relloc.runtime.node import RobotNode

    check_arguments(args)
    for name, value in {**NODE_DEFAULTS, "filter": DEFAULT_FILTER}.items():
        if getattr(args, name) is None:
            setattr(args, name, value)
    parts = node_parts(args)
    if args.realtime:
        return run_realtime(args, parts)
    settings = node_settings(args, parts)
    node = RobotNode(settings, parts.source, parts.driver)
    counters = node.run()
    json.dump({"robot": args.robot, "counters": counters}, sys.stdout, sort_keys=True)
    sys.stdout.write("\n")
    if not node.reached_end:
        how = "left" if counters.get("exit.clock_left") else "was silent"
        raise RellocError(
            f"robot {args.robot!r} stopped before the run's end: the clock {how} "
            f"(after {counters.get('ticks', 0)} ticks; --clock-timeout {args.clock_timeout:g} s)"
        )
    return 0


def check_arguments(args: argparse.Namespace) -> None:
    """ConfigError naming the flag, before any work, for a value out of its range or a flag
    that the node's team source or mode does not read (:func:`refuse_desilva_only`,
    :func:`refuse_node_unread`)."""
    from relloc.errors import ConfigError

    if args.run is not None and args.run < 0:
        raise ConfigError(f"--run: must be ≥ 0, got {args.run}")
    for flag, value in (("--duration", args.duration), ("--tick", args.tick)):
        if value is not None and not 0 < value < math.inf:
            raise ConfigError(f"{flag}: must be a finite number > 0, got {value}")
    refuse_desilva_only(args)
    refuse_node_unread(args)


def node_settings(args: argparse.Namespace, parts: NodeParts) -> NodeSettings:
    """The node's settings from its arguments and parts."""
    from relloc.runtime.node import NodeSettings

    faults = network_faults_from_args(args)
    faults.check_robots(parts.roster)  # as team up does: a partition of no robot is a typo
    return NodeSettings(
        team=args.team,
        robot=args.robot,
        roster=parts.roster,
        transport=transport_from_args(args),
        faults=faults,
        fault_seed=args.seed,
        eqm_period_s=args.eqm_period,
        max_bytes=args.max_bytes,
        clock_timeout_s=args.clock_timeout,
        talkers=parts.talkers,
        share_rows=parts.share_rows,
        only_needed_streams=args.only_needed_streams,
        paced_factor=args.paced,
    )


def run_realtime(args: argparse.Namespace, parts: NodeParts) -> int:
    """``--realtime``: the robot on wall time, its recorded sensors replayed through the live
    sensor API (:mod:`relloc.runtime.realtime`); prints its counters and timing as JSON."""
    from relloc.errors import ConfigError
    from relloc.runtime.realtime import WallClockNode, WallClockSettings
    from relloc.runtime.sources import LiveSource, RecordingSource, ReplayFeeder

    recording = parts.recording
    if recording is None:
        raise ConfigError("--realtime: this team source has no recording to replay")
    t0, t1 = recording.span
    live = LiveSource(args.robot, odometry_sigma=parts.source.odometry_sigma.tolist())
    teammates = (
        {r: RecordingSource(recording, r, all_readings=True) for r in parts.roster}
        if args.teammates == "replay"
        else {}
    )
    teammates.pop(args.robot, None)
    wall = WallClockSettings(
        duration_s=min(args.duration or (t1 - t0), t1 - t0), t0=t0, tick_s=args.tick
    )
    node = WallClockNode(
        node_settings(args, parts),
        live,
        parts.driver,
        wall,
        feeder=ReplayFeeder(recording, args.robot, live, t0=t0),
        teammates=teammates,
    )
    counters = node.run()
    json.dump({"robot": args.robot, "counters": counters}, sys.stdout, sort_keys=True)
    sys.stdout.write("\n")
    return 0


def node_parts(args: argparse.Namespace) -> NodeParts:
    """The robot's sensor source and estimator for the team source the arguments name."""
    from relloc.core.checks import probability
    from relloc.errors import ConfigError
    from relloc.experiments.desilva2015 import sensing_robots
    from relloc.experiments.team_sources import named_node_parts, team_names

    cooperative = args.dataset is not None and args.estimator == "cooperative"
    if args.gate is not None:  # read by the track manager only (READ_BY)
        probability(args.gate, "--gate")
    if args.dataset is None and args.scenario in team_names():
        return named_node_parts(
            args.scenario,
            args.robot,
            args.seed,
            args.run,
            args.duration,
            args.case or "two_landmarks",
            args.sharing_policy or "all",
            sensing_robots(args.sensing),
        )
    if cooperative:
        from pathlib import Path

        from relloc.experiments.mrclam_team import DEFAULT_CASE, cooperative_node_parts

        if args.fit is None:
            raise ConfigError("--estimator cooperative: --fit FILE (written by relloc team up)")
        return cooperative_node_parts(
            args.dataset,
            args.robot,
            args.seed,
            Path(args.fit),
            args.duration,
            args.case or DEFAULT_CASE,
        )
    return track_manager_parts(args)  # --case, which it has none of, refused before


COOPERATIVE = "--estimator cooperative"
"""The team EIF of a dataset folder (a target kind of :data:`READ_BY`, here and in
``relloc team up``)."""
TRACKS = "--estimator track"
"""Seed 000's track managers of a scenario, ``default`` or a dataset folder."""
READ_BY: dict[str, tuple[str, ...]] = {
    "filter": (TRACKS,),
    "init": (TRACKS,),
    "gate": (TRACKS,),
    "fit": (COOPERATIVE,),
    "run": ("desilva2015", "sharma2013"),
    "case": ("sharma2013", COOPERATIVE),
    "duration": ("desilva2015", "sharma2013", COOPERATIVE, "--realtime"),
}
"""The kinds of team source (:func:`target_kind`) that read each of these flags (and, for
``--duration``, every source with ``--realtime``); another is refused, never ignored."""
ON_TICKS = "a node on the clock's ticks"
"""A node without ``--realtime`` (a target of :data:`MODE_READ_BY`)."""
MODE_READ_BY: dict[str, tuple[str, ...]] = {
    "tick": ("--realtime",),
    "teammates": ("--realtime",),
    "clock_timeout": (ON_TICKS,),
    "paced": (ON_TICKS,),
}
"""The flags read only with ``--realtime`` (its wall-clock ticks) or only without it (the
clock process' ticks)."""
NODE_DEFAULTS: dict[str, object] = {
    "run": 0,
    "estimator": "track",
    "init": "measurement",
    "tick": 0.1,
    "teammates": "replay",
    "paced": 0.0,
    "clock_timeout": 60.0,
}
"""The values of the flags above that were not given (after :func:`refuse_node_unread`);
``--filter``'s is :data:`relloc.runtime.launcher.DEFAULT_FILTER`, the filter a team's launcher
does not pass."""


def target_kind(name: str | None, estimator: str | None, reproductions: Collection[str]) -> str:
    """The kind of a team target (:data:`READ_BY` here and in ``relloc team up``): desilva2015
    for both of its teams, a reproduction of ``reproductions`` by its ``name``, a dataset
    folder's team EIF with ``--estimator cooperative``, else seed 000's track managers (of a
    scenario, ``default`` or a dataset folder). ``name`` is None for ``relloc node --dataset``,
    which names no reproduction."""
    from relloc.experiments.team_sources import KIDNAPPED

    if name in KIDNAPPED:
        return "desilva2015"
    if name is not None and name in reproductions:
        return name
    return COOPERATIVE if estimator == "cooperative" else TRACKS


def refuse_node_unread(args: argparse.Namespace) -> None:
    """ConfigError naming a flag that the node's team source (:data:`READ_BY`) or mode
    (:data:`MODE_READ_BY`) does not read, before any work: such a flag was once ignored."""
    from relloc.core.checks import refuse_unread
    from relloc.errors import ConfigError

    if args.estimator is not None and args.dataset is None:
        raise ConfigError(
            f"--estimator: {args.scenario} does not read it; read with --dataset only (a "
            "scenario runs seed 000's track manager, a reproduction its own estimators)"
        )
    from relloc.experiments.team_sources import team_names

    kind = target_kind(
        args.scenario if args.dataset is None else None, args.estimator, team_names()
    )
    given = [name for name in READ_BY if getattr(args, name) is not None]
    if args.realtime:  # every source on wall time reads --duration (the seconds to run)
        given = [name for name in given if name != "duration"]
    refuse_unread(kind, given, READ_BY, label=args.dataset or args.scenario)
    mode = "--realtime" if args.realtime else ON_TICKS
    given = [name for name in MODE_READ_BY if getattr(args, name) is not None]
    refuse_unread(mode, given, MODE_READ_BY)


def track_manager_parts(args: argparse.Namespace) -> NodeParts:
    """Seed 000: the robot's own TrackManager (its relative filters of every teammate) on the
    10 Hz recording grid, on a scenario or a recorded team."""
    import numpy as np

    from relloc.errors import ConfigError
    from relloc.estimators.initialisation import InitPolicy
    from relloc.estimators.track_manager import default_tracker, track_manager_of
    from relloc.pipeline.team_report import RECORD_RATE_HZ
    from relloc.runtime.estimation import WindowDriver, grid_record_times
    from relloc.runtime.node import NodeParts
    from relloc.runtime.scenario import load_team
    from relloc.runtime.sources import RecordingSource

    recording = load_team(args.dataset or args.scenario, args.seed).recording
    if args.robot not in recording.robots:
        raise ConfigError(f"--robot: {args.robot!r} is not in the scenario {recording.robots}")
    index = recording.index(args.robot)
    manager = track_manager_of(
        recording,
        args.robot,
        dataclasses.replace(
            default_tracker(),
            filter=args.filter,
            init=InitPolicy(name=args.init),
            gate_probability=args.gate,
        ),
        rng=np.random.default_rng(np.random.SeedSequence([args.seed, index])),
    )
    driver = WindowDriver(
        manager,
        recording.robots,
        args.robot,
        record_times=grid_record_times(RECORD_RATE_HZ, *recording.span),
    )
    return NodeParts(
        recording.robots, RecordingSource(recording, args.robot), driver, recording=recording
    )


def add_sharing_policy_argument(p: argparse.ArgumentParser) -> None:
    """``--sharing-policy NAME`` of a desilva2015 team's leaders."""
    p.add_argument(
        "--sharing-policy",
        default=None,
        metavar="NAME",
        help="desilva2015 teams: the leaders' sharing policy, 'all' (seed 002's, default) or "
        "'mutual-confirmed' (only confirmed filters broadcast, only mutual messages fused)",
    )


def add_sensing_argument(p: argparse.ArgumentParser) -> None:
    """``--sensing ROBOTS`` of a desilva2015 team: the simulated robots that sense and run the
    fusers (parsed by :func:`relloc.experiments.desilva2015.sensing_robots`)."""
    p.add_argument(
        "--sensing",
        default=None,
        metavar="ROBOTS",
        help="desilva2015 teams: the simulated robots that sense and run Gaussian-sum fusers, "
        "'all' or names such as L1,P2 (default: the paper's leaders L1,L2)",
    )


def refuse_desilva_only(args: argparse.Namespace) -> None:
    """ConfigError when a flag of desilva2015's simulated teams only (``--sharing-policy``,
    ``--sensing``) is given to another team; a bad value is refused where it is parsed."""
    from relloc.errors import ConfigError
    from relloc.experiments.team_sources import KIDNAPPED

    if getattr(args, "dataset", None) is None and args.scenario in KIDNAPPED:
        return
    for flag, value, what in (
        ("--sharing-policy", args.sharing_policy, "share Gaussian-sum beliefs"),
        ("--sensing", args.sensing, "choose their sensing robots"),
    ):
        if value is not None:
            raise ConfigError(f"{flag}: only desilva2015 teams ({', '.join(KIDNAPPED)}) {what}")
