"""``relloc bag inspect BAG``: the topics of a ROS 2 bag and a mapping skeleton to edit.

Prints one line per topic (type, message count, rate, first/last receive time) and then a TOML
mapping (:mod:`relloc.datasets.bag_mapping`) with a robot per odometry or motion-capture topic
and the UWB radios the range topics name; edit it (which radio rides on which robot, which
robot a motion-capture body is) and pass it to ``relloc run BAG --map`` or
``relloc reproduce tiers-uwb --bag BAG --map``.
"""

from __future__ import annotations

import argparse
import re
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from relloc.datasets.rosbag import TopicInfo

_TYPES = {
    "odometry": "nav_msgs/msg/Odometry",
    "truth": "geometry_msgs/msg/PoseStamped",
    "range": "sensor_msgs/msg/Range",
}


def add_parser(subparsers: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    p = subparsers.add_parser(
        "bag",
        help="look into a ROS 2 bag (topics, types, counts, rates, a mapping skeleton)",
        description="Inspect a rosbag2 folder, .db3 or .mcap file (needs the 'ros' extra).",
    )
    sub = p.add_subparsers(dest="bag_command", metavar="ACTION", required=True)
    q = sub.add_parser("inspect", help="print the topic table and a mapping skeleton")
    q.add_argument("bag", type=Path, help="rosbag2 folder, .db3 or .mcap file")
    q.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from relloc.datasets.rosbag import inspect_bag

    infos = inspect_bag(args.bag)
    print(topic_table(infos))
    print()
    print(mapping_skeleton(infos, name=args.bag.name))
    return 0


def topic_table(infos: Sequence[TopicInfo]) -> str:
    """One aligned line per topic; the span of a topic without messages is ``—``."""
    width = max((len(i.topic) for i in infos), default=5)
    kinds = max((len(i.msgtype) for i in infos), default=4)
    lines = [f"{'topic':<{width}}  {'type':<{kinds}}  {'count':>6}  {'rate_hz':>8}  span_s"]
    for i in infos:
        span = f"{i.first_s:.2f}–{i.last_s:.2f}" if i.count else "—"  # no message: no span
        lines.append(
            f"{i.topic:<{width}}  {i.msgtype:<{kinds}}  {i.count:>6}  {i.rate_hz:>8.2f}  {span}"
        )
    return "\n".join(lines)


def _range_template(topics: Sequence[str]) -> tuple[str, list[str]] | None:
    """A template with ``{a}``/``{b}`` covering the range topics (their two differing path
    segments), and the radio names found; ``None`` when they do not share one."""
    split = [t.split("/") for t in topics]
    if not split or len({len(s) for s in split}) != 1:
        return None
    varying = [k for k in range(len(split[0])) if len({s[k] for s in split}) > 1]
    if len(split) > 1 and len(varying) != 2:
        return None
    if len(split) == 1:
        return None
    a, b = varying
    parts = list(split[0])
    parts[a], parts[b] = "{a}", "{b}"
    names = sorted({s[a] for s in split} | {s[b] for s in split})
    return "/".join(parts), names


def _robot_name(topic: str, taken: set[str]) -> str:
    """A robot name guessed from a topic (its last path segment that is not a message word),
    made unique among ``taken`` (which it joins)."""
    words = [w for w in topic.split("/") if w and w not in ("odom", "pose", "vrpn_client_node")]
    base = re.sub(r"[^A-Za-z0-9_.\-]", "_", words[-1] if words else "robot")
    name, k = base, 2
    while name in taken:
        name, k = f"{base}_{k}", k + 1
    taken.add(name)
    return name


def mapping_skeleton(infos: Sequence[TopicInfo], *, name: str) -> str:
    """A mapping TOML naming every odometry and motion-capture topic with data as a robot and
    every radio of the range topics as a static node; edit before use."""
    odometry = [i.topic for i in infos if i.msgtype == _TYPES["odometry"] and i.count > 0]
    truth = [i.topic for i in infos if i.msgtype == _TYPES["truth"] and i.count > 0]
    ranges = [i.topic for i in infos if i.msgtype == _TYPES["range"] and i.count > 0]
    out = [
        "# relloc bag mapping (skeleton from `relloc bag inspect`): edit, then pass with --map.",
        "# Merge the odometry and motion-capture topics of one robot into one [[robots]] table,",
        "# drop the bodies that are not robots, and say which robot carries each UWB radio.",
        f'name = "{name}"',
        'stamp = "header"',
    ]
    taken: set[str] = set()
    for topic in odometry:
        out += ["", "[[robots]]", f'name = "{_robot_name(topic, taken)}"', f'odometry = "{topic}"']
    for topic in truth:
        out += ["", "[[robots]]", f'name = "{_robot_name(topic, taken)}"', f'truth = "{topic}"']
    found = _range_template(ranges)
    if found is not None:
        template, radios = found
        out += ["", "[uwb]", f'topics = "{template}"', "fold_directions = true"]
        for radio in radios:
            out += [
                "",
                "[[uwb.nodes]]",
                f'name = "{radio}"',
                '# robot = "…"  (the robot carrying it; or position = [x, y, z] if static)',
            ]
    elif ranges:
        out += ["", f"# {len(ranges)} sensor_msgs/Range topics share no {{a}}/{{b}} template"]
    return "\n".join(out)
