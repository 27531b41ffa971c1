"""Wire messages of the robot runtime: msgpack with an explicit schema and version.

Every message is one msgpack map with the common header

    ``{"v": SCHEMA_VERSION, "type": <kind>, "sender": <robot id>, "seq": <int ≥ 0>,
    "t": <simulated/robot time, s>, "wall_ns": <sender's wall clock at send, ns>}``

plus the fields of its kind (:data:`SCHEMA`). Arrays travel as (nested) lists of numbers and are
checked against their declared shape, ``-1`` meaning "any length". Kinds:

- ``odom`` — a batch of the sender's own body-velocity samples ``u = (v_x, v_y, v_z, ω_z)``
  (seed 000 Eq. 1 inputs; seed 001 robots exchange velocity and turn rate the same way):
  ``stamps`` (n,), ``u`` (n, 4).
- ``meas`` — a batch of inter-robot measurements the sender made: ``stamps`` (m,), ``targets``
  (m,), ``z`` (m, 3) = (range, azimuth, elevation) (seed 000 Eq. 2) and their standard
  deviations ``sigma`` (m, 3).
- ``eqm`` — an *equivalent measurement* (seed 002 §III-6 "broadcast"): the sender's belief of
  ``target`` relative to itself, ``mean`` (4,) = (x, y, z, φ) and ``cov`` (4, 4), sent at the
  low broadcast rate (1 Hz in seed 002).
- ``rows`` — the sender's own readings of one window, of any kind, shared with the team (seed
  001); see :mod:`relloc.runtime.shared_rows`.
- ``mail`` — what the sender's estimator sends its teammates' estimators (seed 002's equivalent
  measurements, stamped with the event that produced them) and the sender's ``progress``; see
  :mod:`relloc.runtime.mail`.
- ``sync`` — a restarted agent asks a teammate (``target``) for the team belief from
  ``stamp`` on (empty ``mean`` / ``cov``), or the teammate answers the asker (``target``) with
  its belief of the whole team at its event ``stamp``: ``mean`` (d,), ``cov`` (d, d); see
  :mod:`relloc.runtime.handoff`.
- ``est`` — the sender's new estimates of one ``target`` (its track ``track``, ``""`` for the
  one track) for the collector (monitoring, not fusion): one increment of a
  :class:`~relloc.core.estimates.BeliefSeries` — beliefs in ``frame`` (a frame of
  :mod:`relloc.pipeline.frames`, of dimension d) at the record times ``stamps`` (n,),
  ``means`` (n, d), ``covs`` (n, d, d), track ``ages`` (n,) — and of its
  :class:`~relloc.core.estimates.UpdateSeries` — ``update_stamps`` (m,) with the track's
  ``update_ages``, ``nis`` and its degrees of freedom ``update_dofs``, ``cond_r``, ``cond_s``
  (m,) (log10 condition numbers of R, S) — and the beliefs' scalar diagnostics ``info`` (n × k,
  row-major) named ``info_names`` (k). :func:`est_bodies` and :func:`estimates_from_bodies`
  convert between these bodies and :class:`~relloc.core.estimates.Estimates`.
- ``evt`` — track events of the sender: ``stamps`` (e,), ``targets`` (e,), ``kinds`` (e,) in
  ``{"created", "deleted", "recreated"}``.
- ``stats`` — the sender's counters (messages sent/received/rejected, estimates, tracks).
- ``tick`` — the clock process' simulated time step ``k`` of ``n`` (header ``t`` is the time).
- ``ack`` — a node finished tick ``k``.
- ``ctl`` — a control event from the clock process: ``action`` in ``{"kill", "restart",
  "end"}`` and the ``robot`` it concerns (``""`` for ``end``).
- ``cmd`` — a robot's command of tick ``k`` to the world process that moves it (seed 003's
  closed loop): body velocity ``u`` (4,) as in ``odom``.
- ``sense`` — from the world process (sender ``clock``) to robot ``target``: tick ``k`` of
  ``n`` (period ``dt``; header ``t`` is the time), the robot's readings taken at ``t`` (the
  fields of ``rows``), a drone's own ``position`` (3,) (empty for a UGV) and its camera's
  marker fix for its leader track (``fix_subject`` the robot seen, ``""`` for none; ``fix`` its
  x, y and, for the leader, heading); see :mod:`relloc.runtime.airground`.

:func:`decode` validates *everything* a receiver relies on — size limit before unpacking, map
layout, version, kind, field types, array shapes, finite numbers, a symmetric covariance (an
``eqm``'s also positive semidefinite, its mean within bounds), ``odom``/``meas`` stamps in order,
and a sender that is on the team roster and matches the key expression it arrived on, targets
(never the sender itself, for ``meas`` and ``eqm``) and controlled robots on the roster (who
may send which kind on which key, how often and how far ahead of the clock is checked on top of
this by :mod:`relloc.runtime.admission`). Anything else
raises :class:`MessageRejected` whose ``reason`` is a short stable code the node counts (a bad
message is dropped and counted, never crashes a node). Pickle is never used for network input.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Collection, Mapping
from dataclasses import dataclass
from typing import Any, TypeVar

import msgpack
import numpy as np

from relloc.core.estimates import BeliefSeries, Estimates, SeriesKey, UpdateSeries, concatenate
from relloc.core.limits import MAX_SPEED_M_S, MAX_YAW_RATE_RAD_S
from relloc.errors import DataError
from relloc.pipeline.frames import FRAMES
from relloc.runtime import keys

SCHEMA_VERSION = 4
"""The wire layout's version (what each one introduced: :data:`VERSION_CHANGES`). A message of
any other version is rejected (``version``): every process of a team speaks one version."""
VERSION_CHANGES = {
    2: "est carries frame, track and the NIS degrees of freedom update_dofs",
    3: "est carries the beliefs' info in frames of any dimension; rows and mail exist",
    4: "sync, cmd and sense exist",
}
"""What each schema version introduced over the one before."""
DEFAULT_MAX_BYTES = 65_536
"""Default size limit of one encoded message (bytes); larger payloads are rejected unread."""
MIN_MESSAGE_BYTES = 256
MAX_MESSAGE_BYTES = 16 * 2**20
"""The range a process's message size limit (``max_bytes``) may be set in."""

STATE_DIM = 4
"""Relative state (x, y, z, φ) of seed 000 carried by ``eqm`` and ``mail`` (``est`` carries
the states of its frame)."""
MIN_VARIANCE = 1e-18
MAX_VARIANCE = 1e12
"""Eigenvalues a received covariance that a filter fuses or starts from (``mail``, ``sync``)
must lie within: positive definite, and its inverse and its products stay finite."""
MAX_STATE = 1e9
"""Largest |entry| of a received state, position or marker fix (m, rad)."""
MAX_DOF = 10_000
"""Largest degrees of freedom of one reported NIS (``est.update_dofs``)."""

Shape = tuple[int, ...]
HEADER: dict[str, str] = {
    "v": "int",
    "type": "str",
    "sender": "str",
    "seq": "int",
    "t": "float",
    "wall_ns": "int",
}
ROWS: dict[str, str | Shape] = {
    "stamps": (-1,),
    "kinds": "strlist",
    "subjects": "strlist",
    "landmarks": (-1,),
    "sensors": (-1,),
    "values": (-1,),
    "sigmas": (-1,),
}
"""Fields of a table of readings (``rows``; also inside ``sense``), one entry per row."""


def version_mismatch(v: int) -> str:
    """Why a message of schema version ``v`` (not :data:`SCHEMA_VERSION`) is refused: which
    side is older and what the versions between them changed."""
    if v < SCHEMA_VERSION:
        since = "; ".join(f"v{n}: {what}" for n, what in VERSION_CHANGES.items() if n > v)
        return (
            f"schema version {v} is older than this process' {SCHEMA_VERSION} (since then "
            f"{since}): run every process of the team from the same relloc"
        )
    return (
        f"schema version {v} is newer than this process' {SCHEMA_VERSION}: run every process "
        "of the team from the same relloc"
    )


SCHEMA: dict[str, dict[str, str | Shape]] = {
    "odom": {"stamps": (-1,), "u": (-1, 4)},
    "meas": {"stamps": (-1,), "targets": "strlist", "z": (-1, 3), "sigma": (-1, 3)},
    "eqm": {"target": "str", "mean": (STATE_DIM,), "cov": (STATE_DIM, STATE_DIM)},
    "rows": ROWS,
    "mail": {
        "progress": "float",
        "stamps": (-1,),
        "subjects": "strlist",
        "sizes": (-1,),
        "means": (-1, STATE_DIM),
        "covs": (-1, STATE_DIM, STATE_DIM),
        "prior_means": (-1, STATE_DIM),
        "prior_covs": (-1, STATE_DIM, STATE_DIM),
        "weights": (-1,),
    },
    "sync": {"target": "str", "stamp": "float", "mean": (-1,), "cov": (-1, -1)},
    "est": {
        "target": "str",
        "track": "str",
        "frame": "str",
        "stamps": (-1,),
        "means": (-1, -1),
        "covs": (-1, -1, -1),
        "ages": (-1,),
        "update_stamps": (-1,),
        "update_ages": (-1,),
        "nis": (-1,),
        "update_dofs": (-1,),
        "cond_r": (-1,),
        "cond_s": (-1,),
        "info_names": "strlist",
        "info": (-1,),
    },
    "evt": {"stamps": (-1,), "targets": "strlist", "kinds": "strlist"},
    "stats": {"counters": "intmap"},
    "tick": {"k": "int", "n": "int", "dt": "float"},
    "ack": {"k": "int"},
    "ctl": {"action": "str", "robot": "str"},
    "cmd": {"k": "int", "u": (4,)},
    "sense": {
        "k": "int",
        "n": "int",
        "dt": "float",
        "target": "str",
        "position": (-1,),
        "fix_subject": "str",
        "fix": (-1,),
        **ROWS,
    },
}
"""Fields of each kind: a type name or an array shape (``-1`` = any length)."""

_S = TypeVar("_S", BeliefSeries, UpdateSeries)

CTL_ACTIONS = frozenset({"kill", "restart", "end"})
EVENT_KINDS = frozenset({"created", "deleted", "recreated"})
INFRASTRUCTURE_SENDERS = frozenset({keys.CLOCK_ID})
"""Senders that are not robots but are allowed on the team's keys."""


class MessageRejected(DataError):
    """A received message failed validation; ``reason`` is the counter it is filed under."""

    def __init__(self, reason: str, detail: str) -> None:
        super().__init__(f"message rejected ({reason}): {detail}")
        self.reason = reason


@dataclass(frozen=True, kw_only=True)
class Message:
    """A validated message: the header plus its kind's fields (arrays as float64 numpy arrays)."""

    kind: str
    sender: str
    seq: int
    t: float
    wall_ns: int
    body: Mapping[str, Any]


def encode(
    kind: str,
    sender: str,
    seq: int,
    t: float,
    body: Mapping[str, Any],
    *,
    wall_ns: int | None = None,
    max_bytes: int = DEFAULT_MAX_BYTES,
) -> bytes:
    """Pack one message (numpy arrays become nested lists). The result is what :func:`decode`
    accepts; the sender's own output is validated too so a bug never reaches the network."""
    if kind not in SCHEMA:
        raise DataError(f"encode: unknown message kind {kind!r}")
    payload: dict[str, Any] = {
        "v": SCHEMA_VERSION,
        "type": kind,
        "sender": sender,
        "seq": int(seq),
        "t": float(t),
        "wall_ns": int(time.time_ns() if wall_ns is None else wall_ns),
    }
    for name in SCHEMA[kind]:
        if name not in body:
            raise DataError(f"encode {kind}: missing field {name!r}")
        value = body[name]
        if isinstance(value, np.ndarray):
            value = value.astype(float).tolist()
        elif isinstance(value, np.generic):
            value = value.item()
        payload[name] = value
    data: bytes = msgpack.packb(payload, use_bin_type=True)
    _validate(payload, kind)
    if len(data) > max_bytes:
        raise DataError(f"encode {kind}: {len(data)} bytes exceed the limit {max_bytes}")
    return data


def decode(
    data: bytes,
    *,
    roster: Collection[str],
    key_sender: str | None = None,
    max_bytes: int = DEFAULT_MAX_BYTES,
) -> Message:
    """Validate and unpack a received payload.

    ``roster`` are the robot ids of the team (plus :data:`INFRASTRUCTURE_SENDERS`); ``key_sender``
    is the robot id taken from the key expression the message arrived on (a message claiming to
    be from someone else is rejected). Raises :class:`MessageRejected`.
    """
    if len(data) > max_bytes:
        raise MessageRejected("oversized", f"{len(data)} bytes > limit {max_bytes}")
    try:
        payload = msgpack.unpackb(
            data,
            raw=False,
            strict_map_key=True,
            max_str_len=1024,
            max_array_len=max_bytes,
            max_map_len=256,
        )
    except (ValueError, TypeError, msgpack.ExtraData, msgpack.FormatError, msgpack.StackError):
        raise MessageRejected("malformed", "not a msgpack document") from None
    if not isinstance(payload, dict):
        raise MessageRejected("malformed", f"top level is {type(payload).__name__}, not a map")
    for name, kind_name in HEADER.items():
        if name not in payload:
            raise MessageRejected("malformed", f"header field {name!r} missing")
        _check_scalar(payload[name], kind_name, name)
    if payload["v"] != SCHEMA_VERSION:
        raise MessageRejected("version", version_mismatch(payload["v"]))
    kind = payload["type"]
    if kind not in SCHEMA:
        raise MessageRejected("unknown_type", f"message type {kind!r}")
    sender = payload["sender"]
    if sender not in roster and sender not in INFRASTRUCTURE_SENDERS:
        raise MessageRejected("unknown_sender", f"sender {sender!r} is not on the team roster")
    if key_sender is not None and sender != key_sender:
        raise MessageRejected(
            "spoofed", f"sender field {sender!r} differs from key expression robot {key_sender!r}"
        )
    body = _validate(payload, kind)
    if "target" in body and body["target"] not in roster:
        raise MessageRejected("unknown_target", f"target {body['target']!r} is not on the roster")
    if "targets" in body:
        unknown = sorted(set(body["targets"]) - set(roster))
        if unknown:
            raise MessageRejected("unknown_target", f"targets {unknown} are not on the roster")
    if kind in ("meas", "eqm") and sender in body.get("targets", [body.get("target")]):
        raise MessageRejected("malformed", f"{kind}: of its sender {sender!r} itself")
    if kind == "ctl" and (body["robot"] == "") != (body["action"] == "end"):
        raise MessageRejected("malformed", "ctl: 'robot' is empty exactly for action 'end'")
    if kind == "sense" and body["fix_subject"] and body["fix_subject"] not in roster:
        raise MessageRejected("unknown_target", f"sense fix of {body['fix_subject']!r}")
    if kind == "ctl" and body["robot"] and body["robot"] not in roster:
        raise MessageRejected("unknown_target", f"ctl robot {body['robot']!r} is not on the roster")
    return Message(
        kind=kind,
        sender=sender,
        seq=payload["seq"],
        t=float(payload["t"]),
        wall_ns=payload["wall_ns"],
        body=body,
    )


def _check_scalar(value: Any, type_name: str, where: str) -> None:
    ok = {
        "int": isinstance(value, int) and not isinstance(value, bool),
        "str": isinstance(value, str),
        "float": isinstance(value, (int, float)) and not isinstance(value, bool),
    }[type_name]
    if not ok:
        raise MessageRejected("malformed", f"field {where!r}: expected {type_name}")
    if type_name == "float" and not math.isfinite(value):
        raise MessageRejected("non_finite", f"field {where!r} is not finite")
    if type_name == "int" and value < 0:
        raise MessageRejected("malformed", f"field {where!r} is negative")


def _validate(payload: Mapping[str, Any], kind: str) -> dict[str, Any]:
    """Check the kind's fields; return them with arrays converted to float64."""
    body: dict[str, Any] = {}
    for name, spec in SCHEMA[kind].items():
        if name not in payload:
            raise MessageRejected("malformed", f"{kind}: field {name!r} missing")
        value = payload[name]
        where = f"{kind}.{name}"
        if isinstance(spec, tuple):
            body[name] = _as_array(value, spec, where)
        elif spec == "strlist":
            if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
                raise MessageRejected("malformed", f"{where}: expected a list of strings")
            body[name] = list(value)
        elif spec == "intmap":
            if not isinstance(value, dict) or not all(
                isinstance(k, str) and isinstance(v, int) and not isinstance(v, bool) and v >= 0
                for k, v in value.items()
            ):
                raise MessageRejected("malformed", f"{where}: expected a map of str to int ≥ 0")
            body[name] = dict(value)
        else:
            _check_scalar(value, spec, where)
            body[name] = value
    _check_consistency(kind, body)
    return body


def _as_array(value: Any, shape: Shape, where: str) -> np.ndarray:
    if not isinstance(value, list):
        got = type(value).__name__
        raise MessageRejected("malformed", f"{where}: expected an array, got {got}")
    try:
        raw = np.asarray(value)
    except (ValueError, TypeError):
        raise MessageRejected("malformed", f"{where}: not a rectangular numeric array") from None
    if raw.size and raw.dtype.kind not in "iuf":  # strings, bytes, booleans, huge integers
        raise MessageRejected("malformed", f"{where}: not a rectangular numeric array")
    arr = raw.astype(float)
    if arr.size == 0 and shape[0] == -1:
        arr = arr.reshape((0, *(max(s, 0) for s in shape[1:])))
    fits = arr.ndim == len(shape) and all(
        s in (-1, a) for s, a in zip(shape, arr.shape, strict=True)
    )
    if not fits:
        raise MessageRejected("shape", f"{where}: shape {arr.shape}, expected {shape}")
    if not np.all(np.isfinite(arr)):
        raise MessageRejected("non_finite", f"{where}: contains NaN or inf")
    return arr


def _check_consistency(kind: str, body: dict[str, Any]) -> None:
    """Cross-field rules: equal batch lengths, increasing stamps (``odom`` strictly, ``meas``
    non-decreasing), sane covariances/sigmas, states within bounds."""
    if kind == "odom":
        if body["stamps"].shape[0] != body["u"].shape[0]:
            raise MessageRejected("shape", "odom: stamps and u lengths differ")
        if np.any(np.diff(body["stamps"]) <= 0):
            raise MessageRejected("malformed", "odom: stamps not strictly increasing")
        _check_velocities(body["u"], kind)
    elif kind == "cmd":
        _check_velocities(body["u"][None], kind)
    elif kind == "meas":
        m = body["stamps"].shape[0]
        if not (len(body["targets"]) == body["z"].shape[0] == body["sigma"].shape[0] == m):
            raise MessageRejected("shape", "meas: batch lengths differ")
        if np.any(body["sigma"] <= 0) or np.any(body["z"][:, 0] <= 0):
            raise MessageRejected("malformed", "meas: sigma and range must be > 0")
        if np.any(np.diff(body["stamps"]) < 0):
            raise MessageRejected("malformed", "meas: stamps decreasing")
    elif kind == "eqm":
        if np.any(np.abs(body["mean"]) > MAX_STATE):
            raise MessageRejected("out_of_range", f"eqm: a state beyond ±{MAX_STATE:g}")
        eig = np.linalg.eigvalsh(body["cov"])  # singular is honest (a state held fixed)
        if eig[0] < -1e-9 * max(1.0, float(eig[-1])) or eig[-1] > MAX_VARIANCE:
            raise MessageRejected("bad_covariance", "eqm: covariance not positive semidefinite")
    elif kind == "est":
        n = body["stamps"].shape[0]
        if not (body["means"].shape[0] == body["covs"].shape[0] == body["ages"].shape[0] == n):
            raise MessageRejected("shape", "est: record batch lengths differ")
        m = body["update_stamps"].shape[0]
        lengths = {
            body[k].shape[0] for k in ("update_ages", "nis", "update_dofs", "cond_r", "cond_s")
        }
        if lengths != {m}:
            raise MessageRejected("shape", "est: update batch lengths differ")
        f = FRAMES.get(body["frame"])
        if f is None:
            raise MessageRejected("malformed", f"est: {body['frame']!r} is not a frame")
        if n and (body["means"].shape[1:] != (f.dim,) or body["covs"].shape[1:] != (f.dim,) * 2):
            raise MessageRejected("shape", f"est: states are not those of {body['frame']!r}")
        if not n:
            body["means"] = np.zeros((0, f.dim))
            body["covs"] = np.zeros((0, f.dim, f.dim))
        if body["info"].shape[0] != n * len(body["info_names"]):
            raise MessageRejected("shape", "est: info is not one value per record and name")
        dofs = body["update_dofs"]
        if np.any((dofs < 1) | (dofs > MAX_DOF) | (dofs != np.round(dofs))):
            raise MessageRejected("malformed", f"est: update_dofs must be integers in 1…{MAX_DOF}")
    elif kind == "mail":
        sizes = body["sizes"]
        k = body["means"].shape[0]
        if not (len(body["subjects"]) == body["stamps"].shape[0] == sizes.shape[0]):
            raise MessageRejected("shape", "mail: per-message lengths differ")
        if np.any((sizes < 1) | (sizes != np.round(sizes))) or int(sizes.sum()) != k:
            raise MessageRejected("shape", "mail: sizes must be integers ≥ 1 summing to the tracks")
        if not (
            body["covs"].shape[0] == body["prior_means"].shape[0] == body["prior_covs"].shape[0]
        ) or not (body["weights"].shape[0] == body["covs"].shape[0] == k):
            raise MessageRejected("shape", "mail: track arrays of different lengths")
        if np.any(body["weights"] < 0):
            raise MessageRejected("malformed", "mail: negative weights")
    elif kind == "sync" and body["cov"].shape != (body["mean"].shape[0],) * 2:
        raise MessageRejected("shape", "sync: cov is not (d, d) for a mean of d")
    elif kind == "evt":
        if not (len(body["targets"]) == len(body["kinds"]) == body["stamps"].shape[0]):
            raise MessageRejected("shape", "evt: batch lengths differ")
        if not set(body["kinds"]) <= EVENT_KINDS:
            raise MessageRejected("malformed", f"evt: kinds must be in {sorted(EVENT_KINDS)}")
    elif kind == "ctl" and body["action"] not in CTL_ACTIONS:
        raise MessageRejected("malformed", f"ctl: unknown action {body['action']!r}")
    elif kind == "tick" and not (1 <= body["k"] <= body["n"] and body["dt"] > 0):
        raise MessageRejected("malformed", "tick: need 1 ≤ k ≤ n and dt > 0")
    elif kind == "sense" and not (body["k"] <= body["n"] and body["dt"] > 0):
        raise MessageRejected("malformed", "sense: need 0 ≤ k ≤ n and dt > 0")
    elif kind == "sense" and body["position"].size not in (0, 3):
        raise MessageRejected("shape", "sense: position must hold 0 or 3 numbers")
    elif kind == "sense" and body["fix"].size not in ((2, 3) if body["fix_subject"] else (0,)):
        raise MessageRejected("shape", "sense: fix must hold x, y (and a heading) of its subject")
    elif kind == "sense" and np.any(
        np.abs(np.concatenate([body["position"], body["fix"]])) > MAX_STATE
    ):
        raise MessageRejected("out_of_range", f"sense: a position or fix beyond ±{MAX_STATE:g}")
    covs = body.get("cov")
    if kind == "est":
        covs = body["covs"]
    elif kind == "mail":
        covs = np.concatenate([body["covs"], body["prior_covs"]])
    if covs is not None and np.size(covs):
        covs = np.asarray(covs)
        covs = covs.reshape(-1, *covs.shape[-2:])
        asym = np.abs(covs - np.swapaxes(covs, -1, -2)).max(initial=0.0)
        scale = max(1.0, float(np.abs(covs).max(initial=0.0)))
        if asym > 1e-9 * scale or np.any(np.diagonal(covs, axis1=-2, axis2=-1) < 0):
            raise MessageRejected("bad_covariance", f"{kind}: covariance not symmetric PSD-like")


def _check_velocities(u: np.ndarray, kind: str) -> None:
    """Body velocities ``(n, 4)`` within the limits a scenario may ask for (m/s, rad/s)."""
    if np.any(np.abs(u[:, :3]) > MAX_SPEED_M_S) or np.any(np.abs(u[:, 3]) > MAX_YAW_RATE_RAD_S):
        raise MessageRejected(
            "out_of_range",
            f"{kind}: a velocity beyond ±{MAX_SPEED_M_S:g} m/s or a turn rate beyond "
            f"±{MAX_YAW_RATE_RAD_S:g} rad/s",
        )


def check_state_bounds(kind: str, means: np.ndarray, covs: np.ndarray) -> None:
    """Raise :class:`MessageRejected` unless every entry of ``means`` lies within
    ±:data:`MAX_STATE` (``out_of_range``) and every covariance of ``covs`` (…, d, d) is positive
    definite with eigenvalues in [:data:`MIN_VARIANCE`, :data:`MAX_VARIANCE`]
    (``bad_covariance``): what a filter that fuses a received belief or starts from one needs."""
    if np.any(np.abs(means) > MAX_STATE):
        raise MessageRejected("out_of_range", f"{kind}: a state beyond ±{MAX_STATE:g}")
    if covs.size:
        eig = np.linalg.eigvalsh(covs)
        if not (np.all(eig >= MIN_VARIANCE) and np.all(eig <= MAX_VARIANCE)):
            raise MessageRejected(
                "bad_covariance", f"{kind}: a covariance is not positive definite within the bounds"
            )


def est_bodies(increment: Estimates, *, frame: str) -> list[dict[str, Any]]:
    """The ``est`` bodies of an increment of one sender's estimates: one per (target, track),
    its new beliefs and updates together; ``frame`` names the frame of a target that has
    updates but no new beliefs in this increment."""
    beliefs = {s.key: s for s in increment.beliefs}
    updates = {u.key: u for u in increment.updates}
    bodies = []
    for key in sorted(set(beliefs) | set(updates)):
        b = beliefs.get(key)
        u = updates.get(key) or increment.updates_of(*key)
        bodies.append(
            {
                "target": key[1],
                "track": key[2],
                "frame": b.frame if b is not None else frame,
                "stamps": b.t if b is not None else np.zeros(0),
                "means": b.mean if b is not None else np.zeros((0, FRAMES[frame].dim)),
                "covs": b.cov if b is not None else np.zeros((0, *(FRAMES[frame].dim,) * 2)),
                "ages": b.age if b is not None else np.zeros(0),
                "update_stamps": u.t,
                "update_ages": u.age,
                "nis": u.nis,
                "update_dofs": u.dof,
                "cond_r": u.cond_r,
                "cond_s": u.cond_s,
                "info_names": sorted(b.info) if b is not None else [],
                "info": (
                    np.stack([b.info[k] for k in sorted(b.info)], axis=1).reshape(-1)
                    if b is not None and b.info
                    else np.zeros(0)
                ),
            }
        )
    return bodies


def estimates_from_bodies(
    estimator: str, bodies: Collection[tuple[str, Mapping[str, Any]]]
) -> Estimates:
    """One :class:`Estimates` from validated ``(sender, est body)`` pairs in arrival order (a
    sender's increments follow one another; every series is sorted by time, so a restarted
    sender's second life follows its first)."""
    parts = []
    for sender, body in bodies:
        key: SeriesKey = (sender, body["target"], body["track"])
        beliefs: tuple[BeliefSeries, ...] = ()
        if body["stamps"].size:
            beliefs = (
                BeliefSeries(
                    owner=key[0],
                    subject=key[1],
                    track=key[2],
                    frame=body["frame"],
                    t=body["stamps"],
                    mean=body["means"],
                    cov=body["covs"],
                    age=body["ages"],
                    info={
                        name: body["info"].reshape(-1, len(body["info_names"]))[:, i]
                        for i, name in enumerate(body["info_names"])
                    },
                ),
            )
        updates: tuple[UpdateSeries, ...] = ()
        if body["update_stamps"].size:
            updates = (
                UpdateSeries(
                    owner=key[0],
                    subject=key[1],
                    track=key[2],
                    t=body["update_stamps"],
                    age=body["update_ages"],
                    nis=body["nis"],
                    dof=body["update_dofs"].astype(np.int64),
                    cond_r=body["cond_r"],
                    cond_s=body["cond_s"],
                ),
            )
        parts.append(Estimates(estimator=estimator, beliefs=beliefs, updates=updates))
    if not parts:
        return Estimates(estimator=estimator)
    joined = concatenate(parts)
    return Estimates(
        estimator=estimator,
        beliefs=tuple(_by_time(s) for s in joined.beliefs),
        updates=tuple(_by_time(u) for u in joined.updates),
    )


def _by_time(series: _S) -> _S:
    """A series with its rows sorted by time (stable)."""
    order = np.argsort(series.t, kind="stable")
    rows: dict[str, Any] = {
        f.name: getattr(series, f.name)[order]
        for f in dataclasses.fields(series)
        if isinstance(getattr(series, f.name), np.ndarray)
    }
    if isinstance(series, BeliefSeries):
        rows["info"] = {k: v[order] for k, v in series.info.items()}
    return dataclasses.replace(series, **rows)
