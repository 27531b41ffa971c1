"""Small ROS 2 bags written with rosbags for the loader tests (real files, real writer)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import Stores, get_typestore

STORE = get_typestore(Stores.ROS2_HUMBLE)
T = STORE.types
ODOM, POSE, RANGE = (
    "nav_msgs/msg/Odometry",
    "geometry_msgs/msg/PoseStamped",
    "sensor_msgs/msg/Range",
)
STRING = "std_msgs/msg/String"


def header(ns: int, frame: str = "") -> Any:
    stamp = T["builtin_interfaces/msg/Time"](sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)
    return T["std_msgs/msg/Header"](stamp=stamp, frame_id=frame)


def pose(x: float, y: float, z: float, yaw: float) -> Any:
    import math

    return T["geometry_msgs/msg/Pose"](
        position=T["geometry_msgs/msg/Point"](x=x, y=y, z=z),
        orientation=T["geometry_msgs/msg/Quaternion"](
            x=0.0, y=0.0, z=math.sin(yaw / 2), w=math.cos(yaw / 2)
        ),
    )


def quaternion_pose(x: float, y: float, z: float, q: tuple[float, float, float, float]) -> Any:
    return T["geometry_msgs/msg/Pose"](
        position=T["geometry_msgs/msg/Point"](x=x, y=y, z=z),
        orientation=T["geometry_msgs/msg/Quaternion"](x=q[0], y=q[1], z=q[2], w=q[3]),
    )


def odometry(ns: int, v: float, w: float, p: Any = None) -> Any:
    import numpy as np

    V3 = T["geometry_msgs/msg/Vector3"]
    twist = T["geometry_msgs/msg/Twist"](
        linear=V3(x=v, y=0.0, z=0.0), angular=V3(x=0.0, y=0.0, z=w)
    )
    return T[ODOM](
        header=header(ns, "odom"),
        child_frame_id="base_link",
        pose=T["geometry_msgs/msg/PoseWithCovariance"](
            pose=p if p is not None else pose(0, 0, 0, 0), covariance=np.zeros(36)
        ),
        twist=T["geometry_msgs/msg/TwistWithCovariance"](twist=twist, covariance=np.zeros(36)),
    )


def mocap(ns: int, p: Any) -> Any:
    return T[POSE](header=header(ns, "world"), pose=p)


def uwb(ns: int, r: float, lo: float = 0.0, hi: float = 0.0) -> Any:
    return T[RANGE](
        header=header(ns), radiation_type=0, field_of_view=0.0, min_range=lo, max_range=hi, range=r
    )


def write_bag(
    path: Path, messages: list[tuple[str, str, int, Any]], *, storage: str = "sqlite3"
) -> Path:
    """A rosbag2 folder at ``path`` with ``(topic, msgtype, receive_ns, message)`` in order."""
    plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
    with Writer(path, version=8, storage_plugin=plugin) as writer:
        cons: dict[str, Any] = {}
        for topic, msgtype, _, _ in messages:
            if topic not in cons:
                cons[topic] = writer.add_connection(topic, msgtype, typestore=STORE)
        for topic, msgtype, t, msg in messages:
            writer.write(cons[topic], t, STORE.serialize_cdr(msg, msgtype))
    return path


#: A mapping of the sample bags: robots alpha (odometry and motion capture) and beta (motion
#: capture only), radios on each, one surveyed and one unsurveyed static radio.
SAMPLE_MAPPING = """
name = "sample"
[[robots]]
name = "alpha"
odometry = "/alpha/odom"
truth = "/mocap/alpha"
[[robots]]
name = "beta"
truth = "/mocap/beta"
[uwb]
topics = "/u/{a}/{b}/d"
sigma = 0.1
[[uwb.nodes]]
name = "n_1"
robot = "alpha"
[[uwb.nodes]]
name = "n_2"
robot = "beta"
[[uwb.nodes]]
name = "n_3"
position = [0.0, 5.0, 0.0]
[[uwb.nodes]]
name = "n_4"
"""
