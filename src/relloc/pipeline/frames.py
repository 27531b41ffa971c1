"""Named state layouts (frames) of beliefs, and the true state of each from a recording.

A :class:`~relloc.core.contract.Belief` names its frame; evaluation asks the frame for the
true state of ``subject`` as ``owner`` would estimate it, at the record times:

- ``relative_pose4`` — ``(x, y, z, φ)`` of the subject in the owner's body frame (seed 000
  Eq. 1; seed 002's relative pose): ``⊖ pose_owner ⊕ pose_subject``;
- ``world_pose2`` — ``(x, y, θ)`` of the subject in the world frame (seed 001's team state);
- ``world_position2`` — ``(x, y)`` of the subject in the world frame (a range-only team,
  :mod:`relloc.estimators.uwb_range`);
- ``airground_follower`` — ``(r_x, r_y, θ_i, θ_0)`` of seed 003 (:mod:`relloc.models.airground`):
  ``r = p_subject − p_owner`` (the leader seen from the follower) in the common frame whose x
  axis is at ``recording.meta["common_frame_yaw"]`` (default 0), and both headings.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from types import MappingProxyType

import numpy as np
from numpy.typing import NDArray

from relloc.core.checks import number
from relloc.core.recording import Recording
from relloc.errors import ConfigError, DataError

Array = NDArray[np.float64]
TruthFn = Callable[[Recording, str, str, Array], Array]


@dataclass(frozen=True)
class Frame:
    """A state layout: names of the states, which are angles (errors wrapped), which make up
    the position (position RMSE), which one is the yaw (yaw RMSE; ``None`` if none), and how to
    compute the true state ``truth(recording, owner, subject, t) -> (K, dim)``."""

    name: str
    states: tuple[str, ...]
    angles: tuple[int, ...]
    position: tuple[int, ...]
    yaw: int | None
    truth: TruthFn

    @property
    def dim(self) -> int:
        return len(self.states)


def _relative_pose4(rec: Recording, owner: str, subject: str, t: Array) -> Array:
    return rec.relative_truth(owner, subject, t)


def _world_pose2(rec: Recording, owner: str, subject: str, t: Array) -> Array:
    pose = rec.require_truth("world_pose2 truth")[rec.index(subject)].at(t)
    return np.asarray(pose[:, [0, 1, 3]])


def _world_position2(rec: Recording, owner: str, subject: str, t: Array) -> Array:
    pose = rec.require_truth("world_position2 truth")[rec.index(subject)].at(t)
    return np.asarray(pose[:, :2])


def common_frame_yaw(rec: Recording) -> float:
    """The yaw (rad) of the team's common frame in the world, ``recording.meta
    ["common_frame_yaw"]`` (0 when absent); one that is not a finite number would turn every
    true state in that frame into NaN (or fail in ``float``): DataError naming it."""
    try:
        return number(rec.meta.get("common_frame_yaw", 0.0), "recording.meta: common_frame_yaw")
    except ConfigError as exc:  # the recording's data, not a setting
        raise DataError(str(exc)) from None


def _airground_follower(rec: Recording, owner: str, subject: str, t: Array) -> Array:
    """The follower-frame truth (module docstring), in the common frame of
    :func:`common_frame_yaw`."""
    truth = rec.require_truth("airground_follower truth")
    follower = truth[rec.index(owner)].at(t)
    leader = truth[rec.index(subject)].at(t)
    yaw = common_frame_yaw(rec)
    c, s = np.cos(yaw), np.sin(yaw)
    d = leader[:, :2] - follower[:, :2]
    out = np.empty((d.shape[0], 4))
    out[:, 0] = c * d[:, 0] + s * d[:, 1]
    out[:, 1] = -s * d[:, 0] + c * d[:, 1]
    out[:, 2] = follower[:, 3] - yaw
    out[:, 3] = leader[:, 3] - yaw
    return out


#: Every frame by name.
FRAMES: Mapping[str, Frame] = MappingProxyType(
    {
        f.name: f
        for f in (
            Frame("relative_pose4", ("x", "y", "z", "phi"), (3,), (0, 1, 2), 3, _relative_pose4),
            Frame("world_pose2", ("x", "y", "theta"), (2,), (0, 1), 2, _world_pose2),
            Frame("world_position2", ("x", "y"), (), (0, 1), None, _world_position2),
            Frame(
                "airground_follower",
                ("r_x", "r_y", "theta_i", "theta_0"),
                (2, 3),
                (0, 1),
                2,
                _airground_follower,
            ),
        )
    }
)


def frame(name: str) -> Frame:
    """The frame called ``name`` (ConfigError naming the known ones otherwise)."""
    try:
        return FRAMES[name]
    except KeyError:
        raise ConfigError(f"unknown frame {name!r}; known: {', '.join(FRAMES)}") from None
