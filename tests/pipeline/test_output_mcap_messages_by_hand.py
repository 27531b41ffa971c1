"""The MCAP file of one hand-made world-frame belief whose first record is before the truth:
which messages are written at which stamps, in what order and with what sequence numbers."""

from __future__ import annotations

import math
from collections import defaultdict

import numpy as np
import pytest
from export_helpers import standing_pair

from relloc.core.estimates import BeliefSeries, Estimates
from relloc.pipeline.export.mcap_file import write_mcap
from relloc.pipeline.export.poses import pose_set

pytest.importorskip("mcap", reason="extra 'ros' (mcap) is not installed")
pytest.importorskip("rosbags", reason="extra 'ros' (rosbags) is not installed")

S = 1_000_000_000  # ns per s


def _write(tmp_path):  # type: ignore[no-untyped-def]
    """Robots ``a`` and ``b``, truth from 1 s to 3 s; the team's belief of ``b`` at 0.5, 1, 2 s."""
    rec = standing_pair((1.0, 3.0), [0.0, 0.0, 0.0, 0.0], [3.0, 4.0, 0.0, math.pi / 2])
    s = BeliefSeries(
        owner="team",
        subject="b",
        track="",
        frame="world_pose2",
        t=np.array([0.5, 1.0, 2.0]),
        mean=np.array([[3.0, 4.0, 0.0]] * 3),
        cov=np.stack([np.eye(3)] * 3),
        age=np.array([0.0, 0.5, 1.5]),
    )
    poses = pose_set(Estimates(estimator="hand", beliefs=(s,)), rec)
    return write_mcap(tmp_path / "out.mcap", poses, rec, estimator="hand")


def _messages_in_file_order(path):  # type: ignore[no-untyped-def]
    from mcap.reader import make_reader

    with open(path, "rb") as f:
        return [
            (c.topic, m.log_time, m.sequence)
            for _, c, m in make_reader(f).iter_messages(log_time_order=False)
        ]


def test_truth_and_tf_start_at_the_first_stamp_of_the_truth_and_none_is_empty(tmp_path):  # type: ignore[no-untyped-def]
    written = _write(tmp_path)
    stamps = defaultdict(list)
    for topic, ns, _ in _messages_in_file_order(written.path):
        stamps[topic].append(ns)
    assert dict(stamps) == {
        "/team/estimates/b": [S // 2, S, 2 * S],
        "/team/ground_truth/b": [S, 2 * S],
        "/ground_truth/a": [S, 2 * S],
        "/ground_truth/b": [S, 2 * S],
        "/tf": [S, 2 * S],
    }
    assert written.messages == {t: len(v) for t, v in stamps.items()}


def test_messages_are_in_stamp_order_and_numbered_per_topic(tmp_path):  # type: ignore[no-untyped-def]
    messages = _messages_in_file_order(_write(tmp_path).path)
    log_times = [ns for _, ns, _ in messages]
    assert log_times == sorted(log_times)
    sequences = defaultdict(list)
    for topic, _, seq in messages:
        sequences[topic].append(seq)
    assert sequences["/team/estimates/b"] == [0, 1, 2]
    assert sequences["/tf"] == [0, 1]


def test_the_summary_gives_the_time_taken_in_milliseconds(tmp_path):  # type: ignore[no-untyped-def]
    summary = _write(tmp_path).to_dict()
    assert summary["messages"] == 11
    assert summary["seconds"] == round(summary["seconds"], 3)
