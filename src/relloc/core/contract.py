"""The estimator contract: the one interface every relloc estimator implements.

An estimator is an object that lives on a clock and is driven by
:func:`relloc.core.events.run_events` (in-process) or by a robot node (window by window over
the network). At every event time ``t`` the loop calls, in this order,

1. :meth:`Estimator.advance` ``(t, odometry)`` — move the belief from the previous event to ``t``
   with the velocities every robot reported last (:class:`HeldOdometry`, zero-order hold);
2. :meth:`Estimator.measure` ``(batch)`` — the readings stamped at ``t`` (a
   :class:`~relloc.core.recording.Measurements` table; the estimator uses the rows it models —
   its own sensors, or a team's — and counts what it ignores);
3. :meth:`Estimator.outbox` — what it wants to send to teammates now (seed 001 shared readings,
   seed 002 equivalent measurements); the loop hands every message to every other estimator's
   :meth:`Estimator.receive`;
4. at record times, :meth:`Estimator.beliefs` — what it currently believes, one
   :class:`Belief` per subject, each in a named frame of :mod:`relloc.pipeline.frames` (an
   estimator of many subjects in one frame may return them as one :class:`BeliefStack`, which
   the recorder stores without building a :class:`Belief` per subject).

After the loop (and whenever a node ships a report), :meth:`Estimator.take_updates` and
:meth:`Estimator.take_events` hand over the per-update diagnostics (NIS, conditioning of ``R``
and ``S``) and the track events (created, deleted, re-created) recorded since the last call.
An estimator that counts what it did not use (rows of a kind it does not model, of an unknown
target, ...) may also offer ``take_counts() -> dict[str, int]`` (the counts since the last call;
:class:`Silent` gives none); the loop adds them to :attr:`Estimates.counts
<relloc.core.estimates.Estimates.counts>`.

Estimators keep no reference to the truth and never read :attr:`Measurements.origin`.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Literal, Protocol, overload, runtime_checkable

import numpy as np
from numpy.typing import NDArray

from relloc.core.recording import Measurements
from relloc.errors import DataError

Array = NDArray[np.float64]
EventKind = Literal["created", "deleted", "recreated"]


@dataclass(frozen=True)
class HeldOdometry:
    """The odometry in force over the step that ends at the event time.

    ``velocity (n, 4)``: each robot's last reported body velocity ``(v_x, v_y, v_z, ω_z)``
    (zero before its first report); ``stamp (n,)``: the time stamp of that report (NaN before
    the first) — estimators that treat stale odometry differently read it.
    """

    velocity: Array
    stamp: Array

    @staticmethod
    def still(n: int) -> HeldOdometry:
        """No robot has reported yet: every velocity zero, every stamp NaN."""
        return HeldOdometry(velocity=np.zeros((n, 4)), stamp=np.full(n, np.nan))


@dataclass(frozen=True)
class Belief:
    """What an estimator believes about one subject now.

    ``frame`` names the state layout and its reference (a key of
    :data:`relloc.pipeline.frames.FRAMES`); ``age`` is the time since this belief (track) was
    started; ``info`` carries scalar diagnostics recorded beside it (e.g. a mixture's weight);
    ``track`` tells apart several tracks one estimator runs of the same subject (e.g. filter
    variants or initial guesses side by side; empty for the one track).
    """

    subject: str
    frame: str
    mean: Array
    cov: Array
    age: float = 0.0
    info: Mapping[str, float] = field(default_factory=dict)
    track: str = ""

    def __post_init__(self) -> None:
        mean = np.asarray(self.mean, dtype=float).reshape(-1)
        cov = np.asarray(self.cov, dtype=float)
        if cov.shape != (mean.size, mean.size):
            raise DataError(
                f"belief of {self.subject}: covariance {cov.shape} does not match state {mean.size}"
            )
        object.__setattr__(self, "mean", mean)
        object.__setattr__(self, "cov", cov)


class BeliefStack(Sequence[Belief]):
    """The beliefs of ``subjects`` (``m`` of them) in one ``frame``, all of one ``age``, as
    stacked arrays ``mean (m, d)`` and ``cov (m, d, d)`` — what a centralised filter holds for
    its team. It is a sequence of :class:`Belief` (each built when it is read), and
    :meth:`relloc.core.estimates.Recorder.record` stores it as it is."""

    __slots__ = ("age", "cov", "frame", "mean", "subjects")

    def __init__(
        self, subjects: Sequence[str], frame: str, mean: Array, cov: Array, age: float = 0.0
    ) -> None:
        self.subjects = tuple(subjects)
        self.frame = frame
        self.mean = np.asarray(mean, dtype=float)
        self.cov = np.asarray(cov, dtype=float)
        self.age = float(age)
        m = len(self.subjects)
        if self.mean.ndim != 2 or self.mean.shape[0] != m:
            raise DataError(f"belief stack: mean {self.mean.shape} for {m} subjects")
        d = self.mean.shape[1]
        if self.cov.shape != (m, d, d):
            raise DataError(f"belief stack: covariance {self.cov.shape} for means {(m, d)}")

    def __len__(self) -> int:
        return len(self.subjects)

    @overload
    def __getitem__(self, index: int) -> Belief: ...

    @overload
    def __getitem__(self, index: slice) -> list[Belief]: ...

    def __getitem__(self, index: int | slice) -> Belief | list[Belief]:
        if isinstance(index, slice):
            return [self[i] for i in range(len(self))[index]]
        i = range(len(self))[index]  # (IndexError outside, negative indices from the end)
        return Belief(self.subjects[i], self.frame, self.mean[i], self.cov[i], self.age)

    def __iter__(self) -> Iterator[Belief]:
        return (self[i] for i in range(len(self)))


@dataclass(frozen=True)
class UpdateRecord:
    """One measurement update of the belief of ``subject``: its normalised innovation squared
    ``nis = νᵀ S⁻¹ ν`` with ``dof`` degrees of freedom and ``log10`` condition numbers of ``R``
    and ``S`` (seed 000 §7.3); ``age`` is the track's age at the update; ``track`` as in
    :class:`Belief`."""

    t: float
    subject: str
    nis: float
    dof: int
    cond_r: float
    cond_s: float
    age: float = 0.0
    track: str = ""


@dataclass(frozen=True)
class TrackEvent:
    """A change in the set of tracks ``owner`` holds: ``subject``'s track created, deleted or
    re-created."""

    t: float
    owner: str
    subject: str
    kind: EventKind


@runtime_checkable
class Estimator(Protocol):
    """The contract (module docstring). ``owner`` is the robot that runs the estimator, or
    ``"team"`` for an estimator of the whole team (a centralised filter); ``name`` the method
    (``plkf``, ``eif``, ``gaussian_sum``, ...)."""

    owner: str
    name: str

    def advance(self, t: float, odometry: HeldOdometry) -> None: ...

    def measure(self, batch: Measurements) -> None: ...

    def beliefs(self) -> Sequence[Belief]: ...

    def outbox(self) -> list[Any]: ...

    def receive(self, messages: Sequence[Any]) -> None: ...

    def take_updates(self) -> list[UpdateRecord]: ...

    def take_events(self) -> list[TrackEvent]: ...


class Silent:
    """Defaults for an estimator that neither talks to teammates nor records updates or events
    (mix it in and override what the estimator does have)."""

    def outbox(self) -> list[Any]:
        return []

    def receive(self, messages: Sequence[Any]) -> None:
        return None

    def take_updates(self) -> list[UpdateRecord]:
        return []

    def take_events(self) -> list[TrackEvent]:
        return []

    def take_counts(self) -> dict[str, int]:
        return {}
