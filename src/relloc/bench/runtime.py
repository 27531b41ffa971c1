"""``relloc bench runtime`` — how far the robot runtime scales on this machine.

1. **Largest team that keeps its rates.** Teams of ``n`` robot processes (one observing robot
   tracking ``n − 1`` teammates, seed-000 style) run in *real time* (clock paced at 1×, tick
   0.1 s: every robot publishes a 10-sample odometry batch at 10 Hz, the observer a measurement
   batch at 10 Hz, every robot its counters and beliefs at 1 Hz). A size *keeps its rates* when
   the team achieved ≥ 99 % of the nominal tick rate over the run (a stall is caught up, so the
   largest lag behind real time is reported beside it), no robot missed a barrier and the
   transport lost < 1 % of the data messages. Sizes grow until one fails (or the list ends).
2. **Message latency** p50 / p99 (µs, publisher wall clock to subscriber inbox, all robots).
3. **CPU per robot process** (CPU seconds per simulated second; the observer separately, since
   it runs the filters).
4. **Monte-Carlo speed-up** of ``relloc run``'s team task with 2 process workers vs 1 (and
   the check that both give identical results).

Numbers depend on the machine and on its load; the benchmark prints the CPU count.
"""

from __future__ import annotations

import math
import os
import tempfile
import time
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from relloc.estimators.track_manager import default_tracker
from relloc.experiments.team_run import team_task
from relloc.pipeline.montecarlo import executor_from_spec, run_monte_carlo
from relloc.sim.scenario import default_scenario

TEAM_SIZES = (2, 4, 6, 8, 12, 16, 24)
DURATION_S = 8.0
LOSS_LIMIT = 0.01
RATE_LIMIT = 0.99


def team_toml(n: int, duration_s: float) -> str:
    """A team of one observing ground robot and ``n − 1`` hovering teammates in its view."""
    lines = [
        f'name = "bench-{n}"',
        f"duration_s = {duration_s!r}",
        "propagation_rate_hz = 100.0",
        "[arena]",
        "x = [0.0, 40.0]",
        "y = [0.0, 40.0]",
        "z = [-1.0, 4.0]",
        "[[robots]]",
        'name = "observer"',
        'kind = "ground"',
        "initial_pose = [20.0, 2.0, 1.5707963267948966]",
        "[robots.motion]",
        'type = "velocity"',
        "mean = [0.0, 0.0, 0.0, 0.0]",
        "[robots.sensor]",
        "rate_hz = 10.0",
        "fov_deg = 160.0",
        "elevation_fov_deg = 120.0",
        "max_range = 40.0",
    ]
    for i in range(1, n):
        angle = math.radians(-60 + 120 * (i - 0.5) / max(1, n - 1))
        radius = 6.0 + 4.0 * (i % 3)
        x, y = 20.0 + radius * math.sin(angle), 2.0 + radius * math.cos(angle)
        lines += [
            "[[robots]]",
            f'name = "r{i}"',
            'kind = "aerial"',
            f"height = {1.0 + 0.1 * (i % 5)!r}",
            f"initial_pose = [{x!r}, {y!r}, 0.0]",
            "[robots.motion]",
            'type = "velocity"',
            "mean = [0.0, 0.0, 0.0, 0.0]",
            "amplitude = [0.2, 0.2, 0.0, 0.1]",
            f"period_s = [10.0, 12.0, 10.0, {8.0 + i % 4!r}]",
        ]
    return "\n".join(lines) + "\n"


def run_team_size(
    n: int, work: Path, *, duration_s: float = DURATION_S, node_args: tuple[str, ...] = ()
) -> dict[str, Any]:
    """One real-time team of ``n`` robot processes; its rates, loss, latency and CPU
    (``node_args``: extra ``relloc node`` arguments of every robot)."""
    import json

    from relloc.runtime.launcher import TeamLauncher, TeamSettings
    from relloc.runtime.summary import robot_messages, team_message_totals

    scenario = work / f"team{n}.toml"
    scenario.write_text(team_toml(n, duration_s))
    out = work / f"team{n}"
    settings = TeamSettings(
        scenario=str(scenario), out_dir=out, realtime_factor=1.0, node_args=node_args
    )
    roster = ("observer", *(f"r{i}" for i in range(1, n)))
    collected = TeamLauncher(settings, roster, duration_s).run()
    per_robot = robot_messages(collected, roster)
    totals = team_message_totals(per_robot)
    clock = json.loads((out / "clock.json").read_text())
    tick_s = settings.tick_s
    cpu = {r: per_robot[r]["cpu_s"] / duration_s for r in roster}
    latencies = [
        (m["latency_us"]["p50"], m["latency_us"]["p99"])
        for m in per_robot.values()
        if m["latency_us"]["p50"] is not None
    ]
    achieved = clock["ticks"] * tick_s / clock["wall_s"] if clock["wall_s"] > 0 else 0.0
    keeps = (
        achieved >= RATE_LIMIT
        and not clock["ack_timeouts"]
        and (totals["transport_loss_rate"] or 0.0) < LOSS_LIMIT
    )
    return {
        "robots": n,
        "keeps_rates": bool(keeps),
        "achieved_rate_fraction": achieved,
        "max_tick_lag_s": clock["max_tick_lag_s"],
        "ack_timeouts": sum(clock["ack_timeouts"].values()),
        "transport_loss_rate": totals["transport_loss_rate"],
        "data_messages_sent": totals["data_messages_sent"],
        "latency_us_p50": float(np.median([p for p, _ in latencies])) if latencies else None,
        "latency_us_p99": float(max(p for _, p in latencies)) if latencies else None,
        "cpu_per_sim_s_observer": cpu["observer"],
        "cpu_per_sim_s_teammate_mean": float(np.mean([cpu[r] for r in roster[1:]])),
    }


def monte_carlo_speedup(runs: int = 4, duration_s: float = 10.0) -> dict[str, Any]:
    """Wall time of ``runs`` team-task runs with 1 and with 2 process workers."""
    scenario = replace(default_scenario(), duration_s=duration_s)
    args = (scenario, default_tracker(), 10.0)
    timings: dict[int, float] = {}
    results: dict[int, list[Any]] = {}
    for workers in (1, 2):
        with executor_from_spec("process", max_workers=workers) as pool:
            start = time.perf_counter()
            results[workers] = run_monte_carlo(
                team_task, runs, 2026, executor=pool, task_args=args, quiet=True
            )
            timings[workers] = time.perf_counter() - start
    identical = all(
        np.array_equal(a.error, b.error)
        for r1, r2 in zip(results[1], results[2], strict=True)
        for a, b in zip(r1.evaluations, r2.evaluations, strict=True)
    )
    return {
        "runs": runs,
        "scenario_duration_s": duration_s,
        "wall_s_1_worker": timings[1],
        "wall_s_2_workers": timings[2],
        "speedup_2_vs_1": timings[1] / timings[2],
        "identical_results": identical,
    }


def run(quiet: bool = False) -> dict[str, Any]:
    """All runtime numbers (see module docstring)."""
    sizes: list[dict[str, Any]] = []
    with tempfile.TemporaryDirectory(prefix="relloc-bench-runtime-") as tmp:
        for n in TEAM_SIZES:
            result = run_team_size(n, Path(tmp))
            sizes.append(result)
            if not quiet:
                print(
                    f"team of {n:2d}: keeps rates {result['keeps_rates']} "
                    f"({100 * result['achieved_rate_fraction']:.1f} % of real time), "
                    f"lag {result['max_tick_lag_s']:.3f} s, loss {result['transport_loss_rate']}, "
                    f"latency p50/p99 {result['latency_us_p50']}/{result['latency_us_p99']} µs"
                )
            if not result["keeps_rates"]:
                break
    kept = [s["robots"] for s in sizes if s["keeps_rates"]]
    best = max(kept) if kept else None
    at_best = next((s for s in sizes if s["robots"] == best), sizes[-1])
    speedup = monte_carlo_speedup()
    out = {
        "cpu_count": os.cpu_count(),
        "load_average_1min": os.getloadavg()[0],
        "largest_team_keeping_rates": best,
        "latency_us": {"p50": at_best["latency_us_p50"], "p99": at_best["latency_us_p99"]},
        "cpu_per_robot_process": {
            "observer_cpu_s_per_sim_s": at_best["cpu_per_sim_s_observer"],
            "teammate_cpu_s_per_sim_s": at_best["cpu_per_sim_s_teammate_mean"],
        },
        "team_sizes": sizes,
        "monte_carlo": speedup,
    }
    if not quiet:
        print(
            f"largest team keeping its rates: {best} robot processes; "
            f"Monte-Carlo speed-up 2 vs 1 workers: {speedup['speedup_2_vs_1']:.2f}x "
            f"(identical results: {speedup['identical_results']})"
        )
    return out
