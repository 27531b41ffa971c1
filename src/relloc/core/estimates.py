"""The one estimates record: what any estimator believed over time, as plain arrays.

:class:`Estimates` holds, per (owner, subject) — the robot that estimates and the robot it
estimates, or ``"team"`` and a robot for a centralised filter —

- a :class:`BeliefSeries`: the belief recorded at the record times while it existed (``t``,
  ``mean``, ``cov``, the track ``age`` and scalar ``info`` diagnostics), in a named frame of
  :mod:`relloc.pipeline.frames`;
- an :class:`UpdateSeries`: one entry per measurement update (NIS and its degrees of freedom,
  conditioning of ``R`` and ``S``);

plus the track events and the estimators' counters. It ships between processes as it is (Monte
Carlo workers, robot nodes) and is scored by :func:`relloc.pipeline.evaluation.evaluate`.
:class:`Recorder` builds it while a replay runs, and hands out increments for robot nodes.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from relloc.core import checks
from relloc.core.contract import Belief, BeliefStack, TrackEvent, UpdateRecord
from relloc.errors import ConfigError, DataError, ModelError

Array = NDArray[np.float64]
IntArray = NDArray[np.int64]


@dataclass(frozen=True, kw_only=True)
class _Series:
    """What identifies a series: ``owner``'s view of ``subject``, its track ``track``."""

    owner: str
    subject: str
    track: str = ""

    @property
    def key(self) -> SeriesKey:
        return (self.owner, self.subject, self.track)

    @property
    def label(self) -> str:
        return series_label(self.key)


@dataclass(frozen=True, kw_only=True)
class BeliefSeries(_Series):
    """``owner``'s recorded belief of ``subject`` (its track ``track``) in ``frame``:
    ``t (K,)``, ``mean (K, d)``, ``cov (K, d, d)``, ``age (K,)`` and ``info[name] (K,)``."""

    frame: str
    t: Array
    mean: Array
    cov: Array
    age: Array
    info: Mapping[str, Array] = field(default_factory=dict)


@dataclass(frozen=True, kw_only=True)
class UpdateSeries(_Series):
    """``owner``'s measurement updates of its belief of ``subject``, one entry each."""

    t: Array
    age: Array
    nis: Array
    dof: IntArray
    cond_r: Array
    cond_s: Array


#: ``(owner, subject, track)`` — what identifies a series.
SeriesKey = tuple[str, str, str]


def series_label(key: SeriesKey) -> str:
    """``owner->subject``, with ``#track`` appended when the track has a name."""
    owner, subject, track = key
    return f"{owner}->{subject}" + (f"#{track}" if track else "")


def _empty_updates(key: SeriesKey) -> UpdateSeries:
    z = np.zeros(0)
    owner, subject, track = key
    return UpdateSeries(
        owner=owner,
        subject=subject,
        track=track,
        t=z,
        age=z,
        nis=z,
        dof=np.zeros(0, dtype=np.int64),
        cond_r=z,
        cond_s=z,
    )


@dataclass(frozen=True, kw_only=True)
class Estimates:
    """What one or more estimators produced over a recording (module docstring).

    ``beliefs`` and ``updates`` are sorted by (owner, subject); ``events`` by time.
    """

    estimator: str
    beliefs: tuple[BeliefSeries, ...] = ()
    updates: tuple[UpdateSeries, ...] = ()
    events: tuple[TrackEvent, ...] = ()
    counts: Mapping[str, int] = field(default_factory=dict)

    def series(self, owner: str, subject: str, track: str = "") -> BeliefSeries:
        """The belief series of ``owner->subject#track`` (ConfigError if there is none)."""
        for s in self.beliefs:
            if s.key == (owner, subject, track):
                return s
        raise ConfigError(f"no estimates for {series_label((owner, subject, track))}")

    def updates_of(self, owner: str, subject: str, track: str = "") -> UpdateSeries:
        """The update series of ``owner->subject#track`` (empty if it was never updated)."""
        for u in self.updates:
            if u.key == (owner, subject, track):
                return u
        return _empty_updates((owner, subject, track))

    @property
    def labels(self) -> tuple[str, ...]:
        return tuple(s.label for s in self.beliefs)

    def stacked(
        self, owner: str, subjects: Sequence[str], track: str = ""
    ) -> tuple[Array, Array, Array]:
        """``owner``'s beliefs of ``subjects`` side by side: ``(t (K,), mean (K, m, d),
        cov (K, m, d, d))`` for the ``m`` subjects in the given order (e.g. a centralised
        filter's team). The series must share their record times (ConfigError otherwise)."""
        series = [self.series(owner, s, track) for s in subjects]
        if not series:
            raise ConfigError(f"stacked: no subjects of {owner} asked for")
        t = series[0].t
        for s in series[1:]:
            if s.t.shape != t.shape or np.any(s.t != t):
                raise ConfigError(f"stacked: {s.label} was recorded at other times than the rest")
        return (
            t,
            np.stack([s.mean for s in series], axis=1),
            np.stack([s.cov for s in series], axis=1),
        )


@dataclass
class _Rows:
    frame: str = ""
    t: list[float] = field(default_factory=list)
    mean: list[Array] = field(default_factory=list)
    cov: list[Array] = field(default_factory=list)
    age: list[float] = field(default_factory=list)
    info: dict[str, list[float]] = field(default_factory=dict)
    dim: int = 0


@dataclass
class _UpdateRows:
    t: list[float] = field(default_factory=list)
    age: list[float] = field(default_factory=list)
    nis: list[float] = field(default_factory=list)
    dof: list[int] = field(default_factory=list)
    cond_r: list[float] = field(default_factory=list)
    cond_s: list[float] = field(default_factory=list)


class Recorder:
    """Collects beliefs, updates and events while a replay runs.

    :meth:`results` returns everything so far; :meth:`take_new` only what was added since its
    previous call (a robot node ships that every report period).
    """

    def __init__(self, estimator: str) -> None:
        self.estimator = estimator
        self._beliefs: dict[SeriesKey, _Rows] = {}
        self._updates: dict[SeriesKey, _UpdateRows] = {}
        self._events: list[TrackEvent] = []
        self._counts: dict[str, int] = {}
        self._sent_beliefs: dict[SeriesKey, int] = {}
        self._sent_updates: dict[SeriesKey, int] = {}
        self._sent_events = 0

    def record(self, t: float, owner: str, beliefs: Iterable[Belief]) -> None:
        """Store ``owner``'s ``beliefs`` at time ``t`` (a :class:`BeliefStack` as one copy of
        its arrays, without a :class:`Belief` per subject).

        ``beliefs`` that are not an iterable of :class:`Belief` (``None``, a belief without a
        subject, a non-numeric age or diagnostic) break the estimator contract: ModelError
        naming ``owner`` and ``t``; so does a ``t`` that is not a number."""
        try:
            t = float(t)
        except (TypeError, ValueError):
            raise ModelError(f"beliefs of {owner}: the time {t!r:.40} is not a number") from None
        if isinstance(beliefs, BeliefStack):
            mean, cov = beliefs.mean.copy(), beliefs.cov.copy()
            for i, subject in enumerate(beliefs.subjects):
                self._append((owner, subject, ""), beliefs.frame, t, mean[i], cov[i], beliefs.age)
            return
        try:
            for b in beliefs:
                key = (owner, b.subject, b.track)
                self._append(key, b.frame, t, b.mean.copy(), b.cov.copy(), float(b.age), b.info)
        except (AttributeError, TypeError, ValueError) as exc:
            raise ModelError(
                f"beliefs of {owner} at t={t:g}: not a sequence of Belief with numeric age and "
                f"info ({type(exc).__name__}: {exc})"
            ) from exc

    def _append(
        self,
        key: SeriesKey,
        frame: str,
        t: float,
        mean: Array,
        cov: Array,
        age: float,
        info: Mapping[str, float] | None = None,
    ) -> None:
        """One recorded belief of the series ``key`` (``mean`` and ``cov`` kept as given).

        A series keeps its frame (ConfigError) and its state dimension (DataError: the rows
        could not be stacked into ``(K, d)``) from its first record on."""
        rows = self._beliefs.get(key)
        if rows is None:  # (not setdefault: that would build new rows at every call)
            rows = self._beliefs[key] = _Rows(frame=frame, dim=mean.size)
        if rows.frame != frame:
            raise ConfigError(f"{series_label(key)}: frame changed from {rows.frame} to {frame}")
        if mean.size != rows.dim:
            raise DataError(
                f"{series_label(key)}: state dimension changed from {rows.dim} to {mean.size} "
                f"at t={t:g}"
            )
        rows.t.append(t)
        rows.mean.append(mean)
        rows.cov.append(cov)
        rows.age.append(age)
        if rows.info or info:  # (most estimators report no diagnostics)
            info = info or {}
            for name in set(rows.info) | set(info):
                col = rows.info.setdefault(name, [np.nan] * (len(rows.t) - 1))
                col.append(float(info.get(name, np.nan)))

    def add_updates(self, owner: str, updates: Iterable[UpdateRecord]) -> None:
        """Store ``owner``'s measurement updates. Anything but an iterable of
        :class:`UpdateRecord` with numeric fields breaks the estimator contract: ModelError
        naming ``owner`` (the updates before the bad one are stored, each one whole)."""
        try:
            for u in updates:
                key = (owner, u.subject, u.track)
                t, age, nis, dof = float(u.t), float(u.age), float(u.nis), int(u.dof)
                cond_r, cond_s = float(u.cond_r), float(u.cond_s)
                rows = self._updates.get(key)
                if rows is None:
                    rows = self._updates[key] = _UpdateRows()
                rows.t.append(t)
                rows.age.append(age)
                rows.nis.append(nis)
                rows.dof.append(dof)
                rows.cond_r.append(cond_r)
                rows.cond_s.append(cond_s)
        except (AttributeError, TypeError, ValueError) as exc:
            raise ModelError(
                f"updates of {owner}: not a sequence of UpdateRecord with numeric fields "
                f"({type(exc).__name__}: {exc})"
            ) from None

    def add_events(self, events: Iterable[TrackEvent]) -> None:
        """Store track events; anything but an iterable of :class:`TrackEvent` breaks the
        estimator contract: ModelError."""
        try:
            events = tuple(events)
        except TypeError:
            raise ModelError(f"track events: not a sequence, got {type(events).__name__}") from None
        for e in events:
            if not isinstance(e, TrackEvent):
                raise ModelError(f"track events: expected TrackEvent, got {type(e).__name__}")
        self._events.extend(events)

    def count(self, counts: Mapping[str, int]) -> None:
        """Add estimator counters (summed by name): a mapping of names to integers ≥ 0 (else
        ConfigError naming the counter; a float would be truncated)."""
        try:
            items = counts.items()
        except AttributeError:
            raise ConfigError(
                f"Recorder.count: expected a mapping, got {type(counts).__name__}"
            ) from None
        for k, v in items:
            self._counts[k] = self._counts.get(k, 0) + checks.count(
                v, f"Recorder.count: counter {k!r}", low=0
            )

    def _belief_series(self, key: SeriesKey, start: int) -> BeliefSeries:
        r = self._beliefs[key]
        d = r.dim
        return BeliefSeries(
            owner=key[0],
            subject=key[1],
            track=key[2],
            frame=r.frame,
            t=np.asarray(r.t[start:], dtype=float),
            mean=np.asarray(r.mean[start:], dtype=float).reshape(-1, d),
            cov=np.asarray(r.cov[start:], dtype=float).reshape(-1, d, d),
            age=np.asarray(r.age[start:], dtype=float),
            info={k: np.asarray(v[start:], dtype=float) for k, v in r.info.items()},
        )

    def _update_series(self, key: SeriesKey, start: int) -> UpdateSeries:
        r = self._updates[key]
        return UpdateSeries(
            owner=key[0],
            subject=key[1],
            track=key[2],
            t=np.asarray(r.t[start:], dtype=float),
            age=np.asarray(r.age[start:], dtype=float),
            nis=np.asarray(r.nis[start:], dtype=float),
            dof=np.asarray(r.dof[start:], dtype=np.int64),
            cond_r=np.asarray(r.cond_r[start:], dtype=float),
            cond_s=np.asarray(r.cond_s[start:], dtype=float),
        )

    def results(self) -> Estimates:
        """Everything recorded so far, in (owner, subject) order."""
        return Estimates(
            estimator=self.estimator,
            beliefs=tuple(self._belief_series(k, 0) for k in sorted(self._beliefs)),
            updates=tuple(self._update_series(k, 0) for k in sorted(self._updates)),
            events=_by_time(self._events),
            counts=dict(self._counts),
        )

    def take_new(self) -> Estimates:
        """What was recorded since the previous call (counters: the running totals)."""
        beliefs = []
        for k in sorted(self._beliefs):
            start = self._sent_beliefs.get(k, 0)
            self._sent_beliefs[k] = len(self._beliefs[k].t)
            if len(self._beliefs[k].t) > start:
                beliefs.append(self._belief_series(k, start))
        updates = []
        for k in sorted(self._updates):
            start = self._sent_updates.get(k, 0)
            self._sent_updates[k] = len(self._updates[k].t)
            if len(self._updates[k].t) > start:
                updates.append(self._update_series(k, start))
        events = self._events[self._sent_events :]
        self._sent_events = len(self._events)
        return Estimates(
            estimator=self.estimator,
            beliefs=tuple(beliefs),
            updates=tuple(updates),
            events=_by_time(events),
            counts=dict(self._counts),
        )


def _by_time(events: Sequence[TrackEvent]) -> tuple[TrackEvent, ...]:
    """Events sorted by time (stable: one estimator's events at one time keep their order)."""
    return tuple(sorted(events, key=lambda e: e.t))


def concatenate(parts: Sequence[Estimates]) -> Estimates:
    """Join increments of the same estimators (e.g. a node's reports) into one record."""
    if not parts:
        raise ConfigError("concatenate: no estimates to join")
    for i, part in enumerate(parts):
        if not isinstance(part, Estimates):
            raise ConfigError(f"concatenate: part {i} is a {type(part).__name__}, not Estimates")
    beliefs: dict[SeriesKey, list[BeliefSeries]] = {}
    updates: dict[SeriesKey, list[UpdateSeries]] = {}
    for p in parts:
        for s in p.beliefs:
            beliefs.setdefault(s.key, []).append(s)
        for u in p.updates:
            updates.setdefault(u.key, []).append(u)

    def cat(items: Sequence[Any], name: str) -> NDArray[Any]:
        return np.concatenate([getattr(i, name) for i in items])

    joined_beliefs = []
    for key in sorted(beliefs):
        items = beliefs[key]
        names = sorted({n for s in items for n in s.info})
        joined_beliefs.append(
            BeliefSeries(
                owner=key[0],
                subject=key[1],
                track=key[2],
                frame=items[0].frame,
                t=cat(items, "t"),
                mean=cat(items, "mean"),
                cov=cat(items, "cov"),
                age=cat(items, "age"),
                info={
                    n: np.concatenate([s.info.get(n, np.full(s.t.size, np.nan)) for s in items])
                    for n in names
                },
            )
        )
    joined_updates = [
        UpdateSeries(
            owner=key[0],
            subject=key[1],
            track=key[2],
            **{
                name: cat(updates[key], name)
                for name in ("t", "age", "nis", "dof", "cond_r", "cond_s")
            },
        )
        for key in sorted(updates)
    ]
    return Estimates(
        estimator=parts[0].estimator,
        beliefs=tuple(joined_beliefs),
        updates=tuple(joined_updates),
        events=tuple(e for p in parts for e in p.events),
        counts=dict(parts[-1].counts),
    )
