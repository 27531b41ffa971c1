"""Scale of the robot runtime on this machine: many seed-000 robot processes in real time, and
seed-002 teams (leaders and pods as processes); rates, loss, latency, CPU and memory per process.

Usage: ``.venv/bin/python benchmarks/runtime_scale.py [--sizes 16,32] [--desilva-teams 2]
[--json FILE]``. One run of each; the numbers depend on the machine and its load (printed).

- seed 000: :func:`relloc.bench.runtime.run_team_size` (one observer tracking ``n − 1``
  teammates, the clock paced at real time, tick 0.1 s): a size keeps its rates with ≥ 99 % of
  the nominal tick rate, no missed barrier and < 1 % transport loss;
- seed 002: ``k`` teams of ``relloc team up desilva2015`` (2 leaders + 3 pods each) launched at
  once, paced at real time;
- every robot process' resident memory is sampled from ``/proc`` every 0.5 s (its peak is
  reported) and its CPU time comes from its own counters.
"""

from __future__ import annotations

import argparse
import json
import os
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

import numpy as np


def _rss_mb(pid: int) -> float | None:
    try:
        for line in Path(f"/proc/{pid}/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024.0
    except OSError:
        return None
    return None


class MemorySampler:
    """Peak resident memory (MiB) of a launcher's child processes, sampled every 0.5 s."""

    def __init__(self, launchers: list[Any]) -> None:
        self.launchers = launchers
        self.peak: dict[str, float] = {}
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def __enter__(self) -> MemorySampler:
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join()

    def _run(self) -> None:
        while not self._stop.wait(0.5):
            for k, launcher in enumerate(self.launchers):
                for name, proc in list(launcher.procs.items()):
                    if proc.pid is None:
                        continue
                    rss = _rss_mb(proc.pid)
                    key = f"{k}:{name}"
                    if rss is not None:
                        self.peak[key] = max(self.peak.get(key, 0.0), rss)


def seed000_team(
    n: int, work: Path, duration_s: float, node_args: tuple[str, ...] = ()
) -> dict[str, Any]:
    """One real-time seed-000 team of ``n`` processes (rates, loss, latency, CPU, memory)."""
    from relloc.bench import runtime as bench
    from relloc.runtime import launcher as launcher_module

    launchers: list[Any] = []
    original = launcher_module.TeamLauncher.run

    def run_and_watch(self: Any) -> Any:  # sample this launcher's children while it runs
        launchers.append(self)
        return original(self)

    launcher_module.TeamLauncher.run = run_and_watch  # type: ignore[method-assign]
    try:
        with MemorySampler(launchers) as memory:
            result = bench.run_team_size(n, work, duration_s=duration_s, node_args=node_args)
    finally:
        launcher_module.TeamLauncher.run = original  # type: ignore[method-assign]
    robots = [v for k, v in memory.peak.items() if not k.endswith(":clock")]
    result["rss_mb_per_robot"] = {
        "mean": float(np.mean(robots)) if robots else None,
        "max": float(np.max(robots)) if robots else None,
    }
    return result


def desilva_teams(k: int, work: Path, duration_s: float) -> dict[str, Any]:
    """``k`` seed-002 teams at once, paced at real time (clock factor 1)."""
    from relloc.experiments.team_sources import desilva_recording
    from relloc.runtime.launcher import TeamLauncher, TeamSettings
    from relloc.runtime.summary import robot_messages, team_message_totals

    launchers = []
    for i in range(k):
        rec = desilva_recording("desilva2015", 0, i, duration_s)
        settings = TeamSettings(
            scenario="desilva2015",
            out_dir=work / f"desilva{i}",
            team=f"ds{i}",
            realtime_factor=1.0,
            node_args=("--run", str(i), "--duration", repr(duration_s)),
        )
        launchers.append((TeamLauncher(settings, rec.robots, duration_s), rec.robots))
    results: list[Any] = [None] * k

    def go(i: int) -> None:
        results[i] = launchers[i][0].run()

    with MemorySampler([lz for lz, _ in launchers]) as memory:
        threads = [threading.Thread(target=go, args=(i,)) for i in range(k)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
    out: dict[str, Any] = {"teams": k, "processes": 5 * k, "per_team": []}
    for i, (collected, (_, roster)) in enumerate(zip(results, launchers, strict=True)):
        per_robot = robot_messages(collected, roster)
        totals = team_message_totals(per_robot)
        clock = json.loads((work / f"desilva{i}" / "clock.json").read_text())
        lat = [m["latency_us"]["p99"] for m in per_robot.values() if m["latency_us"]["p99"]]
        out["per_team"].append(
            {
                "achieved_rate_fraction": clock["ticks"] * 0.1 / clock["wall_s"],
                "ack_timeouts": sum(clock["ack_timeouts"].values()),
                "transport_loss_rate": totals["transport_loss_rate"],
                "latency_us_p50": float(
                    np.median([m["latency_us"]["p50"] for m in per_robot.values()])
                ),
                "latency_us_p99_max": float(max(lat)) if lat else None,
                "cpu_s_per_sim_s": {r: m["cpu_s"] / duration_s for r, m in per_robot.items()},
                "mail_sent": {r: m["sent"]["mail"] for r, m in per_robot.items()},
            }
        )
    robots = [v for key, v in memory.peak.items() if not key.endswith(":clock")]
    out["rss_mb_per_robot"] = {"mean": float(np.mean(robots)), "max": float(np.max(robots))}
    return out


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__)
    p.add_argument("--sizes", default="16,32", help="seed-000 team sizes, comma-separated")
    p.add_argument("--duration", type=float, default=8.0, help="simulated = wall seconds")
    p.add_argument("--desilva-teams", type=int, default=2, help="seed-002 teams at once")
    p.add_argument("--json", type=Path, default=None)
    p.add_argument(
        "--only-needed-streams",
        action="store_true",
        help="robots subscribe only to the teammates' data they use (relloc node's flag)",
    )
    args = p.parse_args()
    report: dict[str, Any] = {
        "cpu_count": os.cpu_count(),
        "load_average_1min_before": os.getloadavg()[0],
        "seed000": [],
    }
    with tempfile.TemporaryDirectory(prefix="relloc-scale-") as tmp:
        for n in (int(x) for x in args.sizes.split(",") if x):
            start = time.monotonic()
            node_args = ("--only-needed-streams",) if args.only_needed_streams else ()
            r = seed000_team(n, Path(tmp), args.duration, node_args)
            r["wall_s"] = time.monotonic() - start
            r["only_needed_streams"] = args.only_needed_streams
            report["seed000"].append(r)
            print(json.dumps(r))
        if args.desilva_teams:
            report["seed002"] = desilva_teams(args.desilva_teams, Path(tmp), args.duration)
            print(json.dumps(report["seed002"]))
    report["load_average_1min_after"] = os.getloadavg()[0]
    if args.json:
        args.json.write_text(json.dumps(report, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
