"""Where the shared data folder is looked for (:mod:`relloc.datasets.paths`): the
``RELLOC_SHARED_DATA`` variable when set and not empty, then ``../shared/data`` beside the
repository checkout, then ``../shared/data`` from the current folder."""

from __future__ import annotations

from pathlib import Path

from relloc.datasets import paths


def _fake_checkout(monkeypatch, root: Path) -> Path:
    """Make the module believe it lives in the checkout ``root/repo``; return ``root``."""
    monkeypatch.delenv(paths.DATA_ENV, raising=False)
    monkeypatch.setattr(paths, "__file__", str(root / "repo/src/relloc/datasets/paths.py"))
    return root


def test_the_folder_beside_the_checkout_is_found(tmp_path, monkeypatch):
    root = _fake_checkout(monkeypatch, tmp_path)
    (root / "shared/data").mkdir(parents=True)
    (root / "elsewhere/here").mkdir(parents=True)
    monkeypatch.chdir(root / "elsewhere/here")
    assert paths.shared_data_dir() == root / "shared/data"
    assert paths.default_mrclam_dataset() == root / "shared/data/mrclam/MRCLAM_Dataset6"


def test_without_one_beside_the_checkout_the_current_folders_parent_is_tried(tmp_path, monkeypatch):
    root = _fake_checkout(monkeypatch, tmp_path)
    (root / "work/project").mkdir(parents=True)
    monkeypatch.chdir(root / "work/project")
    assert paths.shared_data_dir() == root / "work/shared/data"


def test_an_empty_variable_counts_as_unset(tmp_path, monkeypatch):
    root = _fake_checkout(monkeypatch, tmp_path)
    (root / "shared/data").mkdir(parents=True)
    monkeypatch.setenv(paths.DATA_ENV, "")
    assert paths.shared_data_dir() == root / "shared/data"
    monkeypatch.setenv(paths.DATA_ENV, str(tmp_path / "mine"))
    assert paths.shared_data_dir() == tmp_path / "mine"
