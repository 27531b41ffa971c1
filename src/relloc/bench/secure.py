"""``relloc bench secure`` — the cost of ``--secure`` (mutual TLS + Zenoh access control).

The same team (one observer and ``n − 1`` teammates, :func:`relloc.bench.runtime.team_toml`)
runs as separate processes over loopback, plain and secure in alternation (plain, secure,
plain, secure, … so that drifting machine load hits both alike), as fast as the team can go
(the clock's barrier: throughput is bounded by message round trips). Per run: the clock's tick
loop wall time (start-up excluded), the start-up time (from the launcher's start until every
robot is ready: processes spawned, imports, the TLS handshakes — :func:`startup_wall_s`),
message latency p50/p99 (publisher wall clock to subscriber
inbox) and CPU seconds of all robot processes. Reported: the median of each over the
repetitions and the ratio secure / plain of the medians, and whether the secure runs'
estimates are the plain runs' (same seed: they must be).
"""

from __future__ import annotations

import json
import os
import tempfile
from pathlib import Path
from statistics import median
from typing import Any

from relloc.bench.runtime import team_toml
from relloc.errors import RellocError
from relloc.runtime.keys import CLOCK_ID

ROBOTS = 6
DURATION_S = 20.0
REPETITIONS = 3
METRICS = ("loop_wall_s", "startup_wall_s", "latency_us_p50", "latency_us_p99", "robot_cpu_s")


def run_once(work: Path, name: str, *, secure: bool) -> tuple[dict[str, float], Any]:
    """One team run; its metrics and its assembled estimates."""
    from relloc.runtime.launcher import TeamLauncher, TeamSettings
    from relloc.runtime.summary import assemble_estimates, robot_messages

    scenario = work / "team.toml"
    if not scenario.exists():
        scenario.write_text(team_toml(ROBOTS, DURATION_S))
    roster = ("observer", *(f"r{i}" for i in range(1, ROBOTS)))
    settings = TeamSettings(scenario=str(scenario), out_dir=work / name, secure=secure)
    collected = TeamLauncher(settings, roster, DURATION_S).run()
    per_robot = robot_messages(collected, roster)
    clock = json.loads((work / name / "clock.json").read_text())
    p50 = [m["latency_us"]["p50"] for m in per_robot.values() if m["latency_us"]["p50"]]
    p99 = [m["latency_us"]["p99"] for m in per_robot.values() if m["latency_us"]["p99"]]
    metrics = {
        "loop_wall_s": float(clock["wall_s"]),
        "startup_wall_s": startup_wall_s(collected.presence, float(clock["startup_wall_s"])),
        "latency_us_p50": float(median(p50)),
        "latency_us_p99": float(max(p99)),
        "robot_cpu_s": float(sum(m["cpu_s"] for m in per_robot.values())),
    }
    return metrics, assemble_estimates(collected, roster, "plkf")


def startup_wall_s(presence: list[dict[str, Any]], clock_wait_s: float) -> float:
    """Seconds from the launcher's start until every robot is ready: when the clock's first
    ``alive`` token reached the launcher (its ``presence`` records, s after its start) plus
    the clock's wait from then until every robot was ready (``clock_wait_s``, its report's
    ``startup_wall_s``). The wait alone starts after the clock's own session is up, which
    robots spawned beside the clock may already have passed with their handshakes."""
    joined = [
        float(p["wall_s"])
        for p in presence
        if p["member"] == CLOCK_ID and p["token"] == "alive" and p["event"] == "joined"
    ]
    if not joined:
        raise RellocError("bench secure: the clock's liveliness token never reached the launcher")
    return joined[0] + clock_wait_s


def run(quiet: bool = False) -> dict[str, Any]:
    """Plain vs secure, alternating (see module docstring)."""
    import numpy as np

    runs: dict[str, list[dict[str, float]]] = {"plain": [], "secure": []}
    reference = None
    identical = True
    with tempfile.TemporaryDirectory(prefix="relloc-bench-secure-") as tmp:
        for i in range(REPETITIONS):
            for mode in ("plain", "secure"):
                metrics, estimates = run_once(Path(tmp), f"{mode}{i}", secure=mode == "secure")
                runs[mode].append(metrics)
                if reference is None:
                    reference = estimates
                else:
                    identical &= all(
                        np.array_equal(a.mean, b.mean)
                        for a, b in zip(reference.beliefs, estimates.beliefs, strict=True)
                    )
                if not quiet:
                    print(f"{mode:6s} run {i}: " + json.dumps(metrics))
    medians = {m: {k: median(r[k] for r in runs[m]) for k in METRICS} for m in runs}
    ratio = {k: medians["secure"][k] / medians["plain"][k] for k in METRICS}
    out = {
        "cpu_count": os.cpu_count(),
        "load_average_1min": os.getloadavg()[0],
        "robots": ROBOTS,
        "simulated_s": DURATION_S,
        "repetitions": REPETITIONS,
        "median": medians,
        "secure_over_plain": ratio,
        "identical_estimates": bool(identical),
        "runs": runs,
    }
    if not quiet:
        print("secure / plain (medians): " + json.dumps({k: round(v, 3) for k, v in ratio.items()}))
    return out
