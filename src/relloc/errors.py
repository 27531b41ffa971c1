"""Exception hierarchy. The CLI maps each class to an exit code (see ``relloc.cli``)."""

from __future__ import annotations


class RellocError(Exception):
    """Base class of every error relloc raises on purpose."""

    exit_code = 1


class ConfigError(RellocError):
    """A setting, scenario file or command-line value is invalid. The message names the field."""

    exit_code = 2


class DataError(RellocError):
    """Input data (a dataset file, a message, an array) is malformed. The message names where."""

    exit_code = 3


class ModelError(RellocError):
    """A model or estimator cannot proceed (e.g. a covariance that cannot be factorised)."""

    exit_code = 4


class DependencyError(RellocError):
    """An optional dependency (an extra) is missing; the message says which extra to install."""

    exit_code = 5


def require(module: str, extra: str):  # type: ignore[no-untyped-def]
    """Import an optional module lazily, or raise :class:`DependencyError` naming the extra.

    >>> np = require("numpy", "core")
    """
    import importlib

    try:
        return importlib.import_module(module)
    except ImportError as exc:  # pragma: no cover - depends on the environment
        raise DependencyError(
            f"'{module}' is needed here; install it with: pip install 'relloc[{extra}]'"
        ) from exc
