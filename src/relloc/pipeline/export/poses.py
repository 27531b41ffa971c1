"""Beliefs as ROS poses: each frame of :mod:`relloc.pipeline.frames` mapped to 6-DOF poses.

A ROS pose with covariance (``geometry_msgs/PoseWithCovariance``) has the six degrees of freedom
``x, y, z, roll, pitch, yaw`` (rotation about the fixed X, Y, Z axes), and its covariance is
the row-major 6×6 matrix over them in that order. Each relloc frame fills these from its state
vector by a :class:`PoseMap`: every degree of freedom is a state index, :data:`UNKNOWN` (the
frame does not estimate it: value 0, variance :data:`UNKNOWN_VARIANCE`, no correlation) or
:data:`EXACT_ZERO` (0 by the frame's definition: value 0, variance 0). So the 6×6 covariance is
``C = S P Sᵀ`` for the selection ``S`` of the estimated states, plus the diagonal of the rest.
The yaw is the frame's heading; orientation is the quaternion of a pure yaw
``(0, 0, sin(ψ/2), cos(ψ/2))`` (every relloc frame is level: no roll or pitch is estimated).

- ``relative_pose4`` ``(x, y, z, φ)`` → the subject's pose in the owner's body frame
  ``owner/base_link`` (REP 105), roll and pitch unknown;
- ``world_pose2`` ``(x, y, θ)`` → the subject's pose in the world frame ``map``; ``z`` is not
  estimated (0, unknown variance), nor are roll and pitch;
- ``airground_follower`` ``(r_x, r_y, θ_i, θ_0)`` (seed 003) → two poses in ``owner/common``,
  the frame at the owner's origin whose axes are those of the team's common frame: the
  leader ``(r_x, r_y, ·, θ_0)`` (z unknown) and the owner's own heading ``θ_i`` at the origin
  (position exactly 0 by the frame's definition), published as ``…/observer_heading``.

A frame without a map here has no pose meaning to ROS; its series are skipped and counted.
"""

from __future__ import annotations

import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from types import MappingProxyType

import numpy as np
from numpy.typing import NDArray

from relloc.core.angles import wrap_angle
from relloc.core.estimates import BeliefSeries, Estimates
from relloc.core.recording import Recording
from relloc.errors import ConfigError
from relloc.pipeline.frames import frame

Array = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

#: A degree of freedom the frame does not estimate.
UNKNOWN = -1
#: A degree of freedom that is exactly 0 by the frame's definition.
EXACT_ZERO = -2
#: Variance (m² or rad²) written for a degree of freedom the frame does not estimate — large
#: enough that any consumer treats it as no information (robot_localization-style convention).
UNKNOWN_VARIANCE = 1.0e6

#: The world frame of REP 105.
WORLD_FRAME = "map"
#: Degrees of freedom of a ROS pose, in covariance order.
ROS_DOFS = ("x", "y", "z", "roll", "pitch", "yaw")


@dataclass(frozen=True)
class PoseMap:
    """Where each ROS degree of freedom comes from: ``dofs[k]`` is a state index of the frame,
    :data:`UNKNOWN` or :data:`EXACT_ZERO`; ``parent`` names the ROS frame (``"{owner}"`` is
    replaced by the owner's name); ``suffix`` is appended to the topic (``""`` for the
    subject's pose); ``trajectory`` says whether it is a teammate's trajectory (TUM files)."""

    dofs: tuple[int, int, int, int, int, int]
    parent: str
    suffix: str = ""
    trajectory: bool = True


OWNER_BODY = "{owner}/base_link"
OWNER_COMMON = "{owner}/common"

#: The pose maps of every frame that has one (module docstring).
POSE_MAPS: Mapping[str, tuple[PoseMap, ...]] = MappingProxyType(
    {
        "relative_pose4": (PoseMap((0, 1, 2, UNKNOWN, UNKNOWN, 3), OWNER_BODY),),
        "world_pose2": (PoseMap((0, 1, UNKNOWN, UNKNOWN, UNKNOWN, 2), WORLD_FRAME),),
        "airground_follower": (
            PoseMap((0, 1, UNKNOWN, UNKNOWN, UNKNOWN, 3), OWNER_COMMON),
            PoseMap(
                (EXACT_ZERO, EXACT_ZERO, EXACT_ZERO, UNKNOWN, UNKNOWN, 2),
                OWNER_COMMON,
                suffix="observer_heading",
                trajectory=False,
            ),
        ),
    }
)


@dataclass(frozen=True, kw_only=True)
class PoseSeries:
    """One belief series as ROS poses: ``t (K,)``, ``position (K, 3)``, ``yaw (K,)``,
    ``cov (K, 6, 6)`` (ROS order); ``truth_position``/``truth_yaw`` the true
    values in the same frame (NaN where the recording has no truth at that time)."""

    owner: str
    subject: str
    track: str
    label: str
    topic: str
    frame_id: str
    trajectory: bool
    t: Array
    position: Array
    yaw: Array
    cov: Array
    truth_position: Array
    truth_yaw: Array

    @property
    def has_truth(self) -> BoolArray:
        return np.isfinite(self.truth_yaw)


@dataclass(frozen=True, kw_only=True)
class PoseSet:
    """Every series that has a pose meaning, the names used for ROS, and what was skipped."""

    poses: tuple[PoseSeries, ...]
    names: Mapping[str, str]
    skipped: Mapping[str, int]
    common_frame_owners: tuple[str, ...]


_TOKEN = re.compile(r"[^A-Za-z0-9_]")


def ros_token(name: str) -> str:
    """``name`` as one ROS name token: other characters than ``[A-Za-z0-9_]`` become ``_`` and
    a token starting with a digit (e.g. MRCLAM's robot ``1``) gets the prefix ``r``."""
    token = _TOKEN.sub("_", name)
    return "r" + token if not token or token[0].isdigit() else token


def ros_names(names: Sequence[str]) -> dict[str, str]:
    """A ROS token per name; ConfigError if two names would get the same token."""
    out: dict[str, str] = {}
    for name in names:
        token = ros_token(name)
        clash = [k for k, v in out.items() if v == token and k != name]
        if clash:
            raise ConfigError(
                f"ROS export: names {clash[0]!r} and {name!r} both become {token!r}; rename one"
            )
        out[name] = token
    return out


def _track_path(track: str) -> str:
    return "/".join(ros_token(part) for part in track.split("/") if part)


def series_topic(names: Mapping[str, str], s: BeliefSeries, suffix: str = "") -> str:
    """``/{owner}/estimates/{subject}[/{track}][/{suffix}]`` in ROS tokens. A track whose
    name has no part between slashes (``"/"``) adds nothing: a ROS name never ends in ``/``
    (nor holds ``//``)."""
    parts = [names[s.owner], "estimates", names[s.subject]]
    if _track_path(s.track):
        parts.append(_track_path(s.track))
    if suffix:
        parts.append(suffix)
    return "/" + "/".join(parts)


def select_covariance(cov: Array, dofs: Sequence[int]) -> Array:
    """The ROS 6×6 covariances ``(K, 6, 6)`` of states ``cov (K, d, d)`` (module docstring)."""
    out = np.zeros((cov.shape[0], 6, 6))
    est = np.array([k for k, i in enumerate(dofs) if i >= 0])
    idx = np.array([dofs[k] for k in est])
    out[:, est[:, None], est[None, :]] = cov[:, idx[:, None], idx[None, :]]
    for k, i in enumerate(dofs):
        if i == UNKNOWN:
            out[:, k, k] = UNKNOWN_VARIANCE
    return out


def select_pose(state: Array, dofs: Sequence[int]) -> tuple[Array, Array]:
    """``(position (K, 3), yaw (K,))`` of states ``(K, d)``; what is not estimated is 0."""
    values = np.zeros((state.shape[0], 6))
    for k, i in enumerate(dofs):
        if i >= 0:
            values[:, k] = state[:, i]
    return values[:, :3], np.asarray(wrap_angle(values[:, 5]), dtype=float)


def _truth(rec: Recording, s: BeliefSeries, t: Array) -> Array:
    """The true state of ``s`` at ``t``: NaN rows outside the span of the truth of its robots,
    and everywhere when the recording has no truth or the subject is not one of its robots."""
    f = frame(s.frame)
    out = np.full((t.size, f.dim), np.nan)
    if rec.truth is None or t.size == 0 or s.subject not in rec.robots:
        return out
    robots = [rec.index(r) for r in (s.owner, s.subject) if r in rec.robots]
    t0 = max(rec.truth[i].t[0] for i in robots)
    t1 = min(rec.truth[i].t[-1] for i in robots)
    inside = (t >= t0) & (t <= t1)
    if inside.any():
        out[inside] = f.truth(rec, s.owner, s.subject, t[inside])
    return out


def pose_set(estimates: Estimates, recording: Recording) -> PoseSet:
    """Map every belief series of ``estimates`` to ROS poses (module docstring).

    Skipped and counted: series in a frame without a pose map (``frame without a pose
    meaning: NAME``, one per record) and records with a non-finite mean or covariance.
    ConfigError if two series would share a topic (track names that differ only in what
    :func:`ros_token` replaces, e.g. ``a b`` and ``a_b``): their messages would merge into
    one channel.
    """
    owners = sorted({s.owner for s in estimates.beliefs} - set(recording.robots))
    names = ros_names([*recording.robots, *owners])
    skipped: dict[str, int] = {}
    poses: list[PoseSeries] = []
    common: set[str] = set()
    for s in estimates.beliefs:
        maps = POSE_MAPS.get(s.frame)
        if maps is None:
            reason = f"frame without a pose meaning: {s.frame}"
            skipped[reason] = skipped.get(reason, 0) + s.t.size
            continue
        if s.subject not in names:
            names.update(ros_names([*names, s.subject]))
        finite = np.all(np.isfinite(s.mean), axis=1) & np.all(np.isfinite(s.cov), axis=(1, 2))
        if not finite.all():
            reason = "non-finite belief"
            skipped[reason] = skipped.get(reason, 0) + int((~finite).sum())
        t = s.t[finite]
        truth = _truth(recording, s, t)
        for m in maps:
            if m.parent == OWNER_COMMON:
                common.add(s.owner)
            position, yaw = select_pose(s.mean[finite], m.dofs)
            truth_position, truth_yaw = select_pose(truth, m.dofs)
            known = np.all(np.isfinite(truth), axis=1)
            truth_position[~known] = np.nan
            truth_yaw[~known] = np.nan
            poses.append(
                PoseSeries(
                    owner=s.owner,
                    subject=s.subject,
                    track=s.track,
                    label=s.label + (f"/{m.suffix}" if m.suffix else ""),
                    topic=series_topic(names, s, m.suffix),
                    frame_id=m.parent.format(owner=names[s.owner]),
                    trajectory=m.trajectory,
                    t=t,
                    position=position,
                    yaw=yaw,
                    cov=select_covariance(s.cov[finite], m.dofs),
                    truth_position=truth_position,
                    truth_yaw=truth_yaw,
                )
            )
    check_unique([(p.topic, p.label) for p in poses], "topic")
    return PoseSet(
        poses=tuple(poses),
        names=MappingProxyType(names),
        skipped=MappingProxyType(skipped),
        common_frame_owners=tuple(sorted(common)),
    )


def check_unique(named: Sequence[tuple[object, str]], what: str) -> None:
    """ConfigError if two series labels of ``named`` (``(name, label)`` pairs) share a name."""
    seen: dict[object, str] = {}
    for name, label in named:
        if name in seen:
            raise ConfigError(
                f"ROS export: series {seen[name]!r} and {label!r} both become the {what} "
                f"{str(name)!r}; rename a track or robot"
            )
        seen[name] = label


def yaw_quaternion(yaw: Array) -> Array:
    """Quaternions ``(K, 4)`` as ``(x, y, z, w)`` of rotations by ``yaw`` about z."""
    half = 0.5 * np.asarray(yaw, dtype=float)
    out = np.zeros((half.size, 4))
    out[:, 2] = np.sin(half)
    out[:, 3] = np.cos(half)
    return out
