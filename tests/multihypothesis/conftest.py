"""Shared fixtures: a small synthetic folder in MRCLAM layout (three robots circling in an arena,
one landmark, camera rows at 5 Hz) and ``mrclam-association`` set up to run on it quickly."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from relloc.experiments import mrclam_association

HEADER = "# synthetic\n# MRCLAM layout\n# for relloc tests\n# columns\n"
T0 = 1248272272.0


def _write(folder: Path, name: str, rows: list[str]) -> None:
    (folder / name).write_text(HEADER + "\n".join(rows) + "\n")


def write_circling_folder(folder: Path, rng: np.random.Generator) -> Path:
    """Three robots circling in an arena and one landmark; camera rows at 5 Hz."""
    folder.mkdir(parents=True, exist_ok=True)
    barcodes = {1: 5, 2: 14, 3: 41, 4: 63}
    _write(folder, "Barcodes.dat", [f"{s} {b}" for s, b in barcodes.items()])
    _write(folder, "Landmark_Groundtruth.dat", ["4 0.5 0.5 0.001 0.001"])
    t = np.arange(0.0, 40.0, 0.02)
    poses = {}
    for n, (cx, cy, v, w) in {
        1: (0, 0, 0.25, 0.15),
        2: (2, 1, 0.2, -0.2),
        3: (-1, 2, 0.3, 0.1),
    }.items():
        th = 0.5 * n + w * t
        x = cx + (v / w) * np.sin(th)
        y = cy - (v / w) * np.cos(th)
        poses[n] = (x, y, th)
        gt = [
            f"{T0 + ti:.3f} {xi:.5f} {yi:.5f} {np.angle(np.exp(1j * ti_)):.5f}"
            for ti, xi, yi, ti_ in zip(t, x, y, th, strict=True)
        ]
        _write(folder, f"Robot{n}_Groundtruth.dat", gt)
        odo = [f"{T0 + ti:.3f} {v:.3f} {w:.3f}" for ti in t[::5]]
        _write(folder, f"Robot{n}_Odometry.dat", odo)
    for n in poses:
        rows = []
        for k in range(0, t.size, 10):
            xo, yo, tho = (a[k] for a in poses[n])
            targets = [(m, poses[m][0][k], poses[m][1][k]) for m in poses if m != n]
            targets.append((4, 0.5, 0.5))
            for m, xm, ym in targets:
                r = np.hypot(xm - xo, ym - yo) + 0.05 * rng.normal()
                b = (
                    np.angle(np.exp(1j * (np.arctan2(ym - yo, xm - xo) - tho)))
                    + 0.02 * rng.normal()
                )
                rows.append(f"{T0 + t[k]:.3f} {barcodes[m]} {r:.4f} {b:.4f}")
        _write(folder, f"Robot{n}_Measurement.dat", rows)
    return folder


@pytest.fixture
def circling_mrclam() -> Callable[[Path, np.random.Generator], Path]:
    """``circling_mrclam(folder, rng) -> folder``: write the synthetic MRCLAM folder."""
    return write_circling_folder


@pytest.fixture
def short_association(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """The synthetic folder (seed 0) under ``tmp_path / "data"``, with ``mrclam-association``'s
    calibration, scoring and warm-up windows shortened to fit its 40 s."""
    folder = write_circling_folder(tmp_path / "data", np.random.default_rng(0))
    monkeypatch.setattr(mrclam_association, "CALIBRATION_S", 5.0)
    monkeypatch.setattr(mrclam_association, "EVAL_S", 14.0)
    monkeypatch.setattr(mrclam_association, "WARMUP_S", 6.0)
    return folder
