"""Library field names → command-line flags, so a configuration error names what the user typed.

Settings classes validate themselves and raise :class:`relloc.errors.ConfigError` with
messages that start with the field (``keep_window_s: must be ≥ 0``); the CLI passes its values
through :func:`flag_errors`, which rewrites that prefix into the flag
(``--keep-window: must be ≥ 0``).
"""

from __future__ import annotations

import argparse
import re
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path

from relloc.errors import ConfigError

#: Settings field (as the library's error messages start) → the flag that sets it.
FIELD_FLAGS: dict[str, str] = {
    "YawBankSettings.n_components": "--yaw-bank",
    "keep_window_s": "--keep-window",
    "gate_probability": "--gate",
    "settle_s": "--settle",
    "filter": "--filter",
    "init": "--init",
    "runs": "--runs",
    "seed": "--seed",
    "duration_s": "--duration",
}


def as_flag_message(message: str, fields: Mapping[str, str] = FIELD_FLAGS) -> str:
    """``message`` with a leading ``field:`` replaced by its flag (unchanged otherwise)."""
    head, sep, rest = message.partition(":")
    flag = fields.get(head.strip())
    return f"{flag}:{rest}" if sep and flag else message


@contextmanager
def flag_errors(fields: Mapping[str, str] = FIELD_FLAGS) -> Iterator[None]:
    """Re-raise a :class:`ConfigError` from the block with its field renamed to the flag."""
    try:
        yield
    except ConfigError as exc:
        raise ConfigError(as_flag_message(str(exc), fields)) from None


def nonempty_path(text: str) -> Path:
    """An argparse type: a non-empty path (an empty one would silently mean the current
    folder)."""
    if not text:
        raise argparse.ArgumentTypeError("an empty path")
    return Path(text)


def integer_list(text: str | None, flag: str) -> list[int] | None:
    """``"1,3,5"`` → ``[1, 3, 5]`` (the value of ``flag``); ``None`` stays ``None``."""
    if text is None:
        return None
    try:
        return [int(part) for part in text.split(",")]
    except ValueError:
        raise ConfigError(f"{flag}: {text!r} is not a comma-separated list of integers") from None


def number_pair(text: str | None, flag: str) -> tuple[float, float] | None:
    """``"3.7,-1.2"`` → ``(3.7, -1.2)`` (the value of ``flag``); ``None`` stays ``None``."""
    if text is None:
        return None
    parts = text.split(",")
    try:
        if len(parts) == 2:
            return float(parts[0]), float(parts[1])
    except ValueError:
        pass
    raise ConfigError(f"{flag}: {text!r} is not two numbers X,Y (e.g. {flag}=3.7,-1.2)")


_BARCODE_PAIR = re.compile(r"\s*([0-9]{1,10})\s*:\s*([0-9]{1,10})\s*", re.ASCII)


def barcode_map(text: str | None, flag: str) -> dict[int, int] | None:
    """``"5:11,14:12"`` → ``{5: 11, 14: 12}`` (the value of ``flag``, each old barcode once);
    ``None`` stays ``None``. Only the form is checked here, the barcodes by the library."""
    if text is None:
        return None
    mapping: dict[int, int] = {}
    for part in text.split(","):
        pair = _BARCODE_PAIR.fullmatch(part)
        if pair is None:
            raise ConfigError(
                f"{flag}: {part!r} in {text!r} is not OLD:NEW (barcodes as whole numbers, "
                f"pairs separated by commas, e.g. {flag} 5:11,14:12)"
            )
        old, new = int(pair[1]), int(pair[2])
        if old in mapping:
            raise ConfigError(f"{flag}: barcode {old} is mapped twice in {text!r}")
        mapping[old] = new
    return mapping
