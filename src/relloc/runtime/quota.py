"""How much of each robot's reports the collector keeps: a memory quota per sender, derived from
the roster and the length of the run.

A node ships its new estimates (``est``) and track events (``evt``) once per report period; the
launcher's collector keeps every one it admits until it scores the run. Without a bound, any
roster robot — or anyone holding its certificate — could fill the launcher's memory with
well-formed reports. The collector therefore charges every report to its sender:

    cost = payload bytes + OBJECT_BYTES · (strings and events it holds)

(the decoded Python objects of a short string or of an event tuple take far more memory than
their bytes on the wire), and keeps at most

    quota = REPORT_BYTES_PER_SUBJECT_S · |roster| · (duration + REPORT_SLACK_S)

per sender (a robot estimates at most every robot of the roster). The genuine reports measured
(``team up default`` 60 s, ``desilva2015`` 5 s, ``sharma2013`` 3 s with and without
``--drop 0.3 --delay 400 --jitter 300``, whose re-filtered windows are re-recorded) are at most
2.3 kB per roster robot per simulated second, 14 times below :data:`REPORT_BYTES_PER_SUBJECT_S`.
What exceeds the quota is dropped and counted (``report_quota``).
"""

from __future__ import annotations

from collections import Counter

from relloc.runtime.messages import Message, MessageRejected

REPORT_BYTES_PER_SUBJECT_S = 32_768
"""Report bytes a sender may have stored per roster robot per simulated second."""
REPORT_SLACK_S = 10.0
"""Simulated seconds added to the run's duration (reports after the last tick, restarts)."""
OBJECT_BYTES = 100
"""What the collector charges per string or event of a report beyond its wire bytes."""


def report_cost(msg: Message, payload_bytes: int) -> int:
    """Memory charged for keeping ``msg`` (an ``est`` or ``evt``): see the module docstring."""
    b = msg.body
    objects = len(b.get("info_names", ())) + len(b.get("targets", ())) + len(b.get("kinds", ()))
    return payload_bytes + OBJECT_BYTES * objects


class ReportQuota:
    """Bytes of reports stored per sender, at most :attr:`limit` each (module docstring)."""

    def __init__(self, roster_size: int, duration_s: float) -> None:
        self.limit = int(REPORT_BYTES_PER_SUBJECT_S * roster_size * (duration_s + REPORT_SLACK_S))
        self.used: Counter[str] = Counter()

    def take(self, msg: Message, payload_bytes: int) -> None:
        """Charge ``msg`` to its sender, or raise ``report_quota`` (nothing charged)."""
        cost = report_cost(msg, payload_bytes)
        if self.used[msg.sender] + cost > self.limit:
            raise MessageRejected(
                "report_quota",
                f"{msg.kind} from {msg.sender!r}: {cost} bytes over the quota of {self.limit}",
            )
        self.used[msg.sender] += cost
