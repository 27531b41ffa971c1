"""``rows``: a robot's own readings of one window, shared with its teammates (seed 001).

Seed 001's agents share their measurements: every robot publishes, once per tick, the rows it
recorded in the window ``[t_{k−1}, t_k)`` (the run's last window: ``[t_{n−1}, t_n]``), of any kind
— bearings or range-bearings of a robot or a landmark, absolute pose fixes — so that every agent
can run the team's information filter on all of them. The message is sent even when the window
holds no reading: its header time tells the receivers that the sender's readings up to ``t_k``
are all in. A body holds, per row, ``stamps``, ``kinds`` (names of
:data:`relloc.core.recording.KINDS`), ``subjects`` (the target robot's id, ``""`` for none),
``landmarks`` and ``sensors`` (indices, −1 for no landmark), and the values and σ of every row
flattened in row order, each row contributing its kind's width (σ −1: not stated).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from relloc.core.recording import KIND_NAMES, KINDS, NO_TARGET, VALUE_WIDTH, Measurements
from relloc.errors import DataError
from relloc.runtime.messages import MessageRejected

UNSTATED_SIGMA = -1.0
MAX_INDEX = 2**31 - 1
"""Largest landmark or sensor index a body may carry (they travel as numbers)."""


def rows_body(rows: Measurements, roster: Sequence[str]) -> dict[str, Any]:
    """The ``rows`` body of one robot's readings (module docstring)."""
    assert rows.landmark is not None and rows.sensor is not None
    widths = np.array([KINDS[KIND_NAMES[k]].dim for k in rows.kind], dtype=np.int64)
    keep = np.arange(VALUE_WIDTH)[None, :] < widths[:, None]
    sigma = np.where(np.isnan(rows.sigma), UNSTATED_SIGMA, rows.sigma)
    return {
        "stamps": rows.t,
        "kinds": [KIND_NAMES[k] for k in rows.kind],
        "subjects": [roster[j] if j >= 0 else "" for j in rows.target],
        "landmarks": rows.landmark.astype(float),
        "sensors": rows.sensor.astype(float),
        "values": rows.value[keep],
        "sigmas": sigma[keep],
    }


def rows_from_body(
    body: Mapping[str, Any], roster: Sequence[str], sender: str, landmarks: int | None = None
) -> Measurements:
    """The readings of a validated ``rows`` body from ``sender``; anything that does not make
    a valid table raises :class:`~relloc.runtime.messages.MessageRejected`, and so does a
    landmark index beyond the receiver's map of ``landmarks`` (``unknown_landmark``; None: the
    receiver has no map to check against)."""
    m = body["stamps"].shape[0]
    if not (len(body["kinds"]) == len(body["subjects"]) == m):
        raise MessageRejected("shape", "rows: per-row lengths differ")
    if body["landmarks"].shape[0] != m or body["sensors"].shape[0] != m:
        raise MessageRejected("shape", "rows: per-row lengths differ")
    unknown_kinds = sorted(set(body["kinds"]) - set(KIND_NAMES))
    if unknown_kinds:
        raise MessageRejected("malformed", f"rows: unknown kinds {unknown_kinds}")
    unknown = sorted(set(body["subjects"]) - {*roster, ""})
    if unknown:
        raise MessageRejected("unknown_target", f"rows: subjects {unknown} are not on the roster")
    widths = np.array([KINDS[k].dim for k in body["kinds"]], dtype=np.int64)
    if body["values"].shape[0] != widths.sum() or body["sigmas"].shape[0] != widths.sum():
        raise MessageRejected("shape", "rows: values and sigmas do not match the kinds' widths")
    ints = np.concatenate([body["landmarks"], body["sensors"]])
    if (
        np.any(ints != np.round(ints))
        or np.any(body["landmarks"] < NO_TARGET)
        or np.any(np.abs(ints) > MAX_INDEX)
    ):
        raise MessageRejected("malformed", "rows: landmarks and sensors must be integers")
    if landmarks is not None and np.any(body["landmarks"] >= landmarks):
        raise MessageRejected("unknown_landmark", f"rows: a landmark beyond the map's {landmarks}")
    sig = body["sigmas"]
    if np.any((sig <= 0) & (sig != UNSTATED_SIGMA)):
        raise MessageRejected("malformed", "rows: sigma must be > 0 (or −1: not stated)")
    keep = np.arange(VALUE_WIDTH)[None, :] < widths[:, None]
    value = np.full((m, VALUE_WIDTH), np.nan)
    sigma = np.full((m, VALUE_WIDTH), np.nan)
    value[keep] = body["values"]
    sigma[keep] = np.where(sig == UNSTATED_SIGMA, np.nan, sig)
    try:
        return Measurements(
            t=body["stamps"],
            kind=np.array([KIND_NAMES.index(k) for k in body["kinds"]], dtype=np.int64),
            observer=np.full(m, list(roster).index(sender), dtype=np.int64),
            target=np.array(
                [list(roster).index(s) if s else NO_TARGET for s in body["subjects"]],
                dtype=np.int64,
            ),
            value=value,
            sigma=sigma,
            landmark=body["landmarks"].astype(np.int64),
            sensor=body["sensors"].astype(np.int64),
        )
    except DataError as exc:
        raise MessageRejected("malformed", f"rows: {exc}") from None
