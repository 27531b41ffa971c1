"""Both sides of the ``sync`` handoff of a restarted agent (``relloc.runtime.handoff``), driven
by hand: when a teammate's request is answered, how long the asker waits and whom it asks."""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field

import numpy as np

from relloc.core.gaussian import Gaussian
from relloc.runtime.handoff import RETRY_TICKS, WAIT_TICKS, Handoff

ROSTER = ("1", "2", "3")


@dataclass
class _Driver:
    """What :meth:`Handoff.replies` reads of a window driver."""

    time: float | None
    busy: bool = False
    hands_off: bool = True
    belief: Gaussian = field(default_factory=lambda: Gaussian(np.arange(9.0), np.eye(9)))

    def team_belief(self) -> tuple[float, Gaussian]:
        assert self.time is not None
        return self.time, self.belief


def _reply(stamp: float) -> dict:
    return {"target": "3", "stamp": stamp, "mean": np.zeros(9), "cov": np.eye(9)}


def test_a_request_is_answered_once_the_estimator_reaches_its_time_and_only_once():
    counters: Counter[str] = Counter()
    h = Handoff("1", ROSTER, counters)
    h.note_request("3", {"stamp": 2.0})
    assert counters["sync.requests_received"] == 1
    assert h.replies(_Driver(time=1.9)) == []
    replies = h.replies(_Driver(time=2.0))  # exactly the time asked for
    assert [(r["target"], r["stamp"]) for r in replies] == [("3", 2.0)]
    np.testing.assert_array_equal(replies[0]["mean"], np.arange(9.0))
    assert counters["sync.replies_due"] == 1
    assert h.replies(_Driver(time=2.5)) == []  # answered: forgotten
    assert counters["sync.replies_due"] == 1


def test_every_teammate_due_is_answered_and_counted():
    counters: Counter[str] = Counter()
    h = Handoff("1", ROSTER, counters)
    h.note_request("2", {"stamp": 1.0})
    h.note_request("3", {"stamp": 1.5})
    assert sorted(r["target"] for r in h.replies(_Driver(time=3.0))) == ["2", "3"]
    assert counters["sync.replies_due"] == 2


def test_a_teammates_newer_request_replaces_its_older_one():
    h = Handoff("1", ROSTER, Counter())
    h.note_request("3", {"stamp": 5.0})
    h.note_request("3", {"stamp": 2.0})  # it restarted again, earlier in the run
    assert [r["target"] for r in h.replies(_Driver(time=3.0))] == ["3"]


def test_a_node_waiting_for_a_belief_itself_answers_nobody():
    h = Handoff("1", ROSTER, Counter())
    h.note_request("3", {"stamp": 0.0})
    h.begin(after=1.0)
    assert h.replies(_Driver(time=4.0)) == []
    h.resumed()
    assert [r["target"] for r in h.replies(_Driver(time=4.0))] == ["3"]


def test_a_node_gives_up_after_exactly_wait_ticks_without_a_reply():
    counters: Counter[str] = Counter()
    h = Handoff("3", ROSTER, counters)
    h.begin(after=1.0)
    for _ in range(WAIT_TICKS):
        h.request(["1", "2"])
    assert h.waiting and counters["sync.timeout"] == 0
    assert h.request(["1", "2"]) is None
    assert not h.waiting and counters["sync.timeout"] == 1
    h.give_up()  # at the end of the run: counted once only
    assert counters["sync.timeout"] == 1


def test_giving_up_while_not_waiting_counts_no_timeout():
    counters: Counter[str] = Counter()
    h = Handoff("3", ROSTER, counters)
    h.give_up()
    assert counters["sync.timeout"] == 0


def test_a_node_never_asks_itself_even_when_listed_as_present():
    h = Handoff("1", ROSTER, Counter())
    h.begin(after=1.0)
    asked = []
    for _ in range(3 * RETRY_TICKS):
        request = h.request(["1", "2", "3"])
        if request is not None:
            asked.append(request["target"])
    assert asked == ["2", "3", "2"]


def test_a_reply_after_the_node_resumed_is_unasked():
    counters: Counter[str] = Counter()
    h = Handoff("3", ROSTER, counters)
    h.begin(after=5.0)
    assert h.request(["1"])["target"] == "1"
    assert h.accept("1", _reply(5.2), 5.2, 0.1) is not None
    h.resumed()
    assert h.accept("1", _reply(5.2), 5.2, 0.1) is None
    assert counters["rejected.sync_unasked"] == 1


def test_a_reply_stamped_more_than_one_tick_ahead_is_refused():
    counters: Counter[str] = Counter()
    h = Handoff("3", ROSTER, counters)
    h.begin(after=5.0)
    h.request(["1"])
    assert h.accept("1", _reply(5.35), 5.2, 0.1) is None  # clock 5.2 + one tick 0.1 < 5.35
    assert counters["rejected.sync_stamp"] == 1
    stamp, _ = h.accept("1", _reply(5.3), 5.2, 0.1)
    assert stamp == 5.3
