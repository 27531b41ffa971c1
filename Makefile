# The README's two commands. Each does its own set-up (a .venv with relloc and all extras).
.PHONY: setup run test bench

setup:
	bash scripts/setup.sh

# Main job: relative localization of the built-in default team; prints accuracy, writes a report.
run: setup
	.venv/bin/relloc run --out out/default

# The test suite (what CI runs).
test: setup
	.venv/bin/python -m pytest -q -n 2 --timeout 600 --durations=15

bench: setup
	.venv/bin/python benchmarks/run_all.py
