"""Fixtures shared across test folders: cuts of the real MRCLAM run 6, in MRCLAM layout."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest

from relloc.datasets.paths import default_mrclam_dataset

MrclamCut = Callable[..., Path]


def write_mrclam_cut(
    src: Path, dst: Path, robots: tuple[int, ...] = (1, 2, 3), keep_s: float = 45.0
) -> Path:
    """Barcodes, landmarks and the first ``keep_s`` seconds (from the first robot's first
    ground-truth stamp) of ``robots`` of the MRCLAM folder ``src``, same file names, in ``dst``:
    another run of the same layout, fewer robots and a shorter span."""
    dst.mkdir(parents=True)
    for name in ("Barcodes.dat", "Landmark_Groundtruth.dat"):
        (dst / name).write_text((src / name).read_text())
    first = None
    for n in robots:
        for kind in ("Groundtruth", "Odometry", "Measurement"):
            lines = (src / f"Robot{n}_{kind}.dat").read_text().splitlines()
            header = [ln for ln in lines if ln.startswith("#")]
            rows = [ln for ln in lines if ln.strip() and not ln.startswith("#")]
            if first is None:
                first = float(rows[0].split()[0])
            kept = [ln for ln in rows if float(ln.split()[0]) < first + keep_s]
            (dst / f"Robot{n}_{kind}.dat").write_text("\n".join(header + kept) + "\n")
    return dst


@pytest.fixture(scope="session")
def mrclam_run6_cut() -> MrclamCut:
    """``cut(dst, robots=(1, 2, 3), keep_s=45.0) -> dst``: :func:`write_mrclam_cut` of MRCLAM run
    6 (the test is skipped where the shared data is absent)."""
    src = default_mrclam_dataset()
    if not (src / "Barcodes.dat").is_file():
        pytest.skip(f"MRCLAM run 6 not found at {src} (shared data absent)")

    def cut(dst: Path, robots: tuple[int, ...] = (1, 2, 3), keep_s: float = 45.0) -> Path:
        return write_mrclam_cut(src, dst, robots, keep_s)

    return cut
