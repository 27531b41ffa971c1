"""Checks of settings values: each returns the value as a plain ``float`` or ``int``, or raises
a :class:`~relloc.errors.ConfigError` naming the field (``where``) — also for a value of the
wrong type (a string, ``None``, a ``bool``), which arithmetic would reject with a raw
``TypeError`` or, worse, accept (``"0.1" * 2``). :func:`floats` does the same for an array
argument, with the error its caller names (a DataError for data, a ModelError for a state)."""

from __future__ import annotations

import math
import numbers
from collections.abc import Collection, Iterable, Mapping, Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from relloc.errors import ConfigError, DataError, RellocError

_FLOAT64 = np.dtype(np.float64)


def number(
    value: object,
    where: str,
    *,
    low: float = -math.inf,
    high: float = math.inf,
    open_low: bool = False,
    open_high: bool = False,
) -> float:
    """``value`` as a finite float in ``[low, high]`` (an open end with ``open_low`` or
    ``open_high``)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise ConfigError(f"{where}: expected a number, got {value!r:.40}")
    try:
        x = float(value)
    except OverflowError:  # an integer beyond every float
        x = math.inf
    below = x <= low if open_low else x < low
    above = x >= high if open_high else x > high
    if not math.isfinite(x) or below or above:
        left = "(" if open_low or not math.isfinite(low) else "["
        right = ")" if open_high or not math.isfinite(high) else "]"
        interval = f"{left}{low:g}, {high:g}{right}"
        raise ConfigError(f"{where}: must be a finite number in {interval}, got {value!r:.40}")
    return x


def positive(value: object, where: str) -> float:
    """``value`` as a finite float > 0."""
    return number(value, where, low=0.0, open_low=True)


#: The longest prediction step (s) an estimator takes, about 32,000 years: longer is no robot's
#: (a clock in the wrong unit, or a first stamp read as a step), and the powers of the step in
#: a prediction's covariance overflow double precision long before the step does (a relative
#: filter's at 1e150 s).
MAX_TIME_STEP_S = 1e12


def time_step(dt: object, where: str) -> float:
    """``dt`` as a float in ``0 … MAX_TIME_STEP_S`` (a ConfigError naming ``where``
    otherwise). A float takes a fast path: :func:`number`'s type checks cost a tracker's
    prediction about 2.5 %."""
    if isinstance(dt, float) and 0.0 <= dt <= MAX_TIME_STEP_S:
        return float(dt)
    return number(dt, f"{where}: dt", low=0.0, high=MAX_TIME_STEP_S)


def probability(value: object, where: str) -> float:
    """``value`` as a probability strictly between 0 and 1 (a χ² gate's: one of 1 is
    infinite)."""
    return number(value, where, low=0.0, high=1.0, open_low=True, open_high=True)


def count(value: object, where: str, *, low: int = 1, high: int | None = None) -> int:
    """``value`` as an integer ≥ ``low`` (and ≤ ``high`` when given; a whole float such as
    ``3.0`` is not an integer)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise ConfigError(f"{where}: expected an integer, got {value!r:.40}")
    n = int(value)
    if n < low or (high is not None and n > high):
        bounds = f"≥ {low}" if high is None else f"in {low}…{high}"
        raise ConfigError(f"{where}: must be {bounds}, got {n!r:.40}")
    return n


def sequence(value: object, where: str, what: str, *, length: int | None = None) -> Sequence[Any]:
    """``value`` if it is a list, tuple or array (not a string or bytes, which iterate as
    characters), of ``length`` items when given; else ConfigError ``where: expected what``."""
    if (
        isinstance(value, (str, bytes))
        or not isinstance(value, Sequence | np.ndarray)
        or (length is not None and len(value) != length)
    ):
        raise ConfigError(f"{where}: expected {what}, got {value!r:.40}")
    return value  # type: ignore[return-value]


def refuse_unread(
    target: str,
    given: Iterable[str],
    read_by: Mapping[str, Collection[str]],
    *,
    label: str | None = None,
    flags: Mapping[str, str] | None = None,
) -> None:
    """ConfigError naming the flag of the first option in ``given`` that ``target`` does not
    read: ``read_by`` maps an option to the targets that read it (an option it does not list is
    read by every target). A flag that would be ignored is a typo or a misunderstanding, never
    dropped silently. ``label`` names the target in the message (default ``target``);
    ``flags`` the flag of an option whose flag is not ``--option`` (``_`` becoming ``-``)."""
    for option in given:
        readers = read_by.get(option)
        if readers is not None and target not in readers:
            flag = (flags or {}).get(option, "--" + option.replace("_", "-"))
            raise ConfigError(
                f"{flag}: {label or target} does not read it; read by {', '.join(readers)}"
            )


def floats(value: object, where: str, error: type[RellocError] = DataError) -> NDArray[np.float64]:
    """``value`` as a float array, or ``error`` naming ``where`` when it holds anything but
    integers and floats: ``None`` or an object array (``np.asarray(…, dtype=float)`` reads
    ``None`` as NaN), text or ragged nesting (a raw ``ValueError``), booleans (read as 0 and 1)
    or complex numbers (their imaginary part dropped). A float64 array comes back as it is;
    shapes and values are the caller's to check."""
    if type(value) is np.ndarray and value.dtype is _FLOAT64:
        return value
    try:
        raw = np.asarray(value)
    except ValueError as exc:  # ragged nesting
        raise error(f"{where}: expected an array of numbers ({exc})") from None
    if raw.dtype.kind not in "iuf":
        raise error(f"{where}: expected real numbers, got {raw.dtype} ({value!r:.40})")
    if not isinstance(value, np.ndarray) and raw.size and _holds_a_bool(value):
        raise error(f"{where}: expected real numbers, got a bool among them ({value!r:.40})")
    return np.asarray(raw, dtype=float)


def _holds_a_bool(value: object) -> bool:
    """Whether a nesting of numbers holds a bool, which numpy turns into 0 or 1 when the other
    entries are numbers (``np.asarray([True, 2.5])`` is ``[1.0, 2.5]``)."""
    return any(isinstance(x, (bool, np.bool_)) for x in np.asarray(value, dtype=object).flat)
