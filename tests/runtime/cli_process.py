"""``relloc`` commands as real processes (a fresh ``python -m relloc.cli`` each), for the tests
that start a team, or one of its processes, by hand."""

from __future__ import annotations

import os
import subprocess
import sys


def relloc_process(*args: str, merge_stderr: bool = True) -> subprocess.Popen[str]:
    """``relloc ARGS`` started with this environment; its output as text on ``stdout`` (with
    ``stderr`` merged in, unless ``merge_stderr`` is false)."""
    return subprocess.Popen(
        [sys.executable, "-m", "relloc.cli", *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT if merge_stderr else subprocess.PIPE,
        text=True,
        env=os.environ.copy(),
    )
