"""Speed, scale and interval-coverage benchmarks, runnable as ``relloc bench NAME`` or
``benchmarks/run_all.py``.

Each module ``relloc.bench.<name>`` exposes ``run(quiet: bool = False) -> dict`` returning the
numbers it measured (and the named baseline measured in the same run), printing a table unless
``quiet``. Benchmarks live in the package so an installed relloc can run them; ``benchmarks/`` at
the repository root holds the runner script.
"""

BENCHMARKS: dict[str, str] = {
    "filters": "relloc.bench.filters",
    "observability": "relloc.bench.observability",
    "cooperative": "relloc.bench.cooperative",
    "multihypothesis": "relloc.bench.multihypothesis",
    "runtime": "relloc.bench.runtime",
    "secure": "relloc.bench.secure",
    "intervals": "relloc.bench.intervals",
}
