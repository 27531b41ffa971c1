"""Estimators: pure predict/update functions first, thin stateful wrappers second.

The public classes, importable from ``relloc.estimators`` (loaded on first use):

- one observer–observed pair (seed 000): :class:`RelativeTracker` (PLKF, TEKF or
  bias-compensated PLKF, set by :class:`FilterSettings`), :class:`YawBankTracker` (a bank of
  yaw hypotheses, :class:`YawBankSettings`), :class:`RelativeFilterBatch` (many pairs at once,
  :class:`TrackSpec`);
- every pair an observer sees: :class:`TrackManager` (:class:`TrackManagerSettings`;
  :func:`managers_for` builds one per observing robot), initialised by :class:`InitPolicy`
  inside a :class:`FieldOfView`;
- a team (seed 001): :class:`CooperativeEstimator` (:class:`CooperativeSettings`) over
  :class:`ExtendedInformationFilter` or :class:`JointEkf`;
- unknown correspondence (seed 002): :class:`GaussianSumFuser` (:class:`GaussianSumSettings`);
- air-ground followers (seed 003): :class:`SwitchingEkf` (:class:`SwitchingEkfSettings`).
"""

from __future__ import annotations

import importlib
from typing import Any

#: Public name → the module that defines it.
_API: dict[str, str] = {
    "RelativeTracker": "relloc.estimators.relative",
    "FilterSettings": "relloc.estimators.relative",
    "YawBankTracker": "relloc.estimators.yaw_bank",
    "YawBankSettings": "relloc.estimators.yaw_bank",
    "RelativeFilterBatch": "relloc.estimators.relative_batch",
    "TrackSpec": "relloc.estimators.relative_batch",
    "TrackManager": "relloc.estimators.track_manager",
    "TrackManagerSettings": "relloc.estimators.track_manager",
    "managers_for": "relloc.estimators.track_manager",
    "InitPolicy": "relloc.estimators.initialisation",
    "FieldOfView": "relloc.estimators.initialisation",
    "CooperativeEstimator": "relloc.estimators.cooperative",
    "CooperativeSettings": "relloc.estimators.cooperative",
    "ExtendedInformationFilter": "relloc.estimators.eif",
    "JointEkf": "relloc.estimators.joint_ekf",
    "GaussianSumFuser": "relloc.estimators.gaussian_sum",
    "GaussianSumSettings": "relloc.estimators.gaussian_sum",
    "SwitchingEkf": "relloc.estimators.switching_ekf",
    "SwitchingEkfSettings": "relloc.estimators.switching_ekf",
}

__all__ = sorted(_API)


def __getattr__(name: str) -> Any:
    """Load a public name from its module on first use (PEP 562)."""
    module = _API.get(name)
    if module is None:
        raise AttributeError(f"module 'relloc.estimators' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *_API})
