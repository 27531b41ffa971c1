"""What ``relloc bench filters`` and ``relloc bench intervals`` print without ``--quiet``, on
tiny workloads; an interval benchmark without a ρ is refused."""

from __future__ import annotations

import pytest

from relloc.bench import intervals
from relloc.errors import ConfigError


def test_the_filters_table_names_every_measure(capsys: pytest.CaptureFixture[str]) -> None:
    pytest.importorskip("filterpy", reason="filterpy (extra 'bench') is needed for this benchmark")
    from relloc.bench.filters import BenchSize, run

    result = run(quiet=False, size=BenchSize(steps=30, pairs=12, batch_steps=5, repeats=1))
    out = capsys.readouterr().out
    assert "relloc bench filters (predict + update per pair)" in out
    for measure in ("PLKF tracker", "TEKF tracker", "filterpy / relloc TEKF", "batched / loop"):
        assert measure in out, measure
    assert f"{result['ratio_vs_filterpy']:.1f}x" in out
    assert f"batched PLKF, {result['setup']['pairs']} pairs" in out
    assert f"{result['machine']['load_average_1min']:.2f}" in out


def test_the_intervals_report_prints_every_design(capsys: pytest.CaptureFixture[str]) -> None:
    size = intervals.IntervalBenchSize(
        draws=4,
        samples=200,
        rhos=(0.9,),
        runs=4,
        run_samples=50,
        shared_runs=2,
        subjects=2,
        subject_shares=(0.0,),
    )
    result = intervals.run(quiet=False, size=size, seed=7)
    out = capsys.readouterr().out.splitlines()
    assert out[0].startswith("coverage of the 95 % NEES-share interval (true share 5 %), seed 7")
    one = result["one_run"]["0.9"]
    (row,) = [line for line in out if line.strip().startswith("ρ = 0.9")]
    assert f"{one['coverage']:9.3f}" in row
    assert any(line.startswith("2 subjects, ρ 0.997") for line in out)
    assert any(line.startswith("independent runs (4 runs") for line in out)
    assert any(line.startswith("shared recording (2 runs") for line in out)
    assert out[-1].startswith("wall ")


def test_a_coverage_is_printed_with_its_draws_or_as_a_dash() -> None:
    assert intervals._of(None, 0) == "—"
    assert intervals._of(0.95, 12) == "0.950 (12)"


def test_an_interval_benchmark_needs_a_rho() -> None:
    with pytest.raises(ConfigError, match=r"IntervalBenchSize\.rhos: at least one ρ"):
        intervals.IntervalBenchSize(rhos=())
