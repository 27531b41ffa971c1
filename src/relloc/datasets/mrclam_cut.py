"""A part of an MRCLAM-layout folder written as a run of its own: a time span and a subset of
the robots.

The real-data experiments calibrate on one window of a run and score on another, and they must
hold on runs of the layout that nobody here has. :func:`cut_mrclam` makes such runs from one
recording: ``relloc mrclam cut SRC DST --start 450`` writes run 6 from 450 s on, whose
calibration and scoring windows fall on other data than the whole run's; ``--robots 1,3,5``
keeps three robots (the others' barcodes stay in ``Barcodes.dat``, so their sightings by the
kept robots stay too).

The span ``[start_s, end_s)`` is in seconds on the source's clock: since ``t0_unix`` of
:func:`relloc.datasets.mrclam.load_mrclam` on the whole folder, the earliest stamp of any robot
row. ``Barcodes.dat`` and ``Landmark_Groundtruth.dat`` are copied as they are. Every robot file
keeps its comment lines and the data rows whose time stamp (the first column, Unix seconds) lies
in the span, byte for byte and in their order; blank lines go. A data row whose first column is
not a finite number has no place in time: it is left out and counted (``unreadable``), as the
rows outside the span are (``outside``), so :attr:`CutReport.files` accounts for every data row.

The part is written beside ``DST`` first and loaded with :func:`load_mrclam`; only a part that
loads becomes ``DST``. An existing ``DST``, a span that is empty or not finite at its start and
a robot the source does not have are :class:`~relloc.errors.ConfigError`; a part that is not a
usable run (a robot left with fewer rows than a table needs) is a
:class:`~relloc.errors.DataError` naming the file, and nothing is written.
"""

from __future__ import annotations

import math
import shutil
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

from relloc.datasets.mrclam import (
    BARCODES_FILE,
    LANDMARKS_FILE,
    ROBOT_KINDS,
    data_row,
    leading_time,
    load_mrclam,
)
from relloc.errors import ConfigError, DataError


@dataclass(frozen=True)
class FileCut:
    """What became of one robot file's data rows: ``kept + outside + unreadable`` is all of
    them."""

    kept: int
    outside: int
    unreadable: int


@dataclass(frozen=True)
class CutReport:
    """The part written: its span on the source's clock and every robot file's rows."""

    source: Path
    destination: Path
    t0_unix: float
    start_s: float
    end_s: float
    robots: tuple[int, ...]
    files: dict[str, FileCut]


def cut_mrclam(
    source: Path | str,
    destination: Path | str,
    *,
    start_s: float = 0.0,
    end_s: float = math.inf,
    robots: Sequence[int] | None = None,
) -> CutReport:
    """Write the rows of ``source`` stamped in ``[start_s, end_s)`` s since its ``t0_unix``,
    of ``robots`` (default: all), as the MRCLAM folder ``destination`` (module docstring)."""
    src, dst = Path(source), Path(destination)
    if not (math.isfinite(start_s) and start_s >= 0.0):
        raise ConfigError(f"mrclam cut: start {start_s} s must be a finite time ≥ 0")
    if not end_s > start_s:
        raise ConfigError(f"mrclam cut: end {end_s} s must come after start {start_s} s")
    if dst.exists():
        raise ConfigError(f"mrclam cut: {dst} exists; name a new folder")
    whole = load_mrclam(src)
    chosen = tuple(whole.robot_ids) if robots is None else tuple(robots)
    unknown = sorted(set(chosen) - set(whole.robot_ids))
    if unknown or not chosen:
        what = f"robots {unknown} are not in {src}" if unknown else "no robot chosen"
        raise ConfigError(f"mrclam cut: {what} (robots: {list(whole.robot_ids)})")
    if start_s >= whole.duration:
        raise ConfigError(
            f"mrclam cut: start {start_s:g} s is at or past the end of {src}, whose last row is "
            f"stamped {whole.duration:.3f} s after its first"
        )
    lo, hi = whole.t0_unix + start_s, whole.t0_unix + end_s
    kept_robots = tuple(sorted(set(chosen)))
    files: dict[str, FileCut] = {}

    def write(staging: Path) -> None:
        for name in (BARCODES_FILE, LANDMARKS_FILE):
            shutil.copyfile(src / name, staging / name)
        for n in kept_robots:
            for kind in ROBOT_KINDS:
                name = f"Robot{n}_{kind}.dat"
                files[name] = _cut_file(src / name, staging / name, lo, hi)

    staged_write(
        dst,
        write,
        f"mrclam cut: [{start_s:g}, {end_s:g}) s of robots {list(kept_robots)} of {src} "
        "is not a usable run",
    )
    return CutReport(src, dst, whole.t0_unix, start_s, end_s, kept_robots, files)


def staged_write(destination: Path, write: Callable[[Path], None], failure: str) -> None:
    """``write(staging)`` into a fresh folder beside ``destination``, which becomes
    ``destination`` only once it loads as an MRCLAM run; one that does not (DataError) is
    removed and reported as ``failure: <the loader's error>`` (its paths named as in
    ``destination``), so a failed cut or move leaves nothing behind."""
    staging = destination.with_name(f".{destination.name}.partial")
    shutil.rmtree(staging, ignore_errors=True)
    try:
        staging.mkdir(parents=True)
    except OSError as exc:
        raise DataError(f"{destination}: cannot create the folder ({exc.strerror})") from None
    written = False
    try:
        write(staging)
        load_mrclam(staging)
        written = True
    except DataError as exc:  # named as the files it would have written, not the staging's
        raise DataError(f"{failure}: {str(exc).replace(str(staging), str(destination))}") from exc
    finally:
        if not written:
            shutil.rmtree(staging, ignore_errors=True)
    staging.rename(destination)


def _cut_file(src: Path, dst: Path, lo: float, hi: float) -> FileCut:
    """Copy ``src``'s comment lines and the data rows stamped in ``[lo, hi)`` to ``dst``."""
    lines: list[bytes] = []
    kept = outside = unreadable = 0
    for line in src.read_bytes().split(b"\n"):
        row = data_row(line)
        if row is None:
            if line.strip():  # a comment, not a blank line
                lines.append(line)
            continue
        t = leading_time(row)
        if t is None:
            unreadable += 1
        elif lo <= t < hi:
            lines.append(line)
            kept += 1
        else:
            outside += 1
    dst.write_bytes(b"\n".join(lines) + b"\n")
    return FileCut(kept=kept, outside=outside, unreadable=unreadable)
