"""Estimates as one MCAP file in the ROS 2 profile: opens in Foxglove, replays with ``ros2 bag``.

Written with the ``mcap`` writer; messages are CDR-serialised by ``rosbags`` against the ROS 2
message definitions of its Humble type store, which are embedded as ``ros2msg`` schemas (so no
ROS install is needed to read the file). The file follows the MCAP ``ros2`` profile — message
encoding ``cdr``, schema encoding ``ros2msg``, ``offered_qos_profiles`` on every channel (an
empty list: a player uses its default QoS) — which is what rosbag2's MCAP storage reads, so
``ros2 bag play FILE`` (``-s mcap`` on Humble) replays it. Topics (names in ROS tokens,
:func:`relloc.pipeline.export.poses.ros_token`):

- ``/{owner}/estimates/{subject}[/{track}]`` — ``geometry_msgs/msg/PoseWithCovarianceStamped``
  in the frame of :mod:`relloc.pipeline.export.poses` (``owner/base_link``, ``map`` or
  ``owner/common``), one per record of the belief;
- ``/{owner}/ground_truth/{subject}[/{track}]`` — ``geometry_msgs/msg/PoseStamped``: the true
  value of the same quantity in the same frame at the same stamps (where truth is known);
- ``/ground_truth/{robot}`` — ``geometry_msgs/msg/PoseStamped`` in ``map``, and ``/tf`` —
  ``tf2_msgs/msg/TFMessage`` with ``map → robot/base_link`` for every robot (and
  ``owner/base_link → owner/common`` where a seed-003 belief lives) from the ground truth, at
  every record time of any belief inside the truth's span.

Stamps are the recording's times in seconds (header stamp = log time = publish time); they
must lie in ``[0, 2³¹)`` s, the range of a ``builtin_interfaces/Time``.
"""

from __future__ import annotations

import time
from collections import Counter
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from relloc.core.recording import Recording
from relloc.errors import ConfigError, DataError, require
from relloc.pipeline.export.poses import (
    OWNER_COMMON,
    UNKNOWN_VARIANCE,
    WORLD_FRAME,
    PoseSeries,
    PoseSet,
    yaw_quaternion,
)
from relloc.pipeline.frames import common_frame_yaw
from relloc.pipeline.output import replace_file

Array = NDArray[np.float64]

POSE_COV = "geometry_msgs/msg/PoseWithCovarianceStamped"
POSE = "geometry_msgs/msg/PoseStamped"
TF = "tf2_msgs/msg/TFMessage"
TF_TOPIC = "/tf"
#: ``offered_qos_profiles`` of every channel: none recorded, so a player uses its default.
OFFERED_QOS = "[]"
_MAX_STAMP_S = 2.0**31


@dataclass(frozen=True)
class McapWritten:
    """What was written: the file, its size, the messages per topic and the time it took."""

    path: Path
    bytes: int
    messages: dict[str, int]
    seconds: float

    def to_dict(self) -> dict[str, Any]:
        return {
            "path": str(self.path),
            "bytes": self.bytes,
            "messages": sum(self.messages.values()),
            "topics": dict(sorted(self.messages.items())),
            "seconds": round(self.seconds, 3),
        }


MCAP_MAGIC = b"\x89MCAP0\r\n"
"""The first bytes of every MCAP file (its specification's magic)."""


def check_mcap_path(path: Path) -> Path:
    """``path`` if an MCAP file can be written there (ConfigError naming ``--mcap`` if not): a
    file name ending in ``.mcap`` (so never one of the run's own outputs, e.g.
    ``OUT/summary.json``), not a link, and not an existing file of another format."""
    if path.is_dir():
        raise ConfigError(f"--mcap: {path} is a folder; give a file name such as out.mcap")
    if path.is_symlink():
        raise ConfigError(f"--mcap: {path} is a link; give the file itself")
    if path.suffix != ".mcap":  # also keeps it off the files a run writes beside it
        raise ConfigError(
            f"--mcap: {path} does not end in .mcap, by which ros2 bag play and Foxglove know "
            "the format; give a name such as out.mcap"
        )
    if path.exists():  # replace an earlier export, never a file of another kind
        with path.open("rb") as f:
            if f.read(len(MCAP_MAGIC)) != MCAP_MAGIC:
                raise ConfigError(f"--mcap: {path} exists and is not an MCAP file; not replaced")
    return path


def stamp_ns(t: float, where: str) -> int:
    """Nanoseconds of a time ``t`` in seconds (DataError naming ``where`` outside ``[0, 2³¹)``)."""
    if not (np.isfinite(t) and 0.0 <= t < _MAX_STAMP_S):
        raise DataError(f"{where}: time {t!r} s cannot be a ROS stamp (it must lie in [0, 2^31) s)")
    return round(t * 1e9)


class _Messages:
    """Builds rosbags message objects of the few types written here."""

    def __init__(self) -> None:
        typesys = require("rosbags.typesys", "ros")
        self.store = typesys.get_typestore(typesys.Stores.ROS2_HUMBLE)
        self._t = self.store.types

    def header(self, ns: int, frame_id: str) -> Any:
        sec, nanosec = divmod(ns, 1_000_000_000)
        return self._t["std_msgs/msg/Header"](
            stamp=self._t["builtin_interfaces/msg/Time"](sec=sec, nanosec=nanosec),
            frame_id=frame_id,
        )

    def pose(self, position: Array, quaternion: Array) -> Any:
        return self._t["geometry_msgs/msg/Pose"](
            position=self._t["geometry_msgs/msg/Point"](*map(float, position)),
            orientation=self._t["geometry_msgs/msg/Quaternion"](*map(float, quaternion)),
        )

    def pose_cov(self, ns: int, frame_id: str, position: Array, q: Array, cov: Array) -> Any:
        return self._t[POSE_COV](
            header=self.header(ns, frame_id),
            pose=self._t["geometry_msgs/msg/PoseWithCovariance"](
                pose=self.pose(position, q), covariance=np.ascontiguousarray(cov.reshape(36))
            ),
        )

    def pose_stamped(self, ns: int, frame_id: str, position: Array, q: Array) -> Any:
        return self._t[POSE](header=self.header(ns, frame_id), pose=self.pose(position, q))

    def transform(self, ns: int, parent: str, child: str, position: Array, q: Array) -> Any:
        t = self._t
        return t["geometry_msgs/msg/TransformStamped"](
            header=self.header(ns, parent),
            child_frame_id=child,
            transform=t["geometry_msgs/msg/Transform"](
                translation=t["geometry_msgs/msg/Vector3"](*map(float, position)),
                rotation=t["geometry_msgs/msg/Quaternion"](*map(float, q)),
            ),
        )

    def tf(self, transforms: list[Any]) -> Any:
        return self._t[TF](transforms=transforms)


def _belief_messages(m: _Messages, p: PoseSeries) -> Iterator[tuple[int, str, str, Any]]:
    q = yaw_quaternion(p.yaw)
    q_truth = yaw_quaternion(p.truth_yaw)
    truth_topic = p.topic.replace("/estimates/", "/ground_truth/", 1)
    for k, t in enumerate(p.t):
        ns = stamp_ns(float(t), p.label)
        yield ns, p.topic, POSE_COV, m.pose_cov(ns, p.frame_id, p.position[k], q[k], p.cov[k])
        if p.has_truth[k]:
            msg = m.pose_stamped(ns, p.frame_id, p.truth_position[k], q_truth[k])
            yield ns, truth_topic, POSE, msg


def _truth_messages(
    m: _Messages, poses: PoseSet, recording: Recording
) -> Iterator[tuple[int, str, str, Any]]:
    """World truth and ``/tf`` at every record time of any pose series (module docstring):
    one ``TFMessage`` per stamp with the transforms of every robot whose truth covers it."""
    if recording.truth is None or not poses.poses:
        return
    grid = np.unique(np.concatenate([p.t for p in poses.poses]))
    names = poses.names
    common_yaw = common_frame_yaw(recording)
    pose = np.full((recording.n_robots, grid.size, 4), np.nan)
    for i, gt in enumerate(recording.truth):
        inside = (grid >= gt.t[0]) & (grid <= gt.t[-1])
        if inside.any():
            pose[i, inside] = gt.at(grid[inside])
    q = yaw_quaternion(pose[..., 3].reshape(-1)).reshape(recording.n_robots, grid.size, 4)
    q_common = yaw_quaternion(common_yaw - pose[..., 3].reshape(-1)).reshape(q.shape)
    for k, tk in enumerate(grid):
        ns = stamp_ns(float(tk), "ground truth")
        transforms = []
        for i, robot in enumerate(recording.robots):
            if not np.isfinite(pose[i, k, 3]):
                continue
            body = f"{names[robot]}/base_link"
            yield (
                ns,
                f"/ground_truth/{names[robot]}",
                POSE,
                m.pose_stamped(ns, WORLD_FRAME, pose[i, k, :3], q[i, k]),
            )
            transforms.append(m.transform(ns, WORLD_FRAME, body, pose[i, k, :3], q[i, k]))
            if robot in poses.common_frame_owners:
                common = OWNER_COMMON.format(owner=names[robot])
                transforms.append(m.transform(ns, body, common, np.zeros(3), q_common[i, k]))
        if transforms:
            yield ns, TF_TOPIC, TF, m.tf(transforms)


def write_mcap(
    path: Path, poses: PoseSet, recording: Recording, *, estimator: str = ""
) -> McapWritten:
    """Write ``poses`` (and the recording's truth) to the MCAP file ``path`` (module
    docstring), whole or not at all (:func:`~relloc.pipeline.output.replace_file`)."""
    started = time.perf_counter()
    m = _Messages()
    messages = [msg for p in poses.poses for msg in _belief_messages(m, p)] + list(
        _truth_messages(m, poses, recording)
    )
    messages.sort(key=lambda x: x[0])  # (stable) replay order: by stamp
    path = check_mcap_path(Path(path))
    counts: Counter[str] = Counter()
    replace_file(path, "--mcap", lambda tmp: _write(tmp, messages, m, counts, recording, estimator))
    return McapWritten(
        path=path,
        bytes=path.stat().st_size,
        messages=dict(counts),
        seconds=time.perf_counter() - started,
    )


def _write(
    partial: Path,
    messages: list[tuple[int, str, str, Any]],
    m: _Messages,
    counts: Counter[str],
    recording: Recording,
    estimator: str,
) -> None:
    from relloc import __version__

    writer_module = require("mcap.writer", "ros")
    with open(partial, "wb") as f:
        w = writer_module.Writer(f, compression=writer_module.CompressionType.ZSTD)
        w.start(profile="ros2", library=f"relloc {__version__}")
        schemas = {
            name: w.register_schema(
                name=name,
                encoding="ros2msg",
                data=m.store.generate_msgdef(name, ros_version=2)[0].encode(),
            )
            for name in (POSE_COV, POSE, TF)
        }
        channels: dict[str, int] = {}
        for ns, topic, typename, msg in messages:
            if topic not in channels:
                channels[topic] = w.register_channel(
                    topic=topic,
                    message_encoding="cdr",
                    schema_id=schemas[typename],
                    metadata={"offered_qos_profiles": OFFERED_QOS},
                )
            data = bytes(m.store.serialize_cdr(msg, typename))
            w.add_message(
                channel_id=channels[topic],
                log_time=ns,
                data=data,
                publish_time=ns,
                sequence=counts[topic],
            )
            counts[topic] += 1
        w.add_metadata(
            "relloc",
            {
                "estimator": estimator,
                "source": recording.source,
                "robots": ",".join(recording.robots),
                "unknown_variance": repr(UNKNOWN_VARIANCE),
                "covariance_order": "x,y,z,roll,pitch,yaw (row-major)",
            },
        )
        w.finish()
