"""The calibration window: the stretch of data an error model is fitted on, stated with the fit.

A fitted error model means little without the data it was fitted on. The real-data
experiments fit on one stretch of a recording and evaluate on another (or fit on a separate
recording), and every fit record carries a :class:`CalibrationWindow` so that summary.json says
which. A window is the closed time interval ``[start_s, end_s]`` (seconds, on the recording's
own clock) of ``source`` (the file or folder it was cut from, and the robot where it matters):
an event at time ``t`` is in the window when ``start_s ≤ t ≤ end_s``, and fits that resample
on a time grid use grid points inside it.

How the experiments choose their windows (one function each, so the choice reads as a
sentence where it is made):

- :func:`leading_fraction` — the first ``fraction`` of a span;
- :func:`split_span` — a span cut in two at one instant, one side to fit on and the other
  to score on, chosen by a user's ``first-half`` / ``second-half`` / ``:T`` / ``T:``
  (mrclam-cl's ``--calibration-window``; by default the first half of the run is fitted on and
  the second half is the held-out check);
- :func:`following` — ``length_s`` seconds from a start (mrclam-association: the first
  minute after every robot has started moving; the evaluation starts where it ends);
- :func:`spanning` — from the first to the last time of a recording (a separate calibration
  recording such as the UWB one, or a fit that deliberately uses the whole run);
- :func:`odometry_and_truth` — where one robot has both odometry and ground truth (fits that
  use a robot's whole recording, as the seed-000 replay does).

A window with ``end_s ≤ start_s`` (or an end that is not a finite number) is refused with
:class:`ConfigError`; a fit whose window holds too little data refuses with :class:`DataError`
naming the window.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from relloc.core.checks import number
from relloc.datasets.mrclam import RobotData
from relloc.errors import ConfigError, DataError


@dataclass(frozen=True)
class CalibrationWindow:
    """``[start_s, end_s]`` (s, the recording's clock) of ``source``; see the module docstring."""

    start_s: float
    end_s: float
    source: str

    def __post_init__(self) -> None:
        where = f"CalibrationWindow of {self.source!r}"
        if not self.source:
            raise ConfigError("CalibrationWindow.source: must name the data it was cut from")
        number(self.start_s, f"{where}: start_s")
        number(self.end_s, f"{where}: end_s")
        if not self.end_s > self.start_s:
            raise ConfigError(
                f"{where}: empty window [{self.start_s:g}, {self.end_s:g}] s (end_s ≤ start_s)"
            )

    @property
    def duration_s(self) -> float:
        """``end_s − start_s``."""
        return float(self.end_s - self.start_s)

    def contains(self, t: ArrayLike) -> NDArray[np.bool_]:
        """Mask of the times ``start_s ≤ t ≤ end_s``."""
        tt = np.asarray(t, dtype=float)
        return np.asarray((tt >= self.start_s) & (tt <= self.end_s))

    def describe(self) -> str:
        """One line for reports and error messages."""
        return f"[{self.start_s:.2f}, {self.end_s:.2f}] s of {self.source}"

    def too_little(self, what: str) -> DataError:
        """The error a fit raises when this window holds too little ``what`` to fit on."""
        return DataError(f"calibration window {self.describe()}: {what}")

    def to_dict(self) -> dict[str, float | str]:
        """JSON-ready ``{"start_s", "end_s", "source"}``."""
        return {"start_s": float(self.start_s), "end_s": float(self.end_s), "source": self.source}


def leading_fraction(
    start_s: float, end_s: float, fraction: float, source: str
) -> CalibrationWindow:
    """The first ``fraction`` of ``[start_s, end_s]``: ``[start_s, start_s + fraction·(end_s −
    start_s)]`` (the rest of the span is left for evaluation)."""
    if not 0.0 < fraction <= 1.0:
        raise ConfigError(f"leading_fraction: fraction must be in (0, 1], got {fraction}")
    return CalibrationWindow(start_s, start_s + fraction * (end_s - start_s), source)


#: The named choices of :func:`split_span` (the first is the default).
SPLIT_CHOICES = ("first-half", "second-half")


def split_span(
    spec: str, start_s: float, end_s: float, source: str, flag: str = "--calibration-window"
) -> tuple[CalibrationWindow, CalibrationWindow]:
    """``(fitted on, scored on)``: the span ``[start_s, end_s]`` cut at one instant ``c``.

    ``spec`` (as a user types it; ``flag`` names it in errors):

    - ``first-half``: ``c = start_s + (end_s − start_s)/2``, fit on ``[start_s, c]``, score
      ``[c, end_s]``;
    - ``second-half``: the same ``c``, fit on ``[c, end_s]``, score ``[start_s, c]``;
    - ``:T``: ``c = T``, fit on ``[start_s, T]``, score ``[T, end_s]``;
    - ``T:``: ``c = T``, fit on ``[T, end_s]``, score ``[start_s, T]``;

    ``T`` in seconds on the recording's clock (the one the summaries state windows in), strictly
    inside the span. Anything else is a :class:`ConfigError` naming ``flag``."""
    if spec in SPLIT_CHOICES:
        cut, fit_first = start_s + 0.5 * (end_s - start_s), spec == "first-half"
    else:
        head, colon, tail = spec.partition(":")
        if not colon or bool(head.strip()) == bool(tail.strip()):
            raise ConfigError(
                f"{flag} {spec!r}: expected one of {', '.join(SPLIT_CHOICES)}, ':T' (fit up to "
                "T s, score after) or 'T:' (fit from T s, score before)"
            )
        try:
            cut = float(head or tail)
        except ValueError:
            raise ConfigError(
                f"{flag} {spec!r}: {head or tail!r} is not a time in seconds"
            ) from None
        fit_first = not head.strip()
        if not (math.isfinite(cut) and start_s < cut < end_s):
            raise ConfigError(
                f"{flag} {spec!r}: the cut must lie strictly inside the run's span "
                f"[{start_s:.2f}, {end_s:.2f}] s of {source}"
            )
    before, after = CalibrationWindow(start_s, cut, source), CalibrationWindow(cut, end_s, source)
    return (before, after) if fit_first else (after, before)


def following(start_s: float, length_s: float, source: str) -> CalibrationWindow:
    """``[start_s, start_s + length_s]``."""
    return CalibrationWindow(start_s, start_s + length_s, source)


def spanning(t: ArrayLike, source: str) -> CalibrationWindow:
    """From the first to the last of the times ``t`` (a whole recording). Times that span no
    interval (none, one instant) or are not finite are a DataError naming ``source``."""
    tt = np.asarray(t, dtype=float)
    if tt.size == 0:
        raise DataError(f"{source}: no time stamps, so no calibration window")
    if not np.isfinite(tt).all():
        raise DataError(f"{source}: a time stamp is not finite, so no calibration window")
    start, end = float(tt.min()), float(tt.max())
    if not end > start:
        raise DataError(f"{source}: every time stamp is {start:g} s, so no calibration window")
    return CalibrationWindow(start, end, source)


def odometry_and_truth(robot: RobotData, source: str) -> CalibrationWindow:
    """``[max(first odometry, first ground truth), min(last odometry, last ground truth)]`` of
    ``robot``: everywhere it has both (DataError naming the robot when it lacks either or the
    two do not overlap)."""
    odo, gt = robot.odometry.t, robot.groundtruth.t
    if len(odo) == 0 or len(gt) == 0:
        raise DataError(f"{source}: robot {robot.subject} lacks odometry or ground truth")
    start, end = max(float(odo[0]), float(gt[0])), min(float(odo[-1]), float(gt[-1]))
    if not end > start:
        raise DataError(
            f"{source}: robot {robot.subject}'s odometry [{odo[0]:.2f}, {odo[-1]:.2f}] s and "
            f"ground truth [{gt[0]:.2f}, {gt[-1]:.2f}] s do not overlap"
        )
    return CalibrationWindow(start, end, source)
