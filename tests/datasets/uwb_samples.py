"""Realistic TIERS-layout UWB csv text and the checks every loaded recording must pass.

Shared by the UWB loader tests (imported by module name: pytest puts this folder on the path).
"""

from __future__ import annotations

import itertools

import numpy as np

from relloc.datasets.uwb import MAX_NODE_ID, MAX_RANGE, UwbRecording

HEADER = b"timestamp,node1,node2,uwb_range,mocap_range,tb_node1_yaw,tb_node2_yaw,error"
NODES = (1, 3, 4, 5)
#: One row per node pair and epoch, as in the shared recording.
PAIRS = tuple(itertools.combinations(NODES, 2))


def tiers_lines(n_epochs: int = 6, seed: int = 0) -> list[bytes]:
    """Header and data lines like the shared recording: 6 pairs per epoch, ~41 epochs/s."""
    rng = np.random.default_rng(seed)
    lines = [HEADER]
    t0 = 1671462954.0110343
    for k in range(n_epochs):
        t = t0 + 0.0245 * k + float(rng.uniform(0.0, 0.001))
        yaw = {n: float(rng.uniform(-np.pi, np.pi)) for n in NODES}
        for a, b in PAIRS:
            mocap = float(rng.uniform(1.0, 7.0))
            uwb = mocap + float(rng.normal(0.3, 0.08))
            cells = (t, float(a), float(b), uwb, mocap, yaw[a], yaw[b], uwb - mocap)
            lines.append(",".join(repr(c) for c in cells).encode())
    return lines


def tiers_text(n_epochs: int = 6, seed: int = 0) -> bytes:
    """:func:`tiers_lines` joined, with the trailing newline of a normal file."""
    return b"\n".join(tiers_lines(n_epochs, seed)) + b"\n"


def count_lines(data: bytes) -> tuple[int, int]:
    """(data rows, blank lines) of a file by the loader's documented definition."""
    lines = data.removeprefix(b"\xef\xbb\xbf").split(b"\n")
    if lines[-1] == b"":
        lines.pop()
    body = lines[1:]
    blank = sum(1 for line in body if not line.strip())
    return len(body) - blank, blank


def check_recording(rec: UwbRecording, data: bytes) -> None:
    """The row invariant and what every recording's arrays guarantee."""
    data_rows, blank = count_lines(data)
    assert rec.data_rows == data_rows and rec.blank_lines == blank
    assert rec.n_rows + rec.skipped.n_skipped == data_rows
    assert rec.n_rows >= 1
    for arr in (rec.t, rec.node1, rec.node2, rec.uwb_range, rec.mocap_range):
        assert arr.shape == (rec.n_rows,)
    assert np.all(np.isfinite(rec.t)) and np.all(np.diff(rec.t) >= 0.0)
    assert np.all((rec.node1 >= 0) & (rec.node1 <= MAX_NODE_ID))
    assert np.all((rec.node2 >= 0) & (rec.node2 <= MAX_NODE_ID))
    assert np.all(rec.node1 != rec.node2)
    for r in (rec.uwb_range, rec.mocap_range):
        assert np.all((r > 0.0) & (r <= MAX_RANGE))
    assert len(rec.skipped.examples) == min(rec.skipped.n_skipped, 5)


Row = tuple[float, int, int, float, float]


def recording_rows(rec: UwbRecording) -> list[Row]:
    """The kept rows of ``rec`` as ``(t, node1, node2, uwb_range, mocap_range)``."""
    return list(
        zip(
            rec.t.tolist(),
            rec.node1.tolist(),
            rec.node2.tolist(),
            rec.uwb_range.tolist(),
            rec.mocap_range.tolist(),
            strict=True,
        )
    )
