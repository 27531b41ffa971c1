"""A small measurement table shared by the recording tests."""

from __future__ import annotations

from typing import Any

import numpy as np

from relloc.core.recording import Measurements, kind_code

RBE = kind_code("range_bearing_elevation")


def three_rows(**overrides: Any) -> Measurements:
    """Three range-bearing-elevation rows of robots 0 and 1 at 0.1 s and 0.2 s; any column
    replaced by ``overrides``."""
    fields: dict[str, Any] = dict(
        t=np.array([0.1, 0.1, 0.2]),
        kind=np.full(3, RBE),
        observer=np.array([0, 1, 0]),
        target=np.array([1, 0, 1]),
        value=np.array([[1.0, 0.1, 0.0], [1.0, -0.1, 0.0], [1.1, 0.1, 0.0]]),
        sigma=np.full((3, 3), 0.01),
    )
    fields.update(overrides)
    return Measurements(**fields)
