"""The import direction of README's layout: core ← models ← estimators/association/fusion ← sim,
datasets, calibration ← pipeline ← experiments ← cli; the runtime uses the pipeline, never the
experiments. Checked on every ``import`` statement of the package's source (``ast``), lazy
imports inside functions included."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

import relloc

SRC = Path(relloc.__file__).parent

#: package → the relloc packages its modules must not import
FORBIDDEN = {
    "core": ("models", "estimators", "association", "fusion", "sim", "datasets", "calibration",
             "pipeline", "experiments", "cli", "runtime"),
    "models": ("estimators", "association", "fusion", "sim", "datasets", "calibration",
               "pipeline", "experiments", "cli", "runtime"),
    "sim": ("estimators", "fusion", "pipeline", "experiments", "cli", "runtime"),
    "datasets": ("estimators", "fusion", "sim", "pipeline", "experiments", "cli", "runtime"),
    "estimators": ("sim", "datasets", "pipeline", "experiments", "cli", "runtime"),
    "pipeline": ("experiments", "cli", "runtime"),
    "experiments": ("cli",),
    "runtime": ("experiments",),
}  # fmt: skip


def _imports(path: Path) -> set[str]:
    names: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names.add(node.module)
    return {n for n in names if n.startswith("relloc.")}


@pytest.mark.parametrize("package", sorted(FORBIDDEN))
def test_no_module_imports_against_the_direction(package):
    offences = [
        f"{path.relative_to(SRC)} imports {name}"
        for path in sorted((SRC / package).rglob("*.py"))
        for name in sorted(_imports(path))
        if name.split(".")[1] in FORBIDDEN[package]
    ]
    assert not offences, offences
