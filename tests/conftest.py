"""Fixtures shared across test folders: cuts of the real MRCLAM run 6, in MRCLAM layout."""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path

import pytest

from relloc.datasets.mrclam_cut import cut_mrclam
from relloc.datasets.paths import default_mrclam_dataset

MrclamCut = Callable[..., Path]


def write_mrclam_moved(
    src: Path,
    dst: Path,
    *,
    rotation: float,
    shift: tuple[float, float],
    clock_s: float,
    barcodes: dict[int, int],
) -> Path:
    """The MRCLAM folder ``src`` as if recorded in another world frame, at another time and with
    other barcodes, in ``dst``: every ground-truth position ``p ↦ R(rotation) p + shift`` (robots
    and landmarks), every heading ``θ ↦ wrap(θ + rotation)``, every time stamp ``+ clock_s`` and
    every barcode ``b ↦ barcodes.get(b, b)`` (in Barcodes.dat and in the measurements). Ranges,
    bearings and odometry are body-frame quantities and stay as they are, so every relative
    figure of the run is unchanged."""
    c, s = math.cos(rotation), math.sin(rotation)

    def moved(x: float, y: float) -> str:
        return f"{c * x - s * y + shift[0]:.8f} {s * x + c * y + shift[1]:.8f}"

    def rewrite(name: str, row: Callable[[list[str]], str]) -> None:
        lines = (src / name).read_text().splitlines()
        header = [ln for ln in lines if ln.startswith("#")]
        rows = [row(ln.split()) for ln in lines if ln.strip() and not ln.startswith("#")]
        (dst / name).write_text("\n".join(header + rows) + "\n")

    def stamp(t: str) -> str:
        return f"{float(t) + clock_s:.3f}"

    def heading(th: str) -> str:
        return f"{math.remainder(float(th) + rotation, math.tau):.6f}"

    dst.mkdir(parents=True)
    rewrite("Barcodes.dat", lambda r: f"{r[0]} {barcodes.get(int(r[1]), int(r[1]))}")
    rewrite(
        "Landmark_Groundtruth.dat",
        lambda r: f"{r[0]} {moved(float(r[1]), float(r[2]))} {r[3]} {r[4]}",
    )
    for path in sorted(src.glob("Robot*_Groundtruth.dat")):
        n = path.name.split("_")[0]
        rewrite(
            path.name, lambda r: f"{stamp(r[0])} {moved(float(r[1]), float(r[2]))} {heading(r[3])}"
        )
        rewrite(f"{n}_Odometry.dat", lambda r: f"{stamp(r[0])} {r[1]} {r[2]}")
        rewrite(
            f"{n}_Measurement.dat",
            lambda r: f"{stamp(r[0])} {barcodes.get(int(r[1]), int(r[1]))} {r[2]} {r[3]}",
        )
    return dst


@pytest.fixture(scope="session")
def mrclam_run6_cut() -> MrclamCut:
    """``cut(dst, robots=(1, 2, 3), keep_s=45.0) -> dst``: the first ``keep_s`` seconds of
    ``robots`` of MRCLAM run 6 (:func:`relloc.datasets.mrclam_cut.cut_mrclam`), another run of
    the same layout (the test is skipped where the shared data is absent)."""
    src = default_mrclam_dataset()
    if not (src / "Barcodes.dat").is_file():
        pytest.skip(f"MRCLAM run 6 not found at {src} (shared data absent)")

    def cut(dst: Path, robots: tuple[int, ...] = (1, 2, 3), keep_s: float = 45.0) -> Path:
        return cut_mrclam(src, dst, end_s=keep_s, robots=robots).destination

    return cut


#: Run 6's robot barcodes (5, 14, 41, 32, 23) renumbered to numbers no subject of run 6 carries.
RUN6_NEW_BARCODES = {5: 11, 14: 12, 41: 13, 32: 15, 23: 17}


@pytest.fixture(scope="session")
def mrclam_run6_moved() -> Callable[[Path, Path], Path]:
    """``moved(src, dst) -> dst``: :func:`write_mrclam_moved` of a folder of run 6 (a cut of it)
    into a world frame turned by 2 rad and shifted by (3.7, −1.2) m, a clock 123456.789 s later
    and :data:`RUN6_NEW_BARCODES`."""

    def moved(src: Path, dst: Path) -> Path:
        return write_mrclam_moved(
            src,
            dst,
            rotation=2.0,
            shift=(3.7, -1.2),
            clock_s=123456.789,
            barcodes=RUN6_NEW_BARCODES,
        )

    return moved
