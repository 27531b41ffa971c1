"""A small synthetic folder of the MRCLAM layout for the experiment tests (the writer of
``tests/cooperative/conftest.py``), and one robot's ground truth cut short, as a robot that
left the motion-capture volume."""

from __future__ import annotations

import importlib.util
from pathlib import Path


def write_mrclam_folder(folder: Path, duration: float) -> Path:
    """``duration`` seconds of five simulated robots among six landmarks, written to ``folder``."""
    where = Path(__file__).parents[1] / "cooperative" / "conftest.py"
    spec = importlib.util.spec_from_file_location("cooperative_conftest", where)
    assert spec is not None and spec.loader is not None
    cooperative = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(cooperative)
    return Path(cooperative.write_mrclam_folder(folder, duration=duration))


def truth_ending_before(folder: Path, robot: int, end_s: float) -> None:
    """Keep only robot ``robot``'s ground-truth rows stamped under ``end_s`` s after its first."""
    gt = folder / f"Robot{robot}_Groundtruth.dat"
    lines = gt.read_text().splitlines(keepends=True)
    head = [s for s in lines if s.startswith("#")]
    data = [s for s in lines if not s.startswith("#")]
    t0 = float(data[0].split()[0])
    gt.write_text("".join(head + [s for s in data if float(s.split()[0]) - t0 < end_s]))
