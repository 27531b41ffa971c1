"""The collector's per-sender report quota and a node's latency/deadline bookkeeping, with
hand-computed figures."""

from __future__ import annotations

import numpy as np
import pytest

from relloc.runtime.messages import Message, MessageRejected
from relloc.runtime.quota import ReportQuota, report_cost
from relloc.runtime.timing import EstimateTiming


def _msg(kind: str, sender: str, **body: object) -> Message:
    return Message(kind=kind, sender=sender, seq=0, t=0.0, wall_ns=0, body=body)


def test_a_report_is_charged_its_bytes_and_100_per_string_and_event():
    est = _msg("est", "a", info_names=["weight", "nis", "x"])
    assert report_cost(est, 1000) == 1000 + 300
    evt = _msg("evt", "a", targets=["b", "c"], kinds=["created", "deleted"])
    assert report_cost(evt, 50) == 50 + 400


def test_the_quota_is_32_kib_per_roster_robot_per_second_with_10_s_of_slack():
    assert ReportQuota(roster_size=3, duration_s=5.0).limit == 32_768 * 3 * 15


def test_a_report_that_exactly_fills_the_quota_is_kept_and_the_next_byte_refused():
    quota = ReportQuota(roster_size=1, duration_s=0.0)  # 327 680 bytes
    info = _msg("est", "a", info_names=["w"])
    quota.take(info, quota.limit - 100)  # cost: exactly the limit
    assert quota.used["a"] == quota.limit
    with pytest.raises(MessageRejected) as refused:
        quota.take(_msg("est", "a"), 1)
    assert refused.value.reason == "report_quota"
    assert quota.used["a"] == quota.limit  # nothing charged for the refused one
    quota.take(_msg("est", "b"), 10)  # another sender's quota is its own
    assert quota.used["b"] == 10


def test_a_window_filtered_exactly_at_its_deadline_is_not_missed():
    timing = EstimateTiming(deadline_s=0.25)
    timing.window_done(np.array([0.5]), window_end=1.0, now=1.25)
    assert timing.counters()["deadline.missed"] == 0
    timing.window_done(np.zeros(0), window_end=2.0, now=2.5)
    c = timing.counters()
    assert (c["deadline.windows"], c["deadline.missed"]) == (2, 1)


def test_latencies_are_in_milliseconds_from_each_readings_own_time():
    timing = EstimateTiming(deadline_s=1.0)
    # readings taken 1.7 ms and 0.5 s before the window was filtered
    timing.window_done(np.array([10.0 - 0.0017, 9.5]), window_end=10.0, now=10.0)
    c = timing.counters()
    assert c["latency_ms.samples"] == 2
    assert c["latency_ms.p50"] == 251  # (1.7 + 500) / 2 = 250.85
    assert c["latency_ms.p99"] == 495  # 1.7 + 0.99 · 498.3 = 495.017


def test_one_latency_is_rounded_to_the_nearest_millisecond():
    timing = EstimateTiming(deadline_s=1.0)
    timing.window_done(np.array([1.0 - 0.0017]), window_end=1.0, now=1.0)
    c = timing.counters()
    assert (c["latency_ms.p50"], c["latency_ms.p99"]) == (2, 2)


def test_latency_samples_stop_being_kept_once_200000_are_held():
    timing = EstimateTiming(deadline_s=1.0)
    for _ in range(3):
        timing.window_done(np.zeros(100_000), window_end=0.0, now=0.001)
    c = timing.counters()
    assert c["latency_ms.samples"] == 200_000
    assert c["deadline.windows"] == 3
