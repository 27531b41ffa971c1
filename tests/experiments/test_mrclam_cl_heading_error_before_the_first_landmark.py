"""``heading_error_by_landmark_gap`` (``relloc.experiments.mrclam_cl``): the bins of the time
since the last landmark detection cover every record. A record before the robot's first
landmark detection has no such time (∞, 'never'); it belongs to the open-ended last bin
(``5-infs``), so that the time shares and the squared-error shares each sum to 1."""

from __future__ import annotations

import pytest
from test_scoring_mrclam_cl_evaluate_by_hand import _landmark_gap_inputs


def test_a_record_before_the_first_landmark_is_in_the_last_bin() -> None:
    """First landmark at 0.2 s: the record at 0 s (heading error 0.1 rad) has never seen one;
    the others are 0.3, 1.8, 5.8 and 0.5 s after one."""
    from relloc.experiments.mrclam_cl import heading_error_by_landmark_gap

    out = heading_error_by_landmark_gap(*_landmark_gap_inputs(0.2))
    assert sum(b["time_share"] for b in out.values()) == pytest.approx(1.0)
    assert sum(b["squared_error_share"] for b in out.values()) == pytest.approx(1.0)
    assert out["5-infs"]["time_share"] == pytest.approx(0.4)  # the records at 0 s and 6 s
