"""relloc.plotting.setup.pyplot is the one way matplotlib gets loaded, always with Agg."""

import subprocess
import sys

from relloc.plotting.setup import pyplot


def test_pyplot_selects_the_agg_backend_and_is_loaded_once():
    plt = pyplot()
    assert plt.get_backend().lower() == "agg"
    assert pyplot() is plt
    fig, ax = plt.subplots()
    ax.plot([0.0, 1.0], [1.0, 0.0])
    plt.close(fig)


def test_importing_every_relloc_module_does_not_import_matplotlib():
    code = (
        "import importlib, pkgutil, sys, relloc\n"
        "for m in pkgutil.walk_packages(relloc.__path__, 'relloc.'):\n"
        "    if not m.name.endswith('__main__'):\n"
        "        importlib.import_module(m.name)\n"
        "print('matplotlib' in sys.modules)\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=120
    )
    assert done.stdout.strip() == "False", done.stderr
