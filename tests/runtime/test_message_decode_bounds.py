"""Wire-level limits of ``decode``: field types, string and map sizes, taken from the raw
msgpack document a hostile sender could craft (not from ``encode``, which refuses them)."""

from __future__ import annotations

import msgpack
import numpy as np
import pytest
from test_messages import COV, _est

from relloc.errors import DataError
from relloc.runtime.messages import (
    MessageRejected,
    check_state_bounds,
    decode,
    encode,
    version_mismatch,
)

ROSTER = ("obs", "air1", "gnd1")


def _doc(kind: str, sender: str, body: dict) -> dict:
    return msgpack.unpackb(encode(kind, sender, 1, 0.5, body))


def _reason(doc: dict) -> str:
    with pytest.raises(MessageRejected) as info:
        decode(msgpack.packb(doc, use_bin_type=True), roster=ROSTER)
    return info.value.reason


@pytest.mark.parametrize("field", ["seq", "wall_ns"])
def test_a_boolean_header_integer_is_malformed(field):
    doc = _doc("ack", "air1", {"k": 3})
    doc[field] = True
    assert _reason(doc) == "malformed"


def test_a_boolean_tick_index_is_malformed():
    doc = _doc("tick", "clock", {"k": 1, "n": 4, "dt": 0.1})
    doc["k"] = True
    assert _reason(doc) == "malformed"


def test_a_boolean_time_is_malformed():
    doc = _doc("ack", "air1", {"k": 3})
    doc["t"] = True
    assert _reason(doc) == "malformed"
    doc = _doc("tick", "clock", {"k": 1, "n": 4, "dt": 0.1})
    doc["dt"] = True
    assert _reason(doc) == "malformed"


def test_a_string_list_holding_a_number_is_malformed():
    doc = _doc("est", "obs", _est())
    doc["info_names"] = [7]
    assert _reason(doc) == "malformed"
    doc = _doc("evt", "obs", {"stamps": [0.1], "targets": ["air1"], "kinds": ["created"]})
    doc["targets"] = [None]
    assert _reason(doc) == "malformed"


def test_a_string_longer_than_1024_characters_is_refused_unread():
    name = "x" * 1025
    doc = _doc("stats", "air1", {"counters": {"sent.odom": 1}})
    doc["counters"] = {name: 1}
    assert _reason(doc) == "malformed"
    doc["counters"] = {"y" * 1024: 1}  # the longest string taken
    payload = msgpack.packb(doc, use_bin_type=True)
    assert decode(payload, roster=ROSTER).body["counters"] == {"y" * 1024: 1}


def test_a_map_of_more_than_256_entries_is_refused_unread():
    doc = _doc("stats", "air1", {"counters": {"sent.odom": 1}})
    doc["counters"] = {f"c{i}": i for i in range(257)}
    assert _reason(doc) == "malformed"
    doc["counters"] = {f"c{i}": i for i in range(256)}
    payload = msgpack.packb(doc, use_bin_type=True)
    assert len(decode(payload, roster=ROSTER).body["counters"]) == 256


def test_an_infinite_array_entry_is_non_finite():
    doc = _doc("est", "obs", _est())
    doc["nis"] = [float("inf")]
    assert _reason(doc) == "non_finite"
    doc = _doc("odom", "air1", {"stamps": [0.0, 0.1], "u": np.zeros((2, 4))})
    doc["stamps"] = [0.0, float("inf")]
    assert _reason(doc) == "non_finite"


def test_a_measured_range_of_zero_is_malformed():
    body = {"stamps": [0.1], "targets": ["air1"], "z": [[1.0, 0.0, 0.0]], "sigma": [[0.1] * 3]}
    doc = _doc("meas", "obs", body)
    doc["z"] = [[0.0, 0.1, 0.2]]
    assert _reason(doc) == "malformed"


def _eqm(mean: list[float], cov: np.ndarray) -> dict:
    return {"target": "air1", "mean": mean, "cov": cov}


def test_an_equivalent_measurement_far_below_the_state_bound_is_out_of_range():
    doc = _doc("eqm", "obs", _eqm([0.0] * 4, COV))
    doc["mean"] = [0.0, -2e9, 0.0, 0.0]
    assert _reason(doc) == "out_of_range"


def test_an_equivalent_measurement_covariance_beyond_the_variance_bound_is_refused():
    doc = _doc("eqm", "obs", _eqm([0.0] * 4, COV))
    doc["cov"] = np.diag([1.0, 1.0, 1.0, 1e13]).tolist()
    assert _reason(doc) == "bad_covariance"
    doc["cov"] = np.diag([1.0, 1.0, 1.0, 1e11]).tolist()  # within the bound
    assert decode(msgpack.packb(doc, use_bin_type=True), roster=ROSTER).kind == "eqm"


def test_an_equivalent_measurement_covariance_slightly_indefinite_is_refused():
    # positive diagonal, symmetric, eigenvalues 2 + 1e-6 and -1e-6 in the x-y block
    cov = np.eye(4)
    cov[0, 1] = cov[1, 0] = 1.0 + 1e-6
    doc = _doc("eqm", "obs", _eqm([0.0] * 4, COV))
    doc["cov"] = cov.tolist()
    assert _reason(doc) == "bad_covariance"


def test_estimates_with_more_update_stamps_than_update_values_are_a_shape_error():
    doc = _doc("est", "obs", _est())
    doc["update_stamps"] = [0.1, 0.2]  # the five per-update arrays hold one value each
    assert _reason(doc) == "shape"


def test_estimates_with_more_info_values_than_records_times_names_are_a_shape_error():
    doc = _doc("est", "obs", _est())
    doc["info"] = [0.9, 0.8, 0.7]  # 2 records × 1 name
    assert _reason(doc) == "shape"


def _mail_body(k: int, sizes: list[float]) -> dict:
    return {
        "progress": 1.5,
        "stamps": [1.0] * len(sizes),
        "subjects": ["gnd1"] * len(sizes),
        "sizes": sizes,
        "means": np.zeros((k, 4)),
        "covs": np.stack([COV] * k),
        "prior_means": np.zeros((k, 4)),
        "prior_covs": np.stack([COV] * k),
        "weights": [1.0 / k] * k,
    }


def test_a_mail_message_of_no_tracks_is_a_shape_error():
    doc = _doc("mail", "obs", _mail_body(2, [1, 1]))
    doc["sizes"] = [0.0, 2.0]  # still summing to the 2 tracks
    assert _reason(doc) == "shape"


def test_a_mail_message_of_a_fractional_track_count_is_a_shape_error():
    doc = _doc("mail", "obs", _mail_body(3, [1, 2]))
    doc["sizes"] = [1.5, 1.5]  # sums to the 3 tracks
    assert _reason(doc) == "shape"


def _sense(**overrides: object) -> dict:
    body = {
        "k": 1,
        "n": 10,
        "dt": 0.1,
        "target": "air1",
        "position": [0.0, 0.0, 1.0],
        "fix_subject": "gnd1",
        "fix": [1.0, 2.0, 0.5],
        "stamps": [],
        "kinds": [],
        "subjects": [],
        "landmarks": [],
        "sensors": [],
        "values": [],
        "sigmas": [],
    }
    return _doc("sense", "clock", body | overrides)


def test_a_sense_without_a_fix_subject_carries_no_fix():
    doc = _sense(fix_subject="", fix=[])
    assert decode(msgpack.packb(doc, use_bin_type=True), roster=ROSTER).body["fix"].size == 0
    doc["fix"] = [1.0, 2.0]
    assert _reason(doc) == "shape"


def test_a_sense_marker_fix_beyond_the_state_bound_is_out_of_range():
    doc = _sense()
    doc["fix"] = [1.0, -2e9, 0.0]
    assert _reason(doc) == "out_of_range"


def test_a_reported_covariance_with_a_negative_variance_is_refused():
    cov = COV.copy()
    cov[2, 2] = -0.3
    doc = _doc("est", "obs", _est())
    doc["covs"] = [COV.tolist(), cov.tolist()]
    assert _reason(doc) == "bad_covariance"


def test_a_reported_covariance_asymmetric_by_a_millionth_is_refused():
    cov = COV.copy()
    cov[0, 1] = 1e-6  # scale 1: beyond the 1e-9 allowed
    doc = _doc("est", "obs", _est())
    doc["covs"] = [COV.tolist(), cov.tolist()]
    assert _reason(doc) == "bad_covariance"
    cov[0, 1] = 1e-10  # within it
    doc["covs"] = [COV.tolist(), cov.tolist()]
    assert decode(msgpack.packb(doc, use_bin_type=True), roster=ROSTER).kind == "est"


def test_an_asymmetric_prior_covariance_in_mail_is_refused():
    prior = COV.copy()
    prior[1, 0] = 0.05
    doc = _doc("mail", "obs", _mail_body(1, [1]))
    doc["prior_covs"] = [prior.tolist()]
    assert _reason(doc) == "bad_covariance"


@pytest.mark.parametrize(
    "variances",
    [[1.0, 1.0, 1.0, 0.0], [1.0, 1.0, 1.0, 1e-19], [1.0, 1.0, 1.0, 2e12]],
    ids=["singular", "below-1e-18", "above-1e12"],
)
def test_a_belief_to_fuse_needs_variances_within_1e_18_and_1e12(variances):
    with pytest.raises(MessageRejected) as info:
        check_state_bounds("mail", np.zeros((1, 4)), np.diag(variances)[None])
    assert info.value.reason == "bad_covariance"


def test_a_belief_to_fuse_at_the_variance_bounds_is_taken():
    check_state_bounds("mail", np.zeros((1, 4)), np.diag([1e-18, 1.0, 1.0, 1e12])[None])


def test_a_message_of_an_empty_sender_is_from_nobody_on_the_team():
    doc = _doc("ack", "air1", {"k": 3})
    doc["sender"] = ""
    assert _reason(doc) == "unknown_sender"


def test_an_older_peer_is_told_only_what_changed_after_its_version():
    assert version_mismatch(3) == (
        "schema version 3 is older than this process' 4 (since then v4: sync, cmd and sense "
        "exist): run every process of the team from the same relloc"
    )
    assert "v2:" not in version_mismatch(2) and "v3: est carries" in version_mismatch(2)
    assert version_mismatch(5).startswith("schema version 5 is newer than this process' 4")


def test_encode_refuses_a_message_over_the_size_limit():
    body = {"stamps": np.arange(40) * 0.01, "u": np.zeros((40, 4))}
    size = len(encode("odom", "air1", 1, 0.5, body))
    assert encode("odom", "air1", 1, 0.5, body, max_bytes=size)
    with pytest.raises(DataError, match="exceed the limit"):
        encode("odom", "air1", 1, 0.5, body, max_bytes=size - 1)
    with pytest.raises(DataError, match="exceed the limit"):
        encode("odom", "air1", 1, 0.5, body, max_bytes=size // 2 + 1)


def test_estimates_of_updates_only_carry_empty_beliefs_of_their_frame():
    doc = _doc("est", "obs", _est())
    doc |= {"stamps": [], "means": [], "covs": [], "ages": [], "info_names": [], "info": []}
    body = decode(msgpack.packb(doc, use_bin_type=True), roster=ROSTER).body
    assert body["means"].shape == (0, 4) and body["covs"].shape == (0, 4, 4)
    doc["frame"] = "world_pose2"
    body = decode(msgpack.packb(doc, use_bin_type=True), roster=ROSTER).body
    assert body["means"].shape == (0, 3) and body["covs"].shape == (0, 3, 3)


def test_an_integer_header_time_is_read_as_seconds_in_floating_point():
    doc = _doc("ack", "air1", {"k": 3})
    doc["t"] = 3
    msg = decode(msgpack.packb(doc, use_bin_type=True), roster=ROSTER)
    assert type(msg.t) is float and msg.t == 3.0
