"""Library field names → command-line flags, so a configuration error names what the user typed.

Settings classes validate themselves and raise :class:`relloc.errors.ConfigError` with
messages that start with the field (``keep_window_s: must be ≥ 0``); the CLI passes its values
through :func:`flag_errors`, which rewrites that prefix into the flag
(``--keep-window: must be ≥ 0``).
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from contextlib import contextmanager

from relloc.errors import ConfigError

#: Settings field (as the library's error messages start) → the flag that sets it.
FIELD_FLAGS: dict[str, str] = {
    "YawBankSettings.n_components": "--yaw-bank",
    "keep_window_s": "--keep-window",
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


def integer_list(text: str | None, flag: str) -> list[int] | None:
    """``"1,3,5"`` → ``[1, 3, 5]`` (the value of ``flag``); ``None`` stays ``None``."""
    if text is None:
        return None
    try:
        return [int(part) for part in text.split(",")]
    except ValueError:
        raise ConfigError(f"{flag}: {text!r} is not a comma-separated list of integers") from None
