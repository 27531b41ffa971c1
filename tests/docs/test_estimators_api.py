"""``relloc.estimators`` exports its public classes, each named in the package docstring."""

from __future__ import annotations

import pytest

import relloc.estimators as estimators


def test_every_exported_name_resolves_and_is_documented() -> None:
    assert {"RelativeTracker", "TrackManager", "SwitchingEkf"} <= set(estimators.__all__)
    for name in estimators.__all__:
        assert getattr(estimators, name) is not None
        assert name in (estimators.__doc__ or ""), f"{name} is not named in the docstring"


def test_an_unknown_name_is_an_attribute_error() -> None:
    with pytest.raises(AttributeError, match="no_such_filter"):
        estimators.no_such_filter  # noqa: B018
