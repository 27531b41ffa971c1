#!/usr/bin/env bash
# Statement coverage of the test suite, robot processes included: a report per module, the
# lines never run, and the total. Usage: bash scripts/coverage.sh [PYTEST ARGS] (default: tests).
# Needs coverage and pytest-cov in .venv (installed here if missing; not project dependencies).
set -euo pipefail
cd "$(dirname "$0")/.."
.venv/bin/python -c "import coverage, pytest_cov" 2>/dev/null ||
  .venv/bin/python -m pip install --quiet coverage pytest-cov
data=$(mktemp -d)
export COVERAGE_RCFILE="$PWD/scripts/coverage/coveragerc" COVERAGE_FILE="$data/.coverage"
PYTHONPATH="$PWD/scripts/coverage${PYTHONPATH:+:$PYTHONPATH}" .venv/bin/python -m pytest -q -n 2 \
  --timeout 900 -p no:cacheprovider --cov=relloc --cov-config="$COVERAGE_RCFILE" --cov-report= \
  "${@:-tests}"
.venv/bin/coverage combine --quiet "$data" 2>/dev/null || true
.venv/bin/coverage report -m --skip-covered
rm -rf "$data"
