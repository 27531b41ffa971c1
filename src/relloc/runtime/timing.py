"""Measurement-to-estimate latency and missed deadlines of a node running on wall time.

A reading taken at wall time ``w_r`` is fused when its window is filtered, at wall time ``w_f``;
its latency is ``w_f − w_r``. A window ``[t_{k−1}, t_k)`` misses its deadline when it is
filtered more than ``deadline_s`` after its end ``t_k`` happened on the wall clock. Used by the
wall-clock node (:mod:`relloc.runtime.realtime`) and by a node whose clock is paced at real
time (``relloc team up --realtime FACTOR``).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

LATENCY_SAMPLES = 200_000


class EstimateTiming:
    """Latencies (ms) and deadlines of the windows a node filtered (module docstring)."""

    def __init__(self, deadline_s: float) -> None:
        self.deadline_s = float(deadline_s)
        self.windows = 0
        self.missed = 0
        self._latency_ms: list[float] = []

    def window_done(self, taken: NDArray[np.float64], window_end: float, now: float) -> None:
        """A window ending (on the wall clock) at ``window_end``, holding readings taken at
        ``taken``, filtered at ``now`` (all in seconds of one clock)."""
        self.windows += 1
        if now - window_end > self.deadline_s:
            self.missed += 1
        if taken.size and len(self._latency_ms) < LATENCY_SAMPLES:
            self._latency_ms.extend(((now - taken) * 1000.0).tolist())

    def counters(self) -> dict[str, int]:
        """``deadline.windows``/``deadline.missed`` and ``latency_ms.p50/p99/samples``."""
        out = {"deadline.windows": self.windows, "deadline.missed": self.missed}
        if self._latency_ms:
            p50, p99 = np.percentile(self._latency_ms, [50, 99])
            out["latency_ms.p50"] = int(np.rint(p50))
            out["latency_ms.p99"] = int(np.rint(p99))
            out["latency_ms.samples"] = len(self._latency_ms)
        return out
