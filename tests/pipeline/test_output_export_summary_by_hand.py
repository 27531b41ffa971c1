"""export_estimates on hand-made beliefs: what is skipped is reported, and a clash of TUM file
names fails before any file (the MCAP one included) is written."""

from __future__ import annotations

import numpy as np
import pytest
from export_helpers import standing_pair

from relloc.core.estimates import BeliefSeries, Estimates
from relloc.core.recording import Recording
from relloc.errors import ConfigError
from relloc.pipeline.export import ExportRequest, export_estimates

pytest.importorskip("mcap", reason="extra 'ros' (mcap) is not installed")
pytest.importorskip("rosbags", reason="extra 'ros' (rosbags) is not installed")


def _recording() -> Recording:
    return standing_pair(None, [0.0, 0.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0])


def _world(track: str, mean: np.ndarray) -> BeliefSeries:
    t = np.arange(1.0, 1.0 + mean.shape[0])
    return BeliefSeries(
        owner="team",
        subject="b",
        track=track,
        frame="world_pose2",
        t=t,
        mean=mean,
        cov=np.stack([np.eye(3)] * t.size),
        age=t - 1.0,
    )


def test_the_summary_reports_the_records_not_exported(tmp_path):  # type: ignore[no-untyped-def]
    est = Estimates(
        estimator="hand", beliefs=(_world("", np.array([[1.0, 2.0, 0.0], [np.nan, 2.0, 0.0]])),)
    )
    section = export_estimates(
        ExportRequest(tum=tmp_path / "tum"), est, _recording(), run="run 0 of 1"
    )
    assert section["skipped"] == {"non-finite belief": 1}
    assert section["series"]["team->b"]["records"] == 1
    assert section["tum"]["pairs"]["team->b"]["poses"] == 1


def test_a_tum_name_clash_fails_before_the_mcap_file_is_written(tmp_path):  # type: ignore[no-untyped-def]
    # tracks "k/x" and "k_x" are different topics but the same TUM file b__k_x.tum
    one = np.array([[1.0, 2.0, 0.0]])
    est = Estimates(estimator="hand", beliefs=(_world("k/x", one), _world("k_x", one)))
    request = ExportRequest(mcap=tmp_path / "out.mcap", tum=tmp_path / "tum")
    with pytest.raises(ConfigError, match="both become the TUM file"):
        export_estimates(request, est, _recording(), run="run 0 of 1")
    assert not (tmp_path / "out.mcap").exists()
    assert not (tmp_path / "tum").exists()
