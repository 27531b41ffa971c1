"""``benchmarks/against_tree.py`` and ``benchmarks/run_all.py`` on hand-made inputs: the numeric
leaves of a result, the best-of-rounds figures and the orientation of the ratio (> 1: this
checkout is faster), and the runner's answer to a benchmark name it does not know.

The table is built from hand-made per-run results (``table``); the runs themselves
(``run_tree``) start a benchmark per tree and round, minutes each."""

from __future__ import annotations

import importlib.util
from pathlib import Path
from types import ModuleType

import pytest

ROOT = Path(__file__).resolve().parents[2]


def _script(name: str) -> ModuleType:
    spec = importlib.util.spec_from_file_location(f"bench_script_{name}", ROOT / name)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


against_tree = _script("benchmarks/against_tree.py")


def test_leaves_are_dotted_paths_of_the_numbers_only() -> None:
    result = {
        "a": 1,
        "b": {"c": 2.5, "d": True, "e": None},
        "f": [3, {"g": 4}],
        "h": "text",
    }
    assert list(against_tree.leaves(result)) == [
        ("a", 1.0),
        ("b.c", 2.5),
        ("f[0]", 3.0),
        ("f[1].g", 4.0),
    ]


def _line(lines: list[str], key: str) -> str:
    (line,) = [x for x in lines if x.startswith(key + " ")]
    return line


def test_the_trees_take_turns_to_run_first() -> None:
    assert against_tree.round_order(3) == [
        ("baseline", "this"),
        ("this", "baseline"),
        ("baseline", "this"),
    ]


def test_times_take_the_minimum_rates_the_maximum_and_faster_gives_a_ratio_above_one() -> None:
    runs = {
        "baseline": [
            {"t_s": 2.0, "x_per_s": 10.0, "ratio_vs_x": 3.0, "setup.n": 5.0, "load": 1.0},
            {"t_s": 3.0, "x_per_s": 8.0, "ratio_vs_x": 2.0, "setup.n": 5.0, "load": 1.0},
        ],
        "this": [
            {"t_s": 1.5, "x_per_s": 20.0, "ratio_vs_x": 4.0, "setup.n": 5.0, "load": 4.0},
            {"t_s": 1.0, "x_per_s": 25.0, "ratio_vs_x": 6.0, "setup.n": 5.0},
        ],
    }
    lines = against_tree.table("filters", Path("base"), Path("this"), runs)
    assert lines[0] == "filters: 2 rounds; baseline base; this this; ratio > 1: this is faster"
    # a time: best is the smallest (2.0 and 1.0), this is twice as fast
    assert "baseline           2  this           1  ratio  2.00" in _line(lines, "t_s")
    # a rate (…_per_s): best is the largest (10 and 25)
    assert "baseline          10  this          25  ratio  2.50" in _line(lines, "x_per_s")
    # a name with "ratio": larger is better (3 and 6)
    assert "baseline           3  this           6  ratio  2.00" in _line(lines, "ratio_vs_x")
    # setup leaves and leaves missing from a run are left out
    assert len(lines) == 4


def test_a_zero_best_gives_no_ratio() -> None:
    runs = {"baseline": [{"t_s": 0.0}], "this": [{"t_s": 1.0}]}
    lines = against_tree.table("filters", Path("base"), Path("this"), runs)
    assert _line(lines, "t_s").endswith("ratio   nan")


def test_larger_is_better_for_team_sizes_and_fractions_and_machine_leaves_are_left_out() -> None:
    """bench runtime's largest team keeping its rates (8 against 12 robots) and its achieved
    rate fraction (0.9 against 0.99) are better when larger; load and core count are not
    speeds."""
    runs = {
        "baseline": [
            {"largest_team_keeping_rates": 8.0, "sizes[0].achieved_rate_fraction": 0.9}
            | {"load_average[0]": 1.0, "cpu_count": 2.0, "sizes[0].load_average": 3.0}
        ],
        "this": [
            {"largest_team_keeping_rates": 12.0, "sizes[0].achieved_rate_fraction": 0.99}
            | {"load_average[0]": 2.0, "cpu_count": 2.0, "sizes[0].load_average": 1.0}
        ],
    }
    lines = against_tree.table("runtime", Path("base"), Path("this"), runs)
    assert _line(lines, "largest_team_keeping_rates").endswith("ratio  1.50")
    assert _line(lines, "sizes[0].achieved_rate_fraction").endswith("ratio  1.10")
    assert len(lines) == 3


def test_the_runner_answers_an_unknown_benchmark_with_the_cli_error(
    capsys: pytest.CaptureFixture[str],
) -> None:
    run_all = _script("benchmarks/run_all.py")
    assert run_all.run_all(["no-such-benchmark"]) != 0
    assert "unknown benchmark 'no-such-benchmark'; available: filters" in capsys.readouterr().err


def test_the_comparison_needs_a_round_and_a_relloc_tree(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    with pytest.raises(SystemExit) as exit_info:
        against_tree.main(["filters", str(ROOT / "src"), "--rounds", "0"])
    assert exit_info.value.code == 2
    assert "--rounds must be ≥ 1 and BASELINE_SRC must hold the relloc package" in (
        capsys.readouterr().err
    )
    with pytest.raises(SystemExit) as exit_info:
        against_tree.main(["filters", str(tmp_path)])  # no relloc package there
    assert exit_info.value.code == 2
