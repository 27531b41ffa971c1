"""Read a ROS 2 bag (rosbag2 folder, ``.db3`` or ``.mcap``) into a :class:`Recording` (extra
``ros``: the pure-Python ``rosbags`` package, no ROS install needed).

A :class:`~relloc.datasets.bag_mapping.BagMapping` says which topic is what:

- ``nav_msgs/Odometry`` → the robot's :class:`~relloc.core.recording.Odometry`: the twist
  ``(linear.x, linear.y, linear.z, angular.z)``, which REP 105 states in the body frame
  (``child_frame_id``); the pose is kept (:attr:`BagRecording.odometry_pose`) only if asked;
- ``geometry_msgs/PoseStamped`` (motion capture) → the robot's
  :class:`~relloc.core.recording.GroundTruth` ``(x, y, z, ψ)``, ``ψ`` the yaw of the quaternion
  (``atan2(2(wz + xy), 1 − 2(y² + z²))``);
- ``sensor_msgs/Range`` on the UWB template → one ``range`` reading per message between the
  two named radios (:attr:`BagRecording.ranges`, every valid reading at radio level); those
  between a robot's radio and another robot's or a static radio of known position also enter
  :attr:`Recording.measurements` (observer: the end whose robot carries more radios, so that a
  reading is unambiguous; ``sensor``: which of the observer's radios; a static radio is a
  landmark); the others (two static radios, two radios of one robot, a static radio of unknown
  position) are counted by reason in :attr:`BagRecording.radio_only`
  (``uwb_readings_not_in_recording`` of :meth:`BagRecording.to_dict`).

Time
----
Each message's time is its header stamp; a message whose stamp is zero (an unset header) takes
its bag receive time minus the bag's median offset ``receive − header`` (counted per topic in
:attr:`BagRecording.stamps_from_receive`). ``stamp = "receive"`` in the mapping uses receive times
throughout. The offset per topic and for the bag is reported (:attr:`BagRecording.stamp_offset_s`).
Times are seconds from :attr:`BagRecording.time_origin_ns` (the earliest time read).

Bad messages
------------
Per topic, in receive order, a message is skipped and counted by reason (its 1-based index in
the topic is the ``line`` of the :class:`~relloc.core.recording.SkippedRow`): it cannot be
deserialised; a value is not finite, or finite but beyond what any robot reports (a speed,
turn rate or position beyond :mod:`relloc.core.limits`, a range beyond :data:`MAX_SENSOR_RANGE_M`:
``out of bounds``, which would overflow a filter); a quaternion of zero norm; a range ≤ 0 or
outside the message's own ``[min_range, max_range]`` (when ``max_range > 0``); a time not
after the previous kept message of the topic (unsorted or duplicate stamps); listed by the
bag's metadata but not found in its storage (``not in storage``: a topic whose stored type or
id disagrees with the metadata). A link published in both directions is read from one
direction when ``fold_directions`` is set — the one with more
messages, the first topic in sorted order on a tie — and the other direction's messages are
counted as ``folded: other direction``. Topics the mapping does not name are listed in
:attr:`BagRecording.unknown_topics`; a UWB topic naming a radio the mapping lacks
is counted as skipped (``unknown node``). A topic the mapping names that is missing from the bag
or has another message type is a :class:`~relloc.errors.ConfigError` naming the key; a bag that
cannot be opened is a :class:`~relloc.errors.DataError` naming the path.
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from relloc.core.limits import (
    MAX_ABS_POSITION_M,
    MAX_SENSOR_RANGE_M,
    MAX_SPEED_M_S,
    MAX_YAW_RATE_RAD_S,
)
from relloc.core.recording import (
    NO_TARGET,
    FileSkips,
    GroundTruth,
    Measurements,
    Odometry,
    Recording,
    SkippedRow,
    SkipReport,
    empty_measurements,
    measurement_rows,
)
from relloc.datasets.bag_mapping import BagMapping
from relloc.errors import ConfigError, DataError, require

Array = NDArray[np.float64]
IntArray = NDArray[np.int64]

ODOMETRY_TYPE = "nav_msgs/msg/Odometry"
POSE_TYPE = "geometry_msgs/msg/PoseStamped"
RANGE_TYPE = "sensor_msgs/msg/Range"
#: How many skipped messages per topic are kept as examples.
MAX_SKIP_EXAMPLES = 5


class BadMessage(Exception):
    """A message that cannot be used: ``reason`` is counted, ``detail`` is the example text."""

    def __init__(self, reason: str, detail: str) -> None:
        super().__init__(detail)
        self.reason = reason
        self.detail = detail


# ----------------------------------------------------------------------------------------------
# One message → numbers (pure; fuzzed)
# ----------------------------------------------------------------------------------------------


def stamp_ns(msg: Any) -> int:
    """Header stamp in ns (0 when unset); a negative or malformed stamp is a :class:`BadMessage`."""
    try:
        sec, nsec = int(msg.header.stamp.sec), int(msg.header.stamp.nanosec)
    except (AttributeError, TypeError, ValueError, OverflowError) as exc:
        raise BadMessage("malformed header", f"header stamp unreadable ({exc})") from None
    if sec < 0 or not 0 <= nsec < 1_000_000_000:
        raise BadMessage("malformed header", f"header stamp sec={sec} nanosec={nsec}")
    return sec * 1_000_000_000 + nsec


def _finite(
    values: tuple[float, ...], what: str, limits: tuple[float, ...] | None = None
) -> tuple[float, ...]:
    """The values as floats; each finite and, with ``limits``, within ± its limit."""
    try:
        out = tuple(float(v) for v in values)
    except (TypeError, ValueError) as exc:
        raise BadMessage("not a number", f"{what}: {exc}") from None
    if not all(math.isfinite(v) for v in out):
        raise BadMessage("not finite", f"{what} = {out}")
    if limits is not None and any(abs(v) > lim for v, lim in zip(out, limits, strict=True)):
        raise BadMessage("out of bounds", f"{what} = {out} beyond ±{limits}")
    return out


def yaw_of(qx: float, qy: float, qz: float, qw: float) -> float:
    """Yaw ``ψ = atan2(2(wz + xy), 1 − 2(y² + z²))`` of a quaternion (normalised first)."""
    q = _finite((qx, qy, qz, qw), "orientation")
    norm = math.sqrt(sum(v * v for v in q))
    if not norm > 1e-9:
        raise BadMessage("zero quaternion", f"orientation {q} has zero norm")
    x, y, z, w = (v / norm for v in q)
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


def _pose4(pose: Any) -> tuple[float, float, float, float]:
    try:
        p, q = pose.position, pose.orientation
        xyz = _finite((p.x, p.y, p.z), "position", (MAX_ABS_POSITION_M,) * 3)
        yaw = yaw_of(q.x, q.y, q.z, q.w)
    except AttributeError as exc:
        raise BadMessage("malformed pose", str(exc)) from None
    return xyz[0], xyz[1], xyz[2], yaw


def odometry_sample(msg: Any) -> tuple[tuple[float, ...], tuple[float, float, float, float]]:
    """``(v_x, v_y, v_z, ω_z)`` of a ``nav_msgs/Odometry`` and its pose ``(x, y, z, ψ)``."""
    try:
        lin, ang = msg.twist.twist.linear, msg.twist.twist.angular
        velocity = _finite(
            (lin.x, lin.y, lin.z, ang.z), "twist", (*(MAX_SPEED_M_S,) * 3, MAX_YAW_RATE_RAD_S)
        )
    except AttributeError as exc:
        raise BadMessage("malformed odometry", str(exc)) from None
    return velocity, _pose4(msg.pose.pose)


def truth_sample(msg: Any) -> tuple[float, float, float, float]:
    """``(x, y, z, ψ)`` of a ``geometry_msgs/PoseStamped``."""
    try:
        return _pose4(msg.pose)
    except AttributeError as exc:
        raise BadMessage("malformed pose", str(exc)) from None


def range_sample(msg: Any) -> float:
    """The range (m) of a ``sensor_msgs/Range``: finite, > 0 and, when the message states a
    ``max_range > 0``, inside ``[min_range, max_range]``."""
    try:
        r, lo, hi = _finite((msg.range, msg.min_range, msg.max_range), "range")
    except AttributeError as exc:
        raise BadMessage("malformed range", str(exc)) from None
    if not r > 0:
        raise BadMessage("range ≤ 0", f"range = {r}")
    if r > MAX_SENSOR_RANGE_M:
        raise BadMessage("out of bounds", f"range {r} beyond {MAX_SENSOR_RANGE_M:g} m")
    if hi > 0 and not lo <= r <= hi:
        raise BadMessage("range out of bounds", f"range {r} outside [{lo}, {hi}]")
    return r


# ----------------------------------------------------------------------------------------------
# The bag
# ----------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class TopicInfo:
    """One topic of a bag: type, message count, first/last receive time (s from bag start)."""

    topic: str
    msgtype: str
    count: int
    first_s: float
    last_s: float

    @property
    def rate_hz(self) -> float:
        span = self.last_s - self.first_s
        return (self.count - 1) / span if self.count > 1 and span > 0 else 0.0


@dataclass(frozen=True)
class _Message:
    index: int  # 1-based within its topic
    receive_ns: int
    msg: Any


class _Bag:
    """An open bag: its topics, typed, and their messages deserialised lazily."""

    def __init__(self, path: Path) -> None:
        rosbags = require("rosbags.highlevel", "ros")
        typesys = require("rosbags.typesys", "ros")
        self.path = path
        store = typesys.get_typestore(typesys.Stores.ROS2_HUMBLE)
        try:
            self.reader = rosbags.AnyReader([path], default_typestore=store)
            self.reader.open()
        except FileNotFoundError:
            if path.is_dir() and not (path / "metadata.yaml").exists():
                raise DataError(
                    f"{path}: a rosbag2 folder needs its metadata.yaml, which is missing "
                    "(or give the .db3 / .mcap file itself)"
                ) from None
            raise DataError(f"{path}: no such bag (a rosbag2 folder, .db3 or .mcap)") from None
        except Exception as exc:  # rosbags raises its own classes for unreadable bags
            raise DataError(f"{path}: cannot open as a ROS 2 bag: {exc}") from None
        self.start_ns = int(self.reader.start_time)

    def close(self) -> None:
        self.reader.close()

    def connections(self) -> dict[str, Any]:
        return {c.topic: c for c in self.reader.connections}

    def topic_infos(self) -> tuple[TopicInfo, ...]:
        """Counts and receive-time spans per topic (one pass over the message index)."""
        first: dict[str, int] = {}
        last: dict[str, int] = {}
        count: Counter[str] = Counter()
        for con, t, _ in self.reader.messages():
            first.setdefault(con.topic, t)
            last[con.topic] = t
            count[con.topic] += 1
        out = []
        for con in sorted(self.reader.connections, key=lambda c: c.topic):
            n = count[con.topic]
            t0 = (first.get(con.topic, self.start_ns) - self.start_ns) / 1e9
            t1 = (last.get(con.topic, self.start_ns) - self.start_ns) / 1e9
            out.append(TopicInfo(con.topic, con.msgtype, n, t0, t1))
        return tuple(out)

    def messages(self, topics: list[str]) -> Iterator[tuple[str, _Message | BadMessage]]:
        """Every message of ``topics`` in receive order, deserialised (or the failure)."""
        cons = [c for c in self.reader.connections if c.topic in set(topics)]
        if not cons:  # the reader takes no connections as "every topic"
            return
        index: Counter[str] = Counter()
        for con, t, raw in self.reader.messages(connections=cons):
            index[con.topic] += 1
            try:
                msg = self.reader.deserialize(raw, con.msgtype)
            except Exception as exc:  # a corrupt payload: counted, never fatal
                yield (
                    con.topic,
                    BadMessage("cannot deserialise", f"message {index[con.topic]}: {exc}"),
                )
                continue
            yield con.topic, _Message(index[con.topic], int(t), msg)
        listed: Counter[str] = Counter()
        for con in cons:
            listed[con.topic] += con.msgcount
        for topic in sorted(listed):  # listed by the bag's metadata, not in its storage
            for k in range(index[topic] + 1, listed[topic] + 1):
                yield (
                    topic,
                    BadMessage(
                        "not in storage", f"message {k} of the {listed[topic]} the metadata lists"
                    ),
                )


def inspect_bag(path: Path | str) -> tuple[TopicInfo, ...]:
    """The topics of a bag with type, count and rate (``relloc bag inspect``)."""
    bag = _Bag(Path(path))
    try:
        return bag.topic_infos()
    finally:
        bag.close()


@dataclass(frozen=True, kw_only=True)
class UwbRanges:
    """Every valid UWB reading at radio level: ``node_a``/``node_b`` index the mapping's
    ``uwb.nodes``; sorted by time."""

    t: Array
    node_a: IntArray
    node_b: IntArray
    value: Array

    def link_mask(self, a: int, b: int) -> NDArray[np.bool_]:
        return ((self.node_a == a) & (self.node_b == b)) | ((self.node_a == b) & (self.node_b == a))

    def links(self) -> list[tuple[int, int]]:
        ends = zip(self.node_a.tolist(), self.node_b.tolist(), strict=True)
        return sorted({(min(a, b), max(a, b)) for a, b in ends})


@dataclass(frozen=True, kw_only=True)
class BagRecording:
    """A bag read through a mapping: the :class:`Recording` and what only the bag knows."""

    path: Path
    mapping: BagMapping
    recording: Recording
    ranges: UwbRanges
    time_origin_ns: int
    stamp_offset_s: dict[str, float]
    stamps_from_receive: dict[str, int]
    unknown_topics: tuple[TopicInfo, ...]
    odometry_pose: dict[str, tuple[Array, Array]] = field(default_factory=dict)
    radio_only: dict[str, int] = field(default_factory=dict)
    """UWB readings kept in :attr:`ranges` only, not in the recording's measurements (no
    filter can use them), by reason (:data:`RADIO_ONLY_REASONS`; absent when none)."""

    def node_truth(self, node: int, t: Array) -> Array:
        """World position ``(len(t), 3)`` of radio ``node`` from motion capture (the carrying
        robot's pose ⊕ the antenna offset) or its surveyed position; NaN where unknown."""
        assert self.mapping.uwb is not None
        spec = self.mapping.uwb.nodes[node]
        out = np.full((np.size(t), 3), np.nan)
        if spec.robot is None:
            if spec.position is not None:
                out[:] = spec.position
            return out
        truth = self.recording.truth
        if truth is None:
            return out
        gt = truth[self.mapping.robot_index(spec.robot)]
        inside = (t >= gt.t[0]) & (t <= gt.t[-1])
        pose = gt.at(t[inside])
        c, s = np.cos(pose[:, 3]), np.sin(pose[:, 3])
        ox, oy, oz = spec.offset
        out[inside, 0] = pose[:, 0] + c * ox - s * oy
        out[inside, 1] = pose[:, 1] + s * ox + c * oy
        out[inside, 2] = pose[:, 2] + oz
        return out

    def to_dict(self) -> dict[str, Any]:
        """What the loader did, JSON-ready (for summary.json)."""
        return {
            "bag": str(self.path),
            "mapping": self.mapping.source,
            "time_origin_unix_s": self.time_origin_ns / 1e9,
            "stamp_offset_s": self.stamp_offset_s,
            "stamps_from_receive": self.stamps_from_receive,
            "unknown_topics": [f"{t.topic} ({t.msgtype}, {t.count})" for t in self.unknown_topics],
            "uwb_readings": int(self.ranges.t.size),
            "uwb_readings_not_in_recording": dict(self.radio_only),
            "skips": self.recording.skips.to_dict(),
        }


class _TopicLog:
    """Skips of one topic (reasons counted, first examples kept)."""

    def __init__(self) -> None:
        self.read = 0
        self.kept = 0
        self.reasons: Counter[str] = Counter()
        self.examples: list[SkippedRow] = []

    def skip(self, index: int, reason: str, detail: str) -> None:
        self.reasons[reason] += 1
        if len(self.examples) < MAX_SKIP_EXAMPLES:
            self.examples.append(SkippedRow(index, reason, detail))


@dataclass
class _Stream:
    """Kept samples of one topic: message index, receive time, header stamp (0 = unset) and
    the converted payload."""

    rows: list[tuple[int, int, int, Any]] = field(default_factory=list)


def _check_topics(path: Path, mapping: BagMapping, connections: dict[str, Any]) -> None:
    for i, r in enumerate(mapping.robots):
        for key, topic, msgtype in (
            ("odometry", r.odometry, ODOMETRY_TYPE),
            ("truth", r.truth, POSE_TYPE),
        ):
            if topic is None:
                continue
            where = f"{mapping.source or 'mapping'}: robots[{i}].{key}"
            if topic not in connections:
                raise ConfigError(f"{where}: topic {topic!r} is not in the bag {path}")
            if connections[topic].msgtype != msgtype:
                raise ConfigError(
                    f"{where}: topic {topic!r} carries {connections[topic].msgtype}, "
                    f"expected {msgtype}"
                )


def _uwb_topics(
    mapping: BagMapping, connections: dict[str, Any], logs: dict[str, _TopicLog]
) -> dict[str, tuple[int, int] | None]:
    """UWB topic → node indices ``(a, b)`` (``None``: skipped, reason logged per message)."""
    out: dict[str, tuple[int, int] | None] = {}
    uwb = mapping.uwb
    if uwb is None:
        return out
    for topic in sorted(connections):
        link = uwb.link_of(topic)
        if link is None:
            continue
        if connections[topic].msgtype != RANGE_TYPE:
            raise ConfigError(
                f"{mapping.source or 'mapping'}: uwb.topics: {topic!r} matches the template but "
                f"carries {connections[topic].msgtype}, expected {RANGE_TYPE}"
            )
        a, b = uwb.node_index(link[0]), uwb.node_index(link[1])
        out[topic] = None if a is None or b is None or a == b else (a, b)
        logs[topic] = _TopicLog()
    if uwb.fold_directions:  # per link, the direction with the most messages is read
        kept: dict[tuple[int, int], str] = {}
        for topic in sorted(out, key=lambda tp: (-int(connections[tp].msgcount), tp)):
            ab = out[topic]
            if ab is None:
                continue
            key = (min(ab), max(ab))
            if key in kept:
                out[topic] = None
            else:
                kept[key] = topic
    return out


def _fold_reason(mapping: BagMapping, topic: str) -> str:
    assert mapping.uwb is not None
    link = mapping.uwb.link_of(topic)
    assert link is not None
    if mapping.uwb.node_index(link[0]) is None or mapping.uwb.node_index(link[1]) is None:
        return "unknown node"
    if link[0] == link[1]:
        return "node paired with itself"
    return "folded: other direction"


def load_bag(path: Path | str, mapping: BagMapping) -> BagRecording:
    """Read the bag at ``path`` through ``mapping`` (module docstring)."""
    path = Path(path)
    bag = _Bag(path)
    try:
        connections = bag.connections()
        _check_topics(path, mapping, connections)
        logs: dict[str, _TopicLog] = {}
        for r in mapping.robots:
            for topic in (r.odometry, r.truth):
                if topic is not None:
                    logs[topic] = _TopicLog()
        uwb_links = _uwb_topics(mapping, connections, logs)
        streams = _read_streams(bag, mapping, logs, uwb_links)
        infos = bag.topic_infos()
    finally:
        bag.close()
    return _assemble(path, mapping, streams, logs, uwb_links, infos)


def _convert(topic: str, mapping: BagMapping, msg: Any) -> Any:
    for r in mapping.robots:
        if topic == r.odometry:
            return odometry_sample(msg)
        if topic == r.truth:
            return truth_sample(msg)
    return range_sample(msg)


def _read_streams(
    bag: _Bag,
    mapping: BagMapping,
    logs: dict[str, _TopicLog],
    uwb_links: dict[str, tuple[int, int] | None],
) -> dict[str, _Stream]:
    streams = {topic: _Stream() for topic in logs}
    for topic, item in bag.messages(list(logs)):
        log = logs[topic]
        log.read += 1
        if isinstance(item, BadMessage):
            log.skip(log.read, item.reason, item.detail)
            continue
        if topic in uwb_links and uwb_links[topic] is None:
            reason = _fold_reason(mapping, topic)
            log.skip(item.index, reason, f"{topic} message {item.index}")
            continue
        try:
            header = stamp_ns(item.msg)
            payload = _convert(topic, mapping, item.msg)
        except BadMessage as bad:
            log.skip(item.index, bad.reason, f"message {item.index}: {bad.detail}")
            continue
        streams[topic].rows.append((item.index, item.receive_ns, header, payload))
    return streams


def _offsets(streams: dict[str, _Stream]) -> tuple[dict[str, float], int]:
    """Median ``receive − header`` (s) per topic with set stamps, and for the bag (ns)."""
    per_topic: dict[str, float] = {}
    pooled: list[int] = []
    for topic, s in streams.items():
        d = [rec - hdr for _, rec, hdr, _ in s.rows if hdr > 0]
        if d:
            per_topic[topic] = float(np.median(d)) / 1e9
            pooled.extend(d)
    bag = int(np.median(pooled)) if pooled else 0
    per_topic["bag"] = bag / 1e9
    return per_topic, bag


def _timed(
    stream: _Stream, log: _TopicLog, offset_ns: int, receive_only: bool
) -> tuple[list[int], list[Any], int]:
    """Each kept sample's time (ns) and payload, times strictly increasing (later duplicates or
    earlier times skipped and counted); also how many took their time from receive time."""
    times: list[int] = []
    payloads: list[Any] = []
    from_receive = 0
    for index, rec, hdr, payload in stream.rows:
        if receive_only:
            t = rec
        elif hdr == 0:
            t = rec - offset_ns
            from_receive += 1
        else:
            t = hdr
        if times and t <= times[-1]:
            log.skip(
                index,
                "stamp not after the previous message",
                f"message {index}: stamp {t} ns is not after {times[-1]} ns",
            )
            continue
        times.append(t)
        payloads.append(payload)
    return times, payloads, from_receive


def _assemble(
    path: Path,
    mapping: BagMapping,
    streams: dict[str, _Stream],
    logs: dict[str, _TopicLog],
    uwb_links: dict[str, tuple[int, int] | None],
    infos: tuple[TopicInfo, ...],
) -> BagRecording:
    offsets, bag_offset = _offsets(streams)
    receive_only = mapping.stamp == "receive"
    timed: dict[str, tuple[list[int], list[Any]]] = {}
    from_receive: dict[str, int] = {}
    for topic, stream in streams.items():
        times, payloads, n_rec = _timed(stream, logs[topic], bag_offset, receive_only)
        timed[topic] = (times, payloads)
        if n_rec:
            from_receive[topic] = n_rec
    all_times = [t for times, _ in timed.values() for t in times]
    if not all_times:
        raise DataError(f"{path}: no usable message on the mapped topics")
    origin = min(all_times)

    def seconds(times: list[int]) -> Array:
        return (np.asarray(times, dtype=np.int64) - origin) / 1e9

    odometry: list[Odometry] = []
    poses: dict[str, tuple[Array, Array]] = {}
    truths: list[GroundTruth | None] = []
    for r in mapping.robots:
        where = f"{path}:{r.odometry}"
        if r.odometry is not None and timed[r.odometry][0]:
            times, payloads = timed[r.odometry]
            vel = np.array([p[0] for p in payloads], dtype=float)
            t = seconds(times)
            sigma = np.array(r.odometry_sigma)
            odometry.append(Odometry(t=t, velocity=vel, sigma=sigma, where=where))
            if r.odometry_pose:
                poses[r.name] = (t, np.array([p[1] for p in payloads], dtype=float))
        else:
            odometry.append(
                Odometry(t=np.zeros(0), velocity=np.zeros((0, 4)), sigma=np.array(r.odometry_sigma))
            )
        if r.truth is not None and len(timed[r.truth][0]) >= 2:
            times, payloads = timed[r.truth]
            truths.append(
                GroundTruth(
                    t=seconds(times),
                    pose=np.array(payloads, dtype=float),
                    where=f"{path}:{r.truth}",
                )
            )
        else:
            truths.append(None)
    ranges = _ranges(timed, uwb_links, seconds)
    landmarks, measurements, repeats, radio_only = _range_rows(mapping, ranges)
    file_skips = tuple(
        FileSkips(
            file=f"{path}:{topic}",
            rows_read=log.read,
            rows_kept=log.read - sum(log.reasons.values()),
            skipped=dict(log.reasons),
            examples=tuple(log.examples),
        )
        for topic, log in sorted(logs.items())
    )
    if repeats:
        file_skips += (
            FileSkips(
                file=f"{path}:uwb",
                rows_read=int(ranges.t.size),
                rows_kept=int(ranges.t.size) - repeats,
                skipped={"repeats a reading of another topic": repeats},
            ),
        )
    truth = tuple(t for t in truths if t is not None)
    recording = Recording(
        robots=tuple(r.name for r in mapping.robots),
        platforms=tuple(r.platform for r in mapping.robots),
        odometry=tuple(odometry),
        measurements=measurements,
        truth=truth if len(truth) == len(truths) else None,
        landmarks=landmarks,
        source=str(path),
        meta={
            "dataset": "rosbag2",
            "mapping": mapping.source,
            "time_origin_unix_s": origin / 1e9,
            "robots_without_truth": [
                r.name for r, t in zip(mapping.robots, truths, strict=True) if t is None
            ],
        },
        skips=SkipReport(file_skips),
    )
    named = mapping.topics() | set(uwb_links)
    return BagRecording(
        path=path,
        mapping=mapping,
        recording=recording,
        ranges=ranges,
        time_origin_ns=origin,
        stamp_offset_s=offsets,
        stamps_from_receive=from_receive,
        unknown_topics=tuple(i for i in infos if i.topic not in named),
        odometry_pose=poses,
        radio_only=radio_only,
    )


def _ranges(
    timed: dict[str, tuple[list[int], list[Any]]],
    uwb_links: dict[str, tuple[int, int] | None],
    seconds: Any,
) -> UwbRanges:
    parts = []
    for topic, ab in uwb_links.items():
        times, values = timed.get(topic, ([], []))
        if ab is None or not times:
            continue
        n = len(times)
        parts.append((seconds(times), np.full(n, ab[0]), np.full(n, ab[1]), np.asarray(values)))
    if not parts:
        z = np.zeros(0, dtype=np.int64)
        return UwbRanges(t=np.zeros(0), node_a=z, node_b=z, value=np.zeros(0))
    t = np.concatenate([p[0] for p in parts])
    order = np.argsort(t, kind="stable")
    return UwbRanges(
        t=t[order],
        node_a=np.concatenate([p[1] for p in parts]).astype(np.int64)[order],
        node_b=np.concatenate([p[2] for p in parts]).astype(np.int64)[order],
        value=np.concatenate([p[3] for p in parts]).astype(float)[order],
    )


#: Why a UWB reading stays at radio level (:attr:`BagRecording.radio_only`): its two radios
#: are not a robot and another robot or a static radio of known position.
RADIO_ONLY_REASONS = (
    "between two static radios",
    "between two radios of one robot",
    "to a static radio of unknown position",
)


def _range_rows(
    mapping: BagMapping, ranges: UwbRanges
) -> tuple[Array, Measurements, int, dict[str, int]]:
    """Landmarks (static radios of known position), the ``range`` rows of the recording, how
    many readings repeated another's (time, observer, radio, target) and were left out, and how
    many stay at radio level only, by reason (:data:`RADIO_ONLY_REASONS`)."""
    uwb = mapping.uwb
    if uwb is None or ranges.t.size == 0:
        return np.zeros((0, 3)), empty_measurements(), 0, {}
    robot_of = [None if n.robot is None else mapping.robot_index(n.robot) for n in uwb.nodes]
    carried = Counter(r for r in robot_of if r is not None)
    sensor = [
        -1 if r is None else [k for k, rr in enumerate(robot_of) if rr == r].index(i)
        for i, r in enumerate(robot_of)
    ]
    static = [i for i, n in enumerate(uwb.nodes) if n.robot is None and n.position is not None]
    landmarks = np.array([uwb.nodes[i].position for i in static], dtype=float).reshape(-1, 3)
    keep, observer, target, landmark, sensors = [], [], [], [], []
    seen: set[tuple[float, int, int, int, int]] = set()
    repeats = 0
    radio_only: Counter[str] = Counter()
    for k, (a, b) in enumerate(zip(ranges.node_a.tolist(), ranges.node_b.tolist(), strict=True)):
        ra, rb = robot_of[a], robot_of[b]
        if ra is None or (rb is not None and carried[rb] > carried[ra]):
            a, b, ra, rb = b, a, rb, ra
        if ra is None or ra == rb or (rb is None and b not in static):
            # kept at radio level only (static–static, one robot, unsurveyed radio): counted
            reason = 0 if ra is None else 1 if ra == rb else 2
            radio_only[RADIO_ONLY_REASONS[reason]] += 1
            continue
        row = (
            float(ranges.t[k]),
            ra,
            sensor[a],
            NO_TARGET if rb is None else rb,
            static.index(b) if rb is None else NO_TARGET,
        )
        if row in seen:
            repeats += 1
            continue
        seen.add(row)
        keep.append(k)
        observer.append(row[1])
        sensors.append(row[2])
        target.append(row[3])
        landmark.append(row[4])
    if not keep:
        return landmarks, empty_measurements(), repeats, dict(radio_only)
    idx = np.asarray(keep)
    sigma = np.nan if uwb.sigma is None else uwb.sigma
    rows = measurement_rows(
        "range",
        t=ranges.t[idx],
        observer=np.asarray(observer),
        value=ranges.value[idx],
        sigma=np.array([sigma]),
        target=np.asarray(target),
        landmark=np.asarray(landmark),
        sensor=np.asarray(sensors),
    )
    return landmarks, rows, repeats, dict(radio_only)
