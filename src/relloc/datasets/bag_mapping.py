"""The TOML mapping that says which topics of a ROS 2 bag are which robot's data.

A bag names its data by topic; relloc needs robots, their odometry, their ground truth and the
UWB radios they carry. A mapping file states that once per recording layout (the same file
serves every bag recorded the same way; ``relloc bag inspect BAG`` prints a skeleton)::

    name = "my-team"                      # optional label
    anchors = ["turtlebot4"]              # optional: robots declared standing anchors
    stamp = "header"                      # "header" (default) or "receive" (bag time)

    [[robots]]
    name = "turtlebot1"
    platform = "ground"                   # ground (default) or aerial
    odometry = "/turtle01/odom"           # nav_msgs/Odometry: body-frame twist (optional)
    odometry_sigma = [0.05, 0.0, 0.0, 0.05]   # σ of (v_x, v_y, v_z, ω_z) (optional)
    odometry_pose = false                 # also keep the odometry's pose (used only if asked)
    truth = "/vrpn_client_node/tb1/pose"  # geometry_msgs/PoseStamped motion capture (optional)

    [uwb]
    topics = "/uwb/tof/{a}/{b}/distance"  # sensor_msgs/Range; {a}, {b}: the two node names
    sigma = 0.1                           # stated σ of one range (m) (optional)
    fold_directions = true                # a link published both ways is read once

    [[uwb.nodes]]
    name = "n_7"
    robot = "turtlebot1"                  # the robot carrying the radio, or
    # position = [1.0, 2.0, 0.3]          # a static radio's surveyed world position
    offset = [0.0, 0.0, 0.0]              # antenna in the carrying robot's body frame

Every key is checked: an unknown key, a wrong type or a bad value is a
:class:`~relloc.errors.ConfigError` naming the file and the key (``robots[1].odometry``).
"""

from __future__ import annotations

import re
import sys
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any

from relloc.core.checks import number
from relloc.core.limits import (
    MAX_ABS_POSITION_M,
    MAX_SENSOR_RANGE_M,
    MAX_SPEED_M_S,
    MAX_YAW_RATE_RAD_S,
)
from relloc.core.recording import PLATFORMS
from relloc.errors import ConfigError

#: A mapping is a short file; anything larger is refused before parsing.
MAX_MAPPING_BYTES = 1_000_000
#: σ of the body velocities (v_x, v_y, v_z, ω_z) when the mapping states none (m/s, rad/s).
DEFAULT_ODOMETRY_SIGMA = (0.05, 0.0, 0.0, 0.05)
STAMP_SOURCES = ("header", "receive")
_PLACEHOLDERS = ("{a}", "{b}")
_NAME = re.compile(r"[A-Za-z0-9_.\-]+")


@dataclass(frozen=True, kw_only=True)
class RobotTopics:
    """One robot's topics (``None`` where it has none)."""

    name: str
    platform: str = "ground"
    odometry: str | None = None
    odometry_sigma: tuple[float, float, float, float] = DEFAULT_ODOMETRY_SIGMA
    odometry_pose: bool = False
    truth: str | None = None


@dataclass(frozen=True, kw_only=True)
class UwbNode:
    """One UWB radio: carried by ``robot`` (with its antenna at ``offset`` in the robot's body
    frame), or static at world ``position`` (``None``: a static radio of unknown position)."""

    name: str
    robot: str | None = None
    offset: tuple[float, float, float] = (0.0, 0.0, 0.0)
    position: tuple[float, float, float] | None = None


@dataclass(frozen=True, kw_only=True)
class UwbTopics:
    """The UWB range topics: ``topics`` is a template with ``{a}`` and ``{b}``."""

    topics: str
    nodes: tuple[UwbNode, ...]
    sigma: float | None = None
    fold_directions: bool = True

    def pattern(self) -> re.Pattern[str]:
        """The template as a regular expression capturing the node names ``a`` and ``b``."""
        a, b = self.topics.index("{a}"), self.topics.index("{b}")
        first, second = ("a", "b") if a < b else ("b", "a")
        lo, hi = sorted((a, b))
        head, mid, tail = self.topics[:lo], self.topics[lo + 3 : hi], self.topics[hi + 3 :]
        return re.compile(
            re.escape(head)
            + f"(?P<{first}>[^/]+)"
            + re.escape(mid)
            + f"(?P<{second}>[^/]+)"
            + re.escape(tail)
        )

    def link_of(self, topic: str) -> tuple[str, str] | None:
        """The node names ``(a, b)`` a topic carries, or ``None`` if it is not a UWB topic."""
        m = self.pattern().fullmatch(topic)
        return None if m is None else (m["a"], m["b"])

    def node_index(self, name: str) -> int | None:
        for i, node in enumerate(self.nodes):
            if node.name == name:
                return i
        return None


@dataclass(frozen=True, kw_only=True)
class BagMapping:
    """A parsed mapping (module docstring); ``source`` names the file it came from."""

    robots: tuple[RobotTopics, ...]
    uwb: UwbTopics | None = None
    name: str = ""
    anchors: tuple[str, ...] | None = None
    stamp: str = "header"
    source: str = ""

    def robot_index(self, name: str) -> int:
        return [r.name for r in self.robots].index(name)

    def topics(self) -> set[str]:
        """Every topic named explicitly (the UWB template matches further topics)."""
        out: set[str] = set()
        for r in self.robots:
            out.update(t for t in (r.odometry, r.truth) if t is not None)
        return out


# ----------------------------------------------------------------------------------------------
# Field checks: each names its key
# ----------------------------------------------------------------------------------------------


def _table(value: object, where: str, known: tuple[str, ...]) -> Mapping[str, Any]:
    if not isinstance(value, Mapping):
        raise ConfigError(f"{where}: expected a table, got {type(value).__name__}")
    for key in value:
        if key not in known:
            raise ConfigError(
                f"{where}.{key}: unknown key; expected one of {', '.join(sorted(known))}"
            )
    return value


def _string(value: object, where: str, *, name: bool = False) -> str:
    if not isinstance(value, str) or not value:
        raise ConfigError(f"{where}: expected a non-empty string, got {value!r:.60}")
    if name and not _NAME.fullmatch(value):
        raise ConfigError(f"{where}: {value!r:.60} is not a name (letters, digits, _ . -)")
    return value


def _topic(value: object, where: str) -> str:
    topic = _string(value, where)
    if not topic.startswith("/"):
        raise ConfigError(f"{where}: a topic starts with '/', got {topic!r:.60}")
    return topic


def _bool(value: object, where: str) -> bool:
    if not isinstance(value, bool):
        raise ConfigError(f"{where}: expected true or false, got {value!r:.60}")
    return value


def _float(
    value: object, where: str, *, positive: bool = False, nonneg: bool = False, limit: float
) -> float:
    """A finite number within ±``limit`` (in ``(0, limit]`` with ``positive``, ``[0, limit]``
    with ``nonneg``): :func:`relloc.core.checks.number`."""
    low = 0.0 if positive or nonneg else -limit
    return number(value, where, low=low, high=limit, open_low=positive)


def _vector(
    value: object, where: str, limits: tuple[float, ...], *, nonneg: bool = False
) -> tuple[float, ...]:
    """One number per entry of ``limits``, each within its limit (:func:`_float`)."""
    size = len(limits)
    if not isinstance(value, list) or len(value) != size:
        raise ConfigError(f"{where}: expected a list of {size} numbers, got {value!r:.60}")
    return tuple(
        _float(v, f"{where}[{k}]", nonneg=nonneg, limit=limits[k]) for k, v in enumerate(value)
    )


def _list(value: object, where: str) -> list[Any]:
    if not isinstance(value, list):
        raise ConfigError(f"{where}: expected an array, got {type(value).__name__}")
    return value


# ----------------------------------------------------------------------------------------------
# Tables
# ----------------------------------------------------------------------------------------------


def _robot(value: object, where: str) -> RobotTopics:
    t = _table(
        value, where, ("name", "platform", "odometry", "odometry_sigma", "odometry_pose", "truth")
    )
    if "name" not in t:
        raise ConfigError(f"{where}.name: required")
    platform = _string(t.get("platform", "ground"), f"{where}.platform")
    if platform not in PLATFORMS:
        raise ConfigError(f"{where}.platform: must be one of {PLATFORMS}, got {platform!r:.60}")
    sigma = _vector(
        t.get("odometry_sigma", list(DEFAULT_ODOMETRY_SIGMA)),
        f"{where}.odometry_sigma",
        (MAX_SPEED_M_S,) * 3 + (MAX_YAW_RATE_RAD_S,),
        nonneg=True,
    )
    return RobotTopics(
        name=_string(t["name"], f"{where}.name", name=True),
        platform=platform,
        odometry=None if "odometry" not in t else _topic(t["odometry"], f"{where}.odometry"),
        odometry_sigma=(sigma[0], sigma[1], sigma[2], sigma[3]),
        odometry_pose=_bool(t.get("odometry_pose", False), f"{where}.odometry_pose"),
        truth=None if "truth" not in t else _topic(t["truth"], f"{where}.truth"),
    )


def _node(value: object, where: str, robots: set[str]) -> UwbNode:
    t = _table(value, where, ("name", "robot", "offset", "position"))
    if "name" not in t:
        raise ConfigError(f"{where}.name: required")
    robot = None if "robot" not in t else _string(t["robot"], f"{where}.robot", name=True)
    if robot is not None and robot not in robots:
        raise ConfigError(
            f"{where}.robot: {robot!r} is not a robot of the mapping "
            f"({', '.join(sorted(robots)) or 'none'})"
        )
    if robot is not None and "position" in t:
        raise ConfigError(f"{where}.position: a node on a robot moves with it; give offset")
    if robot is None and "offset" in t:
        raise ConfigError(f"{where}.offset: only a node carried by a robot has an offset")
    bounds = (MAX_ABS_POSITION_M,) * 3
    offset = _vector(t.get("offset", [0.0, 0.0, 0.0]), f"{where}.offset", bounds)
    pos = None if "position" not in t else _vector(t["position"], f"{where}.position", bounds)
    return UwbNode(
        name=_string(t["name"], f"{where}.name", name=True),
        robot=robot,
        offset=(offset[0], offset[1], offset[2]),
        position=None if pos is None else (pos[0], pos[1], pos[2]),
    )


def _uwb(value: object, robots: set[str]) -> UwbTopics:
    t = _table(value, "uwb", ("topics", "sigma", "fold_directions", "nodes"))
    if "topics" not in t:
        raise ConfigError("uwb.topics: required (a topic template with {a} and {b})")
    template = _topic(t["topics"], "uwb.topics")
    for ph in _PLACEHOLDERS:
        if template.count(ph) != 1:
            raise ConfigError(f"uwb.topics: must contain {ph} exactly once, got {template!r:.80}")
    if "}{" in template:
        raise ConfigError("uwb.topics: {a} and {b} must be separated by a character")
    raw_nodes = _list(t.get("nodes", []), "uwb.nodes")
    if not raw_nodes:
        raise ConfigError("uwb.nodes: required (one [[uwb.nodes]] table per radio)")
    nodes = tuple(_node(n, f"uwb.nodes[{i}]", robots) for i, n in enumerate(raw_nodes))
    names = [n.name for n in nodes]
    for i, name in enumerate(names):
        if name in names[:i]:
            raise ConfigError(f"uwb.nodes[{i}].name: {name!r} is named twice")
    sigma = None
    if "sigma" in t:
        sigma = _float(t["sigma"], "uwb.sigma", positive=True, limit=MAX_SENSOR_RANGE_M)
    return UwbTopics(
        topics=template,
        nodes=nodes,
        sigma=sigma,
        fold_directions=_bool(t.get("fold_directions", True), "uwb.fold_directions"),
    )


def mapping_from_dict(data: Mapping[str, Any], source: str = "") -> BagMapping:
    """Build a :class:`BagMapping` from a parsed TOML document (errors name the key)."""
    t = _table(data, "mapping", ("name", "anchors", "stamp", "robots", "uwb"))
    raw_robots = _list(t.get("robots", []), "robots")
    if not raw_robots:
        raise ConfigError("robots: required (one [[robots]] table per robot)")
    robots = tuple(_robot(r, f"robots[{i}]") for i, r in enumerate(raw_robots))
    names = [r.name for r in robots]
    for i, name in enumerate(names):
        if name in names[:i]:
            raise ConfigError(f"robots[{i}].name: {name!r} is named twice")
    for stream in ("odometry", "truth"):  # one robot's messages would drive two
        topics = [getattr(r, stream) for r in robots]
        for i, topic in enumerate(topics):
            if topic is not None and topic in topics[:i]:
                raise ConfigError(
                    f"robots[{i}].{stream}: {topic!r} is robots[{topics.index(topic)}]'s too"
                )
    stamp = _string(t.get("stamp", "header"), "stamp")
    if stamp not in STAMP_SOURCES:
        raise ConfigError(f"stamp: must be one of {STAMP_SOURCES}, got {stamp!r:.60}")
    anchors = None
    if "anchors" in t:
        anchors = tuple(
            _string(a, f"anchors[{k}]", name=True)
            for k, a in enumerate(_list(t["anchors"], "anchors"))
        )
        for k, a in enumerate(anchors):
            if a not in names:
                raise ConfigError(f"anchors[{k}]: {a!r} is not a robot of the mapping")
    return BagMapping(
        robots=robots,
        uwb=None if "uwb" not in t else _uwb(t["uwb"], set(names)),
        name="" if "name" not in t else _string(t["name"], "name"),
        anchors=anchors,
        stamp=stamp,
        source=source,
    )


def parse_mapping(text: str, origin: str) -> BagMapping:
    """Parse mapping TOML text; errors are :class:`ConfigError` prefixed with ``origin``.
    ``tomllib`` reads integers of any size; one of more digits than Python writes as text
    (``sys.get_int_max_str_digits()``, a hexadecimal one included) is an error naming its
    key."""
    try:
        data = tomllib.loads(text)
    except ValueError as exc:  # a TOMLDecodeError, or an integer of over 4300 digits
        raise ConfigError(f"{origin}: not valid TOML ({exc})") from None
    except RecursionError:
        raise ConfigError(f"{origin}: not valid TOML (nested too deeply)") from None
    try:
        _check_integers(data, "")
        return mapping_from_dict(data, origin)
    except ConfigError as exc:
        raise ConfigError(f"{origin}: {exc}") from None


def _check_integers(value: object, where: str) -> None:
    """ConfigError naming the key of the first integer of a parsed TOML document that has more
    digits than ``str`` writes: every later message may quote the value (``{value!r}``)."""
    if isinstance(value, dict):
        for key, item in value.items():
            _check_integers(item, f"{where}.{key}" if where else str(key))
    elif isinstance(value, list):
        for k, item in enumerate(value):
            _check_integers(item, f"{where}[{k}]")
    elif isinstance(value, int):
        try:
            str(value)
        except ValueError:
            raise ConfigError(
                f"{where}: an integer of over {sys.get_int_max_str_digits()} digits"
            ) from None


def load_mapping(path: Path | str) -> BagMapping:
    """Read a mapping file (UTF-8, at most :data:`MAX_MAPPING_BYTES`), or a shipped mapping by
    name (:func:`shipped_mappings`)."""
    p = Path(path)
    if not p.exists() and str(path) in shipped_mappings():
        res = resources.files("relloc.datasets").joinpath("mappings", f"{path}.toml")
        return parse_mapping(res.read_text(encoding="utf-8"), f"{path}.toml")
    try:
        with p.open("rb") as f:
            raw = f.read(MAX_MAPPING_BYTES + 1)
    except OSError as exc:
        raise ConfigError(
            f"{p}: cannot read mapping file ({exc.strerror or exc}); shipped mappings: "
            f"{', '.join(shipped_mappings())}"
        ) from None
    if len(raw) > MAX_MAPPING_BYTES:
        raise ConfigError(f"{p}: larger than {MAX_MAPPING_BYTES} bytes; a mapping is short")
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise ConfigError(f"{p}: not UTF-8 text (byte {exc.start})") from None
    return parse_mapping(text, str(p))


def shipped_mappings() -> tuple[str, ...]:
    """Names of the mappings shipped with relloc (``relloc/datasets/mappings/*.toml``)."""
    folder = resources.files("relloc.datasets").joinpath("mappings")
    return tuple(
        sorted(f.name.removesuffix(".toml") for f in folder.iterdir() if f.name.endswith(".toml"))
    )
