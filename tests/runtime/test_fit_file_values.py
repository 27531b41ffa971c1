"""``fit.json`` values out of what the fits produce, a key of the wrong kind and a file too
large to be a fit: refused with a DataError naming the file and the key."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
from test_estimator_nodes import _handmade_fit

from relloc.errors import DataError
from relloc.experiments.fit_file import MAX_FIT_BYTES, load_fit, save_fit

FIT = _handmade_fit("run")


def _document(tmp_path: Path) -> dict[str, Any]:
    save_fit(FIT, tmp_path / "valid.json")
    doc: dict[str, Any] = json.loads((tmp_path / "valid.json").read_text())
    return doc


def test_the_document_edited_below_reads_back(tmp_path: Path) -> None:
    save_fit(FIT, tmp_path / "fit.json")
    assert load_fit(tmp_path / "fit.json") == FIT


@pytest.mark.parametrize(
    ("section", "key", "value", "message"),
    [
        ("odometry", "k_w", -0.01, r"odometry\.k_w: must be ≥ 0, got -0\.01"),
        ("camera", "n_residuals", -1, r"camera\.n_residuals must be ≥ 0 .* got -1 and"),
        ("camera", "correlation", [0.8], r"camera\.correlation: expected an object, got a list"),
        (
            "camera",
            "correlation",
            {"range": 0.8},
            r"camera\.correlation\.range: expected an object, got 0\.8",
        ),
    ],
)
def test_a_value_out_of_range_or_of_the_wrong_kind_names_the_key(
    tmp_path: Path, section: str, key: str, value: object, message: str
) -> None:
    doc = _document(tmp_path)
    doc[section][key] = value
    path = tmp_path / "fit.json"
    path.write_text(json.dumps(doc))
    with pytest.raises(DataError, match=rf"^{path}: {message}"):
        load_fit(path)


def test_a_target_share_outside_0_100_is_refused(tmp_path: Path) -> None:
    from dataclasses import replace

    from relloc.experiments.mrclam_cl import OdometryInflation

    inflated = replace(FIT, odometry_inflation=OdometryInflation(1.5, True, 100.0, (), None, None))
    path = tmp_path / "fit.json"
    save_fit(inflated, path)
    with pytest.raises(DataError, match=rf"^{path}: .*target_percent in \(0, 100\), got 100 and"):
        load_fit(path)


def test_a_file_too_large_to_be_a_fit_is_refused_unread(tmp_path: Path) -> None:
    path = tmp_path / "fit.json"
    path.write_text(" " * (MAX_FIT_BYTES + 1))
    with pytest.raises(DataError, match=rf"^{path}: .*larger than {MAX_FIT_BYTES} bytes"):
        load_fit(path)
