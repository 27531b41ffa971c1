"""``import relloc`` gives the pipeline types; ``help(relloc)`` names them; importing is cheap."""

from __future__ import annotations

import pydoc
import subprocess
import sys

import relloc


def test_every_public_name_resolves_and_is_documented() -> None:
    doc = relloc.__doc__ or ""
    for name in relloc.__all__:
        assert getattr(relloc, name) is not None
        assert name in doc, f"{name} is public but relloc's docstring does not name it"


def test_help_shows_the_pipeline() -> None:
    text = pydoc.render_doc(relloc, renderer=pydoc.plaintext)
    for name in ("Recording", "replay", "Estimator", "Estimates", "evaluate"):
        assert name in text


def test_importing_relloc_loads_no_numerics() -> None:
    code = "import sys, relloc; print('numpy' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


def test_an_unknown_name_is_an_attribute_error() -> None:
    try:
        relloc.no_such_thing  # noqa: B018
    except AttributeError as exc:
        assert "no_such_thing" in str(exc)
    else:  # pragma: no cover
        raise AssertionError("expected AttributeError")
