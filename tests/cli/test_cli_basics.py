"""CLI smoke tests: help, version, unknown experiment → clear error and exit code."""

import subprocess
import sys

from relloc.cli import main


def test_help_and_version(capsys):
    assert main([]) == 2
    out = subprocess.run(
        [sys.executable, "-m", "relloc", "--version"], capture_output=True, text=True, check=True
    )
    assert "relloc" in out.stdout


def test_unknown_experiment_is_config_error(tmp_path, capsys):
    assert main(["reproduce", "no-such-paper", "--out", str(tmp_path)]) == 2
    assert "unknown experiment" in capsys.readouterr().err
