"""A node's inputs: its own sensor slice (recording or live push API) and teammates' odometry
buffers."""

from __future__ import annotations

import dataclasses
import itertools

import numpy as np
import pytest

from relloc.core.recording import Measurements, measurement_rows
from relloc.errors import DataError
from relloc.runtime.scenario import load_team
from relloc.runtime.sources import LiveSource, RecordingSource
from relloc.runtime.teammates import ReceivedOdometry, SeenSequences


def test_recording_source_windows_partition_the_robot_slice(trio_scenario):
    rec = load_team(str(trio_scenario(3.0)), 1).recording
    src = RecordingSource(rec, "observer")
    edges = np.arange(0, 31) * 0.1
    stamps = np.concatenate([src.odometry(a, b)[0] for a, b in itertools.pairwise(edges)])
    np.testing.assert_array_equal(stamps, rec.odometry[0].t[rec.odometry[0].t < edges[-1]])
    rows = [src.measurements(a, b) for a, b in itertools.pairwise(edges)]
    rows.append(src.measurements(edges[-1], edges[-1], inclusive=True))
    mine = rec.measurements.observer == 0
    assert sum(r.size for r in rows) == int(mine.sum()) > 0
    assert all(set(r.targets) <= {"flyer", "rover"} for r in rows)
    np.testing.assert_array_equal(np.concatenate([r.z for r in rows]), rec.measurements.value[mine])
    assert RecordingSource(rec, "flyer").measurements(0.0, 3.0).size == 0  # no sensor


def test_recording_source_refuses_readings_a_node_cannot_send(trio_scenario):
    rec = load_team(str(trio_scenario(3.0)), 1).recording
    extra = measurement_rows("range", t=[0.5], observer=0, target=1, value=[2.0], sigma=0.1)
    mixed = dataclasses.replace(
        rec, measurements=Measurements.concatenate([rec.measurements, extra])
    )
    with pytest.raises(DataError, match=r"robot 'observer' has 1 readings .*\['range'\]"):
        RecordingSource(mixed, "observer")
    assert RecordingSource(mixed, "rover").measurements(0.0, 3.0).size == 0


def test_live_source_push_api():
    src = LiveSource("r1", odometry_sigma=(0.05, 0.0, 0.0, 0.05))
    for k in range(5):
        src.push_odometry(0.1 * k, (0.3, 0.0, 0.0, 0.1 * k))
    src.push_measurement(0.25, "r2", (2.0, 0.1, 0.0), (0.01, 0.004, 0.004))
    stamps, u = src.odometry(0.0, 0.3)
    assert stamps.tolist() == pytest.approx([0.0, 0.1, 0.2]) and u.shape == (3, 4)
    assert src.measurements(0.0, 0.3).targets == ("r2",)
    src.push_odometry(0.15, (0.0, 0.0, 0.0, 0.0))  # older than what the node consumed
    src.push_measurement(0.2, "r2", (2.0, 0.1, 0.0), (0.01, 0.004, 0.004))
    assert src.late == 2
    assert src.odometry(0.3, 1.0)[0].tolist() == pytest.approx([0.3, 0.4])
    with pytest.raises(DataError, match="finite"):
        src.push_odometry(0.5, (np.nan, 0.0, 0.0, 0.0))
    with pytest.raises(DataError, match="> 0"):
        src.push_measurement(0.5, "r2", (-1.0, 0.0, 0.0), (0.01, 0.01, 0.01))


def test_received_odometry_holds_like_the_recording_and_counts_late_and_duplicates():
    buf = ReceivedOdometry()
    buf.add(np.array([0.0, 0.01, 0.02]), np.arange(12.0).reshape(3, 4))
    buf.add(np.array([0.02]), np.ones((1, 4)))  # duplicate stamp
    assert buf.duplicate_samples == 1
    held = buf.held_at(np.array([-0.5, 0.0, 0.015, 0.5]))
    np.testing.assert_array_equal(held[0], np.zeros(4))
    np.testing.assert_array_equal(held[2], [4.0, 5.0, 6.0, 7.0])
    np.testing.assert_array_equal(held[3], [8.0, 9.0, 10.0, 11.0])
    np.testing.assert_array_equal(buf.stamp_at(np.array([-0.5, 0.015, 0.5])), [np.nan, 0.01, 0.02])
    buf.consume_until(0.02)
    np.testing.assert_array_equal(buf.held_at(np.array([0.015]))[0], [4.0, 5.0, 6.0, 7.0])
    buf.add(np.array([0.019, 0.03]), np.zeros((2, 4)))
    assert buf.late == 1 and buf.stamps_between(0.02, 0.04).tolist() == [0.02, 0.03]


def test_seen_sequences_filters_duplicates_and_forgets_restarted_senders():
    seen = SeenSequences(per_tick=8, window=4)
    assert [seen.is_new("a", "odom", s, tick=1) for s in (0, 1, 1, 3, 2, 0)] == [
        True,
        True,
        False,
        True,
        True,
        False,
    ]
    assert seen.is_new("a", "meas", 1, tick=1)  # per kind
    seen.forget("a")
    assert seen.is_new("a", "odom", 0, tick=2)
