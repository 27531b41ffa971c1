"""The yaw-hypothesis bank: construction, Bayes reweighting, merge/prune/collapse, tracking."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from relloc.core.gaussian import Gaussian, GaussianMixture
from relloc.core.kalman import Innovation
from relloc.errors import ConfigError, ModelError
from relloc.estimators.relative import FilterSettings, RelativeTracker
from relloc.estimators.yaw_bank import (
    YawBankSettings,
    YawBankTracker,
    reduce_bank,
    reweight,
    spread_yaw_bank,
)
from relloc.models.measurement import RangeBearingNoise
from relloc.models.motion import VelocityNoise
from relloc.sim.scenario import default_scenario
from relloc.sim.simulate import simulate

UNKNOWN = np.diag([0.01, 0.01, 0.01, (math.pi / math.sqrt(3)) ** 2])


def test_spread_puts_hypotheses_evenly_on_the_circle() -> None:
    settings = YawBankSettings(n_components=8)
    bank = spread_yaw_bank(np.array([1.0, 2.0, 0.5, 3.0]), UNKNOWN, settings)
    assert bank.means.shape == (8, 4) and bank.covs.shape == (8, 4, 4)
    yaws = np.sort(np.mod(bank.means[:, 3] - 3.0, 2 * math.pi))
    np.testing.assert_allclose(yaws, 2 * math.pi * np.arange(8) / 8, atol=1e-12)
    np.testing.assert_allclose(bank.covs[:, 3, 3], (math.pi / 8) ** 2)
    np.testing.assert_allclose(bank.normalised_weights(), 1 / 8)
    np.testing.assert_allclose(bank.means[:, :3], np.tile([1.0, 2.0, 0.5], (8, 1)))


def test_known_yaw_prior_is_a_single_filter_and_batches_must_agree() -> None:
    known = np.diag([0.01, 0.01, 0.01, 0.02**2])
    bank = spread_yaw_bank(np.zeros(4), known, YawBankSettings())
    assert bank.weights.shape == (1,)
    batch_cov = np.stack([known, UNKNOWN])
    with pytest.raises(ModelError, match="all unknown-yaw or all known-yaw"):
        spread_yaw_bank(np.zeros((2, 4)), batch_cov, YawBankSettings())
    batched = spread_yaw_bank(np.zeros((3, 4)), np.stack([UNKNOWN] * 3), YawBankSettings())
    assert batched.means.shape == (3, 12, 4)
    assert batched.heaviest()[0].shape == (3, 4)


def test_reweight_follows_the_innovation_likelihood() -> None:
    S = np.stack([np.eye(3), np.eye(3), 4 * np.eye(3)])
    inn = Innovation(residual=np.zeros((3, 3)), cov=S, nis=np.array([1.0, 9.0, 1.0]), meas_cov=S)
    w = reweight(np.array([1.0, 1.0, 0.0]), inn)
    # log N ratio between the first two: -(1 - 9)/2 = 4; the dropped slot stays dropped
    assert w[0] == 1.0 and w[1] == pytest.approx(math.exp(-4.0))
    assert w[2] == 0.0


def _bank(yaws: list[float], log_w: list[float], sigma: float = 0.05) -> GaussianMixture:
    k = len(yaws)
    means = np.zeros((k, 4))
    means[:, 0] = np.arange(k)  # distinct states, to see which one survives
    means[:, 3] = yaws
    covs = np.tile(np.diag([0.01, 0.01, 0.01, sigma**2]), (k, 1, 1))
    return GaussianMixture(means=means, covs=covs, weights=np.exp(log_w))


def test_reduce_merges_neighbours_prunes_the_unlikely_and_collapses() -> None:
    settings = YawBankSettings(prune_ratio=1e-3, merge_sigmas=1.0, collapse_weight=0.99)
    # slot 1 sits 0.05 rad from the best (within 1σ of the difference, 0.0707): merged;
    # slot 2 is far and likely enough to stay; slot 3 is far and below the prune ratio
    bank = reduce_bank(_bank([0.0, 0.05, 2.0, -2.0], [0.0, -0.5, -1.0, -9.0]), settings)
    assert list(bank.alive) == [True, False, True, False]
    w = bank.normalised_weights()
    expected = np.array([1 + math.exp(-0.5), math.exp(-1.0)])
    np.testing.assert_allclose(w[[0, 2]], expected / expected.sum())
    # dropped slots carry the best state so they cannot disturb later batched updates
    np.testing.assert_allclose(bank.means[1], bank.means[0])
    # a dominant hypothesis collapses the bank
    collapsed = reduce_bank(_bank([0.0, 2.0], [0.0, -6.0]), settings)
    assert list(collapsed.alive) == [True, False]
    assert collapsed.heaviest()[0][0] == 0.0


def test_settings_are_validated() -> None:
    with pytest.raises(ConfigError, match="n_components"):
        YawBankSettings(n_components=1)
    with pytest.raises(ConfigError, match="prune_ratio"):
        YawBankSettings(prune_ratio=0.0)
    with pytest.raises(ConfigError, match="collapse_weight"):
        YawBankSettings(collapse_weight=0.3)
    with pytest.raises(ModelError, match="weight > 0"):
        GaussianMixture(means=np.zeros((2, 4)), covs=np.zeros((2, 4, 4)), weights=np.zeros(2))


def test_bank_recovers_a_yaw_error_near_pi_where_the_plkf_stalls() -> None:
    """Aerial robot of the default team, yaw guess 3.0 rad off: bank < 0.1 rad in 12 updates."""
    scenario = default_scenario()
    scenario = dataclasses.replace(scenario, robots=scenario.robots[:2], duration_s=3.0)
    rec = simulate(scenario, np.random.default_rng(7))
    odo_l, odo_c = rec.odometry
    settings = FilterSettings(
        kind="plkf",
        motion_noise=VelocityNoise(
            observer=tuple(odo_l.sigma.tolist()),  # type: ignore[arg-type]
            observed=tuple(odo_c.sigma.tolist()),  # type: ignore[arg-type]
        ),
        sensor_noise=RangeBearingNoise(
            sigma_r=0.0068, sigma_azimuth=0.0036, sigma_elevation=0.0036
        ),
    )
    truth0 = rec.relative_truth(0, 1, 0.0)[0]
    guess = truth0 + np.array([0.0, 0.0, 0.0, 3.0])
    prior = Gaussian(mean=guess, cov=np.diag([0.02**2] * 3 + [math.pi**2 / 3]))
    bank = YawBankTracker(prior, settings, YawBankSettings())
    plain = RelativeTracker(prior, settings)
    m = rec.measurements
    dt = float(odo_l.t[1] - odo_l.t[0])
    yaw_err: dict[str, list[float]] = {"bank": [], "plkf": []}
    i = 0
    for k in range(len(odo_l.t)):
        for tracker in (bank, plain):
            tracker.predict(odo_l.velocity[k], odo_c.velocity[k], dt)
        while i < m.size and m.t[i] <= odo_l.t[k] + dt + 1e-9:
            truth = rec.relative_truth(0, 1, m.t[i])[0]
            for name, tracker in (("bank", bank), ("plkf", plain)):
                tracker.update(m.value[i])
                err = tracker.belief.mean[3] - truth[3]
                yaw_err[name].append(abs(math.atan2(math.sin(err), math.cos(err))))
            i += 1
    assert len(yaw_err["bank"]) >= 20
    assert max(yaw_err["bank"][11:20]) < 0.1
    assert bank.n_alive == 1
    assert min(yaw_err["plkf"][11:20]) > 0.1
