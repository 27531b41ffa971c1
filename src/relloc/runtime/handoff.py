"""``sync``: a restarted agent rejoins the team's estimate (seed 001).

A node that joins a run already going (the first tick it hears is not the run's first) and
whose estimator can hand off (:attr:`relloc.runtime.estimation.WindowDriver.hands_off`: every
agent runs the same team filter) does not start from the run's prior — it would be a filter
that has fused nothing since t = 0 while the robots have moved. It asks a present teammate for
its belief of the whole team instead:

- **request** — ``sync`` with ``target`` the teammate asked, ``stamp`` the time of the first
  tick the node heard (it has every teammate's odometry and readings from then on) and an
  empty ``mean`` / ``cov``;
- **reply** — once the teammate's estimator has processed an event at or after that time, it
  answers with ``target`` the asker, ``stamp`` its latest event time ``t_e`` and the team's
  ``mean`` (3n,) and ``cov`` (3n, 3n) at ``t_e`` (its pending prediction applied).

The asker continues from the reply (:meth:`~relloc.runtime.estimation.WindowDriver.resume`) and
filters only the events after ``t_e``: with every message delivered it then performs the same
arithmetic as its teammates, so its beliefs equal theirs up to the round-off of one moment-to-
information conversion. Until the reply it filters nothing (its windows wait); a teammate that
has not answered within :data:`RETRY_TICKS` is replaced by the next present one, and after
:data:`WAIT_TICKS` the node gives up and filters from its prior (``sync.timeout``).

A reply is accepted only from the teammate asked, while the node waits, with the team's
dimensions (``mean`` (3n,), ``cov`` (3n, 3n), symmetric: :mod:`relloc.runtime.messages`
checks the layout and a roster ``target``), a stamp not before the time asked for and not
after the node's clock plus one tick, and a covariance the filter can invert; every refusal is
counted by reason. A request is remembered per teammate (one at a time: bounded).
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from relloc.core.gaussian import Gaussian
from relloc.errors import ModelError
from relloc.runtime.estimation import WindowDriver
from relloc.runtime.messages import MessageRejected, check_state_bounds

RETRY_TICKS = 5
"""Ticks a node waits for a teammate's reply before asking the next one."""
WAIT_TICKS = 100
"""Ticks a restarted node waits for any reply before it filters from its prior."""
TIME_TOL = 1e-9


class Handoff:
    """Both sides of the ``sync`` exchange of one node (module docstring); ``counters`` are the
    node's."""

    def __init__(self, robot: str, roster: Sequence[str], counters: Counter[str]) -> None:
        self.robot = robot
        self.roster = tuple(roster)
        self.counters = counters
        self.waiting = False
        self.after = np.nan
        self._asked: str | None = None
        self._ticks = 0
        self._attempt = 0
        self._requests: dict[str, float] = {}

    # ------------------------------------------------------------------ the restarted node
    def begin(self, after: float) -> None:
        """The node joined mid-run: it has its teammates' data from ``after`` on."""
        self.waiting = True
        self.after = float(after)
        self.counters["sync.asked_for"] += 1

    def request(self, present: Sequence[str]) -> dict[str, Any] | None:
        """Called every tick: the request to send now (a new teammate every
        :data:`RETRY_TICKS`), or None. Gives up after :data:`WAIT_TICKS`."""
        if not self.waiting:
            return None
        self._ticks += 1
        if self._ticks > WAIT_TICKS:
            self.give_up()
            return None
        mates = [r for r in self.roster if r in present and r != self.robot]
        if not mates or (self._ticks - 1) % RETRY_TICKS:
            return None
        self._asked = mates[self._attempt % len(mates)]
        self._attempt += 1
        self.counters["sync.requests_sent"] += 1
        return {"target": self._asked, "stamp": self.after, "mean": np.zeros(0), "cov": _EMPTY}

    def give_up(self) -> None:
        """No reply in time (or the run ends): filter from the prior."""
        if self.waiting:
            self.waiting = False
            self.counters["sync.timeout"] += 1

    def accept(
        self, sender: str, body: Mapping[str, Any], now_s: float, dt: float
    ) -> tuple[float, Gaussian] | None:
        """The belief of a reply addressed to this node, or None (counted) if it is refused."""
        if not self.waiting or sender != self._asked:
            self.counters["rejected.sync_unasked"] += 1
            return None
        dim = 3 * len(self.roster)
        if body["mean"].shape != (dim,):
            self.counters["rejected.shape"] += 1
            return None
        stamp = float(body["stamp"])
        if not (self.after - TIME_TOL <= stamp <= now_s + dt + TIME_TOL):
            self.counters["rejected.sync_stamp"] += 1
            return None
        try:
            check_state_bounds("sync", body["mean"], body["cov"])  # the filter inverts it
            belief = Gaussian(body["mean"], body["cov"])
        except MessageRejected as exc:
            self.counters[f"rejected.{exc.reason}"] += 1
            return None
        except ModelError:
            self.counters["rejected.bad_covariance"] += 1
            return None
        return stamp, belief

    def resumed(self) -> None:
        self.waiting = False
        self.counters["sync.resumed"] += 1

    # ------------------------------------------------------------------ a teammate asked
    def note_request(self, sender: str, body: Mapping[str, Any]) -> None:
        """Teammate ``sender`` asks for the team belief from ``stamp`` on."""
        self._requests[sender] = float(body["stamp"])
        self.counters["sync.requests_received"] += 1

    def replies(self, driver: WindowDriver) -> list[dict[str, Any]]:
        """Replies due now: to every teammate whose time the estimator has reached (none
        while this node waits for a belief itself); counted ``sync.replies_due`` (those sent
        are the node's ``sent.sync``; one too large for a message, its ``sync.too_large``)."""
        t = driver.time
        if self.waiting or t is None or driver.busy or not driver.hands_off:
            return []
        due = [r for r, after in self._requests.items() if t >= after - TIME_TOL]
        if not due:
            return []
        stamp, belief = driver.team_belief()
        for r in due:
            del self._requests[r]
        self.counters["sync.replies_due"] += len(due)
        return [{"target": r, "stamp": stamp, "mean": belief.mean, "cov": belief.cov} for r in due]


_EMPTY = np.zeros((0, 0))
