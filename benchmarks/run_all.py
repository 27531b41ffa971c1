"""Run every installed relloc benchmark and write benchmarks/results/<name>.json.

Usage: ``.venv/bin/python benchmarks/run_all.py [NAME ...]`` (or ``make bench``).
"""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

from relloc.bench import BENCHMARKS
from relloc.cli import main


def run_all(names: list[str]) -> int:
    results = Path(__file__).parent / "results"
    for name in names or list(BENCHMARKS):
        module = BENCHMARKS.get(name)  # an unknown name is the CLI's error (it lists the names)
        if module is not None and importlib.util.find_spec(module) is None:
            print(f"-- {name}: not installed, skipped")
            continue
        print(f"== {name}")
        code = main(["bench", name, "--json", str(results / f"{name}.json")])
        if code:
            return code
    return 0


if __name__ == "__main__":
    sys.exit(run_all(sys.argv[1:]))
