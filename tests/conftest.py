"""Fixtures shared across test folders: the real MRCLAM run 6, cuts of it, and the same moved to
another world frame, clock and barcodes, in MRCLAM layout; a short guler2023 plan."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
import sympy as sp

from relloc.datasets.mrclam_cut import cut_mrclam
from relloc.datasets.mrclam_move import move_mrclam
from relloc.datasets.paths import default_mrclam_dataset, default_uwb_csv
from relloc.experiments.guler2023 import Plan
from relloc.models.symbolic import SymbolicModel

MrclamCut = Callable[..., Path]


@pytest.fixture(scope="session")
def mrclam_run6() -> Path:
    """The folder of MRCLAM run 6 (the test is skipped where the shared data is absent)."""
    src = default_mrclam_dataset()
    if not (src / "Barcodes.dat").is_file():
        pytest.skip(f"MRCLAM run 6 not found at {src} (shared data absent)")
    return src


@pytest.fixture(scope="session")
def mrclam_run6_cut(mrclam_run6: Path) -> MrclamCut:
    """``cut(dst, robots=(1, 2, 3), keep_s=45.0) -> dst``: the first ``keep_s`` seconds of
    ``robots`` of MRCLAM run 6 (:func:`relloc.datasets.mrclam_cut.cut_mrclam`), another run of
    the same layout (the test is skipped where the shared data is absent)."""

    def cut(dst: Path, robots: tuple[int, ...] = (1, 2, 3), keep_s: float = 45.0) -> Path:
        return cut_mrclam(mrclam_run6, dst, end_s=keep_s, robots=robots).destination

    return cut


@pytest.fixture(scope="session")
def shared_uwb_csv() -> Path:
    """The shared UWB ranges file guler2023 fits on (the test is skipped where it is absent)."""
    if not default_uwb_csv().is_file():
        pytest.skip(f"shared UWB data not found at {default_uwb_csv()}")
    return default_uwb_csv()


@pytest.fixture(scope="session")
def guler2023_short_plan(shared_uwb_csv: Path) -> Plan:
    """A guler2023 plan of one run per block at 5 % of the durations, one dwell time (4 s) and
    two drones (the test is skipped where the shared UWB data the experiment fits on is
    absent)."""
    return Plan(
        one_drone_runs=1,
        two_drones_runs=1,
        formation_runs=1,
        sweep_runs=1,
        dwell_times=(4.0,),
        drone_counts=(2,),
        duration_scale=0.05,
    )


@pytest.fixture(scope="session")
def toy_symbolic_model() -> Callable[..., SymbolicModel]:
    """``model(**changes)``: the toy ``ẋ = u``, ``ẏ = 0``, ``h = x`` in the real SymPy symbols
    ``x, y`` and input ``u``, with the :class:`~relloc.models.symbolic.SymbolicModel` fields
    ``changes`` replaced."""
    x, y, u = sp.symbols("x y u", real=True)

    def model(**changes: Any) -> SymbolicModel:
        fields: dict[str, Any] = dict(
            name="toy",
            description="toy",
            states=(x, y),
            drift=(0, 0),
            inputs=(u,),
            input_fields=((1, 0),),
            outputs=(x,),
            output_names=("h",),
        )
        return SymbolicModel(**{**fields, **changes})

    return model


#: Run 6's robot barcodes (5, 14, 41, 32, 23) renumbered to numbers no subject of run 6 carries.
RUN6_NEW_BARCODES = {5: 11, 14: 12, 41: 13, 32: 15, 23: 17}


@pytest.fixture(scope="session")
def mrclam_run6_moved() -> Callable[[Path, Path], Path]:
    """``moved(src, dst) -> dst``: a folder of run 6 (a cut of it) as if recorded in a world
    frame turned by 2 rad and shifted by (3.7, −1.2) m, on a clock 123456.789 s later and with
    :data:`RUN6_NEW_BARCODES` (:func:`relloc.datasets.mrclam_move.move_mrclam`: every position
    ``p ↦ R(2) p + (3.7, −1.2)``, heading ``θ ↦ wrap(θ + 2)``, stamp ``t ↦ t + 123456.789``;
    ranges, bearings and odometry unchanged)."""

    def moved(src: Path, dst: Path) -> Path:
        return move_mrclam(
            src,
            dst,
            rotation_rad=2.0,
            shift_m=(3.7, -1.2),
            clock_s=123456.789,
            barcodes=RUN6_NEW_BARCODES,
        ).destination

    return moved


def _shown_as_printed(text: str, value: float | None) -> bool:
    """``text`` is ``value`` as a terminal summary shows it: four significant digits, ``—`` for
    none."""
    if value is None:
        return text == "—"
    return float(text) == pytest.approx(value, rel=5.001e-4, abs=0.0)


@pytest.fixture
def printed_as() -> Callable[[str, float | None], bool]:
    """The check of a printed figure against its summary.json value (:func:`_shown_as_printed`)."""
    return _shown_as_printed


def _states_skipped_rows(report: str, n_skipped: int, source: str = "the dataset") -> bool:
    """Whether ``report`` states ``n_skipped`` input rows of ``source`` skipped, or none
    (:func:`relloc.pipeline.output.skipped_rows_line`)."""
    if n_skipped:
        return f"Input rows of {source} skipped (not used): {n_skipped} (" in report
    return f"Input rows: every data row of {source} was used." in report


@pytest.fixture
def states_skipped_rows() -> Callable[..., bool]:
    """The check that a report states the input rows its loader skipped
    (:func:`_states_skipped_rows`)."""
    return _states_skipped_rows
