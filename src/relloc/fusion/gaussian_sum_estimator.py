"""Seed 002's distributed fuser as an estimator of the pipeline contract.

Every sensing robot ``i`` runs one :class:`GaussianSumEstimator` (owner ``i``'s name, name
``"gaussian_sum"``): its :class:`~relloc.estimators.gaussian_sum.GaussianSumFuser`, with one
Gaussian-sum filter per teammate, driven by :func:`relloc.pipeline.replay.replay` (seed 002
§II-B and Fig. 1):

- :meth:`~GaussianSumEstimator.advance` fuses the teammates' messages received at the previous
  event, then predicts every track to ``t`` with the held body velocities of ``i`` and of its
  teammates (Eq. 5; the first event only starts the clock);
- :meth:`~GaussianSumEstimator.measure`: ``i``'s rows of the batch form its *direct scans*, one
  per time stamp (in time order): ``"height"`` and ``"range"`` rows of a known teammate
  (``target``) and the bearings of unknown correspondence — ``"bearing_elevation"`` rows, or
  ``"bearing"`` rows for an azimuth-only sensor (``use_elevation=False``), with ``target`` and
  ``landmark`` :data:`~relloc.core.recording.NO_TARGET` — in table order; every other row is
  counted (:meth:`~GaussianSumEstimator.take_counts`), not used;
- :meth:`~GaussianSumEstimator.outbox` broadcasts the equivalent measurements of every filter
  (Eq. 8, :class:`~relloc.fusion.messages.EquivalentMeasurement`) every ``fusion_period``
  seconds after the first event (nothing when ``sharing`` is off);
- :meth:`~GaussianSumEstimator.receive` queues the others' messages; they are fused (mutual
  and indirect fusion, Eqs. 9–12) when the estimator next advances, before its prediction —
  the same arithmetic as fusing them at once, but the belief recorded at a scan time is the
  direct-scan result of that instant (the fused information shows from the next step);
- :meth:`~GaussianSumEstimator.beliefs`: the dominant track of every teammate's filter that
  has tracks, in frame ``relative_pose4``; ``age`` is the time since that filter has held
  tracks without interruption; :meth:`~GaussianSumEstimator.take_events` reports a filter
  gaining its first track (``created``), losing its last (``deleted``), gaining again
  (``recreated``).

Association scoring without reading the truth. A belief's ``info`` holds ``weight`` (of the
dominant track), ``components`` (tracks of the filter), ``confirmed`` (1 or 0, see
:class:`~relloc.estimators.gaussian_sum.GaussianSumSettings`), ``scan_t`` (stamp of the last
direct scan), ``bearing_row`` (which of that scan's bearing rows the dominant track was last
updated with, −1 for none) and ``decision_row`` (the bearing row the fuser's one-to-one joint
decision gave the teammate, −1 for none). Row ``k`` is the ``k``-th row, in table order, of
:func:`bearing_rows` at ``scan_t``, so scoring finds the reading's ``origin`` in the recording;
the estimator itself never reads ``origin``. (A teammate whose filter lost its last track in a
scan has no belief, so a decision made for it on the deleted tracks is not recorded.)
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from relloc.core.contract import Belief, EventKind, HeldOdometry, TrackEvent, UpdateRecord
from relloc.core.events import elapsed
from relloc.core.recording import KIND_NAMES, NO_TARGET, Measurements, kind_code
from relloc.errors import ConfigError, DataError
from relloc.estimators.gaussian_sum import GaussianSumFuser, GaussianSumSettings
from relloc.fusion.messages import EquivalentMeasurement

Array = NDArray[np.float64]
IntArray = NDArray[np.int64]
BoolArray = NDArray[np.bool_]

#: ``info["bearing_row"]`` / ``info["decision_row"]`` when no bearing was used or given.
NO_BEARING = -1
_HEIGHT = kind_code("height")
_RANGE = kind_code("range")
#: The count names of rows used and of rows repeated within a scan, by kind code.
_USED_KEY = {code: f"rows_used:{name}" for code, name in enumerate(KIND_NAMES)}
_REPEATED_KEY = {code: f"rows_repeated_in_a_scan:{name}" for code, name in enumerate(KIND_NAMES)}


def bearing_kind(settings: GaussianSumSettings) -> str:
    """The measurement kind of the fuser's bearing sensor."""
    return "bearing_elevation" if settings.use_elevation else "bearing"


def bearing_rows(measurements: Measurements, observer: int, kind: str) -> IntArray:
    """Indices, in table order, of ``observer``'s bearings of unknown correspondence."""
    return np.flatnonzero(
        _bearing_mask(measurements, kind_code(kind)) & (measurements.observer == observer)
    )


def _bearing_mask(m: Measurements, code: int) -> BoolArray:
    assert m.landmark is not None
    return (m.kind == code) & (m.target == NO_TARGET) & (m.landmark == NO_TARGET)


def _modelled_mask(m: Measurements, code: int) -> BoolArray:
    """Rows a fuser uses: heights and ranges of a known robot, and its bearing kind."""
    known = ((m.kind == _HEIGHT) | (m.kind == _RANGE)) & (m.target >= 0)
    return known | _bearing_mask(m, code)


def scan_times(
    measurements: Measurements,
    robots: Sequence[str],
    sensing: Sequence[int],
    settings: GaussianSumSettings,
) -> dict[str, Array]:
    """Per sensing robot (by name), the time stamps of its direct scans (the stamps of the rows
    its fuser uses) — the record times of :func:`relloc.pipeline.replay.replay`."""
    used = _modelled_mask(measurements, kind_code(bearing_kind(settings)))
    return {
        robots[i]: np.unique(measurements.t[used & (measurements.observer == i)]) for i in sensing
    }


class GaussianSumEstimator:
    """Robot ``robots[index]``'s fuser under the estimator contract (module docstring).

    ``robots`` names every robot of the recording in index order (the fuser's teammates are
    all the others); ``sharing`` switches mutual and indirect fusion on or off;
    ``fusion_period`` is the time between broadcasts (seed 002: 1 s).
    """

    name = "gaussian_sum"

    def __init__(
        self,
        robots: Sequence[str],
        index: int,
        settings: GaussianSumSettings,
        *,
        sharing: bool = True,
        fusion_period: float = 1.0,
    ) -> None:
        names = tuple(str(r) for r in robots)
        if not 0 <= index < len(names):
            raise ConfigError(f"GaussianSumEstimator: robot index {index} not in {names}")
        if not (np.isfinite(fusion_period) and fusion_period > 0.0):
            raise ConfigError(f"GaussianSumEstimator.fusion_period must be > 0: {fusion_period}")
        self.owner = names[index]
        self.robots = names
        self.index = int(index)
        self.sharing = bool(sharing)
        self.fusion_period = float(fusion_period)
        teammates = [j for j in range(len(names)) if j != index]
        self.fuser = GaussianSumFuser(index, teammates, settings)
        self._team = np.asarray(teammates, dtype=np.int64)
        self._local = np.full(len(names), -1, dtype=np.int64)
        self._local[self._team] = np.arange(self._team.size)
        self._bearing_code = kind_code(bearing_kind(settings))
        self._n_bearing = len(settings.bearing_rows)
        self._t: float | None = None
        self._t0 = 0.0
        self._next_fusion = self.fusion_period
        self._pending: list[EquivalentMeasurement] = []
        self._scan_t = float("nan")
        self._since: dict[int, float] = {}
        self._has_tracks = np.zeros(self._team.size, dtype=bool)
        self._ever: set[int] = set()
        self._events: list[TrackEvent] = []
        self._counts: dict[str, int] = {}

    # ------------------------------------------------------------------ the contract

    def advance(self, t: float, odometry: HeldOdometry) -> None:
        """Fuse the queued messages, then predict from the previous event to ``t``."""
        dt = elapsed(self._t, t, f"{self.owner} (gaussian_sum).advance")
        t = float(t)
        if self._pending:
            self._fuse_pending()
        if dt is None:
            self._t = self._t0 = t
            return
        u = odometry.velocity
        if u.shape != (len(self.robots), 4):
            raise DataError(
                f"{self.owner} (gaussian_sum): odometry of {u.shape[0]} robots, "
                f"expected {len(self.robots)} {self.robots}"
            )
        self.fuser.predict(u[self.index], u[self._team], dt)
        self._t = t

    def measure(self, batch: Measurements) -> None:
        """One direct scan per time stamp of this robot's modelled rows (module docstring)."""
        mine = batch.observer == self.index
        if not mine.any():
            return
        bad = mine & (batch.target >= len(self.robots))
        if bad.any():
            raise DataError(
                f"{self.owner} (gaussian_sum): row {int(np.argmax(bad))} of the batch names "
                f"robot {int(batch.target[np.argmax(bad)])}, not one of {self.robots}"
            )
        used = mine & _modelled_mask(batch, self._bearing_code)
        ignored = batch.kind[mine & ~used]
        if ignored.size:
            per_kind = np.bincount(ignored)
            for code in np.flatnonzero(per_kind):
                self._add(f"rows_not_modelled:{KIND_NAMES[code]}", int(per_kind[code]))
        rows = np.flatnonzero(used)
        if rows.size == 0:
            return
        stamps = batch.t[rows]
        if (stamps == stamps[0]).all():  # (the common case: one scan in the batch)
            self._scan(batch, rows, float(stamps[0]))
            return
        for stamp in np.unique(stamps):
            self._scan(batch, rows[stamps == stamp], float(stamp))

    def outbox(self) -> list[Any]:
        """Every filter's equivalent measurements, each ``fusion_period`` (Eq. 8): at the first
        event at or after each broadcast time ``t₀ + k·fusion_period``; after a gap between
        events longer than the period, one broadcast, and the next at the first broadcast time
        after it (not one per period missed, which sent a burst at every event until the
        schedule caught up)."""
        if not self.sharing or self._t is None:
            return []
        since_start = self._t - self._t0
        if since_start < self._next_fusion - 1e-9:
            return []
        self._next_fusion = (math.floor((since_start + 1e-9) / self.fusion_period) + 1) * (
            self.fusion_period
        )
        return list(self.fuser.broadcast())

    def quiet_until(self) -> float:
        """Nothing this estimator sends is stamped before this time (its next broadcast; −∞
        before its first event): a robot node lets teammates run ahead to it."""
        if self._t is None:
            return float("-inf")
        if not self.sharing:
            return float("inf")
        return self._t0 + self._next_fusion - 1e-9

    def receive(self, messages: Sequence[Any]) -> None:
        """Queue the teammates' equivalent measurements (fused at the next :meth:`advance`)."""
        for msg in messages:
            if isinstance(msg, EquivalentMeasurement):
                self._pending.append(msg)
            else:
                self._add("messages_not_modelled", 1)

    def beliefs(self) -> list[Belief]:
        """The dominant track of every teammate's filter that has tracks (module docstring)."""
        out = []
        now = self._t if self._t is not None else 0.0
        for local, j in enumerate(self._team.tolist()):
            s = self.fuser.summary(j)
            if s is None:
                continue
            info: Mapping[str, float] = {
                "weight": s.weight,
                "components": float(s.components),
                "confirmed": float(s.confirmed),
                "scan_t": self._scan_t,
                "bearing_row": float(s.assoc),
                "decision_row": float(self.fuser.last_decision[local]),
            }
            out.append(
                Belief(
                    subject=self.robots[j],
                    frame="relative_pose4",
                    mean=s.belief.mean,
                    cov=s.belief.cov,
                    age=now - self._since.get(j, now),
                    info=info,
                )
            )
        return out

    def take_updates(self) -> list[UpdateRecord]:
        """None: the mixture's updates have no single innovation to report."""
        return []

    def take_events(self) -> list[TrackEvent]:
        """Filters that gained their first track, lost their last, or gained again."""
        events, self._events = self._events, []
        return events

    def take_counts(self) -> dict[str, int]:
        """Rows and messages not used, and the fusion outcomes, since the last call."""
        counts, self._counts = self._counts, {}
        return counts

    # ------------------------------------------------------------------ internals

    def _scan(self, batch: Measurements, rows: IntArray, stamp: float) -> None:
        """Heights, ranges and bearings of ``rows`` (one time stamp) as one direct scan."""
        n_team = self._team.size
        kind, target = batch.kind[rows], batch.target[rows]
        known: dict[int, Array] = {}
        for code in (_HEIGHT, _RANGE):
            values = np.full(n_team, np.nan)
            sel = np.flatnonzero((kind == code) & (target >= 0))
            local = self._local[target[sel]]
            if np.bincount(local + 1).max(initial=0) > 1:  # keep the first row per teammate
                first = np.unique(local, return_index=True)[1]
            else:
                first = np.arange(local.size)
            values[local[first]] = batch.value[rows[sel[first]], 0]
            self._add(_USED_KEY[code], first.size)
            self._add(_REPEATED_KEY[code], sel.size - first.size)
            known[code] = values
        bearings = batch.value[rows[kind == self._bearing_code], : self._n_bearing]
        self._add(_USED_KEY[self._bearing_code], bearings.shape[0])
        self.fuser.direct_scan(known[_HEIGHT], known[_RANGE], bearings)
        self._scan_t = stamp
        self._note_tracks(stamp)

    def _fuse_pending(self) -> None:
        assert self._t is not None
        for msg in self._pending:
            self._add(f"messages_fused:{self.fuser.fuse(msg)}", 1)
        self._pending = []
        self._note_tracks(self._t)

    def _note_tracks(self, t: float) -> None:
        """Track the start time of every filter's tracks and record its events."""
        has = np.zeros(self._team.size, dtype=bool)
        has[self.fuser.tracks.groups] = True
        if np.array_equal(has, self._has_tracks):
            return  # (no filter gained its first track or lost its last)
        self._has_tracks = has
        for local, j in enumerate(self._team.tolist()):
            if has[local] and j not in self._since:
                self._since[j] = t
                kind: EventKind = "recreated" if j in self._ever else "created"
                self._ever.add(j)
                self._events.append(TrackEvent(t, self.owner, self.robots[j], kind))
            elif not has[local] and j in self._since:
                del self._since[j]
                self._events.append(TrackEvent(t, self.owner, self.robots[j], "deleted"))

    def _add(self, key: str, n: int) -> None:
        if n:
            self._counts[key] = self._counts.get(key, 0) + int(n)


def team(
    robots: Sequence[str],
    sensing: Sequence[int],
    settings: GaussianSumSettings,
    *,
    sharing: bool = True,
    fusion_period: float = 1.0,
) -> list[GaussianSumEstimator]:
    """One estimator per sensing robot (in the given order)."""
    if not sensing or len(set(sensing)) != len(sensing):
        raise ConfigError(f"gaussian_sum team: sensing robots must be distinct: {list(sensing)}")
    return [
        GaussianSumEstimator(robots, i, settings, sharing=sharing, fusion_period=fusion_period)
        for i in sensing
    ]
