"""``mail`` bodies: how a large mail is split under the size limit, the progress each part
carries, and the messages a receiver rebuilds from a body."""

from __future__ import annotations

import numpy as np
import pytest

from relloc.errors import DataError
from relloc.fusion.messages import EquivalentMeasurement
from relloc.runtime.mail import mail_body, mail_items
from relloc.runtime.messages import MessageRejected, decode, encode

ROSTER = ("a", "b", "c")


def _eqm(subject: int, time: float, k: int, x0: float = 0.0) -> EquivalentMeasurement:
    means = np.zeros((k, 4))
    means[:, 0] = x0 + np.arange(k)
    return EquivalentMeasurement(
        sender=0,
        subject=subject,
        time=time,
        means=means,
        covs=np.stack([np.eye(4)] * k),
        prior_means=means + 100.0,
        prior_covs=np.stack([2.0 * np.eye(4)] * k),
        weights=np.arange(1.0, k + 1) / np.arange(1.0, k + 1).sum(),
    )


def test_a_part_holds_as_many_tracks_as_fit_after_the_header():
    # (2024 − 1024) // 400 = 2 tracks a part
    sent = [(1.0, _eqm(1, 1.0, 1)), (1.0, _eqm(2, 1.0, 1)), (1.5, _eqm(1, 1.5, 1))]
    parts = mail_body(2.0, sent, ROSTER, max_bytes=2024)
    assert [p["subjects"] for p in parts] == [["b", "c"], ["b"]]
    assert [p["progress"] for p in parts] == [1.0, 2.0]  # every part but the last: earliest


def test_one_message_larger_than_a_part_travels_alone_and_is_never_split():
    sent = [(1.0, _eqm(1, 1.0, 3)), (1.2, _eqm(2, 1.2, 1)), (1.4, _eqm(1, 1.4, 1))]
    parts = mail_body(3.0, sent, ROSTER, max_bytes=2024)
    assert [p["sizes"].tolist() for p in parts] == [[3.0], [1.0, 1.0]]
    assert [p["progress"] for p in parts] == [1.0, 3.0]


def test_a_mail_that_fits_is_one_part_with_the_senders_progress():
    sent = [(1.0, _eqm(1, 1.0, 2)), (1.0, _eqm(2, 1.0, 1))]
    (body,) = mail_body(2.5, sent, ROSTER, max_bytes=65536)
    assert body["progress"] == 2.5 and body["sizes"].tolist() == [2.0, 1.0]
    (empty,) = mail_body(4.0, [], ROSTER, max_bytes=65536)
    assert empty["progress"] == 4.0 and empty["means"].shape == (0, 4)


def test_only_equivalent_measurements_can_be_mailed():
    with pytest.raises(DataError, match="only equivalent measurements"):
        mail_body(1.0, [(1.0, "hello")], ROSTER, max_bytes=65536)


def _wire(body: dict) -> dict:
    return decode(encode("mail", "a", 0, 2.0, body), roster=ROSTER).body


def test_a_receiver_rebuilds_each_message_grouped_by_stamp():
    sent = [(1.0, _eqm(1, 1.0, 2, x0=10.0)), (1.0, _eqm(2, 1.0, 1, x0=20.0))]
    sent.append((1.5, _eqm(1, 1.5, 1, x0=30.0)))
    (body,) = mail_body(2.0, sent, ROSTER, max_bytes=65536)
    items = mail_items(_wire(body), ROSTER, "a")
    assert [(stamp, [m.subject for m in ms]) for stamp, ms in items] == [(1.0, [1, 2]), (1.5, [1])]
    first = items[0][1][0]
    assert first.sender == 0 and first.means[:, 0].tolist() == [10.0, 11.0]
    assert first.prior_means[:, 0].tolist() == [110.0, 111.0]
    np.testing.assert_allclose(first.weights, [1 / 3, 2 / 3])
    assert items[0][1][1].means[:, 0].tolist() == [20.0]


def test_a_prior_track_beyond_the_bounds_is_refused():
    (body,) = mail_body(2.0, [(1.0, _eqm(1, 1.0, 1))], ROSTER, max_bytes=65536)
    wire = _wire(body)
    wire["prior_means"] = np.array([[2e9, 0.0, 0.0, 0.0]])
    with pytest.raises(MessageRejected) as info:
        mail_items(wire, ROSTER, "a")
    assert info.value.reason == "out_of_range"
    wire = _wire(body)
    wire["prior_covs"] = np.array([np.diag([1.0, 1.0, 1.0, 1e13])])
    with pytest.raises(MessageRejected) as info:
        mail_items(wire, ROSTER, "a")
    assert info.value.reason == "bad_covariance"


def test_a_subject_off_the_roster_is_an_unknown_target():
    (body,) = mail_body(2.0, [(1.0, _eqm(1, 1.0, 1))], ROSTER, max_bytes=65536)
    wire = _wire(body)
    wire["subjects"] = ["zz"]
    with pytest.raises(MessageRejected) as info:
        mail_items(wire, ROSTER, "a")
    assert info.value.reason == "unknown_target"
