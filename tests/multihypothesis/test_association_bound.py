"""The truth-placed association bound (``relloc.experiments.association_bound``)."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
from test_mrclam_association import _synthetic_folder

from relloc.core.recording import CLUTTER
from relloc.datasets.mrclam import load_mrclam, to_recording
from relloc.estimators.gaussian_sum import GaussianSumSettings
from relloc.experiments import mrclam_association
from relloc.experiments.association_bound import association_bound
from relloc.models.motion import VelocityNoise


def _settings(clutter: float) -> GaussianSumSettings:
    sig = (0.05, 0.05, 1e-3, 0.05)
    formation = replace(mrclam_association.planar_formation(0.01), p_detect=0.9)
    return GaussianSumSettings(
        velocity_noise=VelocityNoise(observer=sig, observed=sig),
        sigma_height=0.01,
        sigma_range=0.1,
        sigma_azimuth=0.03,
        sigma_elevation=0.03,
        use_elevation=False,
        field_of_view=np.pi,
        expected_clutter=clutter,
        formation=formation,
    )


def test_bound_is_high_without_clutter_and_drops_with_it(tmp_path: Path) -> None:
    raw = to_recording(load_mrclam(_synthetic_folder(tmp_path / "d", np.random.default_rng(3))))
    clean, _ = mrclam_association._hidden_correspondence(
        raw, 5.0, 20.0, np.pi, np.random.default_rng(4), 0.0
    )
    dense, _ = mrclam_association._hidden_correspondence(
        raw, 5.0, 20.0, np.pi, np.random.default_rng(4), 20.0
    )
    b_clean = association_bound(clean, _settings(0.0))
    b_dense = association_bound(dense, _settings(20.0))
    # three robots that see each other in every frame, bearing noise 0.02 rad: a filter that
    # knows where they are takes almost only their bearings
    assert b_clean.used > 100 and b_clean.accuracy is not None and b_clean.accuracy >= 0.95
    # 20 false bearings per scan over the full circle: some fall inside the 0.03-rad gate
    assert b_dense.accuracy is not None and b_dense.accuracy < b_clean.accuracy


def test_bound_reads_the_origin_of_the_bearing_taken(tmp_path: Path) -> None:
    """The same scans with every robot bearing relabelled as clutter: the truth-placed tracks
    take the same bearings, and none of them counts as correct."""
    raw = to_recording(load_mrclam(_synthetic_folder(tmp_path / "d", np.random.default_rng(5))))
    rec, _ = mrclam_association._hidden_correspondence(
        raw, 5.0, 12.0, np.pi, np.random.default_rng(6), 0.0
    )
    m = rec.measurements
    assert m.origin is not None
    relabelled = replace(
        rec, measurements=replace(m, origin=np.where(m.kind == m.kind, CLUTTER, m.origin))
    )
    before = association_bound(rec, _settings(0.0))
    after = association_bound(relabelled, _settings(0.0))
    assert before.used == after.used > 0 and before.correct > 0
    assert after.correct == 0 and after.accuracy == 0.0
