"""A query at a recorded ground-truth sample is measured, not interpolated, so it is never
"in a gap" — as :meth:`relloc.core.recording.GroundTruth.valid_at` already rules ("a time ``t``
is a sample or lies between two samples at most ``gap_s`` apart"). The MRCLAM container
flags the sample that *ends* a gap as in the gap (but not the one that starts it)."""

from __future__ import annotations

import numpy as np

from relloc.core import recording as rec
from relloc.datasets.mrclam import GroundTruth

T = np.array([0.0, 0.5, 1.5, 2.0])  # a 1 s gap between the samples at 0.5 s and 1.5 s


def test_the_sample_ending_a_gap_is_a_valid_query():
    g = GroundTruth(t=T, x=T.copy(), y=0 * T, theta=0 * T, gap_threshold=0.5)
    q = g.at([0.5, 1.0, 1.5])
    assert q.in_gap.tolist() == [False, True, False]
    assert q.valid.tolist() == [True, False, True]


def test_the_recording_ground_truth_agrees_that_both_ends_of_a_gap_are_valid():
    """The pipeline's own container on the same samples (the reference for the rule above)."""
    truth = rec.GroundTruth(t=T, pose=np.zeros((4, 4)), where="t", gap_s=0.5)
    assert truth.valid_at(np.array([0.5, 1.0, 1.5])).tolist() == [True, False, True]
