"""A synthetic bag of the TIERS relative layout (``tiers_relative`` mapping) with five robots
driving circles and two standing — the layout's recordings with moving robots, which the shipped
data lacks. Ranges are the true distances plus a per-link bias (0.37 m ± 0.1 m) and noise (σ
3 cm), rounded to 1 cm, published in both directions; n_8 rides on turtlebot5 with n_5."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parents[1] / "datasets"))
from bag_samples import POSE, RANGE, mocap, pose, uwb, write_bag


def synth(path: Path, duration: float = 20.0, seed: int = 1) -> Path:
    """Write the bag (module docstring) to ``path``."""
    rng = np.random.default_rng(seed)
    T0 = 1_700_000_000 * 10**9
    centres = np.array([[1, 1], [4, 1], [1, 4], [4, 4], [2.5, 2.5], [0, 2.5], [5, 2.5]], float)
    radius = np.array([0.8, 0.7, 0.9, 0.6, 0.0, 0.5, 0.0])
    omega = np.array([0.3, -0.25, 0.2, 0.35, 0.0, -0.3, 0.0])
    msgs = []

    def xy(k: int, t: float) -> tuple[np.ndarray, float]:
        a = omega[k] * t + k
        return centres[k] + radius[k] * np.array([math.cos(a), math.sin(a)]), a + math.pi / 2

    for t in np.arange(0, duration, 1 / 30):
        ns = T0 + int(t * 1e9)
        for k in range(7):
            p, yaw = xy(k, t)
            msgs.append(
                (
                    f"/vrpn_client_node/turtlebot{k + 1}/pose",
                    POSE,
                    ns + 5_000_000,
                    mocap(ns, pose(p[0], p[1], 0.15, yaw)),
                )
            )
    node_robot = [0, 1, 2, 3, 4, 5, 6, 4]
    bias = 0.37 + rng.normal(0, 0.1, (8, 8))
    for t in np.arange(0, duration, 1 / 7.3):
        for a in range(8):
            for b in range(a + 1, 8):
                tt = t + 0.001 * (a * 8 + b)
                ns = T0 + int(tt * 1e9)
                d = np.linalg.norm(xy(node_robot[a], tt)[0] - xy(node_robot[b], tt)[0])
                if d == 0:
                    continue
                r = round(d + bias[a, b] + rng.normal(0, 0.03), 2)
                for x, y in ((a, b), (b, a)):
                    msgs.append(
                        (
                            f"/uwb/tof/n_{x + 1}/n_{y + 1}/distance",
                            RANGE,
                            ns + 20_000_000,
                            uwb(ns, r),
                        )
                    )
    msgs.sort(key=lambda m: m[2])
    return write_bag(path, msgs)
