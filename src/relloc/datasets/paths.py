"""Where the shared recorded data lives.

Looked up in order: the ``RELLOC_SHARED_DATA`` environment variable, ``../shared/data`` beside
the repository checkout, then ``../shared/data`` from the current folder.
"""

from __future__ import annotations

import os
from pathlib import Path


def shared_data_dir() -> Path:
    """The folder holding ``mrclam/`` and ``uwb/`` (may not exist outside the workspace)."""
    env = os.environ.get("RELLOC_SHARED_DATA")
    if env:
        return Path(env)
    beside_checkout = Path(__file__).resolve().parents[3].parent / "shared" / "data"
    if beside_checkout.is_dir():
        return beside_checkout
    return Path.cwd().parent / "shared" / "data"


def default_mrclam_dataset() -> Path:
    """MRCLAM run 6, the default dataset of every MRCLAM experiment."""
    return shared_data_dir() / "mrclam" / "MRCLAM_Dataset6"


def default_uwb_csv() -> Path:
    """The TIERS UWB ranges recording."""
    return shared_data_dir() / "uwb" / "tiers" / "20221011_processed.csv"
