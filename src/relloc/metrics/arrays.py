"""Array arguments of the metrics as float arrays, refused with an error naming the argument
when they are not real numbers."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from relloc.errors import DataError, RellocError

Array = NDArray[np.float64]

_FLOAT64 = np.dtype(np.float64)


def floats(value: object, where: str, error: type[RellocError] = DataError) -> Array:
    """``value`` as a float array, or ``error`` naming ``where`` when it holds anything but
    integers and floats: ``None`` or an object array (``np.asarray(…, dtype=float)`` reads
    ``None`` as NaN), text or ragged nesting (a raw ``ValueError``), booleans (read as 0 and 1)
    or complex numbers (their imaginary part dropped). A float64 array comes back as it is."""
    if type(value) is np.ndarray and value.dtype is _FLOAT64:
        return value
    try:
        raw = np.asarray(value)
    except ValueError as exc:  # ragged nesting
        raise error(f"{where}: expected an array of numbers ({exc})") from exc
    if raw.dtype.kind not in "iuf":
        raise error(f"{where}: expected real numbers, got {raw.dtype} ({value!r:.40})")
    return np.asarray(raw, dtype=float)
