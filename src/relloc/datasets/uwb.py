"""Loader for inter-robot UWB range recordings in the TIERS csv layout.

The TIERS recording (Yu et al., arXiv:2304.06264; shared as ``../shared/data/uwb/tiers``) has the
header ``timestamp,node1,node2,uwb_range,mocap_range,tb_node1_yaw,tb_node2_yaw,error`` with one
row per (time, node pair); ``error = uwb_range − mocap_range``. Several rows share a timestamp
(one row per pair), so timestamps must be non-decreasing, not strictly increasing.

Every row is validated. A row that cannot be used (wrong column count, a non-number, NaN or inf,
a non-positive range, a node paired with itself, a timestamp going back in time, an ``error``
column that disagrees with ``uwb_range − mocap_range``) is skipped, counted, and the first few
are kept with their line number and reason in :attr:`UwbRecording.skipped`. A file that is
missing, empty, lacks a required column or has no usable row raises :class:`DataError` naming
the file.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from relloc.errors import DataError

REQUIRED_COLUMNS = ("timestamp", "node1", "node2", "uwb_range", "mocap_range")
OPTIONAL_COLUMNS = ("tb_node1_yaw", "tb_node2_yaw", "error")
#: Tolerance (m) on ``error − (uwb_range − mocap_range)`` before a row is called inconsistent.
ERROR_COLUMN_TOL = 1e-6
#: How many skipped rows are kept verbatim (with line number and reason).
MAX_SKIP_EXAMPLES = 5


@dataclass(frozen=True, kw_only=True)
class SkipReport:
    """Rows a loader could not use: how many, and the first few as ``"line N: reason"``."""

    count: int = 0
    examples: tuple[str, ...] = ()

    def describe(self) -> str:
        """One line for logs and reports."""
        if self.count == 0:
            return "no rows skipped"
        return f"{self.count} rows skipped (first: {'; '.join(self.examples)})"


@dataclass(frozen=True, kw_only=True)
class UwbRecording:
    """A validated UWB recording; arrays share one row index, in file order."""

    path: Path
    t: NDArray[np.float64]
    node1: NDArray[np.int64]
    node2: NDArray[np.int64]
    uwb_range: NDArray[np.float64]
    mocap_range: NDArray[np.float64]
    skipped: SkipReport = field(default_factory=SkipReport)

    @property
    def error(self) -> NDArray[np.float64]:
        """Range error ``uwb_range − mocap_range`` (m)."""
        return self.uwb_range - self.mocap_range

    @property
    def n_rows(self) -> int:
        """Number of usable rows."""
        return int(self.t.size)

    def links(self) -> list[tuple[int, int]]:
        """The distinct unordered node pairs, sorted."""
        pairs = {
            (min(a, b), max(a, b))
            for a, b in zip(self.node1.tolist(), self.node2.tolist(), strict=True)
        }
        return sorted(pairs)

    def link_mask(self, link: tuple[int, int]) -> NDArray[np.bool_]:
        """Rows of one unordered node pair."""
        a, b = link
        return ((self.node1 == a) & (self.node2 == b)) | ((self.node1 == b) & (self.node2 == a))


def _parse_float(text: str, column: str) -> float:
    try:
        value = float(text)
    except ValueError as exc:
        raise ValueError(f"{column}={text!r} is not a number") from exc
    if not math.isfinite(value):
        raise ValueError(f"{column}={text!r} is not finite")
    return value


def _parse_node(text: str, column: str) -> int:
    value = _parse_float(text, column)
    if value != round(value) or value < 0:
        raise ValueError(f"{column}={text!r} is not a non-negative integer node id")
    return round(value)


def load_uwb_csv(path: Path | str) -> UwbRecording:
    """Read and validate a TIERS-layout UWB csv (see module docstring)."""
    path = Path(path)
    if not path.is_file():
        raise DataError(f"{path}: UWB csv not found")
    try:
        handle = path.open(newline="")
    except OSError as exc:
        raise DataError(f"{path}: cannot open UWB csv: {exc}") from exc
    with handle:
        reader = csv.reader(handle)
        try:
            header = next(reader)
        except StopIteration:
            raise DataError(f"{path}: empty file (expected a header line)") from None
        except (csv.Error, UnicodeDecodeError) as exc:
            raise DataError(f"{path}: line 1: unreadable header: {exc}") from exc
        header = [h.strip() for h in header]
        missing = [c for c in REQUIRED_COLUMNS if c not in header]
        if missing:
            raise DataError(f"{path}: line 1: missing column(s) {missing}; header is {header}")
        col = {name: header.index(name) for name in header}
        has_error = "error" in col
        rows: list[tuple[float, int, int, float, float]] = []
        skipped = 0
        examples: list[str] = []
        last_t = -math.inf
        line_no = 1
        while True:
            try:
                raw = next(reader)
            except StopIteration:
                break
            except (csv.Error, UnicodeDecodeError) as exc:
                line_no += 1
                skipped += 1
                if len(examples) < MAX_SKIP_EXAMPLES:
                    examples.append(f"line {line_no}: unreadable ({exc})")
                continue
            line_no += 1
            if not raw or all(not c.strip() for c in raw):
                continue
            try:
                if len(raw) != len(header):
                    raise ValueError(f"{len(raw)} columns, header has {len(header)}")
                t = _parse_float(raw[col["timestamp"]], "timestamp")
                n1 = _parse_node(raw[col["node1"]], "node1")
                n2 = _parse_node(raw[col["node2"]], "node2")
                uwb = _parse_float(raw[col["uwb_range"]], "uwb_range")
                mocap = _parse_float(raw[col["mocap_range"]], "mocap_range")
                if n1 == n2:
                    raise ValueError(f"node1 = node2 = {n1}")
                if uwb <= 0.0 or mocap <= 0.0:
                    raise ValueError(f"non-positive range (uwb {uwb}, mocap {mocap})")
                if t < last_t:
                    raise ValueError(f"timestamp {t} goes back in time (previous {last_t})")
                if has_error:
                    err = _parse_float(raw[col["error"]], "error")
                    if abs(err - (uwb - mocap)) > ERROR_COLUMN_TOL:
                        raise ValueError(
                            f"error column {err} disagrees with uwb − mocap = {uwb - mocap}"
                        )
            except ValueError as exc:
                skipped += 1
                if len(examples) < MAX_SKIP_EXAMPLES:
                    examples.append(f"line {line_no}: {exc}")
                continue
            last_t = t
            rows.append((t, n1, n2, uwb, mocap))
    if not rows:
        raise DataError(
            f"{path}: no usable row ({skipped} skipped"
            + (f"; first: {'; '.join(examples)}" if examples else "")
            + ")"
        )
    arr = np.array(rows, dtype=float)
    return UwbRecording(
        path=path,
        t=arr[:, 0],
        node1=arr[:, 1].astype(np.int64),
        node2=arr[:, 2].astype(np.int64),
        uwb_range=arr[:, 3],
        mocap_range=arr[:, 4],
        skipped=SkipReport(count=skipped, examples=tuple(examples)),
    )
