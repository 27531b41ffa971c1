"""The checks a loaded table makes on itself, so that data built by hand or by a transform obeys
the loaders' rules too (:class:`relloc.datasets.mrclam.GroundTruth` and its siblings,
:class:`relloc.datasets.uwb.UwbRecording`)."""

from __future__ import annotations

from collections.abc import Collection, Mapping

import numpy as np
from numpy.typing import ArrayLike

from relloc.errors import DataError


def check_columns(
    where: str,
    t: ArrayLike,
    columns: Mapping[str, ArrayLike],
    *,
    integer: Collection[str] = (),
    strictly: bool = False,
) -> None:
    """DataError naming ``where`` and the column unless ``t`` and every column are 1-D arrays of
    one length holding finite numbers (integers for the columns named in ``integer``) and ``t``
    is non-decreasing (strictly increasing with ``strictly``): never an IndexError, a NaN fit or
    a wrong answer from unsorted times later."""
    n = np.shape(t)[0] if np.ndim(t) == 1 else None
    for key, value in {"t": t, **columns}.items():
        a = np.asarray(value)
        if a.ndim != 1 or a.shape[0] != n:
            raise DataError(
                f"{where}.{key}: expected a 1-D array of the length of t, got shape {a.shape}"
            )
        if key in integer:
            if a.dtype.kind not in "iu":
                raise DataError(f"{where}.{key}: values must be integers")
        elif a.dtype.kind not in "fiu" or not np.isfinite(a).all():
            raise DataError(f"{where}.{key}: values must be finite numbers")
    times = np.asarray(t, dtype=float)
    steps = np.diff(times)
    bad = np.flatnonzero(steps <= 0 if strictly else steps < 0)
    if bad.size:
        i = int(bad[0])
        order = "strictly increasing" if strictly else "non-decreasing"
        raise DataError(
            f"{where}.t: times must be {order}; t[{i}] = {float(times[i])!r}, "
            f"t[{i + 1}] = {float(times[i + 1])!r}"
        )
