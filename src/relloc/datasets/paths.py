"""Where the shared recorded data lives.

One way to point relloc at it: the data folder (the one holding ``mrclam/``, ``uwb/`` and
``tiers/``) is
the ``RELLOC_SHARED_DATA`` environment variable, which every subcommand's ``--data-dir DIR``
sets. Without it: ``../shared/data`` beside the repository checkout, then ``../shared/data``
from the current folder. Every "not found" message of the default data ends with
:data:`DATA_HINT`.
"""

from __future__ import annotations

import os
from pathlib import Path

DATA_ENV = "RELLOC_SHARED_DATA"
DATA_HINT = (
    "point relloc at the data folder (the one holding mrclam/, uwb/ and tiers/) with "
    f"--data-dir DIR or the {DATA_ENV} environment variable"
)


def shared_data_dir() -> Path:
    """The folder holding ``mrclam/``, ``uwb/`` and ``tiers/`` (may not exist outside the
    workspace)."""
    env = os.environ.get(DATA_ENV)
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
