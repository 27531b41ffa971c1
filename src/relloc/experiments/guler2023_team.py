"""``relloc team up guler2023 --out DIR``: seed 003's air-ground team as robot processes, in
closed loop, scored beside the in-process reproduction on the same seeds.

Every run ``i`` of ``--runs N`` launches a world process and one process per robot — leader
``R_0``, followers ``R_1 … R_N``, drones ``D_1 … D_M`` — over Zenoh
(:mod:`relloc.runtime.airground`; the launcher and collector is
:class:`relloc.runtime.launcher.TeamLauncher`). The drones schedule themselves over the midpoints
and broadcast their detections; each follower runs its switching EKF and formation controller and
sends its command back to the world process every tick. The case (``--case``, default
``two_drones``: the paper's closed-loop case, four followers holding a hexagon, two drones) and
its seeds are those of ``relloc reproduce guler2023 --seed S``: run ``i`` of a case is run ``i``
of that case's Monte Carlo (:func:`run_seed`), shortened to ``--duration`` seconds. The
distributed run is scored with the reproduction's own reduction
(:func:`relloc.experiments.guler2023.reduce_run`, :func:`~relloc.experiments.guler2023.summarise`)
on the truth the world process recorded; the in-process reference is
:func:`~relloc.experiments.guler2023.simulate_case` on the same seed.

Tolerance. There is no command delay (a follower's command acts on the tick it was computed for,
as in-process) and on a perfect network every process runs the in-process functions on the same
float64 numbers, so the followers' beliefs must agree within :data:`AGREEMENT_TOLERANCE` and the
headline figures within :data:`FIGURE_TOLERANCE` (both are expected to be exactly 0). With faults
what was lost is the point: the differences are reported, not held to the tolerance, and
``fault_outcomes`` gives the accuracy before / during / after each fault
(:mod:`relloc.runtime.outcomes`). The filters' NIS sums per block kind (``mean_nis_per_dof``) and
refusal examples stay in the follower processes and are not compared.

``summary.json``: ``case``, ``distributed`` and ``in_process`` (the reproduction's scenario block:
``rmse_m``, ``rmse_m_max_over_runs``, ``rmse_m_worst``, ``rmse_m_mean``, ``heading_rmse_rad``,
``formation_rmse_m``, ``formation_rmse_m_worst``, ``mode_fraction``, ``anees_position``,
``nees_run_average``, ``gate_rejections``, ``triangle_refusals``), ``difference`` (largest
|distributed − in-process| of every headline number), ``tolerance``, ``agreement``; per run
``agreement`` (largest |Δ| of a belief mean / covariance entry), ``messages`` (per robot: sent,
received on the wire and delivered per kind, rejected by reason, duplicates, late readings,
input timeouts, what the fault emulator did; the world's commands received, missing and
rejected by reason), ``fault_outcomes``, ``world`` (its report), ``wall_s``.
"""

from __future__ import annotations

import dataclasses
import json
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from relloc.calibration.uwb import fit_uwb_noise
from relloc.control.formation import FormationController
from relloc.core.checks import count
from relloc.core.gaussian import Gaussian
from relloc.datasets.paths import default_uwb_csv
from relloc.datasets.uwb import load_uwb_csv
from relloc.errors import ConfigError
from relloc.estimators.switching_ekf import BLOCKS, NAME
from relloc.experiments.guler2023 import (
    Case,
    FilterFactory,
    RunSummary,
    build_cases,
    follower_evaluations,
    reduce_run,
    simulate_case,
    summarise,
    whole_recording,
)
from relloc.pipeline.montecarlo import spawn_seeds
from relloc.pipeline.output import fmt, markdown_table, prepare_out_dir, write_report, write_summary
from relloc.runtime.airground import (
    DroneRole,
    FollowerRole,
    LeaderRole,
    Role,
    load_world,
)
from relloc.runtime.faults import FaultSettings
from relloc.runtime.launcher import Collected, ProcessTeam, TeamLauncher, transport_arguments
from relloc.runtime.outcomes import (
    difference_cell,
    figure_agreement,
    figure_difference,
    outcomes_of,
)
from relloc.runtime.summary import agreement, assemble_estimates
from relloc.sim.airground import AirGroundRun, AirGroundWorld, FollowerAgent, robot_names
from relloc.sim.scenario import MAX_SIMULATED_STEPS

CASES = ("one_drone", "two_drones", "formation")
"""The reproduction's paper scenarios, in the order its seed words are given out."""
DEFAULT_CASE = "two_drones"
AGREEMENT_TOLERANCE = 1e-9
"""Largest |difference| of a follower's belief entry from the in-process one on a perfect
network (the same functions on the same numbers: expected 0)."""
FIGURE_TOLERANCE = 1e-9
"""Largest |difference| of a headline figure on a perfect network (expected 0)."""
HEADLINE = (
    "rmse_m",
    "rmse_m_max_over_runs",
    "rmse_m_worst",
    "rmse_m_mean",
    "heading_rmse_rad",
    "formation_rmse_m",
    "formation_rmse_m_worst",
    "mode_fraction",
    "anees_position",
    "nees_run_average",
    "gate_rejections",
    "triangle_refusals",
)


def team_case(name: str, duration_s: float | None) -> Case:
    """Case ``name`` of the reproduction (UWB noise fitted on the TIERS recording as there),
    shortened to ``duration_s`` seconds."""
    if name not in CASES:
        raise ConfigError(f"--case: {name!r} is not one of {', '.join(CASES)}")
    rec = load_uwb_csv(default_uwb_csv())
    fit = fit_uwb_noise(rec, whole_recording(rec))
    case = build_cases(fit.model)[name]
    if duration_s is not None:
        if not duration_s >= case.scenario.dt:
            raise ConfigError(f"--duration: {duration_s} s is shorter than one tick")
        ticks = duration_s / case.scenario.dt * len(robot_names(case.scenario))
        if not ticks <= MAX_SIMULATED_STEPS:  # the world keeps every tick's state
            raise ConfigError(
                f"--duration: {duration_s:g} s is more than {MAX_SIMULATED_STEPS} robot-ticks"
            )
        case = case.with_scenario(duration=float(duration_s))
    return case


def run_seed(seed: int, case: str, run: int) -> np.random.SeedSequence:
    """Run ``run`` of case ``case`` of ``relloc reproduce guler2023 --seed SEED`` (the case's
    seed word, then the Monte-Carlo task's child sequence)."""
    if seed < 0 or run < 0:
        raise ConfigError(f"--seed {seed} / --run {run}: must be ≥ 0")
    word = int(np.random.SeedSequence(seed).generate_state(9)[CASES.index(case)])
    return spawn_seeds(word, run + 1)[run]


def controller_of(case: Case) -> FormationController | None:
    """The followers' controller of the case (None: externally commanded)."""
    sc = case.scenario
    if sc.control != "formation":
        return None
    return FormationController(offsets=sc.offsets, frame=sc.offset_frame, settings=case.formation)


def start_world(case: Case, seed_seq: np.random.SeedSequence) -> AirGroundWorld:
    """The world of one run at t = 0 (its first draws made)."""
    return AirGroundWorld.start(case.scenario, np.random.default_rng(seed_seq))


def role_of(case: Case, robot: str, seed_seq: np.random.SeedSequence) -> Role:
    """Robot ``robot``'s part in the team: the leader, a follower (its filter and controller,
    its initial guess that of the run) or a drone."""
    sc = case.scenario
    names = robot_names(sc)
    if robot not in names:
        raise ConfigError(f"--robot: {robot!r} is not in the team {', '.join(names)}")
    index = names.index(robot)
    if index == 0:
        return LeaderRole(sc)
    if index > sc.n_followers:
        return DroneRole(sc, index - sc.n_followers - 1)
    factory = FilterFactory(case)
    controller = controller_of(case)

    def make_agent(prior: Gaussian) -> FollowerAgent:
        return FollowerAgent(sc, index, factory(names, robot, prior), controller)

    prior = start_world(case, seed_seq).priors[robot]
    return FollowerRole(sc, index, make_agent, prior)


@dataclass(frozen=True, kw_only=True)
class GulerTeamSettings(ProcessTeam):
    """One ``team up guler2023`` invocation."""

    out_dir: Path
    seed: int = 0
    runs: int = 1
    duration_s: float | None = None
    case: str = DEFAULT_CASE

    def __post_init__(self) -> None:
        super().__post_init__()
        count(self.runs, "--runs")
        count(self.seed, "--seed", low=0)
        if self.case not in CASES:
            raise ConfigError(f"--case: {self.case!r} is not one of {', '.join(CASES)}")
        if self.faults.stalls:
            raise ConfigError("--stall: the air-ground team's robots do not emulate link stalls")


class AirGroundLauncher(TeamLauncher):
    """The team launcher and collector with the air-ground team's children: the world process
    in the clock's place (it announces kills and restarts the same way) and ``relloc airground
    robot`` for every robot."""

    def __init__(self, s: GulerTeamSettings, run: int, out: Path, case: Case) -> None:
        sc = case.scenario
        self.team = s
        self.run_index = run
        self.world_file = out / "world.npz"
        settings = s.launch(scenario="default", out_dir=out, seed=s.seed, preload=(), node_args=())
        settings = dataclasses.replace(settings, tick_s=sc.dt, preload=(__name__,))
        super().__init__(settings, robot_names(sc), sc.duration)

    def _common(self, member: str) -> list[str]:
        """The run's and the transport's arguments of ``member`` (the world speaks as the
        launcher identity, as the clock does: only it may publish under ``clock/``)."""
        s = self.team
        args = ["--case", s.case, "--seed", str(s.seed), "--run", str(self.run_index)]
        if s.duration_s is not None:
            args += ["--duration", repr(s.duration_s)]
        return [*args, "--team", s.team, *transport_arguments(self.endpoint, self.secure, member)]

    def world_argv(self) -> list[str]:
        """``relloc airground world ...``."""
        f = self.team.faults
        argv = ["airground", "world", *self._common("launcher")]
        argv += ["--world-out", str(self.world_file)]
        argv += ["--report", str(self.s.out_dir / "world.json")]
        argv += ["--realtime", repr(self.team.realtime_factor)]
        for e in f.kills:
            argv += ["--kill", e.arg]
        for e in f.restarts:
            argv += ["--restart", e.arg]
        return argv

    def robot_argv(self, robot: str) -> list[str]:
        """``relloc airground robot --robot ROBOT ...`` with the network faults."""
        f = self.team.faults
        argv = ["airground", "robot", "--robot", robot, *self._common(robot)]
        argv += ["--drop", repr(f.drop), "--delay", repr(f.delay_ms), "--jitter", repr(f.jitter_ms)]
        argv += ["--duplicate", repr(f.duplicate), "--reorder", repr(f.reorder)]
        for p in f.partitions:
            argv += ["--partition", p.arg]
        return argv

    def _spawn(self, name: str, argv: list[str]) -> Any:
        """The base class' clock and node commands replaced by the air-ground ones."""
        return super()._spawn(name, self.world_argv() if name == "clock" else self.robot_argv(name))


def follower_counts(collected: Collected, followers: Sequence[str]) -> dict[str, int]:
    """The followers' filter counters (``ekf.*`` of their last reports, every process
    incarnation summed), as the in-process estimates carry them."""
    out: dict[str, int] = {}
    for robot in followers:
        for life in collected.stats.get(robot, []):
            for key, value in life.items():
                if key.startswith("ekf."):
                    out[key[4:]] = out.get(key[4:], 0) + value
    return out


def distributed_run(
    s: GulerTeamSettings, case: Case, run: int, out: Path
) -> tuple[AirGroundRun, Collected, dict[str, Any]]:
    """Run ``run``'s team; the run as the world recorded it with the collected estimates."""
    launcher = AirGroundLauncher(s, run, out, case)
    collected = launcher.run()
    sc = case.scenario
    names = robot_names(sc)
    estimates = assemble_estimates(collected, names, NAME)
    estimates = dataclasses.replace(
        estimates, counts=follower_counts(collected, names[1 : sc.n_followers + 1])
    )
    recording, formation_error = load_world(launcher.world_file, sc)
    world_report = json.loads((out / "world.json").read_text())
    priors = start_world(case, run_seed(s.seed, s.case, run)).priors
    return (
        AirGroundRun(
            recording=recording,
            estimates=estimates,
            priors=priors,
            formation_error=formation_error,
        ),
        collected,
        world_report,
    )


def message_counts(
    collected: Collected, roster: Sequence[str], world: Mapping[str, Any]
) -> dict[str, Any]:
    """Per robot: sent, received (on the wire / delivered) per kind, rejected by reason, …;
    and the world process' ``cmd``/``sense`` traffic."""
    robots: dict[str, Any] = {}
    for robot in roster:
        c: dict[str, int] = {}
        for life in collected.stats.get(robot, []):
            for key, value in life.items():
                c[key] = c.get(key, 0) + value

        def group(prefix: str, counts: Mapping[str, int] = c) -> dict[str, int]:
            return {k[len(prefix) :]: v for k, v in counts.items() if k.startswith(prefix)}

        robots[robot] = {
            "processes": len(collected.stats.get(robot, [])),
            "sent": group("sent."),
            "received_wire": group("wire."),
            "received_delivered": group("delivered."),
            "rejected": c.get("rejected", 0),
            "rejected_by_reason": group("rejected."),
            "duplicates_dropped": c.get("duplicates", 0),
            "late_rows": c.get("late_rows", 0),
            "input_timeouts": c.get("input_timeouts", 0),
            "inputs_missing_at_end": c.get("inputs_missing_at_end", 0),
            "faults": group("fault."),
            "estimates": c.get("estimates", 0),
            "ticks": c.get("ticks", 0),
        }
    return {
        "robots": robots,
        "world": {
            "sent": world["sent"],
            "cmd_received": world["cmd_received"],
            "cmd_missing": world["cmd_missing"],
            "cmd_absent": world["cmd_absent"],
            "rejected": world["rejected"],
            "rejected_by_reason": world["rejected_by_reason"],
        },
        "collector": {
            "rejected": collected.rejected,
            "rejected_by_reason": dict(collected.rejected_by_reason),
        },
    }


def fault_windows(faults: FaultSettings, end_s: float) -> list[tuple[str, float, float]]:
    """``(name, T1, T2)`` of every fault with a time window (a partition; a kill to its
    restart or the end of the run) and, for loss/delay/duplicates/reordering, the whole run."""
    out = [
        (f"partition {','.join(p.side)}@{p.start_s:g}-{p.end_s:g}", p.start_s, p.end_s)
        for p in faults.partitions
    ]
    for kill in faults.kills:
        later = [r.at_s for r in faults.restarts if r.robot == kill.robot and r.at_s > kill.at_s]
        back = min(later) if later else end_s
        out.append((f"kill {kill.robot}@{kill.at_s:g}, back @{back:g}", kill.at_s, back))
    if faults.drop or faults.delay_ms or faults.jitter_ms or faults.duplicate or faults.reorder:
        out.append(
            (
                f"network drop={faults.drop:g} delay={faults.delay_ms:g}ms "
                f"jitter={faults.jitter_ms:g}ms duplicate={faults.duplicate:g} "
                f"reorder={faults.reorder:g}",
                0.0,
                end_s,
            )
        )
    return out


def _tick_times(run: AirGroundRun) -> np.ndarray:
    """The run's tick times (those of its truth)."""
    truth = run.recording.truth
    assert truth is not None  # a simulation always has it
    return truth[0].t


def _window_rmse(run: AirGroundRun, t1: float, t2: float) -> dict[str, float | None]:
    """Position RMSE of the followers' estimates of ``r`` and the true formation RMSE in
    ``[t1, t2)`` (over the followers and the ticks there; None: no sample)."""
    sq = [
        np.sum(e.error[(e.t >= t1 - 1e-9) & (e.t < t2 - 1e-9), :2] ** 2, axis=1)
        for e in follower_evaluations(run)
    ]
    est = np.concatenate(sq) if sq else np.zeros(0)
    t = _tick_times(run)[1 : run.formation_error.shape[0] + 1]
    inside = (t >= t1 - 1e-9) & (t < t2 - 1e-9)
    form = np.sum(run.formation_error[inside] ** 2, axis=2).reshape(-1)
    return {
        "estimate_rmse_m": float(np.sqrt(est.mean())) if est.size else None,
        "formation_rmse_m": float(np.sqrt(form.mean())) if form.size else None,
    }


def fault_accuracy(
    faults: FaultSettings, got: AirGroundRun, ref: AirGroundRun
) -> list[dict[str, Any]]:
    """Per fault: the followers' estimation RMSE and the true formation RMSE before, during and
    after its window, distributed and in-process (fault-free) on the same seed."""
    end = float(_tick_times(got)[-1]) + 1e-6
    out = []
    for name, t1, t2 in fault_windows(faults, end):
        spans = {"before": (0.0, t1), "during": (t1, t2), "after": (t2, end)}
        out.append(
            {
                "fault": name,
                "window_s": [t1, t2],
                **{
                    side: {
                        "distributed": _window_rmse(got, a, b),
                        "in_process": _window_rmse(ref, a, b),
                    }
                    for side, (a, b) in spans.items()
                },
            }
        )
    return out


def _reduce(run: AirGroundRun) -> RunSummary:
    """The reproduction's reduction of a run whose filters' NIS sums are not at hand."""
    return reduce_run(
        run, nis_sums=dict.fromkeys(BLOCKS, float("nan")), refusal_examples=(), keep_traces=False
    )


def run_guler_team(s: GulerTeamSettings) -> dict[str, Any]:
    """Every run's team beside the in-process run; ``summary.json`` and ``report.md``."""
    out = prepare_out_dir(s.out_dir)
    case = team_case(s.case, s.duration_s)
    distributed: list[RunSummary] = []
    in_process: list[RunSummary] = []
    runs: list[dict[str, Any]] = []
    start = time.monotonic()
    for i in range(s.runs):
        got, collected, world = distributed_run(s, case, i, out / f"run{i}")
        ref, _ = simulate_case(case, np.random.default_rng(run_seed(s.seed, s.case, i)))
        distributed.append(_reduce(got))
        in_process.append(_reduce(ref))
        agree = agreement(got.estimates, ref.estimates)
        runs.append(
            {
                "run": i,
                "ticks": int(got.formation_error.shape[0]),
                "agreement": {k: agree[k] for k in ("max_abs_mean_diff", "max_abs_cov_diff")},
                "fault_accuracy": fault_accuracy(s.faults, got, ref),
                "fault_outcomes": outcomes_of(s.faults, got.estimates, got.recording),
                "messages": message_counts(collected, got.recording.robots, world),
                "world": {
                    k: world[k]
                    for k in ("ticks", "wall_s", "startup_wall_s", "events", "max_tick_lag_s")
                },
                "exit_codes": collected.exit_codes,
                "wall_s": collected.wall_s,
            }
        )
    summary = _summary(s, case, summarise(distributed), summarise(in_process), runs)
    summary["wall_s"] = time.monotonic() - start
    write_summary(out, summary)
    write_report(out, report_markdown(summary))
    return summary


def _headline(block: Mapping[str, Any]) -> dict[str, Any]:
    return {k: block[k] for k in HEADLINE}


def largest_difference(a: Any, b: Any) -> float | None:
    """Largest |a − b| over the numbers of two equally shaped JSON-like values (None: nothing
    to compare, e.g. a verdict without enough runs); a differing string or shape, or a figure
    undefined (NaN) in one only, is ∞ (the largest whatever the order it is met in)."""
    if isinstance(a, Mapping) and isinstance(b, Mapping):
        if set(a) != set(b):
            return float("inf")
        parts = [largest_difference(a[k], b[k]) for k in a]
        found = [p for p in parts if p is not None]
        return max(found) if found else None
    if isinstance(a, bool) or isinstance(b, bool) or isinstance(a, str) or a is None:
        return None if a == b else float("inf")
    if isinstance(a, (int, float)) and isinstance(b, (int, float)):
        d = figure_difference(a, b)  # None: undefined in both; NaN: in one only, they differ
        return None if d is None else float("inf") if np.isnan(d) else abs(d)
    if isinstance(a, (list, tuple)) and isinstance(b, (list, tuple)):
        if len(a) != len(b):
            return float("inf")
        found = [
            d for x, y in zip(a, b, strict=True) if (d := largest_difference(x, y)) is not None
        ]
        return max(found) if found else None
    return float("inf")


def _summary(
    s: GulerTeamSettings,
    case: Case,
    ours: dict[str, Any],
    ref: dict[str, Any],
    runs: list[dict[str, Any]],
) -> dict[str, Any]:
    sc = case.scenario
    diff = {k: largest_difference(ours[k], ref[k]) for k in HEADLINE}
    worst = max(max(r["agreement"].values()) for r in runs)
    perfect = not s.faults.network_faulty and not s.faults.kills
    return {
        "experiment": "guler2023",
        "case": s.case,
        "seed": s.seed,
        "runs": s.runs,
        "duration_s": sc.duration,
        "tick_s": sc.dt,
        "processes_per_run": {
            "world": 1,
            "leader": 1,
            "followers": sc.n_followers,
            "drones": sc.n_drones,
        },
        "faults": s.faults.to_dict(),
        "secure": s.secure,
        "distributed": _headline(ours),
        "in_process": _headline(ref),
        "difference": diff,
        **figure_agreement(
            worst,
            perfect,
            diff,
            belief_tolerance=AGREEMENT_TOLERANCE,
            figure_tolerance=FIGURE_TOLERANCE,
        ),
        "per_run": runs,
    }


def report_markdown(summary: Mapping[str, Any]) -> str:
    """``report.md``: the headline figures side by side, the agreement, the messages."""
    d, r = summary["distributed"], summary["in_process"]
    rows = [
        [k, d[k], r[k], difference_cell(summary["difference"][k])]
        for k in ("rmse_m_mean", "rmse_m_worst", "formation_rmse_m_worst", "anees_position")
    ]
    rows += [
        [f"mode_fraction.{m}", d["mode_fraction"][m], r["mode_fraction"][m], ""]
        for m in d["mode_fraction"]
    ]
    agree = summary["agreement"]
    lines = [
        f"# relloc team up guler2023 — case {summary['case']} ({summary['runs']} run(s), seed "
        f"{summary['seed']}, {fmt(summary['duration_s'])} s each)",
        "",
        "A world process steps the air-ground world; the leader, every follower (switching EKF "
        "and formation controller) and every drone (its guidance) run in their own processes "
        "over Zenoh, and the commands go back to the world every tick (closed loop).",
        "",
        markdown_table(["figure", "distributed", "in-process", "largest |Δ|"], rows),
        "",
        f"Largest |Δ| of a belief entry: {fmt(agree['max_abs_diff'])} (tolerance "
        f"{summary['tolerance']['belief_entry']:g}; figures {summary['tolerance']['figure']:g}): "
        f"{'met' if agree['within_tolerance'] else 'not met'}"
        f"{'' if agree['perfect_network'] else ' — faults were injected, so not expected'}.",
        "",
        "## Messages (per run)",
        "",
    ]
    msg_rows = []
    for run in summary["per_run"]:
        for robot, m in run["messages"]["robots"].items():
            msg_rows.append(
                [
                    run["run"],
                    robot,
                    m["sent"].get("rows", 0),
                    m["sent"].get("odom", 0),
                    m["sent"].get("cmd", 0),
                    sum(m["received_delivered"].values()),
                    m["rejected"],
                    m["late_rows"],
                ]
            )
        w = run["messages"]["world"]
        msg_rows.append(
            [run["run"], "world", "", "", sum(w["cmd_received"].values()), "", w["rejected"], ""]
        )
    lines.append(
        markdown_table(
            [
                "run",
                "robot",
                "rows sent",
                "odom sent",
                "cmd sent / received",
                "delivered",
                "rejected",
                "late rows",
            ],
            msg_rows,
        )
    )
    return "\n".join(lines)
