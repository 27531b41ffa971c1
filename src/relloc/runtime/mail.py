"""``mail``: what one robot's estimator sends its teammates' estimators, over the wire.

The estimators of seed 002 exchange *equivalent measurements* (Eq. 8,
:class:`~relloc.fusion.messages.EquivalentMeasurement`) through the contract's
``outbox``/``receive``. A node packs what its estimator sent since its last mail — each message
stamped with the event that produced it — together with its *progress* (every event before it
processed and its messages sent; see :mod:`relloc.runtime.estimation`) into one ``mail`` body:

- ``progress``;
- per message ``stamps (m,)``, ``subjects (m,)`` (robot ids) and ``sizes (m,)`` (its tracks);
- the tracks of all messages stacked: ``means``/``prior_means (K, 4)``,
  ``covs``/``prior_covs (K, 4, 4)``, ``weights (K,)`` with ``K = Σ sizes``.

A mail too large for the size limit is split into several; every part but the last carries as
progress the earliest stamp of the whole mail (true already — the sender had processed every
event before it), so a receiver never runs ahead of a part still on its way.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from itertools import groupby
from typing import Any

import numpy as np

from relloc.errors import DataError
from relloc.fusion.messages import EquivalentMeasurement

TRACK_BYTES = 400
"""Upper bound of one track's size in an encoded mail (41 floats of at most 9 bytes)."""
HEADER_BYTES = 1024


def mail_body(
    progress: float,
    sent: Sequence[tuple[float, Any]],
    roster: Sequence[str],
    max_bytes: int,
) -> list[dict[str, Any]]:
    """The ``mail`` bodies of ``sent`` (``(stamp, message)`` in order) and ``progress``."""
    for _, m in sent:
        if not isinstance(m, EquivalentMeasurement):
            raise DataError(
                f"mail: cannot send a {type(m).__name__} (only equivalent measurements)"
            )
    per_part = max(1, (max_bytes - HEADER_BYTES) // TRACK_BYTES)
    parts: list[list[tuple[float, EquivalentMeasurement]]] = [[]]
    tracks = 0
    for stamp, m in sent:
        if parts[-1] and tracks + m.size > per_part:
            parts.append([])
            tracks = 0
        parts[-1].append((stamp, m))
        tracks += m.size
    early = min((s for s, _ in sent), default=progress)
    return [
        _body(progress if i == len(parts) - 1 else early, part, roster)
        for i, part in enumerate(parts)
    ]


def _body(
    progress: float, part: Sequence[tuple[float, EquivalentMeasurement]], roster: Sequence[str]
) -> dict[str, Any]:
    msgs = [m for _, m in part]

    def stack(name: str, shape: tuple[int, ...]) -> np.ndarray:
        if not msgs:
            return np.zeros((0, *shape))
        return np.concatenate([getattr(m, name) for m in msgs])

    return {
        "progress": float(progress),
        "stamps": np.array([s for s, _ in part], dtype=float),
        "subjects": [roster[m.subject] for m in msgs],
        "sizes": np.array([m.size for m in msgs], dtype=float),
        "means": stack("means", (4,)),
        "covs": stack("covs", (4, 4)),
        "prior_means": stack("prior_means", (4,)),
        "prior_covs": stack("prior_covs", (4, 4)),
        "weights": stack("weights", ()),
    }


def mail_items(
    body: Mapping[str, Any], roster: Sequence[str], sender: str
) -> list[tuple[float, list[EquivalentMeasurement]]]:
    """The messages of a validated ``mail`` body, grouped by stamp (in order). A body whose
    messages cannot be rebuilt — a subject off the roster (``unknown_target``) or that is the
    sender, a state or covariance out of bounds
    (:func:`~relloc.runtime.messages.check_state_bounds`) — raises
    :class:`~relloc.runtime.messages.MessageRejected`."""
    from relloc.runtime.messages import MessageRejected, check_state_bounds

    unknown = sorted(set(body["subjects"]) - set(roster))
    if unknown:
        raise MessageRejected("unknown_target", f"mail: subjects {unknown} are not on the roster")
    check_state_bounds(
        "mail",
        np.concatenate([body["means"], body["prior_means"]]),
        np.concatenate([body["covs"], body["prior_covs"]]),
    )
    ends = np.cumsum(body["sizes"].astype(np.int64))
    starts = ends - body["sizes"].astype(np.int64)
    out: list[tuple[float, EquivalentMeasurement]] = []
    for k, (a, b) in enumerate(zip(starts.tolist(), ends.tolist(), strict=True)):
        try:
            m = EquivalentMeasurement(
                sender=list(roster).index(sender),
                subject=list(roster).index(body["subjects"][k]),
                time=float(body["stamps"][k]),
                means=body["means"][a:b],
                covs=body["covs"][a:b],
                prior_means=body["prior_means"][a:b],
                prior_covs=body["prior_covs"][a:b],
                weights=body["weights"][a:b],
            )
        except DataError as exc:
            raise MessageRejected("malformed", f"mail: {exc}") from None
        out.append((float(body["stamps"][k]), m))
    return [(stamp, [m for _, m in group]) for stamp, group in groupby(out, key=lambda x: x[0])]
