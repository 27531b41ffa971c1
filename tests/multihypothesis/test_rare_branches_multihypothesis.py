"""Branches of the association stages, the Gaussian-sum fuser and its estimator wrapper that
only rarer settings or hostile input reach: each refusal names where, each shortcut returns
what the general path means."""

from __future__ import annotations

import numpy as np
import pytest
from gaussian_sum_samples import gs_settings

from relloc.association.hypotheses import FormationSettings, birth_tracks
from relloc.association.mixture_reduction import heaviest_mask, merge_moments
from relloc.association.nscan import family_keep_mask
from relloc.core.contract import HeldOdometry
from relloc.errors import ConfigError, DataError, ModelError
from relloc.estimators.gaussian_sum import GaussianSumFuser, Tracks
from relloc.fusion.decorrelation import decorrelated_fusion
from relloc.fusion.gaussian_sum_estimator import GaussianSumEstimator


def _one_track(fus: GaussianSumFuser) -> None:
    m = np.array([[3.0, 1.0, 0.5, 0.3]])
    cov = np.diag([0.01, 0.01, 0.01, 0.01])[None]
    fus.tracks = Tracks(
        groups=np.zeros(1, dtype=np.int64),
        means=m.copy(),
        covs=cov.copy(),
        prior_means=m.copy(),
        prior_covs=cov.copy(),
        weights=np.ones(1),
        history=np.zeros((1, fus.settings.nscan_depth + 1), dtype=np.int64),
        assoc=np.full(1, -1, dtype=np.int64),
    )


@pytest.mark.parametrize(
    ("changes", "match"),
    [
        ({"p_gate": 1.0}, r"FormationSettings\.p_gate must be < 1"),
        ({"birth_yaw_components": 65}, r"FormationSettings\.birth_yaw_components must lie in"),
    ],
)
def test_formation_settings_refuse_a_certain_gate_and_too_many_yaw_components(
    changes: dict[str, object], match: str
) -> None:
    """A gate of probability 1 has no threshold (χ² quantile ∞); more than 64 yaw components
    per bearing are refused."""
    with pytest.raises(ConfigError, match=match):
        FormationSettings(**changes)  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("volume", "range_volume", "false_density"),
    [(0.0, 5.0, 0.1), (1.0, -1.0, 0.1), (1.0, 5.0, [0.1, 0.0])],
)
def test_births_need_positive_volumes_and_clutter_density(
    volume: float, range_volume: float, false_density: object
) -> None:
    with pytest.raises(ConfigError, match="birth_tracks: volume, range_volume and false_density"):
        birth_tracks(
            2.0,
            np.array([0.1, 0.2]),
            np.zeros(2),
            0.0,
            FormationSettings(),
            volume=volume,
            range_volume=range_volume,
            false_density=false_density,  # type: ignore[arg-type]
        )


def test_merge_moments_refuses_an_infinite_weight() -> None:
    """A total of ∞ from finite weights is merged at the scale of the largest; an infinite
    weight itself has no share to merge by."""
    means = np.zeros((2, 4))
    covs = np.broadcast_to(np.eye(4), (2, 4, 4)).copy()
    group = np.arange(2)
    with pytest.raises(ModelError, match=r"merge_moments: a weight is not finite \(inf\)"):
        merge_moments(means, covs, np.array([np.inf, 1.0]), group)


def test_heaviest_of_mixtures_without_components_is_an_empty_mask() -> None:
    """``argmax`` of an empty axis is an error; no component means no heaviest one."""
    mask = heaviest_mask(np.zeros((3, 0)))
    assert mask.shape == (3, 0) and mask.dtype == bool
    assert family_keep_mask(np.zeros((0, 2), dtype=np.int64), np.zeros(0), 0.1).shape == (0,)


def test_gaussian_sum_settings_need_a_velocity_noise() -> None:
    with pytest.raises(ConfigError, match=r"GaussianSumSettings\.velocity_noise must be"):
        gs_settings(velocity_noise=(0.2, 0.2, 0.2, 0.1))


def test_fuser_refuses_infinite_readings_and_bad_motion() -> None:
    """NaN marks a missing reading, ∞ is refused; a non-finite velocity or a negative or NaN
    time step is refused before any track moves (the clock included)."""
    fus = GaussianSumFuser(0, [1], gs_settings())
    with pytest.raises(DataError, match=r"fuser 0: range contains inf \(use NaN for missing\)"):
        fus.update_known("range", [np.inf])
    with pytest.raises(DataError, match=r"fuser 0 at t=0\.000: non-finite velocity"):
        fus.predict([0.0, 0.0, 0.0, np.nan], np.zeros((1, 4)), 0.1)
    for dt in (-0.1, np.nan):
        with pytest.raises(DataError, match=r"fuser 0 at t=0\.000: bad time step"):
            fus.predict(np.zeros(4), np.zeros((1, 4)), dt)
    assert fus.time == 0.0


def test_known_update_of_an_unknown_kind_is_refused() -> None:
    fus = GaussianSumFuser(0, [1], gs_settings())
    _one_track(fus)
    with pytest.raises(ConfigError, match="update_known: kind must be 'height' or 'range'"):
        fus.update_known("speed", [1.0])  # type: ignore[arg-type]


def test_estimator_wrapper_refuses_a_robot_outside_the_team_and_is_quiet_without_sharing() -> None:
    settings = gs_settings()
    with pytest.raises(
        ConfigError, match=r"GaussianSumEstimator: robot index 2 not in \('A', 'B'\)"
    ):
        GaussianSumEstimator(("A", "B"), 2, settings)
    quiet = GaussianSumEstimator(("A", "B"), 0, settings, sharing=False)
    assert quiet.quiet_until() == -np.inf
    quiet.advance(0.0, HeldOdometry.still(2))
    assert quiet.quiet_until() == np.inf
    loud = GaussianSumEstimator(("A", "B"), 0, settings)
    loud.advance(0.0, HeldOdometry.still(2))
    assert loud.quiet_until() < np.inf


def test_decorrelated_fusion_names_a_mean_beyond_float_range() -> None:
    """Finite inputs whose difference overflows give a non-finite fused mean."""
    P = np.eye(2)
    with (
        np.errstate(over="ignore", invalid="ignore"),
        pytest.raises(DataError, match="decorrelated_fusion: the fused mean is not finite"),
    ):
        decorrelated_fusion(
            np.full(2, -1e308), P, np.full(2, 1e308), 0.5 * P, np.zeros(2), P, angle_index=None
        )
