"""Message schema: round trips, and every kind of bad input rejected with its counter reason."""

from __future__ import annotations

import math

import msgpack
import numpy as np
import pytest

from relloc.errors import DataError
from relloc.runtime.messages import (
    DEFAULT_MAX_BYTES,
    SCHEMA_VERSION,
    MessageRejected,
    decode,
    encode,
)

ROSTER = ("obs", "air1", "gnd1")


def _odom(n=3):
    return {"stamps": np.arange(n) * 0.01, "u": np.tile([0.3, 0.0, 0.0, 0.1], (n, 1))}


COV = np.diag([0.1, 0.2, 0.3, 0.04])


def _est(**overrides):
    body = {
        "target": "air1",
        "track": "",
        "frame": "relative_pose4",
        "stamps": [0.1, 0.2],
        "means": np.zeros((2, 4)),
        "covs": np.stack([COV, COV]),
        "ages": [0.0, 0.1],
        "update_stamps": [0.1],
        "update_ages": [0.0],
        "nis": [2.5],
        "update_dofs": [3],
        "cond_r": [3.0],
        "cond_s": [2.0],
        "info_names": ["weight"],
        "info": [0.9, 0.8],
    }
    return body | overrides


def test_round_trip_every_kind():
    bodies = {
        "odom": _odom(),
        "meas": {
            "stamps": [0.1, 0.1],
            "targets": ["air1", "gnd1"],
            "z": [[2.0, 0.1, 0.5], [3.0, -0.2, -0.05]],
            "sigma": [[0.01, 0.004, 0.004]] * 2,
        },
        "eqm": {"target": "air1", "mean": [1.0, 2.0, 0.5, 0.1], "cov": COV},
        "est": _est(),
        "evt": {"stamps": [0.1], "targets": ["air1"], "kinds": ["created"]},
        "stats": {"counters": {"sent.odom": 10, "rejected.malformed": 1}},
        "tick": {"k": 5, "n": 40, "dt": 0.1},
        "ack": {"k": 5},
        "ctl": {"action": "kill", "robot": "air1"},
        "mail": {
            "progress": 1.5,
            "stamps": [1.0],
            "subjects": ["gnd1"],
            "sizes": [2],
            "means": np.zeros((2, 4)),
            "covs": np.stack([COV, COV]),
            "prior_means": np.zeros((2, 4)),
            "prior_covs": np.stack([COV, COV]),
            "weights": [0.5, 0.5],
        },
    }
    assert SCHEMA_VERSION == 4
    for kind, body in bodies.items():
        sender = "clock" if kind in ("tick", "ctl") else "obs"
        msg = decode(encode(kind, sender, 7, 1.5, body), roster=ROSTER, key_sender=sender)
        assert (msg.kind, msg.sender, msg.seq, msg.t) == (kind, sender, 7, 1.5)
    msg = decode(encode("odom", "obs", 0, 0.0, _odom(4)), roster=ROSTER)
    np.testing.assert_array_equal(msg.body["u"], np.tile([0.3, 0.0, 0.0, 0.1], (4, 1)))
    empty = _est(target="gnd1", stamps=[], means=[], covs=[], ages=[], info=[])
    assert decode(encode("est", "obs", 1, 0.0, empty), roster=ROSTER).body["means"].shape == (0, 4)


def _raw(**overrides):
    payload = {
        "v": SCHEMA_VERSION,
        "type": "eqm",
        "sender": "obs",
        "seq": 1,
        "t": 0.5,
        "wall_ns": 1,
        "target": "air1",
        "mean": [0.0, 0.0, 0.0, 0.0],
        "cov": np.eye(4).tolist(),
    }
    payload.update(overrides)
    return msgpack.packb(payload, use_bin_type=True)


def test_a_message_of_an_older_schema_is_refused_naming_what_changed_since():
    """Version 4 added ``sync``, ``cmd`` and ``sense``: a version-3 process's messages are
    refused, with an error that says which side is older and what it lacks."""
    with pytest.raises(MessageRejected) as old:
        decode(_raw(v=3), roster=ROSTER)
    assert old.value.reason == "version"
    assert "version 3 is older than this process' 4" in str(old.value)
    assert "sync, cmd and sense" in str(old.value)
    with pytest.raises(MessageRejected) as new:
        decode(_raw(v=SCHEMA_VERSION + 1), roster=ROSTER)
    assert "is newer than this process'" in str(new.value)


@pytest.mark.parametrize(
    ("data", "reason"),
    [
        (b"\xc1\x00garbage", "malformed"),
        (msgpack.packb([1, 2, 3]), "malformed"),
        (_raw(v=99), "version"),
        (_raw(v=3), "version"),
        (_raw(type="teleport"), "unknown_type"),
        (_raw(sender="mallory"), "unknown_sender"),
        (_raw(target="ghost"), "unknown_target"),
        (_raw(mean=[0.0, 0.0, 0.0]), "shape"),
        (_raw(mean=[0.0, math.nan, 0.0, 0.0]), "non_finite"),
        (_raw(t=math.inf), "non_finite"),
        (_raw(mean="1,2,3,4"), "malformed"),
        (_raw(mean=["1e5", 0.0, 0.0, 0.0]), "malformed"),  # a string is not a number
        (_raw(mean=[True, False, True, False]), "malformed"),
        (_raw(seq=-1), "malformed"),
        (_raw(cov=[[1, 5, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]), "bad_covariance"),
        (_raw(cov=(-np.eye(4)).tolist()), "bad_covariance"),
        (b"\x00" * (DEFAULT_MAX_BYTES + 1), "oversized"),
    ],
)
def test_bad_messages_are_rejected_with_a_reason(data, reason):
    with pytest.raises(MessageRejected) as info:
        decode(data, roster=ROSTER)
    assert info.value.reason == reason
    assert isinstance(info.value, DataError)


def test_spoofed_sender_and_inconsistent_batches():
    with pytest.raises(MessageRejected, match="spoofed"):
        decode(_raw(), roster=ROSTER, key_sender="air1")
    bad_odom = {"stamps": [0.0, 0.0], "u": np.zeros((2, 4))}
    with pytest.raises(DataError, match="strictly increasing"):
        encode("odom", "obs", 0, 0.0, bad_odom)
    with pytest.raises(DataError, match="lengths differ"):
        encode("odom", "obs", 0, 0.0, {"stamps": [0.0], "u": np.zeros((2, 4))})
    bad_evt = {"stamps": [0.0], "targets": ["air1"], "kinds": ["vanished"]}
    with pytest.raises(DataError, match="kinds"):
        encode("evt", "obs", 0, 0.0, bad_evt)
    with pytest.raises(DataError, match="exceed the limit"):
        encode("odom", "obs", 0, 0.0, _odom(50), max_bytes=200)


@pytest.mark.parametrize(
    ("overrides", "match"),
    [
        ({"frame": "world_pose2"}, "states are not those of"),  # 4 states, a 3-state frame
        ({"frame": "nowhere"}, "is not a frame"),
        ({"update_dofs": [0]}, "update_dofs must be integers"),
        ({"update_dofs": [2.5]}, "update_dofs must be integers"),
        ({"update_dofs": [1e300]}, "update_dofs must be integers"),  # an int64 cast of garbage
        ({"update_dofs": [3, 3]}, "update batch lengths differ"),
        ({"ages": [0.0]}, "record batch lengths differ"),
        ({"track": 7}, "expected str"),
    ],
)
def test_bad_estimate_batches_are_refused(overrides, match):
    with pytest.raises(DataError, match=match):
        encode("est", "obs", 0, 0.0, _est(**overrides))


def test_estimates_travel_as_est_bodies_and_come_back_whole():
    from relloc.core.contract import Belief, UpdateRecord
    from relloc.core.estimates import Recorder
    from relloc.runtime.messages import est_bodies, estimates_from_bodies

    rec = Recorder("plkf")
    reports = []
    for k in range(4):
        t = 0.1 * k
        rec.record(t, "obs", [Belief("air1", "relative_pose4", np.full(4, t), COV, age=t)])
        if k % 2:
            rec.add_updates("obs", [UpdateRecord(t, "gnd1", 1.0 + k, 3, 1.0, 2.0, age=t)])
        bodies = est_bodies(rec.take_new(), frame="relative_pose4")
        reports += [
            ("obs", decode(encode("est", "obs", len(reports), t, b), roster=ROSTER).body)
            for b in bodies
        ]
    assert [b["target"] for _, b in reports] == ["air1", "air1", "gnd1", "air1", "air1", "gnd1"]
    back = estimates_from_bodies("plkf", reports)
    whole = rec.results()
    assert back.labels == whole.labels == ("obs->air1",)
    for got, ref in zip(back.beliefs, whole.beliefs, strict=True):
        for name in ("t", "mean", "cov", "age"):
            np.testing.assert_array_equal(getattr(got, name), getattr(ref, name))
    np.testing.assert_array_equal(back.updates_of("obs", "gnd1").nis, [2.0, 4.0])
    np.testing.assert_array_equal(back.updates_of("obs", "gnd1").dof, [3, 3])
    # a restarted sender's second life follows its first whatever the arrival order
    swapped = estimates_from_bodies("plkf", [reports[3], reports[0]])
    np.testing.assert_array_equal(swapped.series("obs", "air1").t, [0.0, 0.2])


@pytest.mark.parametrize(
    ("kind", "body", "what"),
    [
        ("odom", {"stamps": [0.0], "u": [[1e154, 0.0, 0.0, 0.0]]}, "velocity"),
        ("odom", {"stamps": [0.0], "u": [[0.1, 0.0, 0.0, -101.0]]}, "turn rate"),
        ("cmd", {"k": 1, "u": [0.0, 0.0, 100.5, 0.0]}, "velocity"),
        (
            "sense",
            {"k": 1, "n": 2, "dt": 0.1, "target": "air1", "position": [0.0, 0.0, 2e9]}
            | {"fix_subject": "", "fix": []}
            | {name: [] for name in ("stamps", "kinds", "subjects", "landmarks", "sensors")}
            | {"values": [], "sigmas": []},
            "position",
        ),
    ],
)
def test_finite_but_absurd_velocities_and_positions_are_out_of_range(kind, body, what):
    """Finite numbers that no robot reports (beyond a scenario's limits, 100 m/s and 100
    rad/s, or ±1e9 m) would overflow a teammate's filter or guidance: refused on decoding."""
    sender = "clock" if kind == "sense" else "obs"
    with pytest.raises(MessageRejected) as info:
        encode(kind, sender, 0, 0.0, body)
    assert info.value.reason == "out_of_range" and what in str(info.value)
    limit = {"stamps": [0.0], "u": [[100.0, -100.0, 0.0, 100.0]]}
    assert decode(encode("odom", "obs", 0, 0.0, limit), roster=ROSTER).body["u"].shape == (1, 4)


_MEAS = {"targets": ["air1", "gnd1"], "z": [[2.0, 0.1, 0.5]] * 2, "sigma": [[0.01] * 3] * 2}


@pytest.mark.parametrize(
    ("kind", "sender", "body", "reason", "what"),
    [
        ("meas", "obs", _MEAS | {"stamps": [0.2, 0.1]}, "malformed", "stamps decreasing"),
        ("meas", "air1", _MEAS | {"stamps": [0.1, 0.2]}, "malformed", "of its sender 'air1'"),
        ("eqm", "air1", {"target": "air1", "mean": [0.0] * 4, "cov": COV}, "malformed", "its"),
        (
            "eqm",
            "obs",
            {"target": "air1", "mean": [0.0] * 4, "cov": np.diag([1.0, 1.0, 1.0, -0.5])},
            "bad_covariance",
            "not positive semidefinite",
        ),
        (
            "eqm",
            "obs",
            {"target": "air1", "mean": [0.0, 0.0, 2e9, 0.0], "cov": COV},
            "out_of_range",
            "beyond",
        ),
    ],
)
def test_readings_and_beliefs_no_robot_makes_are_refused(kind, sender, body, reason, what):
    """These decoded once: unsorted readings, a reading or belief of the sender itself, an
    indefinite belief (counted only, never fused, but counted as received)."""
    with pytest.raises(MessageRejected) as info:
        decode(encode(kind, sender, 0, 0.0, body), roster=ROSTER)
    assert info.value.reason == reason and what in str(info.value)
    held = {"target": "air1", "mean": [0.0] * 4, "cov": np.diag([0.1, 0.1, 0.0, 0.01])}
    assert decode(encode("eqm", "obs", 0, 0.0, held), roster=ROSTER).body["cov"][2, 2] == 0.0


def _payload(kind: str, sender: str = "obs", **fields):
    header = {"v": SCHEMA_VERSION, "type": kind, "sender": sender, "seq": 0, "t": 0.5, "wall_ns": 1}
    return msgpack.packb(header | fields, use_bin_type=True)


_MAIL = {
    "progress": 1.0,
    "stamps": [1.0],
    "subjects": ["gnd1"],
    "sizes": [2],
    "means": [[0.0] * 4] * 2,
    "covs": [np.eye(4).tolist()] * 2,
    "prior_means": [[0.0] * 4] * 2,
    "prior_covs": [np.eye(4).tolist()] * 2,
    "weights": [0.5, 0.5],
}
_EST = {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in _est().items()}


@pytest.mark.parametrize(
    ("data", "reason", "what"),
    [
        (
            _payload("meas", **_MEAS | {"targets": ["air1", "ghost"]}, stamps=[0.1, 0.2]),
            "unknown_target",
            "targets ['ghost']",
        ),
        (_payload("odom", stamps=[0.0]), "malformed", "odom: field 'u' missing"),
        (
            _payload("evt", stamps=[0.1], targets="air1", kinds=["created"]),
            "malformed",
            "evt.targets",
        ),
        (_payload("stats", counters={"sent.odom": -1}), "malformed", "stats.counters"),
        (_payload("stats", counters={"sent.odom": True}), "malformed", "stats.counters"),
        (_payload("odom", stamps=[0.0, [1.0]], u=[[0.0] * 4]), "malformed", "odom.stamps"),
        (_payload("meas", **_MEAS, stamps=[0.1]), "shape", "meas: batch lengths differ"),
        (
            _payload("meas", **_MEAS | {"sigma": [[0.01] * 3, [0.0] * 3]}, stamps=[0.1, 0.2]),
            "malformed",
            "sigma and range must be > 0",
        ),
        (
            _payload(
                "meas", **_MEAS | {"z": [[2.0, 0.1, 0.5], [-1.0, 0.1, 0.5]]}, stamps=[0.1, 0.2]
            ),
            "malformed",
            "sigma and range must be > 0",
        ),
        (_payload("est", **_EST | {"info": [0.9]}), "shape", "est: info is not one value"),
        (_payload("mail", **_MAIL | {"subjects": []}), "shape", "mail: per-message lengths"),
        (_payload("mail", **_MAIL | {"sizes": [1]}), "shape", "mail: sizes must be integers"),
        (_payload("mail", **_MAIL | {"sizes": [1.5]}), "shape", "mail: sizes must be integers"),
        (_payload("mail", **_MAIL | {"weights": [1.0]}), "shape", "mail: track arrays"),
        (
            _payload("mail", **_MAIL | {"prior_means": [[0.0] * 4]}),
            "shape",
            "mail: track arrays",
        ),
        (_payload("mail", **_MAIL | {"weights": [0.5, -0.5]}), "malformed", "negative weights"),
        (
            _payload("evt", stamps=[0.1, 0.2], targets=["air1"], kinds=["created"]),
            "shape",
            "evt: batch lengths differ",
        ),
        (_payload("ctl", "clock", action="pause", robot="air1"), "malformed", "unknown action"),
        (_payload("tick", "clock", k=0, n=40, dt=0.1), "malformed", "tick: need 1 ≤ k ≤ n"),
        (_payload("tick", "clock", k=41, n=40, dt=0.1), "malformed", "tick: need 1 ≤ k ≤ n"),
        (_payload("tick", "clock", k=1, n=40, dt=0.0), "malformed", "tick: need 1 ≤ k ≤ n"),
    ],
)
def test_a_hostile_body_is_rejected_naming_the_field_or_rule(data, reason, what):
    """Bodies a well-behaved sender never writes (``encode`` refuses most of them), packed by
    hand: each is refused with its counter reason and a message that names where it fails."""
    with pytest.raises(MessageRejected) as info:
        decode(data, roster=ROSTER)
    assert info.value.reason == reason
    assert what in str(info.value)


def test_encode_refuses_what_it_cannot_send_and_packs_numpy_scalars():
    with pytest.raises(DataError, match="unknown message kind 'teleport'"):
        encode("teleport", "obs", 0, 0.0, {})
    with pytest.raises(DataError, match="encode ack: missing field 'k'"):
        encode("ack", "obs", 0, 0.0, {})
    msg = decode(encode("ack", "obs", 0, 0.0, {"k": np.int64(5)}), roster=ROSTER)
    assert msg.body["k"] == 5 and type(msg.body["k"]) is int


def test_no_estimate_reports_make_empty_estimates():
    """A team whose collector heard no ``est`` (every robot gone before its first report)."""
    from relloc.runtime.messages import estimates_from_bodies

    none = estimates_from_bodies("plkf", [])
    assert none.estimator == "plkf" and none.labels == () and none.beliefs == ()
